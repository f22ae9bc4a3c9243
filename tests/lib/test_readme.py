"""The README's examples run and do what they say (one per block family)."""

import re
from pathlib import Path

import numpy as np

README = Path(__file__).resolve().parents[2] / "README.md"


def _examples():
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), re.S)
    assert len(blocks) == 5, "README has one example per family: estimator, filter, MFAC, fuzzy, identification"
    return blocks


def _run(code):
    import warnings

    from ctrl_analysis.engine.compiled import SlowPathWarning

    scope = {}
    with warnings.catch_warnings():
        warnings.simplefilter("error", SlowPathWarning)  # the README's loops compile (issue 29)
        exec(compile(code, "README.md", "exec"), scope)
    return scope


def test_estimator_example_estimates_the_derivative(capsys):
    s = _run(_examples()[0])
    res = s["res"]
    assert res["xhat[1]"].shape == (5001, 50) and not res.diverged.any()
    # derivative estimate of sin at t = 5 s within 0.02 of cos(5) in every run
    np.testing.assert_allclose(res["xhat[1]"][-1], np.cos(5.0), atol=0.02)


def test_filter_example_tracks_the_velocity(capsys):
    s = _run(_examples()[1])
    assert np.all(np.abs(s["ab"].poles) < 1)
    # (α + β/2)² = 2β for Kalata's gains; the velocity estimate is within 10 % of 3 m/s
    assert abs((s["alpha"] + s["beta"] / 2) ** 2 - 2 * s["beta"]) < 1e-12
    assert abs(s["y"][-1, 0, 1] - 3.0) < 0.3


def test_mfac_example_tracks_both_setpoints(capsys):
    s = _run(_examples()[2])
    y = s["res"]["y"][:, 0]
    assert abs(y[199] - 1.0) < 1e-6 and abs(y[-1] + 0.5) < 1e-6


def test_fuzzy_example_lookup_matches_inference(capsys):
    s = _run(_examples()[3])
    direct, table = s["fuzzy"].evaluate(s["e"], s["ec"]), s["table"].evaluate(s["e"], s["ec"])
    assert abs(direct[0]) < 1e-9  # odd-symmetric rule table: zero at the origin
    np.testing.assert_allclose(table, direct, atol=0.01 * 10)  # within 1 % of the output range ±10


def test_identification_example_recovers_the_arx_parameters(capsys):
    s = _run(_examples()[4])
    np.testing.assert_allclose(s["theta"][-1], [1.5, -0.7, 0.5], atol=0.01)


def test_readme_verdict_overview_is_the_generated_one():
    """The README's overview table is what report_md.overview_table makes of the committed results."""
    import json

    from analysis import STUDIES
    from ctrl_analysis.reporting.markdown import overview_table

    root = README.parent
    results = [json.loads((root / "figures" / n / "results.json").read_text(encoding="utf-8")) for n in STUDIES]
    table = "\n".join(overview_table(results, {r["study"]: r["settings"].get("cli", {}) for r in results}))
    text = README.read_text(encoding="utf-8")
    shown = text[text.index("\n", text.index("<!-- overview")) + 1:text.index("<!-- /overview -->")].strip()
    assert shown == table.replace("](#", "](figures/REPORT.md#")
