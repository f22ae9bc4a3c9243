"""Helpers for a study's frozen parameter object: printed values and reconstructions, declared once.

A study keeps everything it takes from the paper, and every value the paper does not print, in one
frozen dataclass. Declare each field with :func:`printed` (a value the paper prints, and where) or
:func:`reconstructed` (a value the paper does not print, or prints wrongly, and why this one);
:func:`record_parameters` then writes all of them into a :class:`~ctrl_analysis.reporting.report.StudyResult`
(``settings`` and ``reconstructions``), so the report can never forget a reconstruction.

Examples
--------
>>> from dataclasses import dataclass
>>> from ctrl_analysis.reporting.report import StudyInfo, StudyResult
>>> @dataclass(frozen=True)
... class Example:
...     h: float = printed(0.001, "§4: sampling step 1 ms")
...     r: float = reconstructed(50.0, "TD speed factor not printed; a typical value")
>>> res = StudyResult(StudyInfo("demo", "x.txt", "paper", "nothing"))
>>> record_parameters(res, Example(), prefix="ex1")
>>> res.settings
{'ex1.h': 0.001, 'ex1.r': 50.0}
>>> res.reconstructions[0]["name"], res.reconstructions[0]["value"]
('ex1.r', 50.0)
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from .._validate import check_finite, check_int, check_str

__all__ = ["Claim", "Plausible", "choices", "fixed", "missing_plausible", "printed", "reconstructed",
           "record_parameters", "reconstructions_of", "span", "study_params", "algorithm"]

_SCALES = ("linear", "log", "int")
#: ``box``: a value the paper leaves open, one dimension of the plausible box; ``algorithm``: the paper's printed
#: algorithm against the project's correction, judged apart (never folded into ``depends``)
_AXES = ("box", "algorithm")


@dataclass(frozen=True)
class Claim:
    """A claim the paper makes, declared in the study's ``paper.py`` next to its printed values.

    The study judges it from computed quantities (:meth:`ctrl_analysis.reporting.results.StudyResult.claim`);
    the verdict is ``holds``, ``fails``, ``untestable`` or, when it flips inside the plausible range of
    a reconstruction, ``depends``.

    Parameters
    ----------
    id : str
        Stable id (``"transient-ckf-beats-lpf"``).
    section : str
        Where the paper makes it (``"§4, Fig. 6-7"``).
    statement : str
        The claim in one sentence, as the paper makes it (English).
    beyond : bool
        True for a test the project adds (e.g. a tuning-fair comparison the paper never made): it is
        judged like a claim but listed under "beyond the paper", never in the paper's scorecard or counts.

    Examples
    --------
    >>> Claim("fig2-r", "§4, Fig. 2", "A larger R rejects disturbances more strongly").section
    '§4, Fig. 2'
    """

    id: str
    section: str
    statement: str
    beyond: bool = False

    def __post_init__(self):
        for name in ("id", "section", "statement"):
            check_str(name, getattr(self, name))
        if not isinstance(self.beyond, bool):
            raise TypeError(f"beyond must be a bool (True: the project's own test, not the paper's claim), "
                            f"got {self.beyond!r}")


@dataclass(frozen=True)
class Plausible:
    """The plausible range of a reconstructed value and why: what a reader of the paper could have chosen.

    Build one with :func:`span` (a numeric interval), :func:`choices` (a few alternatives) or
    :func:`fixed` (not varied, with the reason no alternative is plausible or matters).

    Parameters
    ----------
    why : str
        Why this range (non-empty).
    low, high : float, optional
        Ends of a numeric interval.
    options : tuple, optional
        Discrete alternatives (the chosen value need not be among them).
    scale : {"linear", "log", "int"}
        Spacing of the interior points of an interval.
    points : int
        Values of an interval shown on one-at-a-time plots, ends included (>= 2).
    axis : {"box", "algorithm"}
        ``"box"``: a dimension of the study's plausible box (:mod:`ctrl_analysis.reporting.sensitivity`);
        ``"algorithm"``: ``options`` are the paper's printed algorithm and the project's corrected one
        (:func:`algorithm`), each judged on its own.
    """

    why: str
    low: float | None = None
    high: float | None = None
    options: tuple | None = None
    scale: str = "linear"
    points: int = 5
    axis: str = "box"

    def __post_init__(self):
        check_str("why", self.why)
        if self.axis not in _AXES:
            raise ValueError(f"axis must be one of {_AXES}, got {self.axis!r}")
        if self.axis == "algorithm" and (self.options is None or len(self.options) != 2):
            raise ValueError("an algorithm axis has exactly two options: (printed, corrected)")
        if self.scale not in _SCALES:
            raise ValueError(f"scale must be one of {_SCALES}, got {self.scale!r}")
        check_int("points", self.points, minimum=2, maximum=50)
        if (self.low is None) != (self.high is None):
            raise ValueError("low and high must be given together")
        if self.low is not None:
            if self.options is not None:
                raise ValueError("give either low/high or options, not both")
            lo, hi = (float(check_finite(name, value, scalar=True)) for name, value in
                      (("low", self.low), ("high", self.high)))
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                raise ValueError(f"low must be finite and below high, got low={self.low!r}, high={self.high!r}")
            if self.scale == "log" and lo <= 0:
                raise ValueError(f"a log-scale range needs low > 0, got {self.low!r}")
        if self.options is not None and (not isinstance(self.options, tuple) or not self.options):
            raise ValueError(f"options must be a non-empty tuple, got {self.options!r}")

    @property
    def varied(self) -> bool:
        """Whether the sensitivity sweep tries other values (False for :func:`fixed`).

        Returns
        -------
        bool
        """
        return self.low is not None or self.options is not None

    def values(self) -> tuple:
        """The values a sensitivity sweep tries: the interval's ends and interior points, or the options.

        Returns
        -------
        tuple
            Empty for :func:`fixed`.
        """
        if self.options is not None:
            return self.options
        if self.low is None:
            return ()
        lo, hi = float(self.low), float(self.high)
        if self.scale == "log":
            v = np.geomspace(lo, hi, self.points)
        else:
            v = np.linspace(lo, hi, self.points)
        if self.scale == "int":
            return tuple(dict.fromkeys(int(round(x)) for x in v))
        return tuple(float(f"{x:.6g}") for x in v)

    def to_dict(self) -> dict:
        """The range as results.json records it.

        Returns
        -------
        dict
        """
        if self.axis == "algorithm":
            return {"options": list(self.options), "axis": "algorithm", "printed": self.options[0],
                    "corrected": self.options[1], "why": self.why}
        if self.options is not None:
            return {"options": list(self.options), "why": self.why}
        if self.low is None:
            return {"fixed": True, "why": self.why}
        return {"low": float(self.low), "high": float(self.high), "scale": self.scale,
                "values": list(self.values()), "why": self.why}


def span(low, high, why: str, *, scale: str = "linear", points: int = 5) -> Plausible:
    """A numeric plausible interval ``[low, high]``; the sweep tries ``points`` values, ends included.

    Parameters
    ----------
    low, high : float
        Ends (``low < high``; ``low > 0`` on a log scale).
    why : str
        Why a reader of the paper could choose any value in it.
    scale : {"linear", "log", "int"}
        Spacing of the tried values ("int" rounds them to distinct integers).
    points : int
        Values tried, ends included.

    Returns
    -------
    Plausible

    Examples
    --------
    >>> span(1, 100, "a decade either side", scale="log", points=3).values()
    (1.0, 10.0, 100.0)
    """
    return Plausible(why=why, low=low, high=high, scale=scale, points=points)


def choices(options, why: str) -> Plausible:
    """A few plausible alternatives to a reconstructed value (e.g. other readings of an equation).

    Parameters
    ----------
    options : sequence
        The alternatives (immutable values).
    why : str
        Why each is a plausible reading.

    Returns
    -------
    Plausible

    Examples
    --------
    >>> choices(("raw", "filtered"), "the paper does not say which signal").values()
    ('raw', 'filtered')
    """
    if not isinstance(options, (tuple, list)):
        raise TypeError(f"options must be a tuple or list of alternatives, got {options!r:.80}")
    return Plausible(why=why, options=tuple(options))


def algorithm(printed, corrected, why: str) -> Plausible:
    """The paper's printed algorithm and the project's corrected one: an axis judged apart, not a plausible value.

    A claim is judged over the plausible box with each of the two (:func:`ctrl_analysis.reporting.sensitivity.explore`);
    where the verdicts differ the scorecard says "holds only with the corrected algorithm" (or the printed
    one), rather than folding the choice into ``depends``.

    Parameters
    ----------
    printed, corrected : object
        The field's value for the algorithm as printed and for the project's correction (immutable, different).
    why : str
        What the printed algorithm gets wrong and what the correction changes.

    Returns
    -------
    Plausible

    Examples
    --------
    >>> a = algorithm("literal", "wellposed", "the printed accumulation is singular")
    >>> a.axis, a.values()
    ('algorithm', ('literal', 'wellposed'))
    """
    for name, value in (("printed", printed), ("corrected", corrected)):
        if isinstance(value, (list, dict, set)):
            raise TypeError(f"{name} must be immutable (use a tuple), got {type(value).__name__}")
    if printed == corrected:
        raise ValueError(f"printed and corrected must differ, got {printed!r} twice")
    return Plausible(why=why, options=(printed, corrected), axis="algorithm")


def fixed(why: str) -> Plausible:
    """A reconstruction that the sensitivity sweep does not vary, and why (e.g. a plotting grid or a horizon).

    Parameters
    ----------
    why : str
        Why no plausible alternative would change a verdict, or why none exists.

    Returns
    -------
    Plausible

    Examples
    --------
    >>> fixed("a plotting grid; evidence only").varied
    False
    """
    return Plausible(why=why)


def printed(value, where: str):
    """A dataclass field holding a value the paper prints; ``where`` says where (eq., table, section).

    Parameters
    ----------
    value : object
        The printed value (immutable: a number, a string or a tuple).
    where : str
        Where the paper prints it, e.g. ``"§4, Table 1"``.

    Returns
    -------
    dataclasses.Field
        A field with that default and ``metadata["printed"] = where``.
    """
    return _field(value, {"printed": check_str("where", where)})


def reconstructed(value, why: str, plausible: Plausible | None = None):
    """A dataclass field holding a value the paper does not print (or prints wrongly); ``why`` says why this one.

    Parameters
    ----------
    value : object
        The chosen value (immutable).
    why : str
        Why this value (non-empty): what the paper says or does not say, and how it was chosen.
    plausible : Plausible, optional
        What else a reader of the paper could reasonably have chosen (:func:`span`, :func:`choices`) or
        :func:`fixed` with the reason it is not varied. Every reconstruction of a study should have one
        (:func:`missing_plausible` lists those without).

    Returns
    -------
    dataclasses.Field
        A field with that default and ``metadata["reconstruction"] = why``.

    Raises
    ------
    ValueError
        If ``why`` is empty.
    """
    if not isinstance(why, str) or not why.strip():
        raise (TypeError if not isinstance(why, str) else ValueError)(
            f"why must be a non-empty string saying why the value was chosen, got {why!r}")
    if plausible is not None and not isinstance(plausible, Plausible):
        raise TypeError(f"plausible must be a Plausible (span, choices or fixed), got {plausible!r}")
    return _field(value, {"reconstruction": why, "plausible": plausible})


def _field(value, metadata):
    if isinstance(value, (list, dict, set)):
        raise TypeError(f"value must be immutable (use a tuple), got {type(value).__name__}")
    return dataclasses.field(default=value, metadata=metadata)


def reconstructions_of(params) -> list[dict]:
    """``[{"name", "value", "why"}]`` for every field of ``params`` declared with :func:`reconstructed`.

    Parameters
    ----------
    params : dataclass instance
        A study's parameter object.

    Returns
    -------
    list of dict
        One dict per reconstructed field, in field order.
    """
    if not dataclasses.is_dataclass(params) or isinstance(params, type):
        raise TypeError(f"params must be a dataclass instance, got {params!r}")
    out = []
    for f in dataclasses.fields(params):
        if "reconstruction" in f.metadata:
            rec = {"name": f.name, "value": getattr(params, f.name), "why": f.metadata["reconstruction"]}
            if f.metadata.get("plausible") is not None:
                rec["plausible"] = f.metadata["plausible"]
            out.append(rec)
    return out


def missing_plausible(params) -> list[str]:
    """Names of the reconstructed fields of ``params`` declared without a plausible range.

    Parameters
    ----------
    params : dataclass instance
        A study's parameter object.

    Returns
    -------
    list of str
        Empty when every reconstruction says what else was plausible.
    """
    return [rec["name"] for rec in reconstructions_of(params) if "plausible" not in rec]


def record_parameters(result, params, prefix: str = "") -> None:
    """Write every field of ``params`` into ``result.settings`` and its reconstructions into ``result``.

    Parameters
    ----------
    result : ctrl_analysis.reporting.report.StudyResult
    params : dataclass instance
        The study's frozen parameter object (possibly changed by ``dataclasses.replace``).
    prefix : str
        Prefix of the setting names (e.g. ``"ex1"`` gives ``"ex1.h"``).
    """
    if not dataclasses.is_dataclass(params) or isinstance(params, type):
        raise TypeError(f"params must be a dataclass instance, got {type(params).__name__}")
    if not hasattr(result, "settings") or not hasattr(result, "reconstruction"):
        raise TypeError(f"result must be a StudyResult, got {type(result).__name__}")
    check_str("prefix", prefix, empty=True)
    name = (lambda n: f"{prefix}.{n}") if prefix else (lambda n: n)
    for f in dataclasses.fields(params):
        result.settings[name(f.name)] = getattr(params, f.name)
    for rec in reconstructions_of(params):
        result.reconstruction(name(rec["name"]), rec["value"], rec["why"], plausible=rec.get("plausible"))


def _differs(a, b) -> bool:
    try:
        return not bool(np.all(np.asarray(a == b)))
    except (TypeError, ValueError):
        return True


def study_params(defaults: dict, params=None, result=None) -> dict:
    """A study's parameter objects for ``run(ctx, params=None)``: its defaults, with ``params``' overrides applied.

    Every study's ``run(ctx, params=None)`` calls this once. ``defaults`` are the frozen parameter
    objects the study runs with (the paper's values and its reconstructions, or its ``--quick``
    settings), under the prefixes of their names in results.json (:func:`record_parameters`) —
    the dict :func:`ctrl_analysis.reporting.sensitivity.sweep` and the study's ``evaluate(params)`` take.
    ``params`` overrides some of them, each entry either a whole object of the default's class or
    a dict of the fields to change (``{"ex1": {"Q": 0.02}}``).

    Parameters
    ----------
    defaults : dict
        ``{prefix: dataclass instance}``.
    params : dict, optional
        ``{prefix: dataclass instance or {field: value}}``, prefixes among ``defaults``.
    result : ctrl_analysis.reporting.results.StudyResult, optional
        When given and ``params`` changes a value, the changed fields are recorded in
        ``result.settings["overridden"]`` (``{prefix: [field, ...]}``), so a results.json made with
        overrides says so beside the reasons recorded for the defaults.

    Returns
    -------
    dict
        ``{prefix: dataclass instance}``, the keys of ``defaults``.

    Raises
    ------
    TypeError
        ``params`` not a dict, or an entry neither a dict nor an object of the default's class.
    ValueError
        A prefix or a field the study does not have.

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> @dataclass(frozen=True)
    ... class Example:
    ...     Q: float = reconstructed(0.01, "not printed", plausible=span(0.001, 0.1, "a decade either side"))
    ...     n: int = printed(1000, "§4")
    >>> study_params({"ex1": Example()}, {"ex1": {"Q": 0.02}})["ex1"]
    Example(Q=0.02, n=1000)
    """
    if not isinstance(defaults, dict) or not all(
            dataclasses.is_dataclass(d) and not isinstance(d, type) for d in defaults.values()):
        raise TypeError("defaults must be a dict {prefix: dataclass instance}")
    if result is not None and not isinstance(getattr(result, "settings", None), dict):
        raise TypeError(f"result must be a StudyResult (or None), got {type(result).__name__}")
    if params is None:
        return dict(defaults)
    if not isinstance(params, dict):
        raise TypeError(f"params must be a dict {{prefix: parameter object or {{field: value}}}}, got "
                        f"{type(params).__name__}")
    out, changed = dict(defaults), {}
    for prefix, value in params.items():
        if prefix not in defaults:
            raise ValueError(f"params names {prefix!r}, not a parameter object of this study; it takes "
                             f"{sorted(defaults)}")
        default = defaults[prefix]
        if isinstance(value, dict):
            fields = {f.name for f in dataclasses.fields(default)}
            unknown = sorted(set(value) - fields)
            if unknown:
                raise ValueError(f"params[{prefix!r}] names fields {unknown} that {type(default).__name__} "
                                 f"does not have")
            value = dataclasses.replace(default, **value)
        elif not isinstance(value, type(default)):
            raise TypeError(f"params[{prefix!r}] must be a {type(default).__name__} or a dict of its fields, "
                            f"got {type(value).__name__}")
        out[prefix] = value
        diff = [f.name for f in dataclasses.fields(default)
                if _differs(getattr(value, f.name), getattr(default, f.name))]
        if diff:
            changed[prefix] = diff
    if result is not None and changed:
        result.settings["overridden"] = changed
    return out
