"""The plausible box: claims judged jointly over every reconstruction, flips located, cells searched.

Toy studies whose truth is known by construction (issue 26): a flip between the old grid's points found by
bisection, a flip that appears only when two reconstructions move together, a cell reachable only at an
interior point of its range, a measure below its noise floor, and the printed-vs-corrected algorithm axis.
"""

from dataclasses import dataclass

import numpy as np
import pytest

from ctrl_analysis.reporting import sensitivity
from ctrl_analysis.reporting.box import Box
from ctrl_analysis.reporting.markdown import overview_table, write_report_md
from ctrl_analysis.reporting.report import validate_results
from ctrl_analysis.reporting.results import StudyInfo, StudyResult
from ctrl_analysis.reporting.study import (
    Claim,
    algorithm,
    choices,
    fixed,
    reconstructed,
    span,
)
from ctrl_analysis.reporting.verdicts import claim_verdict, printed_tolerance

INFO = StudyInfo("toy", "toy.txt", "A toy paper", "nothing")
BELOW = Claim("below", "§1", "The gain stays below 1.37")
JOINT = Claim("joint", "§2", "a + b stays at most 1.5")
ALWAYS = Claim("always", "§3", "The gain is positive")
OWN = Claim("own", "§9", "A test the paper never made", beyond=True)


@dataclass(frozen=True)
class Toy:
    k: float = reconstructed(1.0, "not printed", plausible=span(0.5, 3.0, "gains a reader might pick", points=5))
    a: float = reconstructed(0.5, "not printed", plausible=span(0.0, 1.0, "a share"))
    b: float = reconstructed(0.5, "not printed", plausible=span(0.0, 1.0, "a share"))
    rule: str = reconstructed("x", "one of two readings", plausible=choices(("y",), "eq. (3) is ambiguous"))
    grid: int = reconstructed(10, "plot grid", plausible=fixed("a plotting grid; no verdict reads it"))


def _evaluate(params):
    p = params["toy"]
    r = StudyResult(INFO)
    r.quantity("gain", "the gain", p.k, unit="")
    # printed 1.02 (two decimals: band ± 0.005): reached only where 1 + (k - 1.7)^2 = 1.02, inside the range
    r.quantity("curve", "a printed curve value", 1.0 + (p.k - 1.7) ** 2, paper=1.02, unit="", cell="Table 1 / c")
    r.quantity("far", "a printed value nothing reaches", 5.0 + p.a, paper=2.5, unit="", cell="Table 1 / far")
    r.claim(BELOW, p.k < 1.37, evidence=["gain"])
    r.claim(JOINT, p.a + p.b <= 1.5, evidence=["gain"])
    r.claim(ALWAYS, p.k > 0, evidence=["gain"])
    r.claim(OWN, p.rule == "x", evidence=["gain"])
    return r


@pytest.fixture(scope="module")
def explored():
    result = _evaluate({"toy": Toy()})
    ex = sensitivity.explore(_evaluate, {"toy": Toy()}, note="toy, deterministic")
    sensitivity.apply(result, ex)
    return result, ex


def test_the_box_spans_every_varied_reconstruction_and_maps_points_to_parameters():
    box = Box({"toy": Toy()})
    assert [d.name for d in box.dims] == ["toy.k", "toy.a", "toy.b", "toy.rule"]  # grid is fixed
    assert box.chosen[0] == pytest.approx(0.2) and box.chosen[3] == pytest.approx(0.25)
    p = box.params_at([1.0, 0.0, 1.0, 0.99])["toy"]
    assert (p.k, p.a, p.b, p.rule, p.grid) == (3.0, 0.0, 1.0, "y", 10)
    U = box.sample(64, seed=3)
    assert U.shape == (64, 4) and 0.0 <= U.min() and U.max() < 1.0
    # a Latin hypercube: each of the 64 strata of each coordinate holds one point (so each quarter 16)
    assert all((np.floor(U[:, j] * 4) == q).sum() == 16 for j in range(4) for q in range(4))


def test_a_flip_between_the_old_grid_points_is_located_by_bisection(explored):
    result, _ = explored
    c = result.get_claim("below")
    # the old one-at-a-time grid (0.5, 1.125, 1.75, 2.375, 3) could only say "flips at 1.75"
    assert c.base_verdict == "holds" and c.verdict == "depends"
    assert c.support == pytest.approx((1.37 - 0.5) / 2.5, abs=0.05)
    (dep,) = c.depends_on
    assert dep["reconstruction"] == "toy.k" and dep["flips_at"] == pytest.approx(1.37, abs=0.04)
    assert c.box["nearest_flip"]["verdict_there"] == "fails"
    assert c.box["drivers"][0]["reconstruction"] == "toy.k" and c.box["drivers"][0]["S1"] > 0.5


