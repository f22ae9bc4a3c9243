"""The figure of a box exploration: each claim's support over the plausible box and what drives it."""

from __future__ import annotations

import numpy as np

from .._validate import check_int
from .results import StudyResult
from .verdicts import SUPPORT_HIGH, SUPPORT_LOW

__all__ = ["plot_sensitivity"]

def plot_sensitivity(result: StudyResult, top: int = 8):
    """Per claim, its support over the plausible box and the reconstructions that drive it.

    Left: each claim's support (share of the box where it holds) with its standard error, the policy's
    thresholds and the verdict as colour. Right: the first-order Sobol' index of each driving
    reconstruction for each claim (claims that never flip have none).

    Parameters
    ----------
    result : StudyResult
        After :func:`apply`.
    top : int
        Reconstructions shown (the most influential over all claims).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from .report import new_figure

    top = check_int("top", top, minimum=1)
    if not isinstance(result, StudyResult):
        raise TypeError(f"result must be a StudyResult, got {type(result).__name__}")
    if not result.sensitivity:
        raise ValueError("result has no box exploration: call apply(result, explore(...)) first")
    claims = [c for c in result.claims if c.box is not None]
    colors = {"holds": "tab:green", "fails": "tab:red", "depends": "tab:orange", "untestable": "0.6"}
    influence: dict = {}
    for c in claims:
        for d in c.box.get("drivers") or []:
            if d.get("significant", True):
                influence[d["reconstruction"]] = max(influence.get(d["reconstruction"], 0.0), d["S1"])
    names = [n for n, v in sorted(influence.items(), key=lambda kv: -kv[1]) if v > 0][:top]
    n = max(len(claims), 1)
    fig, (ax, bx) = new_figure(1, 2, size=(13.0, 2.4 + 0.42 * n),
                               gridspec_kw={"width_ratios": [1.0, max(1.0, 0.35 * max(len(names), 1))]},
                               title=f"{result.info.name}: each claim judged over the plausible box "
                                     f"({result.sensitivity.get('samples')} points of a Latin hypercube, all "
                                     f"{result.sensitivity.get('dimensions')} reconstructions varied jointly)")
    y = np.arange(len(claims))[::-1]
    for yi, c in zip(y, claims, strict=True):
        s = c.box["support"]
        v = c.verdict
        if s["holds"] is None:
            ax.text(0.5, yi, "untestable", va="center", ha="center", fontsize=8, color="0.4")
            continue
        ax.barh(yi, 100 * s["holds"], color=colors[v], alpha=0.85,
                xerr=100 * (s["stderr"] or 0), error_kw={"elinewidth": 1, "capsize": 2})
        ax.text(103, yi, f" {v}", va="center", fontsize=8)
    # an algorithm axis: the other algorithm's support as a marker on the claim's row
    algo = result.sensitivity.get("algorithm") or {}
    other = {"printed": "corrected", "corrected": "printed"}.get(algo.get("chosen"))
    if other:
        for yi, c in zip(y, claims, strict=True):
            s = ((c.box.get("by_algorithm") or {}).get(other) or {}).get("support") or {}
            if s.get("holds") is not None:
                ax.plot(100 * s["holds"], yi, "D", mfc="white", mec="k", ms=6, zorder=5, clip_on=False)
    for t in (SUPPORT_LOW, SUPPORT_HIGH):
        ax.axvline(100 * t, color="k", ls=":", lw=1)
    labels = [(c.claim.id + (" (beyond)" if c.claim.beyond else "")) for c in claims]
    ax.set_yticks(y, labels, fontsize=8)
    ax.set_xlim(0, 118)
    ax.set_xlabel("support: share of the plausible box where the claim holds (%)\n"
                  f"dotted: the policy's thresholds ({100 * SUPPORT_LOW:.0f} % fails, "
                  f"{100 * SUPPORT_HIGH:.0f} % holds)")
    ax.set_title("Support of each claim (± standard error)" + (
        f"\nbars: the {algo['chosen']} algorithm, \u25c7: the {other} one" if other else ""), fontsize=10)
    if names:
        grid = np.full((len(claims), len(names)), np.nan)
        for i, c in enumerate(claims):
            for d in c.box.get("drivers") or []:
                if d["reconstruction"] in names:  # an index not above chance shows as 0
                    grid[i, names.index(d["reconstruction"])] = max(d["S1"], 0.0) if d.get("significant", True) else 0.0
        im = bx.imshow(grid, aspect="auto", cmap="Oranges", vmin=0, vmax=max(0.3, float(np.nanmax(grid))))
        for i in range(grid.shape[0]):
            for j in range(grid.shape[1]):
                if np.isfinite(grid[i, j]) and grid[i, j] >= 0.05:
                    bx.text(j, i, f"{grid[i, j]:.2f}", ha="center", va="center", fontsize=7)
        bx.set_xticks(range(len(names)), names, rotation=35, ha="right", fontsize=8)
        bx.set_yticks(range(len(claims)), labels, fontsize=8)
        bx.grid(False)
        fig.colorbar(im, ax=bx,
                     label="first-order Sobol' index of the verdict\n(shown where above what chance reaches)")
        bx.set_title("What drives each verdict (blank: the claim does not flip)", fontsize=10)
    else:
        bx.text(0.5, 0.5, "no claim flips anywhere in the box:\nno reconstruction drives a verdict",
                ha="center", va="center", transform=bx.transAxes)
        bx.set_axis_off()
    return fig
