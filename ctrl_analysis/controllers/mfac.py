"""Model-free adaptive control (compact-form dynamic linearisation): PPD estimator, control laws, their blocks.

Blocks (each batched, under the protocol of :mod:`ctrl_analysis.engine.blocks`) for any SISO discrete
plant ``y(k+1) = f(y(k), ..., u(k), ...)`` whose (possibly filtered) output ``y_f`` the controller
sees:

* :class:`~ctrl_analysis.engine.blocks.UnitDelay` — ``u(k−1)`` from ``u(k)`` (defined in
  :mod:`ctrl_analysis.engine.blocks`, importable from here too);
* :class:`PPDEstimator` — the pseudo-partial-derivative estimate ``φ̂(k)`` with its reset rule;
* :class:`CFDLLaw` — the CFDL-MFAC control law ``u(k)``;
* :class:`DecreasingGainLaw` — the same law with a decreasing gain inside an error band (D-MFAC),
  with the re-arming rule of the switching instant as a parameter;
* :class:`CFDLPredictor` — the CFDL data model as a one-step predictor of the output increment
  ``φ̂(k−1) Δu(k−1)``, the prediction an
  :class:`~ctrl_analysis.estimators.kalman.ImprovedKalmanFilter` needs.

:func:`mfac_controller` places them in a :class:`~ctrl_analysis.engine.loop.Loop` with standard signal
names: plain MFAC, with a tracking differentiator (TD-MFAC), with the decreasing-gain law
(D-MFAC), or with the improved Kalman filter (IKF-MFAC, :func:`ikf_mfac`).
"""

from __future__ import annotations

import numpy as np

from .._validate import check_finite, check_positive, check_str
from ..engine.blocks import Block, DiscreteBlock, StaticBlock, UnitDelay
from ..engine.kernels import KernelBlock, Kernels, Layout, jitable
from ..engine.loop import place

__all__ = [
    "CFDLLaw",
    "CFDLPredictor",
    "DecreasingGainLaw",
    "PPDEstimator",
    "UnitDelay",
    "ikf_mfac",
    "mfac_controller",
]

NO_PARAMS = Layout()  # CFDLPredictor
PPD = Layout("eta", "mu", "epsilon", "phi_reset", "sign0")
PPD_AT = PPD.at  # parameter offsets, numba constants
LAW = Layout("rho", "lam")
LAW_AT = LAW.at
DGAIN = Layout("rho", "lam", "e_m", "rearm")
DGAIN_AT = DGAIN.at


def _check_step(name: str, value) -> float:
    """A step size in ``(0, 1]`` (per-run values: ``Loop.simulate(params=...)``)."""
    value = float(check_finite(name, value, scalar=True))
    if not 0.0 < value <= 1.0:
        raise ValueError(f"{name} must be in (0, 1], got {value}")
    return value


@jitable
def _cfdl_increment(phi, e, rho, lam):
    """(8) Δu(k) = ρ φ̂(k) e(k) / (λ + φ̂(k)²), the CFDL-MFAC control increment."""
    return rho * phi * e / (lam + phi * phi)


@jitable
def _ppd_projection(phi_prev, du, dy, eta, mu):
    """(6) φ̂(k) = φ̂(k−1) + η Δu(k−1) (Δy_f(k) − φ̂(k−1) Δu(k−1)) / (μ + Δu(k−1)²), before the reset."""
    return phi_prev + eta * du * (dy - phi_prev * du) / (mu + du * du)


# ------------------------------------------------------------------ kernels (one run; see ctrl_analysis.engine.kernels)
# Each equation once: the blocks' batched numpy methods and the compiled engine both call these.
# PPDEstimator's reset (7) and DecreasingGainLaw's band (36) branch per run (columns=False).

@jitable
def ppd_output(t, x, u, p, y):
    """Kernel output of :class:`PPDEstimator`: ``φ̂(k)`` by (6) with the reset (7); ``p`` packed by :data:`PPD`."""
    du = u[1] - x[2]                                     # Δu(k−1) = u(k−1) − u(k−2)
    phi = _ppd_projection(x[0], du, u[0] - x[1], p[PPD_AT.eta], p[PPD_AT.mu])  # (6), Δy_f(k) = y_f(k) − y_f(k−1)
    sign = 1.0 if phi > 0.0 else (-1.0 if phi < 0.0 else phi)   # numpy's sign (0 and NaN kept)
    eps = p[PPD_AT.epsilon]
    # (7) reset if |φ̂(k)| <= ε or |Δu(k−1)| <= ε or sign φ̂(k) ≠ sign φ̂(1)
    if abs(phi) <= eps or abs(du) <= eps or sign != p[PPD_AT.sign0]:
        phi = p[PPD_AT.phi_reset]
    y[0] = phi


