"""Fixed-order robust H∞ synthesis (paper §III.C): the public driver.

Find ``K(s)`` of order ``k`` that stabilises the loop of eq. (14) and makes the worst-case
``‖T_w̄zf‖∞ = γ`` over a set of plants small; by the small-gain theorem the loop then stays
stable for ``|ΔV| < 1/γ``.  HIFOO (used by the paper) and hinfstruct do this with nonsmooth
methods; here it is a sequence of smooth CasADi NLPs solved by Ipopt:

1. stabilisation by short smoothed-spectral-abscissa solves from each start;
2. H∞ phase: epigraph minimax over plants × an adaptive set of frequencies, with a
   Lyapunov certificate that keeps every feasible iterate stable, inside a trust region;
3. after each solve the exact norm (Hamiltonian method) and its peak frequency are computed
   for every plant; the step is accepted only if the *exact* worst-case γ decreased and the
   loop is stable (eigenvalues), otherwise it is backtracked; the peak frequencies are added
   to the grid and the minimax solved again until gridded and exact γ agree.

Several seeded starts are run and the best is kept; the controller is returned in a
well-conditioned real-Schur, balanced realisation and re-verified on the original plants.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Any, Mapping, Sequence

import control
import numpy as np

from ..errors import ConfigError, DimensionError, SynthesisError
from ._nlps import HinfNLP, StabilizationNLP
from ._plant import partition
from ._problem import (_gain_scale, _io_scales, _Problem, _realize, verify_closed_loop)

__all__ = ["SynthesisOptions", "StartRecord", "SynthesisResult", "synthesize",
           "verify_closed_loop"]


@dataclass(frozen=True)
class SynthesisOptions:
    """Settings of :func:`synthesize` (checked on construction)."""

    nslots: int = 16
    """Frequency slots per plant in the minimax NLP (exact peaks, local maxima, grid)."""
    max_outer: int = 300
    """Maximum number of minimax solves (outer iterations) per start."""
    tol: float = 1e-3
    """Relative tolerance: stop when the minimax model predicts a decrease below
    ``tol/10`` *and* the model and exact γ agree to ``tol``."""
    max_stab_rounds: int = 40
    """Maximum number of short stabilisation solves per start."""
    stability_margin: float = 1e-3
    """Required closed-loop decay rate after stabilisation, relative to the plants'
    largest eigenvalue modulus (at least 1e-3 rad/s absolute scale)."""
    trust_region: float = 0.3
    """Initial trust-region radius on the scaled controller step."""
    max_trust_region: float = 0.5
    """Largest trust-region radius."""
    rank: int = 1
    """Singular directions modelled per frequency in the minimax NLP (1–3).  Values above 1
    describe coalescing singular values exactly to first order but cost about 4× per solve
    (measured on AC15: same γ, 4× the time)."""
    polish_rank: int = 3
    """After the starts, the best controller is polished with a minimax model of this rank
    (coalescing singular values modelled exactly to first order); 0 or 1 disables it."""
    polish_tol: float = 1e-5
    """Stopping tolerance of the polishing phase."""
    max_iter: int = 80
    """Ipopt iterations per solve.  Together with ``max_outer`` and ``max_stab_rounds`` this
    is the deterministic budget: without ``time_limit`` the same seed gives the same
    controller on any machine and under any load."""
    zero_start: bool = True
    """Make the first of the ``starts`` the zero controller (the others are seeded random);
    ``False``: all random."""
    time_limit: float | None = None
    """Wall-time budget in seconds for everything (``None``: unlimited); with polishing on,
    the starts get 60 % of it and the polish the rest.  A budget also caps every Ipopt solve
    at 3 s of wall time: the result then depends on the machine's speed and load (use it
    for benchmarks, not where the same seed must give the same controller)."""
    ipopt: Mapping[str, Any] = field(default_factory=dict)
    """Extra flat Ipopt options, e.g. ``{"ipopt.max_iter": 300}``."""

    def __post_init__(self):
        checks = {"nslots": self.nslots >= 2, "max_outer": self.max_outer >= 1,
                  "max_iter": self.max_iter >= 1,
                  "tol": 0 < self.tol < 1, "max_stab_rounds": self.max_stab_rounds >= 1,
                  "stability_margin": self.stability_margin > 0,
                  "trust_region": self.trust_region > 0, "rank": self.rank in (1, 2, 3),
                  "polish_rank": self.polish_rank in (0, 1, 2, 3),
                  "polish_tol": 0 < self.polish_tol < 1,
                  "time_limit": self.time_limit is None or self.time_limit > 0}
        bad = [k for k, ok in checks.items() if not ok]
        if bad:
            raise ConfigError(f"invalid SynthesisOptions field(s) {bad}: need nslots>=2, "
                              "max_outer>=1, max_iter>=1, 0<tol<1, max_stab_rounds>=1, "
                              "stability_margin>0, trust_region>0, rank in 1..3, "
                              "polish_rank in 0..3, 0<polish_tol<1, time_limit None or >0")


@dataclass(frozen=True)
class StartRecord:
    """History of one start.

    Attributes
    ----------
    start : int
        Index of the start.
    kind : str
        ``"given"`` (an initial controller passed in), ``"given-perturbed"`` (the same padded
        to the order with small random couplings of the new states), ``"zero"``,
        ``"random"``, or ``"polish(rank=r)"`` (the polishing of the best start).
    stabilized : bool
        Whether the stabilisation phase reached the required margin.
    spectral_abscissa : float
        Closed-loop spectral abscissa at the end of the start (worst plant).
    gamma : float
        Exact worst-case γ at the end (``inf`` when not stabilised).
    gamma_history : tuple of float
        Exact γ after each accepted H∞ step (first entry: after stabilisation).
    grid_gap : float
        Relative gap between the gridded bound of the last solve and the exact γ.
    statuses : tuple of str
        Ipopt ``return_status`` of every solve (stabilisation and H∞), verbatim.
    outer_iterations : int
        Number of minimax solves.
    converged : bool
        True when the stopping test (no model decrease and grid agreement) was met.
    wall_time : float
        Seconds spent on this start.
    """

    start: int
    kind: str
    stabilized: bool
    spectral_abscissa: float
    gamma: float
    gamma_history: tuple
    grid_gap: float
    statuses: tuple
    outer_iterations: int
    converged: bool
    wall_time: float


@dataclass(frozen=True)
class SynthesisResult:
    """Outcome of :func:`synthesize`.

    Attributes
    ----------
    controller : control.StateSpace
        ``K(s)`` from the ``nmeas`` measurements to the ``ncon`` controls, realised in
        real-Schur form with balanced input/output scaling.
    gamma : float
        Verified worst-case ``‖T_w̄zf‖∞`` over the plants, by the exact norm (never gridded).
    gammas : tuple of float
        Verified γ per plant.
    delta_bound : float
        Certified small-gain bound ``1/γ`` on the uncertainty (``|ΔV| < 1/γ``, paper §III.C).
    omega_peaks : tuple of float
        Exact peak frequency (rad/s) per plant.
    spectral_abscissa : float
        Worst closed-loop spectral abscissa (negative: stable).
    order : int
        Controller order.
    starts : tuple of StartRecord
        Per-start history.
    best_start : int
        Index of the start that produced ``controller``.
    statuses : tuple of str
        Ipopt statuses of the best start's solves.
    converged : bool
        Whether the best start met the stopping test.
    success : bool
        Stable closed loop on every plant with a finite verified γ.
    wall_time : float
        Total seconds.
    norm_method : str
        What computed the verified norm.
    """

    controller: control.StateSpace
    gamma: float
    gammas: tuple
    delta_bound: float
    omega_peaks: tuple
    spectral_abscissa: float
    order: int
    starts: tuple
    best_start: int
    statuses: tuple
    converged: bool
    success: bool
    wall_time: float
    norm_method: str


# ----------------------------------------------------------------------------- driver


def _as_plants(plants) -> list[control.StateSpace]:
    if isinstance(plants, (control.StateSpace, control.TransferFunction)):
        return [control.ss(plants)]
    plants = list(plants)
    if not plants:
        raise DimensionError("need at least one plant")
    return [control.ss(P) for P in plants]


def _initial_gain(prob: _Problem, kind: str, rng: np.random.Generator,
                  given=None) -> np.ndarray:
    nu, ny, k = prob.nu, prob.ny, prob.order
    wk = prob.wscale
    if given is not None:
        G = control.ss(given)
        ki = G.nstates
        if ki > k:
            raise DimensionError(f"initial controller has order {ki} > requested order {k}")
        if G.ninputs != ny or G.noutputs != nu:
            raise DimensionError(f"initial controller is {G.noutputs}x{G.ninputs}, "
                                 f"need {nu}x{ny} (ncon x nmeas)")
        Ak = -wk * np.eye(k)
        Bk = np.zeros((k, ny))
        Ck = np.zeros((nu, k))
        if ki:
            Ak[:ki, :ki] = G.A
            Bk[:ki] = G.B
            Ck[:, :ki] = G.C
        K = prob.from_controller(Ak, Bk, Ck, np.asarray(G.D, float).reshape(nu, ny))
        if kind == "given-perturbed":
            scale = 1e-2 * max(np.max(np.abs(K[:nu, :ny]), initial=0.0), 1.0)
            K[nu + ki:, :ny] += scale * np.sqrt(wk) * rng.standard_normal((k - ki, ny))
            K[:nu, ny + ki:] += scale / np.sqrt(wk) * rng.standard_normal((nu, k - ki))
        return K
    K = np.zeros((nu + k, ny + k))
    K[nu:, ny:] = -wk * np.eye(k)
    if kind == "random":
        K[:nu + k, :ny] = rng.standard_normal((nu + k, ny))
        K[:nu, ny:] = rng.standard_normal((nu, k))
        K[nu:, ny:] += 0.3 * wk * rng.standard_normal((k, k))
        K[nu:, :] *= np.sqrt(wk)
        K[:, ny:] *= np.sqrt(wk) / max(wk, 1e-12)
    return K


def _stabilize(prob, stab: StabilizationNLP, K, opts: SynthesisOptions, margin, statuses,
               deadline):
    alpha = prob.alpha(K)
    delta = 1.0
    for _ in range(opts.max_stab_rounds):
        if alpha <= -margin or time.perf_counter() > deadline:
            break
        shift = max(0.2 * abs(alpha), margin)
        beta0 = -alpha - shift
        try:
            Knew, res = stab.solve(K, _gain_scale(K), delta, beta0, tr_factor=10.0)
        except (np.linalg.LinAlgError, ValueError):
            delta *= 0.5
            continue
        statuses.append(res.return_status)
        a_new = prob.alpha(Knew)
        if np.isfinite(a_new) and a_new < alpha:
            step = np.max(np.abs((Knew - K) / _gain_scale(K)))
            K, alpha = Knew, a_new
            if step > 0.9 * delta:
                delta *= 2.0
        else:
            delta *= 0.5
            if delta < 1e-6:
                break
    return K, alpha


def _hinf_phase(prob, hinf: HinfNLP, K, alpha, opts: SynthesisOptions, statuses, deadline,
                beta_floor):
    gam, _, peaks = prob.exact(K)
    history = [gam]
    peak_hist = [[w] for w in peaks]
    delta = opts.trust_region
    gap, converged, outer = np.inf, False, 0
    for outer in range(1, opts.max_outer + 1):
        if time.perf_counter() > deadline:
            break
        omegas = prob.select_omegas(K, peak_hist, opts.nslots)
        beta = min(0.5 * abs(alpha), beta_floor)
        S = _gain_scale(K)
        try:
            Knew, tgrid, res = hinf.solve(K, S, delta, omegas, gam, beta)
        except (np.linalg.LinAlgError, ValueError):
            delta *= 0.5
            continue
        statuses.append(res.return_status)
        g_new, _, pk_new = prob.exact(Knew)
        for j, w in enumerate(pk_new):
            peak_hist[j].append(w)
        step = np.max(np.abs((Knew - K) / S))
        if np.isfinite(g_new) and g_new < gam:
            gap = abs(g_new - tgrid) / g_new     # model vs exact at the accepted point
            model_drop = (gam - tgrid) / gam
            ratio = (gam - g_new) / max(gam - tgrid, 1e-16 * gam)
            K, gam, alpha = Knew, g_new, prob.alpha(Knew)
            history.append(gam)
            if ratio > 0.5 and step > 0.8 * delta:
                delta = min(2.0 * delta, opts.max_trust_region)
            elif ratio < 0.25:
                delta = 0.5 * min(delta, max(step, 1e-12))
            if model_drop < 0.1 * opts.tol and gap < opts.tol:
                converged = True   # the model sees no further decrease and agrees with exact
                break
            continue
        # the exact norm did not decrease: backtrack along the step, then shrink the region
        accepted = False
        for theta in (0.5, 0.25):
            Kt = K + theta * (Knew - K)
            g_t, _, pk_t = prob.exact(Kt)
            if np.isfinite(g_t) and g_t < gam:
                for j, w in enumerate(pk_t):
                    peak_hist[j].append(w)
                K, gam, alpha = Kt, g_t, prob.alpha(Kt)
                history.append(gam)
                accepted = True
                break
        if not accepted and tgrid >= gam * (1 - opts.tol) and res.success:
            # the gridded minimax cannot improve on the exact value: local optimum
            converged = True
            break
        delta = 0.5 * min(delta, max(step, 1e-12))
        if delta < 1e-7:
            break
    return K, gam, tuple(history), gap, converged, outer


def synthesize(plants, nmeas: int, ncon: int, order: int, *, starts: int = 3, seed: int = 0,
               initial: Sequence[control.StateSpace] | control.StateSpace | None = None,
               options: SynthesisOptions | Mapping[str, Any] | None = None) -> SynthesisResult:
    """Fixed-order H∞ synthesis over one plant or the worst case of several (paper §III.C).

    Parameters
    ----------
    plants : control.StateSpace or sequence of them
        Generalised plant(s) in ``control.hinfsyn`` partitioned form (inputs ``[w, u]``,
        outputs ``[z, y]``, ``D22 = 0``), e.g. the LFT of eq. (14) at several speeds; all with
        the same ``w, z, u, y`` sizes (state dimensions may differ).
    nmeas, ncon : int
        Number of measurements and controls.
    order : int
        Controller order ``k >= 0`` (``0``: static output feedback).
    starts : int
        Number of starts besides the given ``initial`` controllers: the first is the zero
        controller (with a stable ``Ak``) unless ``options.zero_start`` is false, the others
        seeded random.
    seed : int
        Seed of the random starts (same seed, same result).
    initial : StateSpace or sequence, optional
        Controllers of order ``<= order`` to start from (padded with decoupled stable
        states), e.g. the best controller of the next lower order.
    options : SynthesisOptions or dict, optional
        Algorithm settings.

    Returns
    -------
    SynthesisResult
        With the verified (exact) γ and the certified bound ``1/γ``.

    Raises
    ------
    SynthesisError
        If no start stabilises every plant (``.best_spectral_abscissa`` is the best reached).
    DimensionError
        If the plants do not fit together or with ``nmeas``, ``ncon``.
    ConfigError
        If an option is invalid.
    """
    t_start = time.perf_counter()
    if isinstance(options, Mapping):
        options = SynthesisOptions(**options)
    opts = options or SynthesisOptions()
    if int(order) != order or order < 0:
        raise ConfigError(f"order must be an integer >= 0, got {order!r}")
    if starts < 0:
        raise ConfigError(f"starts must be >= 0, got {starts}")
    order = int(order)
    sys_list = _as_plants(plants)
    parts = [partition(P, nmeas, ncon) for P in sys_list]
    if len({P.dims for P in parts}) != 1:
        raise DimensionError(f"plants differ in (nw, nz, nu, ny): {[P.dims for P in parts]}; "
                             "all must share the w, z, u, y sizes")
    su, sy = _io_scales(parts)
    prob = _Problem(parts, order, su, sy)
    given = [] if initial is None else (
        [initial] if isinstance(initial, (control.StateSpace, control.TransferFunction))
        else list(initial))
    if not given and starts == 0:
        raise ConfigError("starts=0 needs at least one initial controller")
    ipopt = {"ipopt.max_iter": opts.max_iter,
             "ipopt.hessian_approximation": "limited-memory", "ipopt.tol": 1e-8,
             "ipopt.acceptable_tol": 1e-5, "ipopt.mu_strategy": "adaptive"}
    if opts.time_limit:
        ipopt["ipopt.max_wall_time"] = 3.0   # budget mode (not reproducible across machines)
    ipopt.update(opts.ipopt)
    stab = StabilizationNLP(prob.aug, ipopt)
    hinf = HinfNLP(prob.aug, opts.nslots, ipopt, rank=opts.rank)
    margin = opts.stability_margin * max(prob.wscale, 1e-3)
    beta_floor = 1e-3 * margin
    polish_rank = min(opts.polish_rank, *parts[0].dims[:2])   # at most min(nw, nz)
    polish = polish_rank > max(opts.rank, 1)
    deadline_all = t_start + opts.time_limit if opts.time_limit else np.inf
    deadline = t_start + (0.6 if polish else 1.0) * opts.time_limit if opts.time_limit \
        else np.inf

    rng = np.random.default_rng(seed)
    plan = [("given", g) for g in given]
    # a lower-order start padded with decoupled states sits on a saddle (zero Bk, Ck for the
    # new states): also start from a slightly perturbed copy
    plan += [("given-perturbed", g) for g in given if control.ss(g).nstates < order and starts]
    plan += [("zero" if i == 0 and opts.zero_start else "random", None)
             for i in range(starts)]
    records, gains = [], []
    best_alpha = np.inf
    for s, (kind, g) in enumerate(plan):
        t0 = time.perf_counter()
        K0 = _initial_gain(prob, kind, rng, g)
        statuses: list[str] = []
        K, alpha = _stabilize(prob, stab, K0, opts, margin, statuses, deadline)
        best_alpha = min(best_alpha, alpha)
        if alpha < 0:
            K, gam, hist, gap, conv, outer = _hinf_phase(prob, hinf, K, alpha, opts, statuses,
                                                         deadline, beta_floor)
            alpha = prob.alpha(K)
        else:
            gam, hist, gap, conv, outer = np.inf, (), np.inf, False, 0
        records.append(StartRecord(start=s, kind=kind, stabilized=bool(alpha < 0),
                                   spectral_abscissa=float(alpha), gamma=float(gam),
                                   gamma_history=tuple(float(h) for h in hist),
                                   grid_gap=float(gap), statuses=tuple(statuses),
                                   outer_iterations=outer, converged=bool(conv),
                                   wall_time=time.perf_counter() - t0))
        gains.append(K)
        if time.perf_counter() > deadline and any(r.stabilized for r in records):
            break
    ok = [r for r in records if r.stabilized and np.isfinite(r.gamma)]
    if not ok:
        raise SynthesisError(
            f"no start stabilised the closed loop (order {order}, {len(records)} starts); best "
            f"spectral abscissa {best_alpha:.4g}. Check that the unstable modes are controllable "
            "from u and observable from y, or try a higher order / more starts",
            best_spectral_abscissa=float(best_alpha))
    best = min(ok, key=lambda r: r.gamma)
    if polish and time.perf_counter() < deadline_all:
        t0 = time.perf_counter()
        statuses = []
        hinf_p = HinfNLP(prob.aug, opts.nslots, ipopt, rank=polish_rank)
        popts = replace(opts, tol=opts.polish_tol)
        Kp, gam, hist, gap, conv, outer = _hinf_phase(
            prob, hinf_p, gains[best.start], prob.alpha(gains[best.start]), popts, statuses,
            deadline_all, beta_floor)
        alpha = prob.alpha(Kp)
        records.append(StartRecord(start=len(records), kind=f"polish(rank={polish_rank})",
                                   stabilized=bool(alpha < 0), spectral_abscissa=float(alpha),
                                   gamma=float(gam), gamma_history=tuple(map(float, hist)),
                                   grid_gap=float(gap), statuses=tuple(statuses),
                                   outer_iterations=outer, converged=bool(conv),
                                   wall_time=time.perf_counter() - t0))
        gains.append(Kp)
        if alpha < 0 and gam <= best.gamma:
            best = records[-1]
    controller = _realize(*prob.to_controller(gains[best.start]))
    checks = [verify_closed_loop(P, controller, nmeas, ncon) for P in sys_list]
    gammas = tuple(float(c[0]) for c in checks)
    gamma = max(gammas)
    alpha_v = max(float(c[2]) for c in checks)
    return SynthesisResult(
        controller=controller, gamma=gamma, gammas=gammas,
        delta_bound=float(1.0 / gamma) if np.isfinite(gamma) and gamma > 0 else 0.0,
        omega_peaks=tuple(float(c[1]) for c in checks), spectral_abscissa=alpha_v,
        order=order, starts=tuple(records), best_start=best.start, statuses=best.statuses,
        converged=best.converged, success=bool(alpha_v < 0 and np.isfinite(gamma)),
        wall_time=time.perf_counter() - t_start,
        norm_method="casflutter.verify.hinf_norm" if _has_verify() else "control.linfnorm")


def _has_verify() -> bool:
    try:
        from ..verify import hinf_norm  # noqa: F401, PLC0415
    except ImportError:
        return False
    return True