def test_a_flip_that_appears_only_when_two_reconstructions_move_together(explored):
    result, _ = explored
    c = result.get_claim("joint")
    # a alone or b alone (the other at its chosen 0.5) never exceeds 1.5: one at a time shows no flip
    assert all(a + 0.5 <= 1.5 for a in np.linspace(0, 1, 11))
    assert c.verdict == "depends" and c.support == pytest.approx(1 - 0.125, abs=0.05)
    flip = c.box["nearest_flip"]["point"]
    assert set(flip) == {"toy.a", "toy.b"} and flip["toy.a"] + flip["toy.b"] > 1.5
    # each has a first-order effect above chance (the permutation test), the others none
    assert {d["reconstruction"] for d in c.box["drivers"] if d["significant"]} == {"toy.a", "toy.b"}


def test_a_claim_that_never_flips_holds_with_full_support_and_no_drivers(explored):
    result, _ = explored
    c = result.get_claim("always")
    assert c.verdict == "holds" and c.support == 1.0 and c.box["drivers"] == [] and c.box["nearest_flip"] is None


def test_a_cell_reachable_only_at_an_interior_point_of_its_range(explored):
    result, _ = explored
    q = result.get("curve")
    assert q.paper == 1.02 and q.effective_tolerance == pytest.approx(0.005 / 1.02)
    assert q.verdict == "reachable" and q.box["verdict"] == "reachable"
    assert set(q.box["reached_at"]) == {"toy.k"} and q.box["drivers"][0]["reconstruction"] == "toy.k"
    k = q.box["reached_at"]["toy.k"]
    assert abs(1.0 + (k - 1.7) ** 2 - 1.02) <= 0.0051 and 1.5 < k < 1.9
    # neither end of k's range is anywhere near the printed value
    assert all(abs(1 + (x - 1.7) ** 2 - 1.02) > 0.3 for x in (0.5, 3.0))


def test_a_cell_no_plausible_point_reaches_differs_with_the_closest_point(explored):
    result, _ = explored
    q = result.get("far")
    assert q.verdict == "differs"
    assert q.box["closest"]["point"]["toy.a"] == pytest.approx(0.0, abs=0.05)
    assert q.box["closest"]["value"] == pytest.approx(5.0, abs=0.05)


def test_the_record_validates_and_a_typed_verdict_is_refused(explored):
    result, _ = explored
    d = validate_results(result.to_dict())
    by = {c["id"]: c for c in d["claims"]}
    assert by["below"]["verdict"] == "depends" and by["below"]["support"]["samples"] == 64
    assert by["own"]["beyond"] is True
    d["claims"][0]["verdict"] = "holds"
    with pytest.raises(ValueError, match="does not follow"):
        validate_results(d)
    d = result.to_dict()
    d["quantities"][1]["box"]["verdict"] = "differs"
    with pytest.raises(ValueError, match="does not follow"):
        validate_results(d)


def test_the_report_keeps_the_papers_claims_apart_from_the_projects_own(explored, tmp_path):
    result, _ = explored
    d = result.to_dict()
    text = write_report_md([d], tmp_path).read_text()
    paper, beyond = text.split("**Beyond the paper**")
    assert "The gain stays below 1.37" in paper and "A test the paper never made" not in paper.split("### ")[0]
    assert "A test the paper never made" in beyond
    assert "35 % ± " in paper or "34 % ± " in paper or "36 % ± " in paper
    row = next(line for line in overview_table([d], {"toy": {}}) if line.startswith("| [toy]"))
    # paper claims: below depends, joint depends, always holds; the beyond test is counted apart
    assert "| 1 | 0 | 2 | 0 | 1 |" in row
    assert "a printed curve value: at `toy.k` = 1.5" in text or "a printed curve value: at `toy.k` = 1.8" in text


def test_the_figure_reads_without_its_caption(explored):
    result, _ = explored
    fig = sensitivity.plot_sensitivity(result)
    ax, hm = fig.axes[0], fig.axes[1]
    assert [t.get_text() for t in ax.get_yticklabels()][:2] == ["below", "joint"]
    assert "support" in ax.get_xlabel() and "thresholds" in ax.get_xlabel()
    assert {t.get_text() for t in hm.get_xticklabels()} == {"toy.k", "toy.rule", "toy.a", "toy.b"}