def ppd_update(t, x, u, p, x_next):
    """Kernel update of :class:`PPDEstimator`: stores ``(φ̂(k), y_f(k), u(k−1))`` (arguments as :func:`ppd_output`)."""
    ppd_output(t, x, u, p, x_next)
    x_next[1] = u[0]
    x_next[2] = u[1]


def cfdl_law_output(t, x, u, p, y):
    """Kernel of :class:`CFDLLaw`: (8) ``u(k) = u(k−1) + Δu(k)``; ``p`` packed by :data:`LAW`."""
    y[0] = u[3] + _cfdl_increment(u[0], u[2] - u[1], p[LAW_AT.rho], p[LAW_AT.lam])


@jitable
def _band_step(e, in_before, armed_before, age_before, e_m, rearm):
    """(36) band state of D-MFAC at sample ``k`` for one run: ``(in_band, armed, age = k − k_m)``."""
    in_band = abs(e) < e_m
    entering = in_band and in_before == 0.0
    start = entering if rearm != 0.0 else (entering and armed_before == 0.0)
    armed = armed_before != 0.0 or entering
    age = 0.0 if start else age_before + 1.0
    return in_band, armed, age


def dgain_output(t, x, u, p, y):
    """Kernel output of :class:`DecreasingGainLaw`: (36); ``p`` packed by :data:`DGAIN`."""
    e = u[2] - u[1]
    in_band, armed, age = _band_step(e, x[0], x[1], x[2], p[DGAIN_AT.e_m], p[DGAIN_AT.rearm])
    du = _cfdl_increment(u[0], e, p[DGAIN_AT.rho], p[DGAIN_AT.lam])
    # (36) Δu(k) / (k − k_m + 1) inside the band
    y[0] = u[3] + (du / (age + 1.0) if in_band and armed else du)


def dgain_update(t, x, u, p, x_next):
    """Kernel update of :class:`DecreasingGainLaw`: the band state ``(in_band, armed, age)`` of sample ``k``."""
    in_band, armed, age = _band_step(u[2] - u[1], x[0], x[1], x[2], p[DGAIN_AT.e_m], p[DGAIN_AT.rearm])
    x_next[0] = 1.0 if in_band else 0.0
    x_next[1] = 1.0 if armed else 0.0
    x_next[2] = age


def predictor_output(t, x, u, p, y):
    """Kernel of :class:`CFDLPredictor`: (4)/(11) ``δ(k) = φ̂(k−1) (u(k−1) − u(k−2))``."""
    y[0] = x[0] * (x[1] - x[2])


def predictor_update(t, x, u, p, x_next):
    """Kernel update of :class:`CFDLPredictor`: stores ``(φ̂(k), u(k), u(k−1))``."""
    x_next[0] = u[0]
    x_next[1] = u[1]
    x_next[2] = x[1]


