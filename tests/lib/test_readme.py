"""The README's API example runs and does what it says (z_2 tracks the derivative of the sine)."""

import re
from pathlib import Path

import numpy as np

README = Path(__file__).resolve().parents[2] / "README.md"


def test_readme_example_runs_and_estimates_the_derivative(capsys):
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), re.S)
    assert blocks, "README has no python example"
    scope = {}
    exec(compile(blocks[0], "README.md", "exec"), scope)
    res = scope["res"]
    assert res.x.shape == (5001, 50, 4) and not res.diverged.any()
    # derivative estimate of sin at t = 5 s within 0.02 of cos(5) in every run
    np.testing.assert_allclose(res["xhat[1]"][-1], np.cos(5.0), atol=0.02)
