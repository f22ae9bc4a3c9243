"""CLI: exit codes, one-line errors, files written."""

import subprocess
import sys

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
    ],
)
def test_bad_input_is_one_line_and_exit_2(argv, fragment):
    proc = subprocess.run([sys.executable, "-m", "ctrl_analysis.cli", *argv], capture_output=True, text=True,
                          check=False)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and fragment in lines[0] and "Traceback" not in proc.stderr




@pytest.mark.parametrize("argv", [["--help"], ["reproduce", "--help"], ["list", "--help"]])
def test_help_is_plain_text(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 0
    text = capsys.readouterr().out
    assert text.startswith("usage: ctrl-analysis")
    for markup in ("``", ":func:", ":class:", ":mod:", ":meth:", ".. "):
        assert markup not in text, markup
