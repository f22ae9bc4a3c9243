"""The arena's verdicts on the papers' estimator-against-estimator claims, and their link in REPORT.md."""

import numpy as np
import pytest

from ctrl_analysis.arena.claims import ClaimCheck, judge_claims
from ctrl_analysis.arena.recommend import INFO, arena_claim_links, arena_report_lines
from ctrl_analysis.arena.tuning import Case, Setup
from ctrl_analysis.reporting.markdown import write_report_md
from ctrl_analysis.reporting.report import StudyInfo, StudyResult
from ctrl_analysis.reporting.study import Claim

SETUP = Setup(dt=0.01, n=300, transient=1.0)
CASES = [Case("sines", "uniform", e, 2.0, (5,)) for e in (0.005, 0.01, 0.02)]


def _table(sigma, neso):
    return {"sigma": {c.key: {"rms": s} for c, s in zip(CASES, sigma, strict=True)},
            "neso": {c.key: {"rms": v} for c, v in zip(CASES, neso, strict=True)}}


def _check(**kw):
    base = {"claim": "demo/a-beats-b", "winners": ("sigma",), "losers": ("neso",), "signals": ("sines",),
            "statement": "Σ beats the fal ESO", "how": "each at its best"}
    base.update(kw)
    return ClaimCheck(**base)


@pytest.mark.parametrize("sigma, neso, verdict", [
    ([1.0, 1.0, 1.0], [1.1, 2.0, 1.01], "holds"),
    ([1.0, 1.0, 1.0], [0.9, 0.5, 0.99], "fails"),
    ([1.0, 1.0, 1.0], [1.1, 0.5, 1.01], "mixed"),
])
def test_verdict_follows_from_every_case(sigma, neso, verdict):
    r = StudyResult(INFO)
    out = judge_claims(r, CASES, _table(sigma, neso), SETUP, checks=[_check()])
    assert out == [("demo/a-beats-b", verdict)]
    f = r.findings[-1]
    assert (f["id"], f["claim"], f["claim_verdict"]) == ("claim-demo-a-beats-b", "demo/a-beats-b", verdict)
    ratios = list(f["evidence"]["neso / sigma"].values())
    assert ratios == pytest.approx(np.array(neso) / np.array(sigma))
    assert f"sigma better in {sum(n > s for s, n in zip(sigma, neso, strict=True))} of 3" in f["text"]


def test_untestable_when_the_claim_or_its_classes_are_not_in_the_arena():
    r = StudyResult(INFO)
    out = judge_claims(r, CASES, _table([1] * 3, [2] * 3), SETUP,
                       checks=[_check(winners=(), losers=(), how="the arena has no model input"),
                               _check(claim="demo/other", signals=("chirp",))])
    assert out == [("demo/a-beats-b", "untestable"), ("demo/other", "untestable")]
    assert "the arena has no model input" in r.findings[0]["text"]
    assert "(chirp) were not run" in r.findings[1]["text"]


def test_a_fixed_configuration_loser_is_evaluated_on_the_same_records():
    # the raw backward difference (algebraic, window 2, degree 1) on noisy sines: its RMS error of f' is about
    # √2 ε_rms / dt ≈ 0.8 at ε = 0.01, dt = 0.01; a winner at 0.1 beats it everywhere, one at 10 nowhere
    chk = _check(winners=("sigma",), losers=(("algebraic", (2.0, 1.0)),))
    for sigma, verdict in ((0.1, "holds"), (10.0, "fails")):
        r = StudyResult(INFO)
        assert judge_claims(r, CASES, _table([sigma] * 3, [1] * 3), SETUP, checks=[chk])[0][1] == verdict
    err = np.array(list(r.findings[0]["evidence"]["algebraic fixed at window = 2, degree = 1 / sigma"].values())) * 10.0
    eps = np.array([c.eps for c in CASES])
    assert err == pytest.approx(np.sqrt(2) * eps / np.sqrt(3) / SETUP.dt, rel=0.15)  # uniform noise: σ = ε/√3


@pytest.mark.parametrize("kw, match", [
    ({"claim": "no-slash"}, "claim"),
    ({"winners": ("nope",)}, "winners"),
    ({"losers": (("algebraic", (2.0,)),)}, "losers"),
    ({"losers": ()}, "winners and losers"),
    ({"signals": ["sines"]}, "signals"),
])
def test_claim_check_errors_name_the_argument(kw, match):
    with pytest.raises((ValueError, TypeError), match=match):
        _check(**kw)


