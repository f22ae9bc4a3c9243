"""The `meso` study's own blocks, kernel-first: the plant (27), the modelled ESO (29) and the parameter path.

:class:`Plant` is the second-order plant with the disturbance level, :class:`ModelledESO` the (M)ESO fed the
identified model Θ, :class:`ParameterPath` the smoothing W(s) of Θ or its bypass. Every block has compiled
kernels; what differs per run is given to the simulation (:func:`.loops.run_params`).
"""


import numpy as np

from ctrl_analysis._validate import check_bool, check_finite, check_positive
from ctrl_analysis.engine.blocks import ContinuousBlock, DiscreteBlock, signal_names
from ctrl_analysis.engine.codegen import kernel_of
from ctrl_analysis.engine.kernels import KernelBlock, Kernels, Layout, copy_output
from ctrl_analysis.estimators.eso import ExtendedStateObserver, eso_rhs

from .paper import PAPER, Paper

__all__ = ["ModelledESO", "ParameterPath", "Plant", "meso_rhs", "path_output", "plant_output", "plant_rhs"]


#: Plant (27)'s kernel parameters.
PLANT = Layout("theta1", "theta2", "b")
AT_PLANT = PLANT.at


def plant_rhs(t, x, u, p, dx):
    """(27)/(31)/(32) of one run (or a batch's columns): ``x1' = x2``, ``x2' = θ1 x1 + θ2 x2 + θ4 + b u``.

    Parameters
    ----------
    t : float
        Time (unused).
    x : ndarray
        ``[x1, x2]``.
    u : ndarray
        ``[u, θ4, v]``.
    p : ndarray
        :data:`PLANT`: ``θ1, θ2, b``.
    dx : ndarray
        The derivative, written in place.
    """
    dx[0] = x[1]
    dx[1] = p[AT_PLANT.theta1] * x[0] + p[AT_PLANT.theta2] * x[1] + u[1] + p[AT_PLANT.b] * u[0]


def plant_output(t, x, u, p, y):
    """Outputs ``[x1, x2, y]`` with (27) ``y = x1 + 0.002 n0`` (the noise ``v`` is an input).

    Parameters
    ----------
    t, x, u, p
        As :func:`plant_rhs`.
    y : ndarray
        The outputs, written in place.
    """
    y[0] = x[0]
    y[1] = x[1]
    y[2] = x[0] + u[2]


class Plant(KernelBlock, ContinuousBlock):
    """Plant (27) with the disturbance (31)/(32): ``x1' = x2``, ``x2' = θ1 x1 + θ2 x2 + θ4 + b u``, ``y = x1 + v``.

    Kernels :func:`plant_rhs` / :func:`plant_output` (the batched methods are derived from them).

    Parameters
    ----------
    paper : Paper
        ``θ1``, ``θ2`` are read from it.
    b : float
        Input gain of the simulated plant (per run through ``Loop.simulate(params={"plant": {"b": ...}})``).

    Block signals: inputs ``u``, ``level`` (θ4, held), ``v`` (measurement noise, held); outputs
    ``x1``, ``x2``, ``y``; states ``x1``, ``x2``.
    """

    inputs = ("u", "level", "v")
    outputs = ("x[0]", "x[1]", "y")
    states = ("x[0]", "x[1]")
    feedthrough = True
    kernels = Kernels(output=plant_output, rhs=plant_rhs)

    def __init__(self, paper: Paper, b: float):
        self.theta1, self.theta2 = paper.theta1, paper.theta2
        self.b = check_finite("b", b, scalar=True)
        self.kernel_params = PLANT.pack(theta1=self.theta1, theta2=self.theta2, b=self.b)


def _eso_vector(paper: Paper, epsilon: float) -> np.ndarray:
    """The parameter vector of :func:`~ctrl_analysis.engine.codegen.eso_rhs` for the linear ESO (29) at ε, b0 slot 0."""
    return kernel_of(ExtendedStateObserver.from_epsilon(paper.n, epsilon, paper.beta, b0=0.0)).params


#: (29)'s kernel parameters: ``eso_rhs``'s vector (its b0 slot 0, see :func:`meso_rhs`), then b0.
OBSERVER = Layout(("eso", _eso_vector(PAPER, PAPER.epsilon).size), "b0")
AT_OBSERVER = OBSERVER.at


