"""The start-up window, scored apart: how far each tuned estimator errs before its scoring window begins.

Every causal family starts at rest on its record's first sample (:data:`~ctrl_analysis.arena.interface.INITS`,
``Setup.init = "first"``): ``f̂ = y_0`` and every derivative estimate 0. Its start-up error (:data:`~.tuning.METRICS`'
``"startup"``, the worst ``|f̂' - f'|`` before ``Setup.transient``) is never part of a tuning cost; it is reported
relative to the records' ``max |f'|``, beside the same tunings started from the zero state (as the papers'
estimators start), so that what the initialisation buys is measured, not asserted.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .tuning import _tasks, evaluate

__all__ = ["record_startup", "startup_calls"]


def startup_calls(names, cases, tuned, setup) -> list:
    """``(evaluate, task)`` calls: each family's worst-case-tuned configurations (one per case) started from zero.

    Parameters
    ----------
    names : sequence of str
        Families.
    cases : sequence of Case
    tuned : dict
        :func:`~ctrl_analysis.arena.tuning.tune_family` output per family (its ``best`` per case).
    setup : Setup

    Returns
    -------
    list of tuple
        One call per family; each returns the :data:`~.tuning.METRICS` rows of its configurations.
    """
    zero = replace(setup, init="zero")
    out = []
    for n in names:
        configs = [(i, b["worst"][0]) for i, b in enumerate(tuned[n]["best"])]
        out += [(evaluate, task) for task in _tasks(n, zero, list(cases), configs, "auto", 1)]
    return out


def record_startup(result, setup, cases, table) -> None:
    """Quantities ``<signal>.<noise>.<ε>.<family>.startup`` and the finding ``start-up`` from ``table``.

    Parameters
    ----------
    result : StudyResult
    setup : Setup
    cases : list of Case
    table : dict
        ``table[family][case key]`` with ``startup`` and ``startup_zero`` (relative to ``max |f'|``).
    """
    fams = list(table)
    first = np.array([[table[n][c.key]["startup"] for c in cases] for n in fams])
    zero = np.array([[table[n][c.key]["startup_zero"] for c in cases] for n in fams])
    for i, n in enumerate(fams):
        for j, c in enumerate(cases):
            result.quantity(f"{c.signal}.{c.noise}.{c.eps:g}.{n}.startup",
                            f"{c.key}, {n}: worst |f̂' - f'| in the start-up window / max |f'| (worst-case tuning, "
                            "started at rest on the first sample)", float(first[i, j]), unit="",
                            note=f"started from the zero state: {zero[i, j]:.4g}")
    top, top0 = first.max(axis=1), zero.max(axis=1)
    worst_fam = fams[int(np.argmax(top))]
    result.finding(
        "start-up",
        f"The start-up window (the first {setup.transient:g} s, before every cost's window) scored apart: each "
        f"family at its worst-case tuning, started at rest on the record's first sample (f̂ = y0, derivatives 0), "
        f"errs there by at most {first.max():.2f}× the records' max |f'| ({worst_fam}; at the first sample its error "
        "is |f'(0)| <= max |f'| by construction, the rest is the overshoot while it converges); the same tunings "
        f"started from the zero state, as the papers' estimators start, err by up to {zero.max():.3g}× (the error "
        "of a zero start grows with |y0|, so it depends on the signal's offset, not only on the estimator). Worst "
        f"over the {len(cases)} cases per family, at rest on the first sample / from the zero state: "
        + ", ".join(f"{n} {a:.2f}/{b:.3g}" for n, a, b in zip(fams, top, top0, strict=True)) + ".",
        {"first_max": float(first.max()), "zero_max": float(zero.max())})