class PPDEstimator(KernelBlock, DiscreteBlock):
    """Projection estimate of the pseudo partial derivative (PPD) ``φ̂(k)`` with its reset rule.

    From its state ``(φ̂(k−1), y_f(k−1), u(k−2))`` and its inputs ``y_f(k)``, ``u(k−1)``::

        φ̂(k) = φ̂(k−1) + η Δu(k−1) (Δy_f(k) − φ̂(k−1) Δu(k−1)) / (μ + Δu(k−1)²)     (6)
        φ̂(k) = φ_reset  if |φ̂(k)| <= ε or |Δu(k−1)| <= ε or sign φ̂(k) ≠ sign φ̂(1)   (7)

    The update stores ``(φ̂(k), y_f(k), u(k−1))``. The reset rule (7) applies at every sample,
    the first one included: the paper states (6)-(7) for every ``k``, with no exception for the
    first sample and no other first value than ``φ̂(1)``. At the first sample ``k0``, (6) starts from
    ``φ̂(k0−1) = phi0`` with ``Δu(k0−1) = u(k0−1) − u0``; when ``|Δu(k0−1)| <= ε`` — in
    particular when the loop starts at rest, ``u(k0−1) = u0`` (Lu & Hou's ``u(1:2) = 0``) — (6)
    leaves ``φ̂ = phi0`` and (7) replaces it: the first estimate is ``phi_reset``, and ``phi0``
    is never used as an estimate, only as the sign (7) keeps.

    Block signals: inputs ``y`` (the output the controller sees, ``y_f``) and ``u_prev``
    (``u(k−1)``); states ``phi_hat``, ``y_prev``, ``u_prev_prev``; output ``phi_hat``; direct
    feedthrough.

    Parameters
    ----------
    eta : float
        Step size ``η`` in ``(0, 1]``.
    mu : float
        Weight ``μ > 0``.
    epsilon : float
        Reset threshold ``ε > 0``.
    phi0 : float
        ``φ̂(1)`` of (7), non-zero, in two roles: (a) the sign every estimate must keep (7), for
        the whole run; (b) the state's ``φ̂(k0−1)``, the previous estimate (6) starts from at the
        first sample — which (7) then replaces by ``phi_reset`` if ``|Δu(k0−1)| <= ε`` (see
        above), so with a loop starting at rest ``phi0`` only sets the sign.
    phi_reset : float, optional
        The value (7) sets whenever it fires, at any sample including the first; non-zero with
        the sign of ``phi0``. Default ``phi0``: eq. (7) as printed resets to ``φ̂(1)``. Lu & Hou's
        simulations state ``φ̂(1) = 2`` and a separate reset value 0.5; with their ``u(1:2) = 0``
        the first estimate is then 0.5.
    y0, u0 : float
        ``y_f`` and ``u`` before the first sample: ``y_f(k0−1)`` and ``u(k0−2)`` (the state's
        ``y_prev``, ``u_prev_prev``).

    Raises
    ------
    ValueError
        ``eta`` outside ``(0, 1]``, ``mu``/``epsilon`` not ``> 0``, ``phi0 = 0``, or a
        ``phi_reset`` of the wrong sign.

    References
    ----------
    Hou Z., Jin S., *Model Free Adaptive Control: Theory and Applications*, CRC Press 2013, §4.2;
    Lu & Hou (2022), eq. (6)-(7) and (33)-(34).

    Examples
    --------
    Starting at rest (``u(k0−1) = u0 = 0``), the first estimate is the reset value, not ``phi0``;
    the second one is (6) from it:

    >>> import numpy as np
    >>> est = PPDEstimator(eta=0.5, mu=1.0, epsilon=1e-5, phi0=2.0, phi_reset=0.5, y0=1.0)
    >>> y, _ = est.run(np.array([[1.3, 0.0], [1.7, 0.4]]))   # inputs (y_f(k), u(k−1))
    >>> y[:, 0, 0].round(6)                                    # 0.5, 0.5 + 0.5·0.4·(0.4 − 0.2)/1.16
    array([0.5     , 0.534483])
    """

    inputs = ("y", "u_prev")
    states = ("phi_hat", "y_prev", "u_prev_prev")
    outputs = ("phi_hat",)
    feedthrough = True
    kernels = Kernels(output=ppd_output, update=ppd_update, columns=False)

    def __init__(self, eta: float, mu: float, epsilon: float, phi0: float, phi_reset: float | None = None,
                 y0: float = 0.0, u0: float = 0.0):
        self.eta = _check_step("eta", eta)
        self.mu = float(check_positive("mu", mu, scalar=True))
        self.epsilon = float(check_positive("epsilon", epsilon, scalar=True))
        self.phi0 = float(check_finite("phi0", phi0, scalar=True))
        if self.phi0 == 0.0:
            raise ValueError("phi0 must be non-zero (its sign is what the reset rule keeps), got 0.0")
        self.phi_reset = self.phi0 if phi_reset is None else float(check_finite("phi_reset", phi_reset, scalar=True))
        if np.sign(self.phi_reset) != np.sign(self.phi0):
            raise ValueError(f"phi_reset must have the sign of phi0={self.phi0:g}, got {self.phi_reset:g}")
        self.sign0 = float(np.sign(self.phi0))
        self.y0 = float(check_finite("y0", y0, scalar=True))
        self.u0 = float(check_finite("u0", u0, scalar=True))
        self.kernel_params = PPD.pack(eta=self.eta, mu=self.mu, epsilon=self.epsilon, phi_reset=self.phi_reset,
                                      sign0=self.sign0)

    def initial_state(self) -> np.ndarray:
        return np.array([self.phi0, self.y0, self.u0])

    def __repr__(self) -> str:
        return (f"PPDEstimator(eta={self.eta:g}, mu={self.mu:g}, epsilon={self.epsilon:g}, phi0={self.phi0:g}, "
                f"phi_reset={self.phi_reset:g})")


