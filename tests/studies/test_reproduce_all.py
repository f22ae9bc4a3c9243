"""`ctrl-analysis reproduce all --quick` end to end: every study writes a results.json that passes the schema."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
from hang import limit

from analysis import STUDIES
from ctrl_analysis.reporting.report import validate_results

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.timeout(660)  # the run itself may take up to its subprocess limit (conftest scales both)
def test_reproduce_all_quick_writes_valid_results(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "ctrl_analysis.cli", "reproduce", "all", "--quick", "--out",
                           str(tmp_path)], capture_output=True, text=True, cwd=REPO, timeout=limit(600))
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr
    # studies run side by side (default --jobs) but their summaries print in the registry's order
    positions = [proc.stdout.index(f"== {name}:") for name in STUDIES]
    assert positions == sorted(positions)
    assert "not reproduced:" in proc.stdout  # every study lists what it does not reproduce
    for name in STUDIES:
        data = json.loads((tmp_path / name / "results.json").read_text(encoding="utf-8"))
        validate_results(data)  # raises ValueError on any schema violation
        assert data["study"] == name and data["quantities"] and data["missing"], name
        assert data["settings"]["cli"] == {"seed": 0, "runs": None, "quick": True}
        for fig in data["figures"]:
            assert (tmp_path / name / fig).stat().st_size > 5_000, (name, fig)
    report = (tmp_path / "REPORT.md").read_text(encoding="utf-8")
    assert all(f"## {name}" in report or f"`{name}`" in report for name in STUDIES)
