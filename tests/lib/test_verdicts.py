"""The verdict policy, claims and the sensitivity sweep on small hand-made examples.

Each example is built so that it would fail if the policy were not applied: a value within the
relative tolerance but outside the runs' central 95 %, an SNR whose own tolerance would agree while its
RMSE differs, a quantity with half its runs diverged, a toy study whose claim flips at a known value.
"""

from dataclasses import dataclass

import numpy as np
import pytest

from ctrl_analysis.reporting import sensitivity
from ctrl_analysis.reporting.markdown import not_reproduced, tally, write_report_md
from ctrl_analysis.reporting.report import (
    StudyInfo,
    StudyResult,
    count_verdicts,
    validate_results,
)
from ctrl_analysis.reporting.study import (
    Claim,
    choices,
    fixed,
    missing_plausible,
    reconstructed,
    span,
)
from ctrl_analysis.reporting.verdicts import central_interval, digits_tolerance

INFO = StudyInfo("toy", "x.txt", "A paper", "things")


def _runs(mean, std, n=200, seed=1):
    return np.random.default_rng(seed).normal(mean, std, n)


def test_percentile_policy_overrides_a_loose_tolerance():
    r = StudyResult(INFO)
    samples = _runs(1.0, 0.01)
    # 1.05 is within a 10 % tolerance of the mean but above every run: differs under the percentile policy
    q = r.quantity("a", "a", float(samples.mean()), paper=1.05, std=float(samples.std()), runs=200,
                   tolerance=0.1, samples=samples)
    assert q.policy == "percentile" and q.verdict == "differs" and q.percentile == 100.0
    # 0.99 lies inside the central 95 % of the runs
    q2 = r.quantity("b", "b", float(samples.mean()), paper=0.99, runs=200, samples=samples)
    lo, hi = central_interval(samples)
    assert lo < 0.99 < hi and q2.verdict == "agrees" and 10 < q2.percentile < 20
    d = validate_results(r.to_dict())
    assert d["quantities"][0]["interval"] == pytest.approx([lo, hi]) and d["quantities"][0]["policy"] == "percentile"
    # the validator recomputes the percentile verdict: a typed "agrees" is refused
    d["quantities"][0]["verdict"] = "agrees"
    with pytest.raises(ValueError, match="percentile policy"):
        validate_results(d)


def test_derived_quantity_takes_the_verdict_of_its_source():
    r = StudyResult(INFO)
    rmse = r.quantity("rmse", "RMSE", 0.101, paper=0.1248, tolerance=0.1)  # -19 %: differs
    # SNR = -20 lg RMSE: 19.9 vs 19.05 is within 5 %, but it must take the RMSE's verdict
    snr = r.quantity("snr", "SNR", 19.92, paper=19.05, tolerance=0.05, unit="dB", derived_from="rmse")
    assert rmse.verdict == "differs" and snr.policy == "derived"
    d = r.to_dict()
    assert d["quantities"][1]["verdict"] == "differs" and d["quantities"][1]["derived_from"] == "rmse"
    validate_results(d)
    d["quantities"][1]["verdict"] = "agrees"
    with pytest.raises(ValueError, match="derived"):
        validate_results(d)
    r.quantity("orphan", "SNR of nothing", 1.0, paper=1.0, derived_from="nope")
    with pytest.raises(ValueError, match="nope"):
        r.to_dict()


def test_half_the_runs_diverged_is_diverged_and_the_count_is_shown(tmp_path):
    r = StudyResult(INFO)
    q = r.quantity("lit", "literal", 7.59, paper=0.58, runs=100, runs_diverged=97, std=3.6)
    assert q.verdict == "diverged"  # a mean of 3 survivors is not a reproduction
    assert r.quantity("half", "half", 1.0, paper=1.0, runs=10, runs_diverged=5).verdict == "diverged"
    assert r.quantity("few", "few", 1.0, paper=1.0, runs=10, runs_diverged=4).verdict == "agrees"
    validate_results(r.to_dict())
    text = write_report_md([r.to_dict()], tmp_path).read_text()
    assert "diverged (100 runs, 97 diverged)" in text
    assert "(10 runs, 4 diverged)" in text


def test_checks_are_listed_apart_and_not_counted(tmp_path):
    r = StudyResult(INFO)
    r.quantity("cell", "a cell", 1.0, paper=1.0, tolerance=0.01)
    r.check("identity", "breakaway point −n0·a for n0 = 5, a = 2", -10.0, paper=-10.0, tolerance=1e-12,
            note="the paper prints the formula")
    r.finding("slip", "0.1 rad is 5.7296°, not 5.7325° as printed.", kind="erratum")
    d = r.to_dict()
    assert count_verdicts(d) == {"agrees": 1, "reachable": 0, "differs": 0, "new": 0, "diverged": 0}
    assert tally(d)["checks"] == 1 and tally(d)["printed"] == 1
    text = write_report_md([d], tmp_path).read_text()
    section = text.split("### Checks and errata")[1].split("###")[0]
    assert "breakaway point" in section and "**Erratum** — 0.1 rad is 5.7296°" in section
    assert "### Findings" not in text  # the erratum is not repeated as a finding


