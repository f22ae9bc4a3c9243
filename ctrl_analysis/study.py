"""Helpers for a study's frozen parameter object: printed values and reconstructions, declared once.

A study keeps everything it takes from the paper, and every value the paper does not print, in one
frozen dataclass. Declare each field with :func:`printed` (a value the paper prints, and where) or
:func:`reconstructed` (a value the paper does not print, or prints wrongly, and why this one);
:func:`record_parameters` then writes all of them into a :class:`~ctrl_analysis.report.StudyResult`
(``settings`` and ``reconstructions``), so the report can never forget a reconstruction.

Examples
--------
>>> from dataclasses import dataclass
>>> from ctrl_analysis.report import StudyInfo, StudyResult
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
from ._validate import check_str

__all__ = ["printed", "reconstructed", "record_parameters", "reconstructions_of"]


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


def reconstructed(value, why: str):
    """A dataclass field holding a value the paper does not print (or prints wrongly); ``why`` says why this one.

    Parameters
    ----------
    value : object
        The chosen value (immutable).
    why : str
        Why this value (non-empty): what the paper says or does not say, and how it was chosen.

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
    return _field(value, {"reconstruction": why})


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
    return [{"name": f.name, "value": getattr(params, f.name), "why": f.metadata["reconstruction"]}
            for f in dataclasses.fields(params) if "reconstruction" in f.metadata]


def record_parameters(result, params, prefix: str = "") -> None:
    """Write every field of ``params`` into ``result.settings`` and its reconstructions into ``result``.

    Parameters
    ----------
    result : ctrl_analysis.report.StudyResult
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
        result.reconstruction(name(rec["name"]), rec["value"], rec["why"])