class CFDLLaw(KernelBlock, StaticBlock):
    """The CFDL-MFAC control law, a static block: ``u(k) = u(k−1) + ρ φ̂(k) (y*(k+1) − y_f(k)) / (λ + φ̂(k)²)``.

    Block signals: inputs ``phi_hat``, ``y`` (``y_f(k)``), ``y_ref_next`` (``y*(k+1)``),
    ``u_prev`` (``u(k−1)``); output ``u``.

    Parameters
    ----------
    rho : float
        Step size ``ρ`` in ``(0, 1]`` (per-run values: ``Loop.simulate(params={"law": {"rho": ...}})``).
    lam : float
        Weight ``λ > 0`` on the control increment.

    Raises
    ------
    ValueError
        ``rho`` outside ``(0, 1]`` or ``lam`` not ``> 0``.

    References
    ----------
    Lu & Hou (2022), eq. (8) and (35); Hou & Jin (2013), §4.2.
    """

    inputs, outputs = ("phi_hat", "y", "y_ref_next", "u_prev"), ("u",)
    kernels = Kernels(output=cfdl_law_output)

    def __init__(self, rho: float, lam: float):
        self.rho = _check_step("rho", rho)
        self.lam = float(check_positive("lam", lam, scalar=True))
        self.kernel_params = LAW.pack(rho=self.rho, lam=self.lam)

    def __repr__(self) -> str:
        return f"CFDLLaw(rho={self.rho:g}, lam={self.lam:g})"


class DecreasingGainLaw(KernelBlock, DiscreteBlock):
    """CFDL-MFAC law whose increment is divided by ``k − k_m + 1`` inside an error band (D-MFAC).

    With ``e(k) = y*(k+1) − y_f(k)`` and ``Δu_0(k) = ρ φ̂(k) e(k) / (λ + φ̂(k)²)`` of (8)::

        Δu(k) = Δu_0(k)                     if |e(k)| >= e_m
        Δu(k) = Δu_0(k) / (k − k_m + 1)     if |e(k)| <  e_m          (36)

    where ``k_m`` is the instant ``|e|`` entered the band. Whether ``k_m`` moves when ``|e|``
    leaves the band and enters it again is not said by the paper: with ``rearm=True`` every entry
    sets ``k_m = k``; with ``rearm=False`` only the first one does (later entries resume the
    decreasing gain of the first). The band is entered when ``|e(k)| < e_m`` and
    ``|e(k−1)| >= e_m`` (before the first sample ``|e|`` counts as outside).

    Block signals: inputs ``phi_hat``, ``y``, ``y_ref_next``, ``u_prev`` (as :class:`CFDLLaw`);
    states ``in_band`` (1 if ``|e(k−1)| < e_m``), ``armed`` (1 once ``k_m`` is set), ``age``
    (``k − 1 − k_m``); output ``u``; direct feedthrough.

    Parameters
    ----------
    rho, lam : float
        As in :class:`CFDLLaw`.
    e_m : float
        Error threshold ``> 0``.
    rearm : bool
        Re-arm ``k_m`` at every entry into the band (default ``True``).

    Raises
    ------
    ValueError
        As :class:`CFDLLaw`, or ``e_m`` not ``> 0``.

    References
    ----------
    Lu & Hou (2022), eq. (36), after Bu, Hou, Yu et al., "Robust model free adaptive control with
    measurement disturbance", IET Control Theory Appl. 2012.
    """

    inputs = ("phi_hat", "y", "y_ref_next", "u_prev")
    states = ("in_band", "armed", "age")
    outputs = ("u",)
    feedthrough = True
    kernels = Kernels(output=dgain_output, update=dgain_update, columns=False)

    def __init__(self, rho: float, lam: float, e_m: float, rearm: bool = True):
        self.rho = _check_step("rho", rho)
        self.lam = float(check_positive("lam", lam, scalar=True))
        self.e_m = float(check_positive("e_m", e_m, scalar=True))
        if not isinstance(rearm, (bool, np.bool_)):
            raise TypeError(f"rearm must be a bool, got {type(rearm).__name__}")
        self.rearm = bool(rearm)
        self.kernel_params = DGAIN.pack(rho=self.rho, lam=self.lam, e_m=self.e_m, rearm=1.0 if self.rearm else 0.0)

    def __repr__(self) -> str:
        return f"DecreasingGainLaw(rho={self.rho:g}, lam={self.lam:g}, e_m={self.e_m:g}, rearm={self.rearm})"


