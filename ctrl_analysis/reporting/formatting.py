"""Number and text formatting shared by the REPORT.md writers: values, evidence, Markdown table cells."""

from __future__ import annotations

import re

import numpy as np

__all__ = ["MAX_LIST", "summarise"]

#: Longest list quoted as is; longer numeric lists are summarised as min / median / max.
MAX_LIST = 8
def fmt(value, std=None, digits: int = 4) -> str:
    if value is None:
        return "—"
    if isinstance(value, (list, tuple, np.ndarray)):
        flat = list(np.ravel(np.asarray(value, dtype=object)))
        if len(flat) > MAX_LIST and _numeric(flat):
            return _array_summary(flat)
        return "[" + ", ".join(fmt(v, digits=digits) for v in flat) + "]"
    if isinstance(value, (bool, np.bool_)):
        return str(value)  # True / False, as the reconstruction reads (not 1 / 0)
    if isinstance(value, (int, np.integer)):
        return str(value)
    try:
        v = float(value)
    except (TypeError, ValueError):
        return str(value)
    text = f"{v:.{digits}g}"
    if std is not None:
        text += f" ± {fmt(std)}"
    return text


def _numeric(items) -> bool:
    return all(isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) or v is None
               for v in items)


def _array_summary(items) -> str:
    vals = np.array([np.nan if v is None else v for v in items], dtype=float)
    fin = vals[np.isfinite(vals)]
    if fin.size == 0:
        return f"[{len(items)} values, none finite]"
    return (f"[{len(items)} values: min {np.min(fin):.4g} / median {np.median(fin):.4g} / max {np.max(fin):.4g}"
            + (f"; {len(items) - fin.size} not finite" if fin.size < len(items) else "") + "]")


def summarise(value, depth: int = 0) -> str:
    """Evidence as short text: long numeric arrays as min / median / max, nested dicts and lists compact.

    Parameters
    ----------
    value : object
        A JSON-like value (dict, list, number, string, None).
    depth : int
        Nesting depth (deeper levels are abbreviated).

    Returns
    -------
    str
    """
    if isinstance(value, dict):
        if depth >= 3:
            return f"{{{len(value)} entries}}"
        return "{" + "; ".join(f"{k}: {summarise(v, depth + 1)}" for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple, np.ndarray)):
        items = list(value) if not isinstance(value, np.ndarray) else value.tolist()
        if _numeric(items):
            return fmt(items)
        if len(items) > MAX_LIST or depth >= 3:
            return f"[{len(items)} records]"
        return "[" + ", ".join(summarise(v, depth + 1) for v in items) + "]"
    if isinstance(value, str):
        return value
    return fmt(value)


_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_LONG_LIST = re.compile(rf"\[\s*{_NUM}(?:\s*,\s*{_NUM}){{{MAX_LIST},}}\s*\]")


def shorten_lists(text: str) -> str:
    """Replace numeric lists longer than :data:`MAX_LIST` inside a text by their min / median / max."""
    return _LONG_LIST.sub(lambda m: _array_summary([float(x) for x in re.findall(_NUM, m.group(0))]), text)


def cell(text) -> str:
    """Text safe inside a Markdown table cell (pipes escaped, one line)."""
    return str(text or "").replace("|", "\\|").replace("\n", " ")


def check_results(name: str, results) -> None:
    """Raise ``TypeError`` naming ``name`` unless ``results`` is a results.json dict (``study``, ``quantities``)."""
    if not isinstance(results, dict) or not isinstance(results.get("quantities"), list) \
            or not isinstance(results.get("study"), str):
        raise TypeError(f"{name} must be a results.json dict with 'study' and a 'quantities' list, got {results!r:.80}")


def one_line(exc: BaseException, limit: int = 400) -> str:
    """An exception as one line: ``Type: message`` with its whitespace folded, cut at ``limit`` characters.

    Parameters
    ----------
    exc : BaseException
    limit : int

    Returns
    -------
    str

    Examples
    --------
    >>> one_line(ValueError("bad\\n  value"))
    'ValueError: bad value'
    """
    text = " ".join(str(exc).split())
    if len(text) > limit:
        text = text[: limit - 1] + "…"
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__