def test_not_reproduced_adds_up_to_its_count(tmp_path):
    r = StudyResult(INFO)
    r.quantity("a", "a", 2.0, paper=1.0, cell="Table 1 / x / a", primary=True)
    r.quantity("b", "b", 1.0, paper=1.0, cell="Table 1 / x / b", primary=True)
    r.quantity("c", "c", None, paper=1.0, runs=3, runs_diverged=3, cell="Table 1 / y / a", primary=True)
    r.missing = ["Fig. 9: the experiment"]
    items = not_reproduced(r.to_dict())
    assert len(items) == 3 and items[0].startswith("Table 1 / x / a (2 vs 1)") and items[-1] == "Fig. 9: the experiment"
    text = write_report_md([r.to_dict()], tmp_path).read_text()
    assert "**Not reproduced (3: 2 printed cells that differ or diverged, 1 part of the paper):**" in text


def test_digits_tolerance_is_half_a_unit_of_the_last_printed_digit():
    assert digits_tolerance(0.950, 3) == pytest.approx(0.0005 / 0.95)
    assert digits_tolerance(-10, 0) == pytest.approx(0.05)
    with pytest.raises(ValueError, match="paper"):
        digits_tolerance(0.0, 2)


CLAIM = Claim("below-two", "§3", "The gain stays below 2")
ROBUST = Claim("positive", "§3", "The gain is positive")


@dataclass(frozen=True)
class Toy:
    k: float = reconstructed(1.0, "not printed", plausible=span(0.5, 3.0, "gains a reader might pick", points=6))
    reading: str = reconstructed("a", "one of two readings", plausible=choices(("a", "b"), "eq. (3) is ambiguous"))
    grid: int = reconstructed(10, "plot grid", plausible=fixed("a plotting grid; no verdict reads it"))


def _evaluate(params):
    p = params["toy"]
    r = StudyResult(INFO)
    gain = p.k * (1.0 if p.reading == "a" else 1.1)
    r.quantity("gain", "the gain", gain, paper=1.0, tolerance=0.2, cell="§3 / gain")
    r.claim(CLAIM, gain < 2, evidence=["gain"], note=f"gain {gain:.3g}")
    r.claim(ROBUST, gain > 0, evidence=["gain"])
    return r


def test_a_typed_claim_verdict_is_refused():
    result = _evaluate({"toy": Toy()})
    d = result.to_dict()
    d["claims"][0]["verdict"] = "fails"
    with pytest.raises(ValueError, match="does not follow"):
        validate_results(d)
    d = result.to_dict()
    d["claims"][0]["evidence"] = ["nope"]
    with pytest.raises(ValueError, match="nope"):
        validate_results(d)


def test_every_reconstruction_states_a_plausible_range():
    assert missing_plausible(Toy()) == []

    @dataclass(frozen=True)
    class Bare:
        k: float = reconstructed(1.0, "not printed")

    assert missing_plausible(Bare()) == ["k"]
    with pytest.raises(ValueError, match="low"):
        span(2.0, 1.0, "reversed")


def _evaluate_breaking(params):
    """The claim holds below k = 2 and cannot be judged at k >= 2 (the method breaks down there)."""
    p = params["toy"]
    r = StudyResult(INFO)
    r.quantity("gain", "the gain", p.k, unit="")
    r.claim(CLAIM, None if p.k >= 2 else True, evidence=["gain"])
    return r


def test_a_value_where_the_claim_cannot_be_judged_is_not_a_flip():
    result = _evaluate_breaking({"toy": Toy()})
    sensitivity.apply(result, sensitivity.explore(_evaluate_breaking, {"toy": Toy()}))
    c = result.get_claim("below-two")
    # k >= 2 is 40 % of k's range: those points count as untestable, not as points where the claim fails
    assert c.verdict == "holds" and c.support == 1.0 and c.depends_on == []
    assert c.box["support"]["untestable"] == pytest.approx(0.4 * 64, abs=4)
    assert c.box["support"]["samples"] + c.box["support"]["untestable"] == 64


def test_a_chain_of_derivations_is_followed_and_a_circle_refused():
    r = StudyResult(INFO)
    r.quantity("rmse", "RMSE", 0.101, paper=0.1248, tolerance=0.1)
    r.quantity("snr", "SNR", 19.92, paper=19.05, tolerance=0.05, derived_from="rmse")
    r.quantity("snr2", "SNR again", 19.92, paper=19.05, tolerance=0.05, derived_from="snr")
    assert [q["verdict"] for q in r.to_dict()["quantities"]] == ["differs", "differs", "differs"]
    r.quantity("a", "a", 1.0, paper=1.0, derived_from="b")
    r.quantity("b", "b", 1.0, paper=1.0, derived_from="a")
    with pytest.raises(ValueError, match="circle"):
        r.to_dict()
