"""The skeleton's figure: a function of data returning a Figure (saving is ``ctx.save_figure``'s job)."""

from __future__ import annotations

from ctrl_analysis.reporting.report import new_figure

__all__ = ["plot_step"]


def plot_step(t, y, y_meas, y_hat, *, tau: float):
    """Fig. 1: the plant's step response, its noisy measurement and the filtered estimate (one run).

    Parameters
    ----------
    t : numpy.ndarray, shape (N+1,)
        Time (s).
    y, y_meas, y_hat : numpy.ndarray, shape (N+1,)
        Plant output, measurement and filter output of one run.
    tau : float
        Plant time constant (s), marked on the time axis.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = new_figure(title="Fig. 1 — first-order lag step response: measured, filtered and true output")
    ax.plot(t, y_meas, color="0.7", lw=0.6, label="measured y + v")
    ax.plot(t, y_hat, color="C0", lw=1.2, label="filtered ŷ")
    ax.plot(t, y, color="k", lw=1.2, ls="--", label="true y")
    ax.axvline(tau, color="C3", lw=0.8, ls=":", label="t = τ")
    ax.set_xlabel("time t (s)")
    ax.set_ylabel("output (unit step = 1)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return fig
