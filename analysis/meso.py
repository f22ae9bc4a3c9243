"""Study `meso`: Chen & Gao 2018, modified extended state observer: analysis and implementation.

Reproduces
----------
(a) the linear observer of eq. (29) (ε = 0.05, β = (3, 3, 1)): characteristic polynomial, poles,
    bandwidth form ω_o, Bode plots of the disturbance-to-estimation-error transfer functions, and a
    numerical check of the ε^(n+2-i) error-scaling law (4)/(7);
(b) situations 1 and 2 of section 4 (eq. (27)-(32)): PD control with feed-forward (30) on the
    double integrator with a state-dependent disturbance, observed by the conventional ESO (6) or by
    the MESO (29) whose model XᵀΘ is identified by batch least squares (Table 1, eq. (9)-(23)) and
    smoothed by W(s) = ω_f²/(s + ω_f)²;
(c) Fig. 3-6 and Tables 2-3, with noise on and off, the literal Table-1 accumulation rule and a
    well-posed variant, and an identifiability report (rank, condition number) for every batch.

Everything the paper does not print is a named reconstruction in ``results.json``.
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass

import numpy as np

from ctrl_analysis.controllers.pd import PDFeedforward
from ctrl_analysis.estimators.eso import ExtendedStateObserver
from ctrl_analysis.estimators.lowpass import LowPassFilter
from ctrl_analysis.identification import batch_least_squares
from ctrl_analysis.metrics import mean_abs_error, mean_std
from ctrl_analysis.report import StudyContext, StudyInfo, StudyResult, new_figure
from ctrl_analysis.simulate import draw_noise, run_seeds, simulate_sampled, uniform_noise

__all__ = ["INFO", "PAPER", "Situation", "SITUATIONS", "Row", "simulate_situation", "run"]

INFO = StudyInfo(
    name='meso',
    seed_file='003_69569f7e4aa9c67b.txt',
    paper='Chen & Gao 2018, modified extended state observer: analysis and implementation',
    reproduces='linear ESO analysis (omega_o, poles, Bode, eps-scaling), Tables 2-3, Fig. 3-6',
)


# ----------------------------------------------------------------------------------------------
# The paper's numbers
# ----------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Paper:
    """Parameters printed in section 4 of the paper."""

    n: int = 2                       # plant order, (27)
    b: float = 3.95                  # true input gain, below (30)
    epsilon: float = 0.05            # observer (29)
    beta: tuple = (3.0, 3.0, 1.0)    # observer (29)
    omega_c: float = 10.0            # controller bandwidth, (30)
    h: float = 0.003                 # simulation step 3 ms
    omega_f: float = 1.8             # parameter low-pass W(s)
    noise_amp: float = 0.002         # y = x1 + 0.002 n0, n0 ~ U[-1, 1], (27)
    theta1: float = 1.3              # d(t), (31)/(32)
    theta2: float = -1.6
    step: float = 1.8                # "non-model-class" term after t_step
    t_step: float = 30.0


PAPER = Paper()


@dataclass(frozen=True)
class Situation:
    """One simulation case of section 4."""

    key: str                # "s1" / "s2"
    b0: float               # nominal gain of observer and controller
    T: float                # horizon (s)
    N: int                  # LSM batch size (samples)
    regression: str         # "reduced" (22): theta3 = 0; "full" (16)-(20)
    theta3_printed: float   # the u-term printed in d(t): 0 in (31), 0.95 in (32)
    figs: tuple             # (states figure, theta figure)
    table: str


SITUATIONS = {
    "s1": Situation("s1", b0=3.95, T=60.0, N=1000, regression="reduced", theta3_printed=0.0,
                    figs=("fig3_situation1.png", "fig4_theta_situation1.png"), table="Table 2"),
    "s2": Situation("s2", b0=3.0, T=210.0, N=2000, regression="full", theta3_printed=0.95,
                    figs=("fig5_situation2.png", "fig6_theta_situation2.png"), table="Table 3"),
}

#: Tables 2 and 3: mean |error| of estimates x1, x2, x3 and tracking x1, x2.
METRICS = ("est_x1", "est_x2", "est_x3", "track_x1", "track_x2")
TABLES = {
    "s1": {"meso": (5.4572e-05, 0.0024, 0.0481, 0.0012, 0.0035),
           "eso": (1.7115e-04, 0.0102, 0.2081, 0.0045, 0.0065)},
    "s2": {"meso": (6.7639e-05, 0.0038, 0.5404, 0.0017, 0.0026),
           "eso": (1.1862e-04, 0.0070, 0.5797, 0.0031, 0.0037)},
}
TOLERANCE = 0.10
COND_WARN = 1e2      # column-scaled condition number above which a batch is called ill-conditioned
EPS_GRID = (0.1, 0.05, 0.025, 0.0125)
#: horizons under --quick (s); the full run uses the paper's 60 s and 210 s
QUICK = {"s1": 9.0, "s2": 12.0, "eps_T": 4.0, "eps_from": 2.0}


# ----------------------------------------------------------------------------------------------
# Closed-loop simulation of one situation, all configurations on the batch axis
# ----------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Row:
    """One configuration on the batch axis.

    observer : "eso" or "meso"; variant : "literal" (Table 1 accumulation) or "wellposed"
    (re-identify the total disturbance each batch), ignored for the ESO; seed : noise seed or None
    (noise off); b_plant : input gain of the simulated plant.
    """

    observer: str
    variant: str | None
    seed: int | None
    b_plant: float

    @property
    def label(self) -> str:
        v = "" if self.observer == "eso" else f"-{self.variant}"
        return f"{self.observer}{v}/" + ("no-noise" if self.seed is None else f"seed{self.seed}") + f"/b={self.b_plant}"


def _identify(sit: Situation, variant: str, xh, u, kbar, f_obs, k_gains, b0, theta3_held=0.0):
    """One LSM batch for one run: returns (theta (4,), report).

    literal: regress the MESO's own x̂3 (the residual d − Σ f_j) and return the increment Θ̂_i;
    wellposed: regress the total-disturbance estimate x̂3 + XᵀΘ_used and return Θ̂ itself.
    """
    ones = np.ones(len(u))
    if variant == "literal":
        z = xh[:, 2]
        if sit.regression == "reduced":
            # (22)-(23): [x̂1 x̂2 1] [θ1 θ2 θ4]ᵀ = x̂3
            res = batch_least_squares(np.column_stack([xh[:, 0], xh[:, 1], ones]), z, warn=False,
                                      cond_threshold=COND_WARN)
            th = np.array([res.theta[0], res.theta[1], 0.0, res.theta[2]])
            return th, res.report
        # (16)-(17): [x̂1 x̂2 K̄ 1] Λ = x̂3
        res = batch_least_squares(np.column_stack([xh[:, 0], xh[:, 1], kbar, ones]), z, warn=False,
                                  cond_threshold=COND_WARN)
        th = _theta_from_lambda(res.theta, k_gains, b0)
        return th, res.report
    # well-posed: re-identify the total disturbance z = x̂3 + XᵀΘ_used each batch (no accumulation)
    z = xh[:, 2] + f_obs
    if sit.regression == "reduced":
        # (22)-(23) on the total disturbance
        res = batch_least_squares(np.column_stack([xh[:, 0], xh[:, 1], ones]), z, warn=False,
                                  cond_threshold=COND_WARN)
        return np.array([res.theta[0], res.theta[1], 0.0, res.theta[2]]), res.report
    if variant == "direct":
        # (10) directly: [x̂1 x̂2 u 1] Θ = z  (u carries x̂3's noise: closed-loop bias)
        res = batch_least_squares(np.column_stack([xh[:, 0], xh[:, 1], u, ones]), z, warn=False,
                                  cond_threshold=COND_WARN)
        return res.theta.copy(), res.report
    # (13)-(20) on the total disturbance: substituting b0 u = K̄ + f - Σ k_l x̂_l - z gives
    # z = λ1 x̂1 + λ2 x̂2 + λ3 (K̄ + f) + λ4 with the λ of (15) for the total Θ
    res = batch_least_squares(np.column_stack([xh[:, 0], xh[:, 1], kbar + f_obs, ones]), z, warn=False,
                              cond_threshold=COND_WARN)
    if res.report.well_conditioned:
        return _theta_from_lambda(res.theta, k_gains, b0), res.report
    # Theorem 1 gate: the full problem is not identifiable from this batch, so identify only the
    # identifiable part, (22) with θ3 held at its current value: z - θ3 u = [x̂1 x̂2 1] [θ1 θ2 θ4]ᵀ
    red = batch_least_squares(np.column_stack([xh[:, 0], xh[:, 1], ones]), z - theta3_held * u,
                              warn=False, cond_threshold=COND_WARN)
    return np.array([red.theta[0], red.theta[1], theta3_held, red.theta[2]]), res.report


def _theta_from_lambda(lam, k_gains, b0):
    """(18)-(19): solve X_Θ Θ = b0 Λ for Θ."""
    k1, k2 = k_gains[0], k_gains[1]
    X_theta = np.array([
        [b0, 0.0, -(k1 + lam[0]), 0.0],
        [0.0, b0, -(k2 + lam[1]), 0.0],
        [0.0, 0.0, 1.0 - lam[2], 0.0],
        [0.0, 0.0, -lam[3], b0],
    ])
    return b0 * np.linalg.solve(X_theta, lam)


def simulate_situation(sit: Situation, rows: list, T: float | None = None, paper: Paper = PAPER,
                       epsilon: float | None = None, progress=None) -> dict:
    """Run every configuration in ``rows`` of situation ``sit`` at once on the batch axis.

    The continuous state of each run is ``[x1, x2, x̂1, x̂2, x̂3]`` (plant (27) and observer (29)),
    integrated with RK4 at the paper's 3 ms step; at each sample the PD law (30) is computed from the
    sampled estimates and held (ZOH) together with the measurement noise and the disturbance level.
    MESO runs feed ``XᵀΘ_used`` into the observer (with the held ``u``) and the controller (with the
    previous sample's ``x̂`` and ``u``, eq. (12)); ESO runs have ``Θ_used ≡ 0``.

    Returns a dict of trajectories (samples 0..K-1) and identification records.
    """
    T = sit.T if T is None else T
    h = paper.h
    K = int(round(T / h))
    B = len(rows)
    eps = paper.epsilon if epsilon is None else epsilon
    b0 = sit.b0
    is_meso = np.array([r.observer == "meso" for r in rows])
    b_plant = np.array([r.b_plant for r in rows], dtype=float)

    pd = PDFeedforward(b0=b0, omega_c=paper.omega_c, order=paper.n)
    lpf = LowPassFilter(paper.omega_f, order=2).digital(h, channels=4)

    # noise: one draw per distinct seed (ESO and MESO runs with the same seed see the same noise)
    noise = np.zeros((K, B, 1))
    seeds = sorted({r.seed for r in rows if r.seed is not None})
    if seeds:
        drawn = draw_noise(seeds, K, uniform_noise(-1.0, 1.0))
        for b, r in enumerate(rows):
            if r.seed is not None:
                noise[:, b, 0] = paper.noise_amp * drawn[:, seeds.index(r.seed), 0]

    # mutable loop state (closures below)
    st = {
        "theta_used": np.zeros((B, 4)),   # Θ entering observer and controller (after W(s))
        "theta_cum": np.zeros((B, 4)),    # LSM result (input of W(s))
        "xh_prev": np.zeros((B, 3)),
        "u_prev": np.zeros(B),
        "lpf": np.tile(lpf.initial_state(), (B, 1)),
    }

    def known(t, xh, uu, params):
        # (29) XᵀΘ with X = [x̂1, x̂2, u, 1]; u is the held control of this step
        th = st["theta_used"]
        return th[:, 0] * xh[:, 0] + th[:, 1] * xh[:, 1] + th[:, 2] * uu[:, 1] + th[:, 3]

    obs = ExtendedStateObserver.from_epsilon(paper.n, eps, paper.beta, b0=b0, known=known)

    def rhs(t, z, U, params):
        u = U[:, 0]
        # (27)/(31)/(32): x1' = x2, x2' = θ1 x1 + θ2 x2 + θ4 + b u  (θ4 held per sample)
        dx2 = paper.theta1 * z[:, 0] + paper.theta2 * z[:, 1] + U[:, 2] + b_plant * u
        y = z[:, 0] + U[:, 1]
        dxh = obs.rhs(t, z[:, 2:], np.stack([y, u], axis=1))
        return np.concatenate([z[:, 1:2], dx2[:, None], dxh], axis=1)

    # records
    xh_hist = np.empty((K, B, 3))
    u_hist = np.empty((K, B))
    kbar_hist = np.empty((K, B))
    fobs_hist = np.empty((K, B))
    th_used_hist = np.empty((K, B, 4))
    n_batches = K // sit.N
    th_batch = np.full((n_batches, B, 4), np.nan)
    rank = np.zeros((n_batches, B), dtype=int)
    cond = np.full((n_batches, B), np.nan)
    cond_scaled = np.full((n_batches, B), np.nan)
    t_batch = np.empty(n_batches)
    meso_idx = np.flatnonzero(is_meso)
    every = max(1, K // 10)

    def controller(k, t, z, w):
        if k > 0:
            # W(s) on the LSM result, exact ZOH (the LSM result is held between samples)
            filtered = lpf.output(t, st["lpf"], st["theta_cum"])
            st["lpf"] = lpf.update(t, st["lpf"], st["theta_cum"])
            st["theta_used"] = np.where(is_meso[:, None], filtered, 0.0)
        th = st["theta_used"]
        xh = z[:, 2:]
        ref = np.array([np.sin(t), np.cos(t), -np.sin(t)])
        # (12): XᵀΘ in the control law uses the previous sample's x̂ and u
        xp, up = st["xh_prev"], st["u_prev"]
        f_prev = th[:, 0] * xp[:, 0] + th[:, 1] * xp[:, 1] + th[:, 2] * up + th[:, 3]
        # (30) u = (Σ k_i (ξ^(i-1) - x̂_i) - XᵀΘ) / b0
        u = pd.control(ref, xh, f_prev)
        # (14) K̄ = Σ k_l ξ^(l-1) - previous-model terms, so that b0 u = K̄ - Σ k_l x̂_l
        kbar = pd.k @ ref - f_prev
        xh_hist[k] = xh
        u_hist[k] = u
        kbar_hist[k] = kbar
        fobs_hist[k] = th[:, 0] * xh[:, 0] + th[:, 1] * xh[:, 1] + th[:, 2] * u + th[:, 3]
        th_used_hist[k] = th
        st["xh_prev"], st["u_prev"] = xh.copy(), u
        if (k + 1) % sit.N == 0 and meso_idx.size:
            i = (k + 1) // sit.N - 1
            sl = slice(k + 1 - sit.N, k + 1)
            t_batch[i] = t
            for b in meso_idx:
                data = (xh_hist[sl, b], u_hist[sl, b], kbar_hist[sl, b], fobs_hist[sl, b])
                if not all(np.all(np.isfinite(d)) for d in data):
                    continue
                theta, rep = _identify(sit, rows[b].variant, *data, pd.k, b0, st["theta_cum"][b, 2])
                rank[i, b], cond[i, b], cond_scaled[i, b] = rep.rank, rep.cond, rep.cond_scaled
                if rows[b].variant == "literal":
                    # Table 1: Σ_j Θ̂_j
                    st["theta_cum"][b] = st["theta_cum"][b] + theta
                else:
                    st["theta_cum"][b] = theta
                th_batch[i, b] = st["theta_cum"][b]
        if progress is not None and k % every == 0 and k:
            progress(f"{sit.key}: t = {t:.0f} / {T:.0f} s")
        level = paper.step if t >= paper.t_step - 0.5 * h else 0.0
        return np.stack([u, w[:, 0], np.full(B, level)], axis=1)

    x0 = np.zeros((B, 5))
    res = simulate_sampled(rhs, x0, h, K, controller=controller, noise=noise, bound=1e6)
    t = res.t[:K]
    x = res.x[:K]
    level = np.where(t >= paper.t_step - 0.5 * h, paper.step, 0.0)
    # derivative of x2 at the samples (exact, from the plant equation)
    x2dot = paper.theta1 * x[:, :, 0] + paper.theta2 * x[:, :, 1] + level[:, None] + b_plant * u_hist
    # true extended state: what x̂3 should converge to, x3 = x2' - b0 u - XᵀΘ_used (ESO: Θ_used = 0)
    x3_true = x2dot - b0 * u_hist - fobs_hist
    return {
        "rows": rows, "t": t, "x": x[:, :, :2], "xh": xh_hist, "u": u_hist, "x3_true": x3_true,
        "f_obs": fobs_hist, "theta_used": th_used_hist, "theta_batch": th_batch, "t_batch": t_batch,
        "rank": rank, "cond": cond, "cond_scaled": cond_scaled, "diverged": res.diverged,
        "diverged_step": res.diverged_step, "level": level, "noise": noise[:, :, 0],
    }


def table_metrics(sim: dict, paper_b: float, b0: float) -> dict:
    """Tables 2/3 metrics per run: e_mean = Σ|e|/N over the whole run (shape (B,) each).

    ``est_x3`` uses the true extended state (with the (b − b0)u part); ``est_x3_no_bu`` the same
    minus ``(b_paper − b0) u`` (the printed d(t) without the input-gain mismatch).
    """
    t, x, xh = sim["t"], sim["x"], sim["xh"]
    ref1, ref2 = np.sin(t)[:, None], np.cos(t)[:, None]
    return {
        "est_x1": mean_abs_error(x[:, :, 0], xh[:, :, 0]),
        "est_x2": mean_abs_error(x[:, :, 1], xh[:, :, 1]),
        "est_x3": mean_abs_error(sim["x3_true"], xh[:, :, 2]),
        "est_x3_no_bu": mean_abs_error(sim["x3_true"] - (paper_b - b0) * sim["u"], xh[:, :, 2]),
        "track_x1": mean_abs_error(ref1, x[:, :, 0]),
        "track_x2": mean_abs_error(ref2, x[:, :, 1]),
    }


def equivalent_theta(theta_true, b: float) -> np.ndarray:
    """Θ that explains the total disturbance on the perfectly tracked trajectory x1 = sin t, x2 = cos t.

    There ``x2' = -x1 = θ1 x1 + θ2 x2 + θ4 + b u``, so ``u = -((1 + θ1) x1 + θ2 x2 + θ4) / b`` lies in
    span{x1, x2, 1} and ``θ3 u`` folds into the other three parameters:
    ``Θ_eq = [θ1 - θ3 (1 + θ1)/b, θ2 (1 - θ3/b), 0, θ4 (1 - θ3/b)]``.
    """
    t1, t2, t3, t4 = np.asarray(theta_true, dtype=float)
    r = t3 / b
    return np.array([t1 - r * (1.0 + t1), t2 * (1.0 - r), 0.0, t4 * (1.0 - r)])


# ----------------------------------------------------------------------------------------------
# (a) Linear observer analysis
# ----------------------------------------------------------------------------------------------

def eps_scaling(paper: Paper = PAPER, eps_grid=EPS_GRID, T: float = 10.0, t_from: float = 5.0) -> dict:
    """Mean |e_i| of the ESO in the noise-free situation-1 loop (before the step) for several ε.

    One batch row per ε (each row its own observer); the mean is taken over ``[t_from, T]`` so the
    initial transient is excluded. Returns ``eps``, ``err`` (len(eps), 3) and the log-log ``slope``.
    """
    h = paper.h
    K = int(round(T / h))
    b0 = paper.b
    observers = [ExtendedStateObserver.from_epsilon(paper.n, e, paper.beta, b0=b0) for e in eps_grid]
    pd = PDFeedforward(b0=b0, omega_c=paper.omega_c, order=paper.n)
    B = len(observers)

    def rhs(t, z, U, params):
        u = U[:, 0]
        dx2 = paper.theta1 * z[:, 0] + paper.theta2 * z[:, 1] + paper.b * u
        dxh = np.stack([o.rhs(t, z[b, 2:], np.array([z[b, 0], u[b]])) for b, o in enumerate(observers)])
        return np.concatenate([z[:, 1:2], dx2[:, None], dxh], axis=1)

    def controller(k, t, z, w):
        ref = np.array([np.sin(t), np.cos(t), -np.sin(t)])
        return pd.control(ref, z[:, 2:])[:, None]

    res = simulate_sampled(rhs, np.zeros((B, 5)), h, K, controller=controller)
    x, u = res.x[:K], res.u[:, :, 0]
    d = paper.theta1 * x[:, :, 0] + paper.theta2 * x[:, :, 1] + (paper.b - b0) * u
    keep = res.t[:K] >= t_from
    err = np.stack([mean_abs_error(x[keep, :, 0], x[keep, :, 2]),
                    mean_abs_error(x[keep, :, 1], x[keep, :, 3]),
                    mean_abs_error(d[keep], x[keep, :, 4])], axis=1)
    slope = np.array([np.polyfit(np.log(eps_grid), np.log(err[:, i]), 1)[0] for i in range(3)])
    return {"eps": np.asarray(eps_grid, dtype=float), "err": err, "slope": slope, "T": T, "t_from": t_from}


def plot_error_bode(obs: ExtendedStateObserver, omega_o: float):
    """Bode plot of the disturbance-to-estimation-error transfer functions E_i(s)/H(s)."""
    import control as ct

    w = np.logspace(-2, 3.5, 600)
    fig, (ax_m, ax_p) = new_figure(2, 1, size=(7.5, 6.5), sharex=True,
                                   title=f"Linear ESO (ε = {1 / omega_o:g}, β = (3, 3, 1)): "
                                         f"disturbance → estimation error, ωₒ = {omega_o:g} rad/s")
    for i, g in enumerate(obs.disturbance_error_tf(), start=1):
        resp = ct.frequency_response(g, w)
        c = np.squeeze(resp.complex)
        ax_m.semilogx(w, 20 * np.log10(np.abs(c)), label=f"$E_{i}(s)/H(s)$, $e_{i} = x_{i} - \\hat x_{i}$")
        ax_p.semilogx(w, np.degrees(np.unwrap(np.angle(c))), label=f"$E_{i}/H$")
    ax_m.axvline(omega_o, color="k", ls=":", lw=1, label=f"$\\omega_o$ = {omega_o:g} rad/s")
    ax_m.set_ylabel("magnitude (dB)")
    ax_m.legend(fontsize=8, loc="lower left")
    ax_p.set_ylabel("phase (deg)")
    ax_p.set_xlabel("frequency ω (rad/s)")
    ax_m.set_title("input h = dx₃/dt (derivative of the total disturbance)", fontsize=9)
    return fig


def plot_eps_scaling(sc: dict, n: int):
    fig, ax = new_figure(size=(6.5, 4.8), title="ESO error scaling with ε (situation 1 loop, no noise)")
    eps = sc["eps"]
    for i in range(3):
        line, = ax.loglog(eps, sc["err"][:, i], "o-", label=f"mean $|e_{i + 1}|$: slope {sc['slope'][i]:.2f} "
                                                             f"(law: {n + 2 - (i + 1)})")
        ref = sc["err"][1, i] * (eps / eps[1]) ** (n + 1 - i)
        ax.loglog(eps, ref, ":", color=line.get_color(), lw=1)
    ax.set_xticks(eps, [f"{e:g}" for e in eps])
    ax.minorticks_off()
    ax.set_xlabel("ε (observer high-gain parameter)")
    ax.set_ylabel(f"mean |estimation error| over [{sc['t_from']:g}, {sc['T']:g}] s")
    ax.legend(fontsize=8, title="dotted: ε^(n+2-i) through ε = 0.05", title_fontsize=8)
    return fig


# ----------------------------------------------------------------------------------------------
# (c) Figures of the simulations
# ----------------------------------------------------------------------------------------------

_COLORS = {"eso": "tab:red", "meso": "tab:blue", "literal": "tab:orange", "direct": "tab:purple"}


def plot_situation(sim: dict, i_eso: int, i_meso: int, title: str, max_points: int = 4000):
    """Fig. 3 / Fig. 5: tracking, estimation errors and control, ESO vs MESO (one noise realisation)."""
    dec = max(1, len(sim["t"]) // max_points)
    t = sim["t"][::dec]
    x, xh, u = sim["x"][::dec], sim["xh"][::dec], sim["u"][::dec]
    x3 = sim["x3_true"][::dec]
    fig, ax = new_figure(4, 2, size=(12, 11), sharex=True, title=title)
    ax[0, 0].plot(t, np.sin(t), "k--", lw=1.2, label="reference ξ = sin t")
    ax[0, 1].plot(t, np.cos(t), "k--", lw=1.2, label="ξ' = cos t")
    series = [(i_eso, "ESO", _COLORS["eso"]), (i_meso, "MESO", _COLORS["meso"])]
    for b, name, c in series:
        ax[0, 0].plot(t, x[:, b, 0], color=c, lw=0.8, label=f"$x_1$ ({name})")
        ax[0, 1].plot(t, x[:, b, 1], color=c, lw=0.8, label=f"$x_2$ ({name})")
        ax[1, 0].plot(t, np.sin(t) - x[:, b, 0], color=c, lw=0.8, label=name)
        ax[1, 1].plot(t, np.cos(t) - x[:, b, 1], color=c, lw=0.8, label=name)
        ax[2, 0].plot(t, x[:, b, 0] - xh[:, b, 0], color=c, lw=0.6, label=name)
        ax[2, 1].plot(t, x[:, b, 1] - xh[:, b, 1], color=c, lw=0.6, label=name)
        ax[3, 0].plot(t, x3[:, b] - xh[:, b, 2], color=c, lw=0.6, label=name)
        ax[3, 1].plot(t, u[:, b], color=c, lw=0.6, label=name)
    labels = [("$x_1$", "$x_2$ (1/s)"), ("tracking error ξ − $x_1$", "tracking error ξ' − $x_2$ (1/s)"),
              ("estimation error $x_1 − \\hat x_1$", "estimation error $x_2 − \\hat x_2$ (1/s)"),
              ("estimation error $x_3 − \\hat x_3$ (1/s²)", "control u")]
    for r, (l0, l1) in enumerate(labels):
        ax[r, 0].set_ylabel(l0)
        ax[r, 1].set_ylabel(l1)
    for r in range(1, 4):
        for c in range(2):
            y = np.concatenate([np.abs(l.get_ydata()[len(t) // 10:]) for l in ax[r, c].get_lines()])
            lim = 1.2 * np.nanpercentile(y, 99.9) if y.size else 1.0
            if np.isfinite(lim) and lim > 0:
                ax[r, c].set_ylim(-lim, lim)
    for a in ax.ravel():
        a.legend(fontsize=7, loc="upper right")
    ax[3, 0].set_xlabel("time t (s)")
    ax[3, 1].set_xlabel("time t (s)")
    return fig


def plot_theta(sim: dict, rows_to_plot: list, truth_fn, title: str, equivalent=None, max_points: int = 3000):
    """Fig. 4 / Fig. 6: identified Θ per batch (markers) and the smoothed Θ used (lines) vs the truth."""
    dec = max(1, len(sim["t"]) // max_points)
    t = sim["t"][::dec]
    tb = sim["t_batch"]
    fig, axes = new_figure(2, 2, size=(12, 8.5), sharex=True, title=title)
    names = ["θ₁ (x₁ coefficient)", "θ₂ (x₂ coefficient)", "θ₃ (u coefficient)", "θ₄ (non-model-class term)"]
    truth = truth_fn(t)
    for j, ax in enumerate(axes.ravel()):
        ax.plot(t, truth[:, j], "k--", lw=1.5, label="true Θ")
        if equivalent is not None:
            eq = equivalent(t)
            ax.plot(t, eq[:, j], color="tab:green", ls=":", lw=1.8, label="trajectory-equivalent Θ")
        lo, hi = np.nanmin(truth[:, j]), np.nanmax(truth[:, j])
        if equivalent is not None:
            lo, hi = min(lo, np.nanmin(eq[:, j])), max(hi, np.nanmax(eq[:, j]))
        for b, label, color in rows_to_plot:
            ax.plot(t, sim["theta_used"][::dec, b, j], color=color, lw=1.0, label=f"{label}: Θ after W(s)")
            ax.plot(tb, sim["theta_batch"][:, b, j], "o", ms=3.5, color=color, label=f"{label}: LSM per batch")
        span = max(hi - lo, 1.0)
        ax.set_ylim(lo - 0.8 * span, hi + 0.8 * span)
        ax.set_title(names[j] + (" — fixed at 0 by the reduced regression (22)"
                                 if j == 2 and np.all(sim["theta_batch"][:, :, 2][np.isfinite(sim["theta_batch"][:, :, 2])] == 0)
                                 and np.all(truth[:, 2] == 0) else ""), fontsize=10)
        ax.set_ylabel("value")
    for ax in axes[1]:
        ax.set_xlabel("time t (s)")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=8)
    return fig


def plot_identifiability(per_sit: dict):
    fig, axes = new_figure(1, 2, size=(12, 4.5), title="Identifiability of each LSM batch (Theorem 1): "
                                                         "condition number of the column-scaled regression matrix")
    for ax, (key, (sim, rows_to_plot, label)) in zip(np.atleast_1d(axes), per_sit.items()):
        for b, name, color, ls in rows_to_plot:
            c = sim["cond_scaled"][:, b]
            ax.semilogy(sim["t_batch"], c, marker="o", ms=3, ls=ls, color=color, label=name)
        ax.axhline(COND_WARN, color="k", ls=":", lw=1, label=f"threshold {COND_WARN:g}")
        ax.set_title(label, fontsize=10)
        ax.set_xlabel("end of batch t (s)")
        ax.set_ylabel("cond (column-scaled)")
        ax.legend(fontsize=7)
    return fig


# ----------------------------------------------------------------------------------------------
# The study
# ----------------------------------------------------------------------------------------------

def _rows(sit: Situation, seeds: list) -> list:
    rows = []
    for obs, var in (("eso", None), ("meso", "wellposed"), ("meso", "literal")):
        for s in list(seeds) + [None]:
            rows.append(Row(obs, var, s, PAPER.b))
    if sit.regression == "full":
        rows += [Row("meso", "direct", seeds[0], PAPER.b), Row("meso", "direct", None, PAPER.b),
                 Row("eso", None, None, PAPER.b + sit.theta3_printed)]
    return rows


def _select(rows, observer, variant, noise: bool, b_plant=PAPER.b):
    return [i for i, r in enumerate(rows) if r.observer == observer and r.variant == variant
            and (r.seed is not None) == noise and r.b_plant == b_plant]


def _nanmedian(a) -> float:
    a = np.asarray(a, dtype=float)
    a = a[np.isfinite(a)]
    return float(np.median(a)) if a.size else float("nan")


def _first_divergence(sim, idx):
    bad = [i for i in idx if sim["diverged"][i]]
    if not bad:
        return None
    i = min(bad, key=lambda j: sim["diverged_step"][j])
    return float(sim["diverged_step"][i] * PAPER.h)


def run(ctx: StudyContext) -> StudyResult:
    """Reproduce the linear analysis, situations 1 and 2 (Tables 2-3, Fig. 3-6) and the findings."""
    import sympy as sp

    from ctrl_analysis.symbolic.eso import bandwidth_match, characteristic_polynomial, error_scaling_exponents

    result = StudyResult(INFO)
    paper = PAPER
    runs = ctx.runs_or(4, 2)
    seeds = run_seeds(ctx.seed, runs)
    horizons = {"s1": QUICK["s1"], "s2": QUICK["s2"]} if ctx.quick else {"s1": SITUATIONS["s1"].T, "s2": SITUATIONS["s2"].T}
    result.seeds = {"noise": seeds}
    result.settings = {
        **asdict(paper), "beta": list(paper.beta),
        "situations": {k: {**asdict(v), "T_run": horizons[k]} for k, v in SITUATIONS.items()},
        "runs": runs, "quick": ctx.quick, "tolerance": TOLERANCE, "cond_threshold": COND_WARN,
        "eps_grid": list(EPS_GRID), "integrator": "rk4, one step per 3 ms sample, u and noise held (ZOH)",
        "table_metric": "e_mean = sum |e_k| / N over every 3-ms sample of the whole run",
        "x0": [0.0, 0.0], "x_hat0": [0.0, 0.0, 0.0], "theta0": [0.0, 0.0, 0.0, 0.0],
    }

    # ---------------------------------------------------------------- (a) linear observer
    ctx.progress("linear observer analysis")
    obs = ExtendedStateObserver.from_epsilon(paper.n, paper.epsilon, paper.beta, b0=paper.b)
    match = bandwidth_match(paper.beta, epsilon=paper.epsilon)
    omega_o = float(match.omega_o)
    p_sym = characteristic_polynomial(paper.n).subs(dict(zip(sp.symbols("beta1:4", positive=True), paper.beta)))
    p_sym = sp.expand(p_sym.subs(sp.Symbol("epsilon", positive=True), sp.nsimplify(paper.epsilon)))
    poles = np.sort_complex(obs.poles)
    result.quantity("leso.omega_o", "LESO bandwidth ω_o: s³ + β₁/ε s² + β₂/ε² s + β₃/ε³ = (s + ω_o)³",
                    omega_o, unit="rad/s",
                    note=f"exact (sympy): β = (3, 3, 1) = C(3, i)·1^i is a bandwidth form with ω_o = 1/ε; "
                         f"p(s) = {p_sym}")
    result.quantity("leso.poles", "LESO poles (real parts; triple root)", poles.real, unit="1/s",
                    note=f"numerical roots of a triple root at -{omega_o:g}; |imag| <= {np.max(np.abs(poles.imag)):.1e}; "
                         f"python-control ss poles {np.sort(obs.ss.poles().real).round(3).tolist()}")
    dc = [float(np.real(g.dcgain())) for g in obs.disturbance_error_tf()]
    result.quantity("leso.error_dc_gains", "steady e_i per unit constant dx3/dt: (β_{i-1}/β₃) ε^(n+2-i)", dc,
                    note="DC gains of E_i(s)/H(s) (python-control); sympy gives ε³/β₃, β₁ε²/β₃, β₂ε/β₃ = "
                         f"{[paper.epsilon**3, 3 * paper.epsilon**2, 3 * paper.epsilon]}")
    ctx.save_figure(result, plot_error_bode(obs, omega_o), "leso_error_bode.png")

    sc = eps_scaling(paper, T=QUICK["eps_T"] if ctx.quick else 10.0, t_from=QUICK["eps_from"] if ctx.quick else 5.0)
    law = error_scaling_exponents(paper.n)
    for i in range(3):
        result.quantity(f"leso.eps_slope.x{i + 1}", f"log-log slope of mean |e_{i + 1}| vs ε (law (4)/(7): {law[i]})",
                        float(sc["slope"][i]),
                        note=f"ESO in the noise-free situation-1 loop, ε ∈ {list(EPS_GRID)}, mean over "
                             f"[{sc['t_from']:g}, {sc['T']:g}] s: {np.array2string(sc['err'][:, i], precision=3)}")
    ctx.save_figure(result, plot_eps_scaling(sc, paper.n), "leso_eps_scaling.png")

    # ---------------------------------------------------------------- (b) situations 1 and 2
    sims = {}
    for key, sit in SITUATIONS.items():
        ctx.progress(f"{key}: simulating {horizons[key]:g} s, {len(_rows(sit, seeds))} runs on the batch axis")
        rows = _rows(sit, seeds)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            sims[key] = simulate_situation(sit, rows, T=horizons[key], paper=paper, progress=ctx.progress)
    for key, sim in sims.items():
        c = sim["cond_scaled"][:, [i for i, r in enumerate(sim["rows"]) if r.observer == "meso"]]
        bad = int(np.sum(c[np.isfinite(c)] > COND_WARN))
        if bad:
            ctx.progress(f"warning: {key}: {bad} of {int(np.isfinite(c).sum())} LSM batches are ill-conditioned "
                         f"(column-scaled cond > {COND_WARN:g}); see the identifiability finding")
    ctx.progress("metrics and figures")

    truth = {}
    for key, sit in SITUATIONS.items():
        sim, rows = sims[key], sims[key]["rows"]
        th3 = sit.theta3_printed
        t_true_before = np.array([paper.theta1, paper.theta2, th3, 0.0])
        t_true_after = np.array([paper.theta1, paper.theta2, th3, paper.step])
        truth[key] = (t_true_before, t_true_after)
        met = table_metrics(sim, paper.b, sit.b0)
        for noise in (True, False):
            tag = f"{key}." if noise else f"{key}.nonoise."
            for obs_name, var in (("meso", "wellposed"), ("eso", None), ("literal", "literal")):
                o = "meso" if obs_name == "literal" else obs_name
                if obs_name == "literal" and not noise:
                    continue
                idx = _select(rows, o, var, noise)
                ok = ~sim["diverged"][idx]
                t_div = _first_divergence(sim, idx)
                for j, m in enumerate(METRICS):
                    mean, std, n_ok = mean_std(met[m][idx], ok)
                    paper_v = TABLES[key][o][j]
                    what = ("MESO, Table-1 literal accumulation" if obs_name == "literal" else
                            "MESO (well-posed identification)" if o == "meso" else "ESO")
                    note = f"noise {'on' if noise else 'off'}; {what}"
                    if m == "est_x3":
                        note += "; true x3 = x2' - b0 u - XᵀΘ_used (with the (b-b0)u part)"
                    if t_div is not None:
                        note += f"; {len(idx) - n_ok}/{len(idx)} runs diverged (first at t = {t_div:.2f} s)"
                    qid = f"{key}.literal.meso.{m}" if obs_name == "literal" else f"{tag}{o}.{m}"
                    result.quantity(qid, f"{sit.table}, {what}, mean |e| {m}, noise {'on' if noise else 'off'}",
                                    None if n_ok == 0 else float(mean), paper=paper_v,
                                    std=None if n_ok == 0 else float(std), runs=int(n_ok),
                                    tolerance=TOLERANCE, note=note)
            if key == "s2":
                for o, var in (("eso", None), ("meso", "wellposed")):
                    idx = _select(rows, o, var, noise)
                    mean, std, n_ok = mean_std(met["est_x3_no_bu"][idx], ~sim["diverged"][idx])
                    result.quantity(f"{tag}{o}.est_x3_no_bu",
                                    f"Table 3, {o.upper()}, mean |e| est_x3 against x3 without (b-b0)u, "
                                    f"noise {'on' if noise else 'off'}",
                                    float(mean), paper=TABLES[key][o][2], std=float(std), runs=int(n_ok),
                                    tolerance=TOLERANCE,
                                    note="true x3 taken as the printed d(t) minus 0.95u (i.e. 1.3x1 - 1.6x2 + θ4) "
                                         "minus XᵀΘ_used")
        # final Θ (well-posed, noise on)
        idx = _select(rows, "meso", "wellposed", True)
        ok = ~sim["diverged"][idx]
        last = sim["theta_batch"][-1, idx]
        mean, std, n_ok = mean_std(last, ok)
        t_end = horizons[key]
        true_end = t_true_after if t_end > paper.t_step else t_true_before
        note = f"truth Θ = {true_end.tolist()} (at t = {t_end:g} s)"
        if key == "s2":
            eq = equivalent_theta(true_end, paper.b)
            note += f"; trajectory-equivalent Θ_eq = {eq.round(4).tolist()} (θ3 not identifiable in closed loop)"
        result.quantity(f"{key}.theta_final", f"{sit.table}: identified Θ after the last LSM batch "
                        "(well-posed, noise on)", np.asarray(mean), std=np.asarray(std), runs=int(n_ok), note=note)

    # ---------------------------------------------------------------- figures
    def truth_fn(key):
        before, after = truth[key]
        return lambda t: np.where((t >= paper.t_step - 0.5 * paper.h)[:, None], after, before)

    for key, sit in SITUATIONS.items():
        sim, rows = sims[key], sims[key]["rows"]
        i_eso = _select(rows, "eso", None, False)[0]
        i_meso = _select(rows, "meso", "wellposed", False)[0]
        fig = plot_situation(sim, i_eso, i_meso,
                             f"Fig. {3 if key == 's1' else 5} ({'situation 1' if key == 's1' else 'situation 2'}, "
                             f"b0 = {sit.b0:g}, b = {paper.b:g}): PD control with ESO vs MESO\n"
                             f"noise off (the setting Table {2 if key == 's1' else 3} matches); MESO with the "
                             f"well-posed LSM; x3 = x2' - b0 u - XᵀΘ_used")
        i_meso = _select(rows, "meso", "wellposed", True)[0]
        ctx.save_figure(result, fig, sit.figs[0])
        plot_rows = [(i_meso, "MESO well-posed (noise on)", _COLORS["meso"]),
                     (_select(rows, "meso", "literal", True)[0], "MESO Table-1 literal (noise on; diverges, clipped)",
                      _COLORS["literal"])]
        eq_fn = None
        if key == "s2":
            plot_rows.append((_select(rows, "meso", "direct", True)[0], "MESO direct (10) (noise on; diverges)",
                              _COLORS["direct"]))
            before, after = truth[key]
            eq_fn = lambda t, b_=before, a_=after: np.where(  # noqa: E731
                (t >= paper.t_step - 0.5 * paper.h)[:, None], equivalent_theta(a_, paper.b),
                equivalent_theta(b_, paper.b))
        fig = plot_theta(sim, plot_rows, truth_fn(key),
                         f"Fig. {4 if key == 's1' else 6} ({'situation 1' if key == 's1' else 'situation 2'}): "
                         f"LSM-identified parameters of d(t), batch N = {sit.N} ({sit.N * paper.h:g} s)",
                         equivalent=eq_fn)
        ctx.save_figure(result, fig, sit.figs[1])

    per_sit = {}
    for key, sit in SITUATIONS.items():
        rows = sims[key]["rows"]
        rp = [(_select(rows, "meso", "wellposed", True)[0], "well-posed, noise on", _COLORS["meso"], "-"),
              (_select(rows, "meso", "wellposed", False)[0], "well-posed, noise off", _COLORS["meso"], "--"),
              (_select(rows, "meso", "literal", True)[0], "Table-1 literal, noise on", _COLORS["literal"], "-")]
        if key == "s2":
            rp.append((_select(rows, "meso", "direct", True)[0], "direct (10), noise on", _COLORS["direct"], "-"))
        per_sit[key] = (sims[key], rp, f"situation {key[1]}: regression "
                        + ("(22) [x̂1 x̂2 1]" if sit.regression == "reduced" else "(16) [x̂1 x̂2 K̄ 1] / (10)"))
    ctx.save_figure(result, plot_identifiability(per_sit), "identifiability.png")

    _reconstructions(result, paper)
    _findings(result, sims, truth, seeds, paper, sc, horizons)
    return result


def _reconstructions(result: StudyResult, paper: Paper) -> None:
    r = result.reconstruction
    r("initial_state", {"x": [0, 0], "x_hat": [0, 0, 0], "theta": [0, 0, 0, 0]},
      "the paper prints no initial conditions; plant and observers start at rest, Θ = 0 (W(s) at rest)")
    r("integration", "RK4, h = 3 ms, u / noise / disturbance level held over each step",
      "the paper gives only the 3 ms step; the plant and observer are integrated jointly, the observer "
      "sees y(t) = x1(t) + 0.002 n0_k with n0_k ~ U[-1, 1] drawn per step")
    r("control_sampling", "u_k from the estimates at t_k, held (ZOH)",
      "(30) is continuous; u must be sampled to use the previous sample inside XᵀΘ as eq. (12) requires")
    r("eq12_previous_sample", "controller: XᵀΘ = Θ_used(t_k)ᵀ [x̂1(t_{k-1}), x̂2(t_{k-1}), u_{k-1}, 1]; "
      "observer: Θ_used(t_k)ᵀ [x̂1(t), x̂2(t), u_k, 1]",
      "X contains u itself; eq. (12) breaks the algebraic loop with the previous sample in the control law; "
      "inside the observer the held u_k is already known, so no delay is needed there")
    r("Kbar_reference_index", "K̄_j uses ξ^(l-1)(t_j) and the model term actually subtracted in u_j",
      "eq. (12)/(14) write x*_{j+1} and Σ_m Θ_m (unsmoothed); with W(s) in the loop the identity "
      "b0 u_j = K̄_j - Σ k_l x̂_jl only holds with the smoothed Θ used in u_j and ξ at t_j")
    r("lowpass_discretisation", "exact ZOH of W(s) = 1.8²/(s + 1.8)², input = latest LSM result, held",
      "the LSM result changes only at batch ends, so the exact discretisation equals the continuous filter")
    r("disturbance_step", "θ4 = 1.8 from the sample at t = 30 s on",
      "(31)/(32) switch at t = 30 s; 30 s is a sample instant (and a batch boundary in both situations)")
    r("situation2_plant", "x2' = 1.3 x1 - 1.6 x2 (+1.8) + 3.95 u with b0 = 3, i.e. 0.95 u = (b - b0) u",
      "3.95 - 3 = 0.95 exactly; the paper keeps b = 3.95 and only lowers b0. The alternative (0.95 u as an "
      "extra term, total gain 4.9) is simulated for the ESO and reported in the findings")
    r("true_x3", "x3 = x2' - b0 u - XᵀΘ_used (the extended state of eq. (2) for the observer used)",
      "the paper does not define the reference for the x3 error; ESO: the total disturbance d + (b - b0)u; "
      "MESO: the part not covered by the identified model. Also reported without (b - b0)u (`*.est_x3_no_bu`)")
    r("table_identification_variant", "well-posed: re-identify the total disturbance x̂3 + XᵀΘ_used each batch",
      "the literal Table-1 accumulation does not converge (findings); the MESO rows of Tables 2/3 use the "
      "well-posed form, the literal values are reported as s*.literal.meso.*")
    r("situation2_gate", f"full regression (16)-(20) on the total disturbance; if its column-scaled condition "
      f"number > {COND_WARN:g}, only (22) with θ3 held is solved",
      "Theorem 1 used as the paper suggests (check identifiability from the MESO's own data); the threshold "
      f"{COND_WARN:g} is a choice (situation-2 batches are either ~10² at start-up or >=5·10² after)")
    r("monte_carlo", "noise-on values are mean ± std over the runs; noise-off runs are deterministic",
      "the paper shows one realisation")


def _findings(result, sims, truth, seeds, paper, sc, horizons) -> None:
    def q(id_):
        return result.get(id_)

    def fmt(v, none="—"):
        return none if v is None else f"{v:.4g}"

    # noise on vs off
    lines = []
    for key in ("s1", "s2"):
        for o in ("eso", "meso"):
            for m in ("est_x1", "est_x2", "track_x2"):
                on, off = q(f"{key}.{o}.{m}"), q(f"{key}.nonoise.{o}.{m}")
                lines.append(f"{key} {o.upper()} {m}: paper {on.paper:.4g}, noise on {fmt(on.value)}, off {fmt(off.value)}")
    n_agree = {nz: sum(q(f"{k}.{'nonoise.' if nz == 'off' else ''}eso.{m}").verdict == "agrees"
                       for k in ("s1", "s2") for m in METRICS) for nz in ("on", "off")}
    result.finding(
        "tables-are-noise-free",
        f"Tables 2 and 3 match the noise-free simulation, not the stated 0.002·U[-1,1] measurement noise. The ESO "
        f"rows (no identification, so no reconstruction beyond initial conditions and integrator): "
        f"{n_agree['off']}/10 entries agree within {TOLERANCE:.0%} with noise off, {n_agree['on']}/10 with noise on "
        f"(x3 of Table 3 compared against the paper's own reference, see table3-x3-reference). The noise doubles "
        f"the x1 estimation errors, which the tables do not show: " + "; ".join(lines[:6]) + ".",
        evidence=lines)

    # literal accumulation
    s1, s2 = sims["s1"], sims["s2"]
    il = _select(s1["rows"], "meso", "literal", False)[0]
    iw = _select(s1["rows"], "meso", "wellposed", False)[0]
    norm_l = np.linalg.norm(s1["theta_batch"][:, il] - np.where(
        (s1["t_batch"] >= paper.t_step)[:, None], truth["s1"][1], truth["s1"][0]), axis=1)
    norm_w = np.linalg.norm(s1["theta_batch"][:, iw] - np.where(
        (s1["t_batch"] >= paper.t_step)[:, None], truth["s1"][1], truth["s1"][0]), axis=1)
    t_div2 = _first_divergence(s2, _select(s2["rows"], "meso", "literal", True)
                               + _select(s2["rows"], "meso", "literal", False))
    result.finding(
        "table1-accumulation-diverges",
        "The literal Table-1 rule (Θ = Σ Θ̂_i, each Θ̂_i fitted to the MESO's residual x̂3) does not converge once "
        "the identified parameters pass through W(s) = 1.8²/(s+1.8)² before entering the observer: W(s) needs "
        "≈2/ω_f = 1.1 s to settle, so Θ_used changes during each 3-6 s batch and the residual regression no longer "
        "returns Θ_true − Θ_previous; the accumulated errors grow. Situation 1, noise off, |Θ_cum − Θ_true| per "
        f"batch: literal {np.array2string(norm_l, precision=2, max_line_width=400)}; well-posed "
        f"(re-identify x̂3 + XᵀΘ_used every batch) {np.array2string(norm_w, precision=3, max_line_width=400)}. "
        f"Situation 2: literal runs diverge (first at t = {fmt(t_div2, 'no time within the run')} s).",
        evidence={"s1_literal_error_norm": norm_l, "s1_wellposed_error_norm": norm_w})

    # situation 2 identifiability
    iw_on = _select(s2["rows"], "meso", "wellposed", True)
    iw_off = _select(s2["rows"], "meso", "wellposed", False)[0]
    idir = _select(s2["rows"], "meso", "direct", True)[0]
    idir_off = _select(s2["rows"], "meso", "direct", False)[0]
    c_on = _nanmedian(s2["cond_scaled"][1:, iw_on])
    c_off = s2["cond_scaled"][:, iw_off]
    ranks = s2["rank"][:, iw_off]
    c1 = _nanmedian(s1["cond_scaled"][:, _select(s1["rows"], "meso", "wellposed", True)])
    th_fin = s2["theta_batch"][-1, iw_on].mean(axis=0)
    true_end = truth["s2"][1] if horizons["s2"] > paper.t_step else truth["s2"][0]
    eq = equivalent_theta(true_end, paper.b)
    dir_th = s2["theta_batch"][:, idir, 2]
    dir_th = dir_th[np.isfinite(dir_th)]
    passed = int(np.sum(s2["cond_scaled"][:, iw_on + [iw_off]] <= COND_WARN))
    total = int(np.sum(np.isfinite(s2["cond_scaled"][:, iw_on + [iw_off]])))
    result.finding(
        "situation2-not-identifiable",
        "Situation 2's full parameter vector is not identifiable from closed-loop data with ξ = sin t, contrary to "
        "the paper's Fig. 6 and its claim that Theorem 1 removes the need for excitation: once the loop tracks, "
        "x1 ≈ sin t, x2 ≈ cos t and u = −((1+θ1)x1 + θ2x2 + θ4)/b all lie in span{sin t, cos t, 1}, so the 4-column "
        "regression has rank 3 up to transients and noise. Column-scaled condition numbers per batch: situation 1 "
        f"(3 columns) median {c1:.3g}; situation 2 (16) noise off {np.array2string(c_off, precision=2, max_line_width=600)} "
        f"(numerical rank {ranks.min()}–{ranks.max()}, rank test passes while cond grows without bound), noise on median "
        f"{c_on:.3g}. The well-posed identification therefore converges to the trajectory-equivalent "
        f"Θ_eq = {eq.round(3).tolist()} (θ3·u folded into x1, x2, 1), reached: {th_fin.round(3).tolist()} "
        f"(mean of {len(iw_on)} noise runs), not to the true {true_end.tolist()}; {passed} of {total} situation-2 "
        f"batches passed the identifiability gate (cond <= {COND_WARN:g}), so θ3 stayed at its initial 0. The direct regression (10) on "
        f"[x̂1 x̂2 u 1] is well conditioned only because of the noise, and biased by it (u carries −x̂3/b0, the same "
        f"noise as the regressand): θ3 drifts {np.array2string(dir_th, precision=2, max_line_width=400)} towards −b0 "
        f"and the loop diverges at t = {fmt(_first_divergence(s2, [idir]), 'no time within the run')} s "
        f"(noise off: t = {fmt(_first_divergence(s2, [idir_off]), 'no time within the run')} s).",
        evidence={"s2_cond_noise_off": c_off, "s2_rank_noise_off": ranks,
                  "s2_cond_noise_on": s2["cond_scaled"][:, iw_on].T, "s2_rank_noise_on": s2["rank"][:, iw_on].T,
                  "s1_cond_noise_on": s1["cond_scaled"][:, _select(s1["rows"], "meso", "wellposed", True)].T,
                  "s1_rank_noise_on": s1["rank"][:, _select(s1["rows"], "meso", "wellposed", True)].T,
                  "theta_final": th_fin, "theta_equivalent": eq})

    # true x3 in situation 2
    a, b_ = q("s2.nonoise.eso.est_x3"), q("s2.nonoise.eso.est_x3_no_bu")
    am, bm = q("s2.nonoise.meso.est_x3"), q("s2.nonoise.meso.est_x3_no_bu")
    iB = [i for i, r in enumerate(s2["rows"]) if r.b_plant != paper.b][0]
    metB = table_metrics({k: (v[:, [iB]] if isinstance(v, np.ndarray) and v.ndim >= 2 else v)
                          for k, v in s2.items()}, paper.b, SITUATIONS["s2"].b0)
    result.finding(
        "table3-x3-reference",
        f"Table 3's x3 errors are explained by a reference that omits the (b − b0)u = 0.95u part of the extended "
        f"state: ESO (noise off) {fmt(b_.value)} against 1.3x1 − 1.6x2 + θ4 versus paper {a.paper}, but "
        f"{fmt(a.value)} against the true extended state d + (b − b0)u; MESO {fmt(bm.value)} vs {fmt(am.value)} "
        f"(paper {am.paper}). The large, nearly equal x3 errors of both observers in Table 3 are therefore the "
        f"omitted 0.95|u|, not estimation error. Reading 0.95u as an extra term on top of b = 3.95 (total gain 4.9) "
        f"fits worse: ESO est_x3 {float(metB['est_x3'][0]):.4g} / {float(metB['est_x3_no_bu'][0]):.4g}, "
        f"track_x1 {float(metB['track_x1'][0]):.4g} (paper 0.0031, same-plant reading "
        f"{fmt(q('s2.nonoise.eso.track_x1').value)}).")

    # eps scaling
    law = [paper.n + 2 - i for i in (1, 2, 3)]
    result.finding(
        "eps-scaling",
        f"The steady estimation errors scale as ε^(n+2−i): fitted log-log slopes over ε ∈ {list(EPS_GRID)} are "
        f"{np.array2string(sc['slope'], precision=2)} against the law {law} (exact for the DC gains of E_i(s)/H(s), "
        f"derived in sympy: ε³/β3, β1ε²/β3, β2ε/β3).")

    # MESO vs ESO
    better = [m for m in METRICS if (q(f"s1.nonoise.meso.{m}").value or np.inf) < (q(f"s1.nonoise.eso.{m}").value or 0)]
    better2 = [m for m in METRICS if (q(f"s2.nonoise.meso.{m}").value or np.inf) < (q(f"s2.nonoise.eso.{m}").value or 0)]
    result.finding(
        "meso-better-than-eso",
        f"The paper's qualitative claim holds with the well-posed identification: the MESO beats the ESO in "
        f"{len(better)}/5 metrics in situation 1 ({', '.join(better)}) and {len(better2)}/5 in situation 2 "
        f"({', '.join(better2)}), noise off; in situation 2 this needs only the trajectory-equivalent model, "
        f"not the true Θ.")

    div = []
    for key, sim in sims.items():
        for i, r in enumerate(sim["rows"]):
            if sim["diverged"][i]:
                div.append(f"{key} {r.label} at t = {sim['diverged_step'][i] * paper.h:.2f} s")
    if div:
        result.finding("diverged-runs", "Runs flagged as diverged (|state| > 1e6, excluded from every mean): "
                       + "; ".join(div) + ".")
