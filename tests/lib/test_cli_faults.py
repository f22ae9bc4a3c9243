"""Faults against one --out folder: Ctrl-C and kill -9 at several points of `reproduce all --quick`, two runs
at once, odd things in the folder. After each, REPORT.md agrees with every results.json on disk (base seed,
runs, per-run seeds, which studies), no staging folder is left once a run has finished, and no process of
the run is left.

The runs use three small stand-in studies (a package named ``analysis`` put first on PYTHONPATH) so that
each takes about a second: the CLI, its worker processes, the lock and the commits are the real ones.
"""

import json
import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from hang import limit

import analysis
from ctrl_analysis.cli import main
from ctrl_analysis.reporting.report import StudyInfo, StudyResult

REPO = Path(__file__).resolve().parents[2]
NAMES = ["alpha", "beta", "gamma"]

STUDY = '''
import os
import time
from ctrl_analysis.reporting.report import StudyInfo, StudyResult
from ctrl_analysis.noise import run_seeds

INFO = StudyInfo(name=__name__.split(".")[-1], seed_file="s.txt", paper="P", reproduces="r")


def run(ctx, params=None):
    ctx.progress("started")
    result = StudyResult(INFO)
    seeds = run_seeds(ctx.seed, ctx.runs_or(8, quick_default=4))
    result.seeds = {"noise": seeds}
    result.quantity("base_seed", "base seed seen by the study", float(ctx.seed), runs=len(seeds), unit="")
    (ctx.out_dir / "marker.txt").write_text(str(ctx.seed))
    end = time.monotonic() + SECONDS
    hold = os.environ.get("FAKE_HOLD")  # a file: the study also runs until it exists (60 s at most)
    while time.monotonic() < end or (hold and not os.path.exists(hold) and time.monotonic() < end + 60):
        if os.environ.get("FAKE_BUSY"):  # busy in exec() of a string, where a caught Ctrl-C used to end as -2
            exec("x = sum(range(2000))")
        else:
            time.sleep(0.01)
    return result
'''


@pytest.fixture
def fake(tmp_path):
    """A stand-in ``analysis`` package of three studies (0.05, 0.1 and 0.6 s) and the environment that uses it."""
    pkg = tmp_path / "fake" / "analysis"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text(textwrap.dedent(f'''
        import importlib
        STUDIES = {{n: "analysis." + n for n in {NAMES!r}}}
        def load_study(name):
            return importlib.import_module(STUDIES[name])
        '''))
    for i, name in enumerate(NAMES):
        (pkg / f"{name}.py").write_text(STUDY.replace("SECONDS", str([0.05, 0.1, 0.6][i])))
    # run from the package's folder: `python -m` puts the working directory first on sys.path
    yield {**os.environ, "PYTHONPATH": os.pathsep.join([str(pkg.parent), str(REPO)]), "CTRL_ANALYSIS_PROGRESS": "0",
            "FAKE_CWD": str(pkg.parent)}
    for proc in _STARTED:  # a failed test leaves no run behind
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=limit(30))
    _STARTED.clear()


_STARTED: list = []


def sigint_default():
    """In the child before exec: SIGINT back to its default, so Python installs its Ctrl-C handler even when the
    suite itself was started in the background by a shell without job control (which ignores SIGINT for it)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start(env, out, seed, jobs=2):
    # --verbose: the studies' progress lines on stderr tell the test when a study has started
    argv = [sys.executable, "-m", "ctrl_analysis.cli", "reproduce", "all", "--quick", "--verbose", "--jobs", str(jobs),
            "--out", str(out), "--seed", str(seed)]
    _STARTED.append(subprocess.Popen(argv, cwd=env["FAKE_CWD"], env=env, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, preexec_fn=sigint_default))
    return _STARTED[-1]


def _children(pid: int) -> list[int]:
    """Processes whose parent is ``pid`` (from /proc), recursively."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            if ppid == pid:
                found += [int(entry.name), *_children(int(entry.name))]
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state not in ("Z", "X")  # a zombie is dead, only not yet reaped by its new parent


def _wait_gone(pids, timeout=30.0) -> list[int]:
    end = time.monotonic() + limit(timeout)
    while time.monotonic() < end and any(_alive(p) for p in pids):
        time.sleep(0.02)
    return [p for p in pids if _alive(p)]


