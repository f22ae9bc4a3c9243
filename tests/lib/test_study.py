"""ctrl_analysis.reporting.study.study_params: the one `params` of every study's run(ctx, params=None)."""

import inspect
from dataclasses import dataclass

import pytest

from analysis import STUDIES, load_study
from ctrl_analysis.reporting.report import StudyContext, StudyInfo, StudyResult
from ctrl_analysis.reporting.study import printed, reconstructed, span, study_params


@dataclass(frozen=True)
class Example:
    Q: float = reconstructed(0.01, "not printed", plausible=span(0.001, 0.1, "a decade either side"))
    n: int = printed(1000, "§4")


@dataclass(frozen=True)
class Readings:
    bar: float = reconstructed(0.1, "a judging bar", plausible=span(0.05, 0.2, "half to twice"))


DEFAULTS = {"ex1": Example(), "claims": Readings()}


def test_none_gives_the_defaults_and_overrides_replace_objects_or_fields():
    assert study_params(DEFAULTS) == DEFAULTS and study_params(DEFAULTS) is not DEFAULTS
    got = study_params(DEFAULTS, {"ex1": {"Q": 0.02}})
    assert got == {"ex1": Example(Q=0.02), "claims": Readings()} and list(got) == ["ex1", "claims"]
    assert study_params(DEFAULTS, {"claims": Readings(bar=0.2)})["claims"].bar == 0.2
    assert DEFAULTS["ex1"].Q == 0.01  # the defaults are not changed


def test_the_result_records_what_was_overridden():
    result = StudyResult(StudyInfo("s", "f", "p", "r"))
    study_params(DEFAULTS, None, result)
    assert "overridden" not in result.settings  # the study's own values: nothing recorded, results unchanged
    study_params(DEFAULTS, {"ex1": {"Q": 0.02, "n": 1000}, "claims": Readings()}, result)
    assert result.settings["overridden"] == {"ex1": ["Q"]}  # only values that differ from the defaults


@pytest.mark.parametrize("params, error, match", [
    ({"ex2": Example()}, ValueError,
     r"params names 'ex2', not a parameter object of this study; it takes \['claims', 'ex1'\]"),
    ({"ex1": {"R": 1.0}}, ValueError, r"params\['ex1'\] names fields \['R'\] that Example does not have"),
    ({"ex1": Readings()}, TypeError, r"params\['ex1'\] must be a Example or a dict of its fields, got Readings"),
    ([("ex1", Example())], TypeError, "params must be a dict"),
])
def test_bad_params_name_the_key(params, error, match):
    with pytest.raises(error, match=match):
        study_params(DEFAULTS, params)


@pytest.mark.parametrize("module", [*STUDIES.values(), "analysis._skeleton"])
def test_every_study_runs_as_run_ctx_params_none(module, tmp_path):
    name = next((k for k, v in STUDIES.items() if v == module), None)
    study = load_study(name) if name else __import__(module, fromlist=["run"])
    sig = inspect.signature(study.run)
    assert list(sig.parameters) == ["ctx", "params"] and sig.parameters["params"].default is None
    # an unknown prefix stops the run at once, naming what the study takes
    with pytest.raises(ValueError, match=r"params names 'nope', not a parameter object of this study; it takes"):
        study.run(StudyContext(out_dir=tmp_path, quick=True), params={"nope": {}})