class CFDLPredictor(KernelBlock, DiscreteBlock):
    """The CFDL data model (4) as a one-step predictor: output ``δ(k) = φ̂(k−1) Δu(k−1)``.

    ``y(k) ≈ y(k−1) + φ̂(k−1) Δu(k−1)``; the block stores ``(φ̂(k−1), u(k−1), u(k−2))`` and has
    no direct feedthrough, so an :class:`~ctrl_analysis.estimators.kalman.ImprovedKalmanFilter`
    can read its prediction (11) before the estimator and the law of sample ``k`` run.

    Block signals: inputs ``phi_hat``, ``u`` (``φ̂(k)``, ``u(k)``, stored by the update);
    states ``phi_prev``, ``u_prev``, ``u_prev_prev``; output ``dy_model``.

    Parameters
    ----------
    phi0, u0, u00 : float
        Initial ``φ̂(k0−1)``, ``u(k0−1)``, ``u(k0−2)``.

    References
    ----------
    Lu & Hou (2022), eq. (4), (9), (11) and (28).
    """

    inputs = ("phi_hat", "u")
    states = ("phi_prev", "u_prev", "u_prev_prev")
    outputs = ("dy_model",)
    feedthrough = False
    kernels = Kernels(output=predictor_output, update=predictor_update)

    def __init__(self, phi0: float = 0.0, u0: float = 0.0, u00: float = 0.0):
        self.x0 = np.array([check_finite(name, value, scalar=True)
                            for name, value in (("phi0", phi0), ("u0", u0), ("u00", u00))])
        self.kernel_params = NO_PARAMS.pack()

    def initial_state(self) -> np.ndarray:
        return self.x0.copy()

    def __repr__(self) -> str:
        return f"CFDLPredictor(x0={self.x0.tolist()})"


