"""CLI: exit codes, one-line errors, files written."""

import subprocess
import sys
from pathlib import Path

import pytest

from analysis import STUDIES
from ctrl_analysis.cli import main


def test_list_names_all_five_studies(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    for name in ["ikf-mfac", "ckf", "differential-estimator", "meso", "pendulum"]:
        assert name in out
    assert len(STUDIES) == 5


@pytest.mark.parametrize(
    "argv,fragment",
    [
        (["reproduce", "nope"], "unknown study 'nope'"),
        (["reproduce", "ckf", "--runs", "0"], "--runs: must be a positive integer"),
        (["reproduce", "ckf", "--seed", "-3"], "--seed: must be a non-negative integer"),
        (["reproduce", "ckf", "--runs", "many"], "--runs: must be a positive integer"),
        (["frobnicate"], "invalid choice"),
        (["reproduce", "all", "nosuch"], "unknown study 'nosuch'; choose from"),
        (["reproduce", "pendulm"], "unknown study 'pendulm'; did you mean 'pendulum'?"),
        (["reproduce", "differential_estimator"], "did you mean 'differential-estimator'?"),
        (["reproduce", "pendulum", "--runs", "1000000000", "--out", "/nonexistent-not-created"],
         "--runs 1000000000 would need about "),
        (["reproduce", "all", "--quick", "--runs", "1000000000", "--out", "/nonexistent-not-created"],
         "GiB available; use --runs "),
    ],
)
def test_bad_input_is_one_line_and_exit_2(argv, fragment):
    proc = subprocess.run([sys.executable, "-m", "ctrl_analysis.cli", *argv], capture_output=True, text=True,
                          check=False)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and fragment in lines[0] and "Traceback" not in proc.stderr
    assert not Path("/nonexistent-not-created").exists()  # refused before --out is created




@pytest.mark.parametrize("argv", [["--help"], ["reproduce", "--help"], ["list", "--help"]])
def test_help_is_plain_text(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 0
    text = capsys.readouterr().out
    assert text.startswith("usage: ctrl-analysis")
    for markup in ("``", ":func:", ":class:", ":mod:", ":meth:", ".. "):
        assert markup not in text, markup