def _wait_committed(out: Path, seed: int, timeout=120.0) -> str:
    """The first study whose results.json on disk comes from the run with ``seed``."""
    end = time.monotonic() + limit(timeout)
    while time.monotonic() < end:
        for name in NAMES:
            try:
                if json.loads((out / name / "results.json").read_text())["settings"]["cli"]["seed"] == seed:
                    return name
            except (OSError, ValueError, KeyError):
                pass
        time.sleep(0.01)
    raise AssertionError(f"no study of the run with seed {seed} was committed within {timeout} s")


def _consistent(out: Path, committed_by=None) -> None:
    """REPORT.md (when present) describes exactly the results.json files on disk."""
    on_disk = {n: json.loads((out / n / "results.json").read_text()) for n in NAMES
               if (out / n / "results.json").exists()}
    report = out / "REPORT.md"
    if report.exists():
        text = report.read_text()
        rows = dict(re.findall(r"^\| (\w+) \| ((?:yes|\*\*no).*)$", text.split("### Provenance")[1], re.MULTILINE))
        assert set(rows) == set(on_disk), (rows, sorted(on_disk))
        for name, data in on_disk.items():
            row = rows[name]
            seeds = data["seeds"]["noise"]
            assert f"[{seeds[0]}, {seeds[1]}, " in row  # the per-run seeds shown are those of the file
            cli = data["settings"]["cli"]
            if row.startswith("yes"):
                assert row.startswith(f"yes (quick) | {cli['seed']} | default |"), (name, row, cli)
                assert data["quantities"][0]["value"] == cli["seed"]
            else:  # stale: the base seed and runs of the run that wrote the file, read from it
                stale = f"**no — stale** (results of an earlier run, quick) | {cli['seed']} | default |"
                assert row.startswith(stale), (name, row, cli)
    leftovers = [p.name for p in out.iterdir() if p.name.startswith(".") and p.name != ".ctrl-analysis.lock"]
    if committed_by is not None:
        assert not leftovers, leftovers


def _interrupt(env, out, seed, sig, when):
    """Start a run, deliver ``sig`` at ``when`` ("start": its first progress line; "commit": its first study
    on disk), and check what is left: the exit status, REPORT.md against the files, the processes."""
    proc = _start(env, out, seed)
    assert proc.stderr.readline().startswith("[")  # a study has started
    if when == "commit":
        _wait_committed(out, seed)
    kids = _children(proc.pid)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=limit(300))
    assert _wait_gone(kids) == [], "worker processes outlived the run"
    if sig == signal.SIGINT:
        assert proc.returncode == 130 and "Traceback" not in err
        assert err.strip().splitlines()[-1].startswith("ctrl-analysis: interrupted")
        assert [p.name for p in out.iterdir() if p.name.startswith(".")] == []  # no staging, no lock
    else:
        assert proc.returncode == -signal.SIGKILL
    _consistent(out)


def test_interrupts_and_kills_at_several_points_leave_report_and_results_in_agreement(tmp_path, fake):
    out = tmp_path / "out"
    first = _start(fake, out, 1)
    assert first.wait(timeout=limit(300)) == 0, first.stderr.read()
    _consistent(out, committed_by=1)
    _interrupt(fake, out, 2, signal.SIGINT, "start")
    _interrupt(fake, out, 3, signal.SIGINT, "commit")
    _interrupt(fake, out, 4, signal.SIGKILL, "start")
    _interrupt(fake, out, 5, signal.SIGKILL, "commit")
    # the next run takes the lock a killed run held, cleans its staging folders and agrees with the files
    last = _start(fake, out, 6)
    stdout, err = last.communicate(timeout=limit(300))
    assert last.returncode == 0, err
    assert stdout.strip().splitlines()[-1].startswith(f"ctrl-analysis: {len(NAMES)} of {len(NAMES)} studies OK, "
                                                      f"0 failed, ")
    _consistent(out, committed_by=6)
    assert sorted(p.name for p in out.iterdir()) == ["REPORT.md", *NAMES]


