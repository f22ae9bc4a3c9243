"""The tree is clean under the project's ruff configuration ([tool.ruff] in pyproject.toml), so CI runs the linter."""

import subprocess
import sys
from pathlib import Path

from hang import limit

ROOT = Path(__file__).resolve().parents[2]


def test_ruff_check_is_clean_with_the_projects_configuration():
    proc = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "--output-format", "concise", "."],
                          cwd=ROOT, capture_output=True, text=True, timeout=limit(120))
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-2000:]