def _evaluate_noisy(params):
    """The filter lowers the peak by 1e-4 k on average while 100 runs resolve only about 1e-3: untestable."""
    p = params["toy"]
    r = StudyResult(INFO)
    rng = np.random.default_rng(2)
    change = -1e-4 * p.k + 0.005 * rng.standard_normal(100)
    r.quantity("peak_change", "peak with filter minus without", float(change.mean()), std=float(change.std()),
               runs=100, unit="rad")
    r.claim(BELOW, change.mean() < 0, evidence=["peak_change"], measure=change.mean(),
            noise_floor=2 * change.std() / np.sqrt(change.size))
    return r


def test_a_measure_below_its_noise_floor_is_untestable_never_fails():
    result = _evaluate_noisy({"toy": Toy()})
    c = result.get_claim("below")
    assert c.holds is None and c.verdict == "untestable" and "below its own noise floor" in c.note
    sensitivity.apply(result, sensitivity.explore(_evaluate_noisy, {"toy": Toy()}, names=["toy.k"], samples=16))
    assert result.get_claim("below").verdict == "untestable"


@dataclass(frozen=True)
class Alg:
    rule: str = reconstructed("wellposed", "the printed accumulation is singular",
                              plausible=algorithm("literal", "wellposed", "Table 1 divides by a singular matrix"))
    k: float = reconstructed(1.0, "not printed", plausible=span(0.5, 2.0, "gains"))


def _evaluate_alg(params):
    p = params["alg"]
    r = StudyResult(INFO)
    r.quantity("gain", "the gain", p.k, unit="")
    r.claim(ALWAYS, p.rule == "wellposed" or p.k < 0.55, evidence=["gain"])
    return r


def test_the_printed_and_the_corrected_algorithm_are_judged_apart(tmp_path):
    result = _evaluate_alg({"alg": Alg()})
    ex = sensitivity.explore(_evaluate_alg, {"alg": Alg()})
    assert [d.name for d in ex.box.dims] == ["alg.k"] and ex.box.algorithms == ("corrected", "printed")
    sensitivity.apply(result, ex)
    c = result.get_claim("always")
    by = c.box["by_algorithm"]
    assert c.verdict == "holds" and by["corrected"]["verdict"] == "holds"
    assert by["printed"]["verdict"] == "fails" and by["printed"]["support"]["holds"] < 0.1
    text = write_report_md([result.to_dict()], tmp_path).read_text()
    assert "holds only with the corrected algorithm (printed: fails" in text


def test_the_policy_thresholds_and_printed_digits():
    assert [claim_verdict(s, "holds") for s in (0.95, 0.949, 0.051, 0.05)] == ["holds", "depends", "depends",
                                                                               "fails"]
    assert claim_verdict(0.99, "untestable") == "untestable"
    assert printed_tolerance(1.3179e-4) == pytest.approx(0.5e-8 / 1.3179e-4)
    assert printed_tolerance([0.95, 0.863]) == pytest.approx(0.0005 / 0.863)
    with pytest.raises(ValueError, match="printed and corrected"):
        algorithm("a", "a", "same")


def _batch(variants):
    """Every point at once, as a study would on the batch axis: the same results as point by point."""
    return [_evaluate(v) for v in variants]


def test_a_batch_evaluator_gives_the_same_exploration_as_point_by_point():
    one = sensitivity.explore(_evaluate, {"toy": Toy()}, samples=16)
    many = sensitivity.explore(_evaluate, {"toy": Toy()}, samples=16, batch=_batch)
    assert one.claims == many.claims and one.cells == many.cells
    assert one.summary["evaluations"] == many.summary["evaluations"]
    with pytest.raises(ValueError, match="one StudyResult per parameter set"):
        sensitivity.explore(_evaluate, {"toy": Toy()}, samples=4, batch=lambda v: v[:1])


def _evaluate_derived(params):
    r = _evaluate(params)
    # a derived cell (e.g. SNR from RMSE) takes the verdict of its source and has no box of its own
    r.quantity("curve_db", "the curve in dB", 20 * np.log10(r.get("curve").value), paper=0.172, unit="dB",
               cell="Table 1 / c dB", derived_from="curve")
    return r