def test_two_runs_into_one_folder_do_not_interleave(tmp_path, fake):
    out = tmp_path / "out"
    release = tmp_path / "release"
    # a's studies run until b has been refused: on a loaded machine b's start-up alone may outlast a's
    # 0.6 s, and b then (rightly) finds no lock
    a = _start({**fake, "FAKE_HOLD": str(release)}, out, 11)
    assert a.stderr.readline().startswith("[")  # a holds the lock
    b = _start(fake, out, 12)
    _, err_b = b.communicate(timeout=limit(300))
    release.write_text("")
    _, err_a = a.communicate(timeout=limit(300))
    assert a.returncode == 0, err_a
    assert b.returncode == 2 and err_b.strip().splitlines() == [
        (f"ctrl-analysis: error: another ctrl-analysis run (pid {a.pid}) is writing into --out {str(out)!r}; "
         f"wait for it to finish or choose another --out")]
    _consistent(out, committed_by=11)
    assert all(json.loads((out / n / "results.json").read_text())["settings"]["cli"]["seed"] == 11 for n in NAMES)


def test_ctrl_c_exits_130_every_time(tmp_path, fake):
    # each study (run in the main process, --jobs 1) spends its time in exec() of a string, where a caught
    # KeyboardInterrupt used to make `python -m` kill itself with SIGINT at exit (status -2, 1 interrupt in
    # 15 on a real study): here nearly every interrupt lands there, so 6 interrupts fail the old code
    busy = {**fake, "FAKE_BUSY": "1"}
    for i in range(6):
        proc = _start(busy, tmp_path / f"out{i}", i, jobs=1)
        assert proc.stderr.readline().startswith("[")
        time.sleep(0.05 * i)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=limit(300))
        assert proc.returncode == 130, (i, err)


# ------------------------------------------------------------------ odd things in --out (in process)
def _fake_study(name):
    class Fake:
        INFO = StudyInfo(name=name, seed_file="s.txt", paper="P", reproduces="r")

        @staticmethod
        def run(ctx, params=None):
            result = StudyResult(Fake.INFO)
            result.quantity("q", "q", float(ctx.seed), runs=ctx.runs)
            return result

    return Fake