def meso_rhs(t, x, u, p, dx):
    """(29) of one run: the ESO of :func:`ctrl_analysis.engine.codegen.eso_rhs` plus ``b0 u + XᵀΘ`` in row n.

    ``eso_rhs`` is called with ``b0 = 0`` in its parameters (adding ``0 u`` is exact), and the drive
    ``b0 u + XᵀΘ`` is added afterwards.

    Parameters
    ----------
    t : float
        Time (unused).
    x : ndarray
        ``x̂1..x̂3``.
    u : ndarray
        ``[y, u, θ1, θ2, θ3, θ4]``.
    p : ndarray
        :data:`OBSERVER`: ``eso_rhs``'s parameters (first, as it reads them), then ``b0``.
    dx : ndarray
        The derivative, written in place.
    """
    eso_rhs(t, x, u, p, dx)
    m = x.shape[0]
    # (29) XᵀΘ with X = [x̂1, x̂2, u, 1]
    f = u[2] * x[0] + u[3] * x[1] + u[4] * u[1] + u[5]
    dx[m - 2] = dx[m - 2] + (p[AT_OBSERVER.b0] * u[1] + f)


class ModelledESO(KernelBlock, ContinuousBlock):
    """The linear (M)ESO (29) with the identified model XᵀΘ as the known part, Θ an input signal.

    The observer of :class:`~ctrl_analysis.estimators.eso.ExtendedStateObserver` (its kernel
    :func:`~ctrl_analysis.engine.codegen.eso_rhs`, gains ``L_i = β_i / ε^i``) with ``b0 u + XᵀΘ`` in the
    n-th equation (:func:`meso_rhs`); Θ = 0 gives the conventional ESO (6). ``eso_rhs`` branches on
    its parameters, so the batched methods call the kernel run by run.

    Parameters
    ----------
    paper : Paper
        ``n`` and ``β`` are read from it.
    b0 : float
        Nominal input gain.
    epsilon : float
        High-gain parameter ε (> 0; per run through ``Loop.simulate(params={"observer": {"epsilon": ...}})``).

    Block signals: inputs ``y``, ``u``, ``theta[0..3]``; states and outputs ``xhat[0..2]``.
    """

    inputs = ("y", "u") + signal_names("theta", 4)
    outputs = states = ("xhat[0]", "xhat[1]", "xhat[2]")
    kernels = Kernels(rhs=meso_rhs, columns=False)

    def __init__(self, paper: Paper, b0: float, epsilon: float):
        self.b0 = check_finite("b0", b0, scalar=True)
        self.epsilon = check_positive("epsilon", epsilon, scalar=True)
        self.kernel_params = OBSERVER.pack(eso=_eso_vector(paper, self.epsilon), b0=self.b0)


#: The W(s) bypass flag of :class:`ParameterPath`.
PATH = Layout("bypass")
AT_PATH = PATH.at


def path_output(t, x, u, p, y):
    """Θ_used of one run: the LSM result ``c`` if bypassed, else its W(s)-smoothed ``w``.

    Parameters
    ----------
    t, x : float, ndarray
        Time and (empty) state, unused.
    u : ndarray
        ``[c0..c3, w0..w3]``.
    p : ndarray
        :data:`PATH`: ``bypass`` (1 or 0).
    y : ndarray
        Θ_used, written in place.
    """
    off = 0 if p[AT_PATH.bypass] != 0.0 else 4
    for i in range(4):
        y[i] = u[off + i]


class ParameterPath(KernelBlock, DiscreteBlock):
    """Θ_used = W(s)-smoothed LSM result, or the raw LSM result with ``bypass`` (a discrete block without state).

    Discrete (its inputs change only at the samples), so the compiled engine evaluates it once per
    sample, not at every RK4 stage; kernel :func:`path_output` (a branch on the flag: the batched
    methods call it run by run).

    Parameters
    ----------
    bypass : bool
        The observer and the controller receive the LSM result without W(s) (the literal rule
        without W(s), a claim check); per run through ``Loop.simulate(params={"path": {"bypass": ...}})``.

    Block signals: inputs ``c[0..3]`` (LSM result), ``w[0..3]`` (after W(s)); outputs ``theta[0..3]``.
    """

    inputs = signal_names("c", 4) + signal_names("w", 4)
    outputs = signal_names("theta", 4)
    states = ()
    feedthrough = True
    kernels = Kernels(output=path_output, update=copy_output, columns=False)

    def __init__(self, bypass: bool = False):
        self.bypass = check_bool("bypass", bypass)
        self.kernel_params = PATH.pack(bypass=float(self.bypass))