def mfac_controller(estimator: PPDEstimator, law: Block, output_filter: Block | None = None, *,
                    u0: float = 0.0, measured: str = "y_m", reference: str = "y_ref_next",
                    control: str = "u") -> list:
    """Place an MFAC controller in a loop: delay, optional output filter, PPD estimator and law.

    Signals: the loop must supply ``measured`` (``y_m(k)``) and ``reference`` (``y*(k+1)``);
    the controller produces ``control`` (``u(k)``) and the internal signals ``u_prev``,
    ``phi_hat``, ``y_f`` (what estimator and law see). Block names: ``delay``, ``ppd``, ``law``,
    and ``filter`` (plus ``model`` for the IKF; a TD with feedthrough is placed as its steps,
    ``filter``, and two delays ``filter_x1``, ``filter_x2`` holding its state).

    Parameters
    ----------
    estimator : PPDEstimator
    law : CFDLLaw or DecreasingGainLaw
    output_filter : TrackingDifferentiator or ImprovedKalmanFilter, optional
        ``None``: the law sees ``y_m`` (MFAC, D-MFAC); a tracking differentiator: it sees ``x1``
        (TD-MFAC, eq. (37)); an improved Kalman filter: it sees ``ŷ(k|k)``, predicted with a
        :class:`CFDLPredictor` (IKF-MFAC, eq. (28)-(35)).
    u0 : float
        ``u(k0−1)`` before the first sample (delay and predictor).
    measured, reference, control : str
        Names of the measured output, the reference ``y*(k+1)`` and the control signal.

    Returns
    -------
    list of ctrl_analysis.engine.loop.Placed
        To be given to :class:`~ctrl_analysis.engine.loop.Loop` with the plant and the measurement.

    Raises
    ------
    TypeError
        If a block is of the wrong kind.

    References
    ----------
    Lu & Hou (2022), Fig. 1 and eq. (6)-(8), (28)-(37).
    """
    from ..estimators.kalman.ikf import ImprovedKalmanFilter
    from ..estimators.tracking import TrackingDifferentiator

    if not isinstance(estimator, PPDEstimator):
        raise TypeError(f"estimator must be a PPDEstimator, got {type(estimator).__name__}")
    if not isinstance(law, (CFDLLaw, DecreasingGainLaw)):
        raise TypeError(f"law must be a CFDLLaw or a DecreasingGainLaw, got {type(law).__name__}")
    u0 = float(check_finite("u0", u0, scalar=True))
    for name, value in (("measured", measured), ("reference", reference), ("control", control)):
        check_str(name, value)
    y_f = measured
    blocks = [place(UnitDelay(u0), "delay", inputs=[control], outputs=["u_prev"])]
    if isinstance(output_filter, TrackingDifferentiator) and output_filter.feedthrough:
        # the TD's steps once per sample (the block's output and update would run them twice): its
        # state (x1, x2) in two delays fed by the steps' outputs, the same numbers
        y_f = "y_f"
        blocks.append(place(output_filter.step_block(), "filter", inputs=[measured, "td_x[0]", "td_x[1]"],
                            outputs=["y_f", "y_f_rate"]))
        blocks += [place(UnitDelay(output_filter.x0[i]), f"filter_x{i + 1}", inputs=[s], outputs=[f"td_x[{i}]"])
                   for i, s in enumerate(("y_f", "y_f_rate"))]
    elif isinstance(output_filter, TrackingDifferentiator):
        y_f = "y_f"
        blocks.append(place(output_filter, "filter", inputs=[measured], outputs=["y_f", "y_f_rate"]))
    elif isinstance(output_filter, ImprovedKalmanFilter):
        y_f = "y_f"
        blocks.append(place(CFDLPredictor(estimator.phi0, u0, estimator.u0), "model",
                            inputs=["phi_hat", control], outputs=["dy_model"]))
        blocks.append(place(output_filter, "filter", inputs=[measured, "dy_model"], outputs=["y_f", "K", "P"]))
    elif output_filter is not None:
        raise TypeError("output_filter must be None, a TrackingDifferentiator or an ImprovedKalmanFilter, "
                        f"got {type(output_filter).__name__}")
    blocks.append(place(estimator, "ppd", inputs=[y_f, "u_prev"], outputs=["phi_hat"]))
    blocks.append(place(law, "law", inputs=["phi_hat", y_f, reference, "u_prev"], outputs=[control]))
    return blocks


def ikf_mfac(estimator: PPDEstimator, law: CFDLLaw, ikf, **kw) -> list:
    """IKF-MFAC (eq. (28)-(35)): :func:`mfac_controller` with an improved Kalman filter on the output.

    Parameters
    ----------
    estimator : PPDEstimator
    law : CFDLLaw
    ikf : ctrl_analysis.estimators.kalman.ImprovedKalmanFilter
        Its ``R`` is the measurement noise variance ``σ²``; its ``Q`` the variance of the output's
        change per step that the loop must follow (to follow a setpoint ``r``, ``Q ≈ mean(Δr²)``).
        ``Q/R`` sets the filter's bandwidth and lag: too small a ``Q`` lags, and the loop stops
        following the setpoint; ``Q ≫ R`` is no filter (CFDL-MFAC). See
        :class:`~ctrl_analysis.estimators.kalman.ImprovedKalmanFilter` and the user guide's sweep.
    **kw
        Passed to :func:`mfac_controller`.

    Returns
    -------
    list of ctrl_analysis.engine.loop.Placed
    """
    from ..estimators.kalman.ikf import ImprovedKalmanFilter

    if not isinstance(ikf, ImprovedKalmanFilter):
        raise TypeError(f"ikf must be an ImprovedKalmanFilter, got {type(ikf).__name__}")
    return mfac_controller(estimator, law, ikf, **kw)