def test_a_file_named_like_a_study_is_refused_not_deleted(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(analysis, "load_study", _fake_study)
    name = next(iter(analysis.STUDIES))
    (tmp_path / name).write_text("my notes")
    assert main(["reproduce", name, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"holds {name!r}, which is not a folder ctrl-analysis wrote" in err[0]
    assert (tmp_path / name).read_text() == "my notes"
    foreign = tmp_path / "other"
    (foreign / name).mkdir(parents=True)
    (foreign / name / "notes.txt").write_text("mine")
    assert main(["reproduce", name, "--out", str(foreign)]) == 2
    assert "with files but no results.json" in capsys.readouterr().err
    assert (foreign / name / "notes.txt").read_text() == "mine"


def test_another_studys_unreadable_results_json_is_left_out_of_the_report_not_counted_as_failed(
        tmp_path, monkeypatch, capsys):
    # the run's one study succeeds; a study it did not run has a results.json that is not a results record:
    # REPORT.md leaves that study out and says so, a warning names it, and the run is OK (exit 0): the
    # file is not this run's and nothing of this run failed
    monkeypatch.setattr(analysis, "load_study", _fake_study)
    names = list(analysis.STUDIES)
    assert main(["reproduce", "all", "--out", str(tmp_path), "--seed", "3", "--jobs", "1"]) == 0
    (tmp_path / names[1] / "results.json").write_text('{"study": "x", "numbers": [1, 2]}')
    capsys.readouterr()
    assert main(["reproduce", names[0], "--out", str(tmp_path), "--seed", "4"]) == 0
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith(f"ctrl-analysis: warning: REPORT.md leaves out {names[1]}, not run now: ")
    assert f"is not a results record of {names[1]}" in err[0]
    assert captured.out.strip().splitlines()[-1].startswith("ctrl-analysis: 1 of 1 studies OK, 0 failed, ")
    report = (tmp_path / "REPORT.md").read_text()
    assert f"| {names[0]} | yes | 4 |" in report and f"## {names[1]}" not in report
    left_out = report.split("## Left out of this report")[1]
    assert f"- **{names[1]}**: " in left_out and "is not a results record" in left_out
    assert "Failed in this run" not in report and "**no — failed**" not in report
    # the studies not run now are stale, with the base seed and runs their results.json records
    for name in names[2:]:
        assert f"| {name} | **no — stale** (results of an earlier run) | 3 | default |" in report


def test_a_kill_between_the_two_renames_of_a_swap_is_repaired_by_the_next_run(tmp_path, monkeypatch):
    # where the atomic exchange is unavailable, the swap is two renames through .<name>.old-*/dir
    monkeypatch.setattr(analysis, "load_study", _fake_study)
    name = next(iter(analysis.STUDIES))
    assert main(["reproduce", name, "--out", str(tmp_path), "--seed", "1"]) == 0
    old = tmp_path / f".{name}.old-x1"
    old.mkdir()
    (tmp_path / name).rename(old / "dir")  # the state a kill after the first rename leaves
    (tmp_path / f".{name}.new-y2").mkdir()  # and a staging folder of the killed run
    assert main(["reproduce", list(analysis.STUDIES)[1], "--out", str(tmp_path)]) == 0
    assert json.loads((tmp_path / name / "results.json").read_text())["settings"]["cli"]["seed"] == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([name, list(analysis.STUDIES)[1]])


def test_a_report_md_that_is_a_folder_is_refused_before_any_work(tmp_path, monkeypatch, capsys):
    # it used to run the study, fail to put REPORT.md in place, and report "0 of 1 studies OK ... failed:
    # REPORT.md, <study>" although the study was written
    monkeypatch.setattr(analysis, "load_study", _fake_study)
    name = next(iter(analysis.STUDIES))
    (tmp_path / "REPORT.md").mkdir()
    assert main(["reproduce", name, "--out", str(tmp_path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.strip().splitlines() == [
        (f"ctrl-analysis: error: --out {str(tmp_path)!r} holds REPORT.md, which is not a file ctrl-analysis wrote "
         f"(a folder); it is not replaced: move it away or choose another --out")]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["REPORT.md"]


def _study_making_report_a_folder(name):
    """A study that, while it runs, makes ``REPORT.md`` in its --out a folder (so the report cannot be put in place)."""
    fake = _fake_study(name)

    class Study:
        INFO = fake.INFO

        @staticmethod
        def run(ctx, params=None):
            report = ctx.out_dir.parent / "REPORT.md"
            report.unlink(missing_ok=True)
            report.mkdir()
            return fake.run(ctx, params)

    return Study


def test_a_report_md_that_cannot_be_written_is_its_own_line_and_the_studies_count_as_ok(tmp_path, monkeypatch,
                                                                                       capsys):
    monkeypatch.setattr(analysis, "load_study", _fake_study)
    names = list(analysis.STUDIES)
    assert main(["reproduce", "all", "--out", str(tmp_path), "--seed", "1", "--jobs", "1"]) == 0
    capsys.readouterr()
    # the report cannot be put in place after the study is: the study is written and OK, REPORT.md is not
    # written (its own line), and the run exits 1: an output it was asked for is missing
    monkeypatch.setattr(analysis, "load_study", _study_making_report_a_folder)
    assert main(["reproduce", names[0], "--out", str(tmp_path), "--seed", "2"]) == 1
    captured = capsys.readouterr()
    out, err = captured.out.strip().splitlines(), captured.err.strip().splitlines()
    assert out[0].startswith(f"== {names[0]}: ") and len(out) == 2
    assert out[-1].startswith("ctrl-analysis: 1 of 1 studies OK, 0 failed, ") and out[-1].endswith(
        "; REPORT.md not written")
    assert len(err) == 1 and err[0].startswith("ctrl-analysis: error: REPORT.md not written: IsADirectoryError: ")
    assert json.loads((tmp_path / names[0] / "results.json").read_text())["settings"]["cli"]["seed"] == 2
    assert not [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]  # no staging, no lock left
    # rendering it fails (a full disk, say) while an earlier run's REPORT.md is there: the line says that
    # REPORT.md no longer describes this run's studies
    (tmp_path / "REPORT.md").rmdir()
    monkeypatch.setattr(analysis, "load_study", _fake_study)
    assert main(["reproduce", "all", "--out", str(tmp_path), "--seed", "3", "--jobs", "1"]) == 0

    def full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("ctrl_analysis.reporting.run_folder.write_report_md", full)
    capsys.readouterr()
    assert main(["reproduce", names[0], "--out", str(tmp_path), "--seed", "4"]) == 1
    captured = capsys.readouterr()
    assert captured.out.strip().splitlines()[-1].startswith("ctrl-analysis: 1 of 1 studies OK, 0 failed, ")
    assert captured.err.strip().splitlines() == [
        ("ctrl-analysis: error: REPORT.md not written: OSError: [Errno 28] No space left on device; the REPORT.md in "
         "--out is an earlier run's, which does not describe the studies of this run")]
    assert json.loads((tmp_path / names[0] / "results.json").read_text())["settings"]["cli"]["seed"] == 4