def test_report_shows_the_arena_verdict_beside_the_study_claim(tmp_path):
    arena = StudyResult(INFO)
    judge_claims(arena, CASES, _table([1.0] * 3, [2.0] * 3), SETUP, checks=[_check()])
    data = arena.to_dict()
    links = arena_claim_links(data)
    assert links == {"demo/a-beats-b": "arena: holds at best tuning"}
    assert any("| demo/a-beats-b | holds at best tuning |" in line for line in arena_report_lines(data))
    study = StudyResult(StudyInfo("demo", "x.txt", "A paper", "things"))
    study.quantity("q", "a quantity", 1.0, unit="")
    study.claim(Claim("a-beats-b", "§4", "A beats B"), False, ["q"])
    study.claim(Claim("other", "§5", "Something else"), True, ["q"])
    text = write_report_md([study.to_dict()], tmp_path,
                           claim_links={"demo/a-beats-b": "[arena: holds](#x)"}).read_text()
    rows = {line.split("|")[1].strip(): line for line in text.splitlines()
            if line.startswith(("| A beats B", "| Something else"))}
    assert "[arena: holds](#x)" in rows["A beats B"] and "arena" not in rows["Something else"]
    with pytest.raises(ValueError, match="claim and claim_verdict"):
        StudyResult(INFO).finding("x", "text", claim="demo/a")


def test_cli_reads_the_arena_links_for_the_report(tmp_path):
    import json

    from ctrl_analysis.arena.report_section import arena_links as _arena_links

    assert _arena_links(tmp_path) == {}  # no arena run: no links
    arena = StudyResult(INFO)
    judge_claims(arena, CASES, _table([1.0] * 3, [0.5] * 3), SETUP, checks=[_check()])
    (tmp_path / "arena").mkdir()
    (tmp_path / "arena" / "results.json").write_text(json.dumps(arena.to_dict(), default=str))
    assert _arena_links(tmp_path) == {"demo/a-beats-b": "[arena: does not hold at best tuning](#estimator-arena)"}


def test_a_fixed_winner_at_given_gains_is_run_as_given_and_the_verdict_says_so():
    # the α-β filter at α = β = 1 is the backward difference: x̂_k = y_k and v̂_k = (y_k - y_(k-1)) / T
    # (the prediction y_(k-1) + T v̂_(k-1) is corrected by β/T times its error), so against the raw backward
    # difference (algebraic, window 2, degree 1) every ratio is 1
    chk = _check(winners=(("ab", (1.0, 1.0)),), losers=(("algebraic", (2.0, 1.0)),))
    r = StudyResult(INFO)
    judge_claims(r, CASES, {}, SETUP, checks=[chk])
    f = r.findings[0]
    ratios = list(f["evidence"]["algebraic fixed at window = 2, degree = 1 / ab fixed at alpha = 1, beta = 1"].values())
    assert ratios == pytest.approx([1.0] * 3, rel=1e-9)
    assert "fixed configurations as given" in f["text"] and "at best tuning" not in f["text"]
    with pytest.raises(ValueError, match="winners"):
        _check(winners=("ab",))  # a given-gains estimator is not tuned: only as a fixed configuration


def test_a_claim_on_both_states_holds_only_where_it_holds_on_each():
    table = _table([1.0] * 3, [2.0] * 3)  # the derivative: sigma better everywhere
    for c, v in zip(CASES, (0.5, 0.5, 0.5), strict=True):  # the signal: sigma worse everywhere
        table["sigma"][c.key]["rms_f"], table["neso"][c.key]["rms_f"] = 1.0, v
    r = StudyResult(INFO)
    assert judge_claims(r, CASES, table, SETUP, checks=[_check(measures=("rms_f", "rms"))])[0][1] == "mixed"
    ev = r.findings[0]["evidence"]
    assert list(ev["rms_f: neso / sigma"].values()) == [0.5] * 3 and list(ev["neso / sigma"].values()) == [2.0] * 3
    assert "RMS error of f̂, neso / sigma" in r.findings[0]["text"]
    r = StudyResult(INFO)
    assert judge_claims(r, CASES, table, SETUP, checks=[_check()])[0][1] == "holds"  # the derivative alone
    with pytest.raises(ValueError, match="measures"):
        _check(measures=("rms_g",))


def test_a_check_with_its_own_errors_is_judged_on_them_and_they_are_checked():
    def errors(cases, setup):
        return {"A": {"rms": np.ones(len(cases))}, "B": {"rms": np.full(len(cases), 2.0)}}

    r = StudyResult(INFO)
    chk = _check(winners=("A",), losers=("B",), errors=errors)
    assert judge_claims(r, CASES, {}, SETUP, checks=[chk])[0][1] == "holds"
    assert list(r.findings[0]["evidence"]["B / A"].values()) == [2.0] * 3
    bad = _check(winners=("A",), losers=("C",), errors=errors)
    with pytest.raises(ValueError, match="'C', 'rms'"):
        judge_claims(StudyResult(INFO), CASES, {}, SETUP, checks=[bad])
    with pytest.raises(TypeError, match="errors must be a callable"):
        _check(errors=3)