def test_a_derived_cell_takes_its_sources_reachable_verdict_and_the_report_lists_the_source(tmp_path):
    result = _evaluate_derived({"toy": Toy()})
    sensitivity.apply(result, sensitivity.explore(_evaluate_derived, {"toy": Toy()}, names=["toy.k"], samples=16))
    d = {q["id"]: q for q in result.to_dict()["quantities"]}
    assert d["curve"]["verdict"] == "reachable" and d["curve_db"]["verdict"] == "reachable"
    assert "box" not in d["curve_db"]
    text = write_report_md([result.to_dict()], tmp_path).read_text()
    assert "a printed curve value: at `toy.k`" in text and "the curve in dB: at" not in text


@dataclass(frozen=True)
class Near:
    a: float = reconstructed(0.5, "not printed", plausible=span(0.0, 1.0, "a share"))
    rule: str = reconstructed("x", "one of two readings", plausible=choices(("y",), "the other reading"))


def _evaluate_near(params):
    """A printed 1.02 reached only with the other reading at the chosen a (within 1e-4 of it)."""
    p = params["near"]
    r = StudyResult(INFO)
    value = 1.02 + 50.0 * abs(p.a - 0.5) if p.rule == "y" else 5.0
    r.quantity("cell", "a printed value", value, paper=1.02, unit="", cell="Table 2 / c")
    r.claim(ALWAYS, True, evidence=["cell"])
    return r


def test_a_cell_reached_by_switching_one_alternative_of_the_chosen_values():
    result = _evaluate_near({"near": Near()})
    ex = sensitivity.explore(_evaluate_near, {"near": Near()})
    # no sample lands within 1e-4 of a = 0.5, and the value never crosses 1.02: neither bisection nor search reach it
    U = ex.box.sample(64, ex.summary["seed"])
    assert np.abs(U[:, 0] - 0.5).min() > 1e-4
    sensitivity.apply(result, ex)
    q = result.get("cell")
    assert q.verdict == "reachable" and q.box["how"] == "neighbour" and q.box["reached_at"] == {"near.rule": "y"}


@dataclass(frozen=True)
class Unset:
    delta: object = reconstructed(None, "None: follows another setting",
                                  plausible=choices((5e-3, 1e-2), "two fixed values"))


def test_a_chosen_none_is_a_level_of_its_own():
    box = Box({"u": Unset()})
    assert box.chosen[0] == pytest.approx(1 / 6) and box.changed(box.chosen) == {}
    assert box.params_at([0.1])["u"].delta is None and box.params_at([0.5])["u"].delta == 5e-3
    assert box.distance(box.chosen, [0.1]) == 0.0 and box.distance(box.chosen, [0.9]) == 0.5


_PRUNE_SCRIPT = """
import sys
import numpy as np
sys.path.insert(0, "tests/lib")
from test_box import Toy
from ctrl_analysis.reporting import sensitivity
from ctrl_analysis.reporting.box import Box

box = Box({"toy": Toy()})
u = np.where(np.asarray(box.chosen) < 0.5, 1.0, 0.0)  # a point where every reconstruction moved
assert len(box.changed(u)) == 4

class Runner:
    box, calls = box, []

    def run(self, points):
        self.calls.append(points)
        return [{"claims": {"c": True}} for _ in points]  # never flips: no bisection follows

runner = Runner()
seg = {"kind": "nearest", "claim": "c", "b": u, "algorithm": None, "va": True}
sensitivity._prune(runner, box, {"c": {"drivers": [{"reconstruction": "toy.b"}]}}, [seg], 0, None)
print([list(box.changed(c)) for c, _ in runner.calls[0]])
"""


def test_the_reconstructions_a_nearest_flip_keeps_do_not_depend_on_the_hash_seed():
    """Past the ranked drivers, the flip search keeps the moved reconstructions in the box's order. It took them
    from a set of names, whose order changes with each process's string-hash seed: meso's box exploration
    (claims' boundary, nearest flip, depends_on) differed from one run of the same commit to the next."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    seen = set()
    for seed in ("1", "2", "3", "4"):
        env = {**os.environ, "PYTHONHASHSEED": seed, "PYTHONPATH": str(root)}
        out = subprocess.run([sys.executable, "-c", _PRUNE_SCRIPT], capture_output=True, text=True, cwd=root,
                             env=env, timeout=120, check=True).stdout.strip()
        seen.add(out)
    # driver first, then the box's order k, a, (b,) rule: k = 1, 2, 3 reconstructions kept
    assert seen == {"[['toy.b'], ['toy.k', 'toy.b'], ['toy.k', 'toy.a', 'toy.b']]"}
