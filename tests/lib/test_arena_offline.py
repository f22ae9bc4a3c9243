"""The arena's offline smoothers: exact on what their models hold exactly, tuned like the causal families, and ranked
apart from them in a record run (the price of causality)."""

import json

import numpy as np
import pytest

from ctrl_analysis.arena.interface import FAMILIES, OFFLINE, estimate, family, scales
from ctrl_analysis.arena.offline import rts_smoother, savgol_smoother, spline_smoother
from ctrl_analysis.cli import main

DT = 0.01
T = DT * np.arange(500)


def test_savitzky_golay_is_exact_on_a_polynomial_of_its_degree_edges_included():
    y = (3 * T**2 + T)[:, None]
    e = savgol_smoother(y, np.array([31]), np.array([2]), DT)
    np.testing.assert_allclose(e[:, 0, 1], 6 * T + 1, atol=1e-9)
    np.testing.assert_allclose(e[:, 0, 2], 6.0, atol=1e-8)


def test_spline_with_a_light_penalty_follows_a_smooth_signal():
    e = spline_smoother(np.sin(T)[:, None], np.array([1e-8]), DT)
    assert np.max(np.abs(e[20:-20, 0, 1] - np.cos(T[20:-20]))) < 1e-6


def test_rts_is_exact_on_the_constant_velocity_model_it_assumes():
    y = np.column_stack([2 * T + 1, -3 * T])
    for lam in (0.01, 1.0):
        e = rts_smoother(y, np.array([lam, lam]), DT)
        np.testing.assert_allclose(e[:, :, 1], [[2.0, -3.0]] * T.size, atol=1e-9)


def test_rts3_is_exact_on_the_constant_acceleration_model_it_assumes():
    y = (1.5 * T**2 + 2 * T + 1)[:, None]
    for lam in (1e-6, 0.01, 1.0):
        e = rts_smoother(y, np.array([lam]), DT, order=3)
        assert e.shape == (T.size, 1, 3)
        np.testing.assert_allclose(e[:, 0, 1], 3 * T + 2, atol=1e-9)
        np.testing.assert_allclose(e[:, 0, 2], 3.0, atol=1e-7)
    # the constant-velocity smoother is not (a parabola is outside its model): the test can fail
    assert np.max(np.abs(rts_smoother(y, np.array([1e-6]), DT)[:, 0, 1] - (3 * T + 2))) > 0.1
    assert estimate("rts3", [[0.01]], y, DT).shape == (T.size, 1, 3)


def test_a_record_without_its_derivative_gets_each_familys_pareto_front():
    from ctrl_analysis.arena.recommend import recommend_for_record

    t = 0.01 * np.arange(600)
    y = np.sin(t) + 0.01 * np.random.default_rng(3).uniform(-1, 1, t.size)
    rows = recommend_for_record(t, y, None, 0.01, 1.0, rounds=1)
    for r in rows:
        p = np.array(r["pareto"])
        assert p.ndim == 2 and p.shape[1] == 2 and len(p) >= 1
        # non-dominated: the lag grows and the noise-induced error falls along the front
        assert np.all(np.diff(p[:, 0]) >= 0) and np.all(np.diff(p[:, 1]) < 0)
    with_d1 = recommend_for_record(t, y, np.cos(t), 0.01, 1.0, rounds=0)
    assert all(r["pareto"] == [] for r in with_d1)


def test_offline_families_use_the_future_and_beat_the_causal_best_on_a_noisy_record():
    rng = np.random.default_rng(5)
    t = 0.002 * np.arange(3000)
    y = (np.sin(2 * t) + 0.01 * rng.uniform(-1, 1, t.size))[:, None]
    s = scales(0.01, 4.0, 0.002)
    k = slice(500, 2500)
    causal = estimate("abg", [[s["lambda3"]]], y, 0.002)[k, 0, 1]
    smooth = estimate("sg", [[3 * s["window"], 2]], y, 0.002)[k, 0, 1]
    err = [np.sqrt(np.mean((e - 2 * np.cos(2 * t[k])) ** 2)) for e in (causal, smooth)]
    assert err[1] < err[0] / 2
    # non-causal: a change at the end of the record moves the smoothed estimate before it
    y2 = y.copy()
    y2[2000:] += 1.0
    before = [estimate("sg", [[101, 2]], v, 0.002)[1960, 0] for v in (y, y2)]
    assert not np.allclose(*before)
    assert all(f.causal for f in FAMILIES) and not any(f.causal for f in OFFLINE)
    assert family("spline").name == "spline"


def test_a_record_run_ranks_online_and_offline_apart_with_the_price_of_causality(tmp_path, capsys):
    t = 0.002 * np.arange(2000)
    y = np.sin(2 * t) + 0.01 * np.random.default_rng(2).uniform(-1, 1, t.size)
    f = tmp_path / "r.csv"
    np.savetxt(f, np.column_stack([t, y, 2 * np.cos(2 * t)]), delimiter=",", header="t,y,dy", comments="")
    assert main(["arena", "--signal", str(f), "--noise-bound", "0.01", "--accel-bound", "4", "--out",
                 str(tmp_path / "o"), "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    assert "offline smoothers" in out and "price of causality" in out
    r = json.loads((tmp_path / "o" / "arena" / "results.json").read_text())
    assert sorted(r["settings"]["offline_families"]) == sorted(f.name for f in OFFLINE)
    q = {x["id"]: x["value"] for x in r["quantities"]}
    best_causal = min(q[f"{fam.name}.worst"] for fam in FAMILIES)
    best_offline = min(q[f"{fam.name}.worst"] for fam in OFFLINE)
    assert q["price_of_causality.worst"] == pytest.approx(best_causal / best_offline)
    # the untuned reference keeps its guarantee on this admissible record (|f''| <= 4, |noise| <= 0.01)
    assert q["reference.difference_quotient.worst"] <= q["reference.difference_quotient.guarantee"]
    csv = np.loadtxt(tmp_path / "o" / "arena" / "estimate.csv", delimiter=",", skiprows=1)
    assert csv.shape[1] in (4, 5, 6) and csv.shape[0] == t.size
    report = (tmp_path / "o" / "arena" / "REPORT.md").read_text()
    assert "**Offline smoothers (the whole record)**" in report and "**Causal filters" in report
