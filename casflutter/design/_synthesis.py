"""Fixed-order robust H∞ synthesis (paper §III.C): the public driver.

Find ``K(s)`` of order ``k`` that stabilises the loop of eq. (14) and makes the worst-case
``‖T_w̄zf‖∞ = γ`` over a set of plants small (eq. 16); by the small-gain theorem the loop
then stays stable for ``|ΔV| < 1/γ``.  HIFOO (used by the paper) and hinfstruct solve this
nonsmooth, nonconvex problem locally; here it is done in the manner of Apkarian & Noll
(2006) with a HIFOO-like first phase:

1. *stabilisation*: minimise the worst spectral abscissa (plus the required decay rates)
   over every plant, until the loop decays at the requested rate;
2. *H∞ phase*: minimise the worst exact H∞ norm, keeping every stability-only plant at its
   decay rate and every loop with a feed-through well posed.

Both phases are the same trust-region bundle iteration.  At the current gain the nonsmooth
function is replaced by its *cuts* (:mod:`._problem`): the singular values at the active
frequencies (local maxima of σ_max, from the Hamiltonian level sets of :mod:`._norm`) or
the eigenvalues that can become the rightmost within the trust region, each with its exact
gradient from singular/eigen-vectors, computed in numpy on the plant.  A QP in the gain
parameters only (:mod:`._qp`, through :mod:`casflutter._nlp`: Ipopt, or qpOASES in the
multi-speed design) with a BFGS model of the curvature gives the step; it is accepted only
if the *exact* objective (eigenvalues, or the Hamiltonian norm of every plant) decreased
and the constraints hold exactly; otherwise the region shrinks and the trial point's peak
frequencies join the model, or, where it broke a stability plant's decay rate, the
eigenvalue cuts it broke (linearised there) join the constraints.  The cost per iteration
is a few eigenvalue problems of the plant size plus a QP of the controller size.

Several seeded starts are run and the best is kept; the controller is returned in a
well-conditioned real-Schur, balanced realisation and re-checked on the original plants.
The budget is counted in iterations (``time_limit`` is an optional extra cap), and the
BLAS pools are pinned to one thread, so the same seed gives the same controller however
the process was launched.

*Decisions and last bits.*  On another machine the arithmetic differs in its last bits, and
a nonconvex local optimiser can amplify that into another path; what must not change is a
decision between results that are equally good.  The start returned is the one of lowest γ,
but a later start replaces an earlier one only when it is lower by more than
``GAMMA_TIE_RTOL`` = 1e-6 relative (:func:`_best_start`); the other tests are relative
thresholds far from any tie (a start is abandoned above 1.5 times the best γ, stalled below
``stall_tol`` of relative decrease over ``stall_window`` iterations; well-posedness and the
decay of the stability plants are checked with a relative slack of 1e-6).

*Failures.*  Plants with a non-finite entry are refused before any work
(:class:`~casflutter.errors.DataError`).  A numerical failure inside a start (a singular
loop or Hamiltonian, an eigenvalue or singular value solver that does not converge, an
overflow on a badly scaled plant) ends that start only: its :class:`StartRecord` says
``status="failed"`` and why, and the other starts go on.  Trial points whose norm cannot be
computed count as infinitely bad (the step is rejected).  :class:`SynthesisError` is raised
only when no start ends with a stable loop, and carries every start's record.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field, replace
from typing import Any, Mapping, Sequence

import control
import numpy as np

from .._format import result_repr
from .._settings import build_settings
from .._threads import single_threaded
from ..errors import CasflutterError, ConfigError, DataError, DimensionError, SynthesisError
from ._fullorder import full_order_controller, reduced_controllers
from ._out_of_reach import modes_out_of_reach
from ._plant import Partition, controller_only, partition
from ._problem import Cut, Problem, realize, verify_closed_loop
from ._qp import CutQP

__all__ = ["SynthesisOptions", "StartRecord", "SynthesisResult", "synthesize",
           "verify_closed_loop"]

log = logging.getLogger("casflutter.design")

GAMMA_TIE_RTOL = 1e-6
"""Relative margin by which a later start's γ must beat an earlier one's to be returned
instead (:func:`_best_start`)."""

_NUMERICAL_FAILURES = (np.linalg.LinAlgError, FloatingPointError, ZeroDivisionError,
                       OverflowError, ValueError)
"""Exceptions that end one start as ``"failed"`` (scipy raises ``ValueError`` on arrays
with infs or NaNs); the package's own errors (e.g. an Ipopt option refused when the first QP
is built) are raised as they are."""


#: why a design asked for a stable controller (``stable_controller``) may find none
STABLE_CONTROLLER_NOTE = (
    "the controller's own poles had to decay too (stable_controller); a plant with an odd "
    "number of real poles between two of its real zeros in the right half-plane (infinity "
    "counted) has no stable stabilising controller at all (the parity interlacing "
    "property): with stable_controller = false the controller may be unstable itself")


@dataclass(frozen=True)
class SynthesisOptions:
    """Settings of :func:`synthesize` (checked on construction)."""

    max_outer: int = 600
    """Maximum number of H∞ iterations (QP steps, accepted or not) per start, before
    ``extra_outer``."""
    extra_outer: int = 0
    """Further H∞ iterations past ``max_outer``, each spent only while γ is still falling:
    by more than ``extra_rate`` (relative) over the last ``stall_window`` iterations.  A
    phase that starts far from a minimum (a held controller whose loop barely decays has a
    sensitivity in the thousands) is then not cut off while it still makes headway, and one
    that creeps stops at ``max_outer`` as before (counted in iterations: deterministic)."""
    extra_rate: float = 0.01
    """See ``extra_outer``."""
    max_stab_rounds: int = 150
    """Maximum number of stabilisation iterations per start."""
    tol: float = 1e-5
    """Relative stopping tolerance: stop when the local model predicts a decrease below
    ``tol`` times the objective."""
    stability_margin: float = 1e-3
    """Decay rate required of the H∞ plants at the end of the stabilisation phase, relative to
    the plants' time scale (geometric mean of the smallest and largest pole moduli)."""
    decay: float = 0.0
    """Decay rate (rad/s, >= 0) that every *stability* plant (``stability_plants`` of
    :func:`synthesize`) must keep during the H∞ phase."""
    min_det: float = 0.2
    """Lower bound on ``det(I - Dk D22)`` for plants with a control-to-measurement
    feed-through (keeps the loop well posed with margin)."""
    trust_region: float = 0.3
    """Initial trust-region radius (box) on the scaled gain step, relative to max(1, ``|K|``)."""
    max_trust_region: float = 10.0
    """Largest trust-region radius (same units)."""
    active_ratio: float = 0.6
    """Local maxima of σ_max above this fraction of γ enter the local model."""
    max_iter: int = 300
    """Ipopt iterations per QP subproblem that Ipopt solves (``qp_solver``)."""
    strictly_proper: bool = False
    """Keep ``Dk = 0`` (a strictly proper controller): no algebraic loop through a
    control-to-measurement feed-through at any operating point."""
    stable_controller: bool = False
    """Keep the controller's own poles stable too (in the H∞ phase at the rate ``decay``):
    its state matrix ``Ak`` joins the stability plants (:func:`._plant.controller_only`),
    so the loop stays stable when it is opened, e.g. by a sensor or actuator that drops
    out."""
    zero_start: bool = True
    """Make the first of the ``starts`` the zero controller (the others are seeded random);
    ``False``: all random."""
    time_limit: float | None = None
    """Optional wall-time budget in seconds for all starts (``None``: none).  With a budget
    the result depends on the machine's speed and load; without one the budget is the
    iteration counts above and the same seed gives the same controller."""
    stall_window: int = 30
    """Stop a start's H∞ phase when γ fell by less than ``stall_tol`` (relative) over this
    many iterations (counted in iterations: deterministic)."""
    stall_tol: float = 1e-4
    """See ``stall_window`` (at most ``10 tol``)."""
    abandon_after: int = 40
    """A start whose γ is still above ``abandon_ratio`` times the best start's after this many
    H∞ iterations is stopped (deterministic: counted in iterations)."""
    abandon_ratio: float = 1.5
    """See ``abandon_after``."""
    full_order_start: bool = True
    """For a single H∞ plant without stability plants: also start from the full-order H∞
    central controller reduced to the order (:mod:`._fullorder`; only with slycot
    installed).  A singular plant (``D12`` or ``D21`` rank deficient) is regularised first
    (``full_order_regularization``)."""
    full_order_regularization: float = 1e-3
    """Relative size ``ε`` of the small channels that make a singular plant regular for its
    full-order start (:func:`._fullorder.regularized`); ``0``: singular plants get no
    full-order start."""
    full_order_gamma_factor: float = 1.1
    """The full-order controller is the central one at this factor times the optimal
    full-order level (``> 1``)."""
    qp_solver: str | None = None
    """Solver of the trust-region QPs (:mod:`._qp`): ``"qpoases"`` (dense active set,
    Ipopt only where it fails) or ``"ipopt"`` (interior point); ``None``: qpOASES in the
    multi-speed design (:func:`~casflutter.design.design_over_speeds`), whose hundreds of
    σ cuts per step it solves ten times faster with results as good, Ipopt here.  On
    COMPleib's single plants the interior point's steps (its multipliers are central where
    many cuts are active at a kink) went further: with qpOASES the static γ of HE6 stalls at
    417 instead of 194, HE4's at 0.6 % above HIFOO's instead of 0.01 %."""
    ipopt: Mapping[str, Any] = field(default_factory=dict)
    """Extra flat Ipopt options of the QP subproblems Ipopt solves."""

    def __post_init__(self):
        checks = {"max_outer": (self.max_outer >= 1, "an integer >= 1"),
                  "extra_outer": (self.extra_outer >= 0, "an integer >= 0"),
                  "extra_rate": (0 < self.extra_rate < 1, "a number in (0, 1)"),
                  "max_stab_rounds": (self.max_stab_rounds >= 1, "an integer >= 1"),
                  "max_iter": (self.max_iter >= 1, "an integer >= 1"),
                  "tol": (0 < self.tol < 1, "a number in (0, 1)"),
                  "stability_margin": (self.stability_margin > 0, "a number > 0"),
                  "decay": (self.decay >= 0, "a number >= 0"),
                  "min_det": (0 < self.min_det < 1, "a number in (0, 1)"),
                  "trust_region": (self.trust_region > 0, "a number > 0"),
                  "max_trust_region": (self.max_trust_region >= self.trust_region,
                                       "a number >= trust_region"),
                  "active_ratio": (0 < self.active_ratio < 1, "a number in (0, 1)"),
                  "abandon_after": (self.abandon_after >= 1, "an integer >= 1"),
                  "stall_window": (self.stall_window >= 2, "an integer >= 2"),
                  "stall_tol": (0 <= self.stall_tol < 1, "a number in [0, 1)"),
                  "abandon_ratio": (self.abandon_ratio > 1, "a number > 1"),
                  "time_limit": (self.time_limit is None or self.time_limit > 0,
                                 "None or a number > 0"),
                  "full_order_gamma_factor": (self.full_order_gamma_factor > 1,
                                              "a number > 1"),
                  "full_order_regularization": (0 <= self.full_order_regularization < 1,
                                                "a number in [0, 1)"),
                  "qp_solver": (self.qp_solver is None or self.qp_solver in CutQP.SOLVERS,
                                "None, " + " or ".join(f'"{v}"' for v in CutQP.SOLVERS))}
        bad = [f"{k} = {getattr(self, k)!r}: give {need}"
               for k, (ok, need) in checks.items() if not ok]
        if bad:
            raise ConfigError(f"{'; '.join(bad)} (SynthesisOptions)")


@dataclass(frozen=True)
class StartRecord:
    """History of one start.

    Attributes
    ----------
    start : int
        Index of the start.
    kind : str
        ``"given"`` (an initial controller passed in), ``"given-perturbed"`` (the same padded
        to the order with small random couplings of the new states),
        ``"full-order-reduced"`` (the full-order H∞ controller reduced to the order,
        :mod:`._fullorder`), ``"zero"``, ``"random"`` or ``"order-descent"`` (when no other
        start stabilised: a stabilising controller continued down from the full-order one,
        :func:`_order_descent`).
    stabilized : bool
        Whether the stabilisation phase ended with a stable, well-posed loop (the decay
        rates met, or at least a negative spectral abscissa).
    spectral_abscissa : float
        Closed-loop spectral abscissa at the end of the start (worst H∞ plant, rad/s).
    gamma : float
        Exact worst-case γ at the end (``inf`` when not stabilised).
    gamma_history : tuple of float
        Exact γ after each accepted H∞ step (first entry: after stabilisation).
    model_decrease : float
        Relative decrease predicted by the last local model (small at a local optimum).
    statuses : tuple of str
        The solver's status of every QP subproblem, verbatim.
    stab_iterations, outer_iterations : int
        Iterations of the two phases.
    converged : bool
        True when the stopping test was met: the local model sees no decrease within a
        trust region no smaller than a tenth of the first one.
    wall_time : float
        Seconds spent on this start.
    status : str
        ``"converged"`` (the stopping test met), ``"stopped"`` (iteration or time budget
        spent, stalled, abandoned for a far better start, or the trust region collapsed:
        trial points that left the feasible set or did not decrease shrank it while the
        local model still predicts a decrease), ``"not-stabilized"`` (no stable, well-posed
        loop at the end of the stabilisation phase) or ``"failed"`` (a numerical
        failure ended the start: a singular loop or Hamiltonian, non-finite numbers, a solver
        that did not converge; see ``reason``).
    reason : str
        Why the start did not converge (empty when it did).
    """

    __repr__ = result_repr

    start: int
    kind: str
    stabilized: bool
    spectral_abscissa: float
    gamma: float
    gamma_history: tuple
    model_decrease: float
    statuses: tuple
    stab_iterations: int
    outer_iterations: int
    converged: bool
    wall_time: float
    status: str
    reason: str


@dataclass(frozen=True)
class SynthesisResult:
    """Outcome of :func:`synthesize`.

    Attributes
    ----------
    controller : control.StateSpace
        ``K(s)`` from the ``nmeas`` measurements to the ``ncon`` controls (``u = K y``, on the
        plant's own measurement including any ``D22`` feed-through), realised in real-Schur
        form with balanced input/output scaling.
    gamma : float
        Worst-case ``‖T_w̄zf‖∞`` over the plants by the exact norm (never gridded).
    gammas : tuple of float
        γ per plant.
    delta_bound : float
        Small-gain bound ``1/γ`` on the uncertainty (``|ΔV| < 1/γ``, paper §III.C).
    omega_peaks : tuple of float
        Exact peak frequency (rad/s) per plant.
    spectral_abscissa : float
        Worst closed-loop spectral abscissa over the H∞ plants (negative: stable).
    stability_abscissa : float
        Worst closed-loop spectral abscissa over the stability plants (``-inf`` if none).
    order : int
        Controller order.
    starts : tuple of StartRecord
        Per-start history.
    best_start : int
        Index of the start that produced ``controller``.
    statuses : tuple of str
        QP statuses of the best start.
    converged : bool
        Whether the best start met the stopping test.
    success : bool
        Stable closed loop on every plant with a finite γ and the stability plants at their
        decay rate.
    wall_time : float
        Total seconds.
    norm_method : str
        What computed γ.
    """

    __repr__ = result_repr

    controller: control.StateSpace
    gamma: float
    gammas: tuple
    delta_bound: float
    omega_peaks: tuple
    spectral_abscissa: float
    stability_abscissa: float
    order: int
    starts: tuple
    best_start: int
    statuses: tuple
    converged: bool
    success: bool
    wall_time: float
    norm_method: str

    @property
    def best(self) -> StartRecord:
        """The record of the start whose controller this is (``best_start``)."""
        return next(r for r in self.starts if r.start == self.best_start)


# ----------------------------------------------------------------------------- driver


def _as_plants(plants) -> list[control.StateSpace]:
    if isinstance(plants, (control.StateSpace, control.TransferFunction)):
        return [control.ss(plants)]
    plants = list(plants)
    return [control.ss(P) for P in plants]


def _check_finite(groups) -> None:
    """Refuse a system with a non-finite entry, naming it (``plants[1].B[2, 0] = nan``)."""
    for what, systems in groups:
        for i, G in enumerate(systems):
            for name in ("A", "B", "C", "D"):
                M = np.asarray(getattr(G, name), dtype=float)
                bad = np.argwhere(~np.isfinite(M))
                if bad.size:
                    idx = tuple(int(j) for j in bad[0])
                    raise DataError(f"{what}[{i}].{name}{list(idx)} = {M[idx]}: every entry of "
                                    f"a plant or controller must be finite ({len(bad)} "
                                    f"non-finite entr{'y' if len(bad) == 1 else 'ies'} in "
                                    f"{name}); fix or rescale the model")


def _check_initial(G: control.StateSpace, order: int, nmeas: int, ncon: int) -> None:
    """An initial controller must map the ``nmeas`` measurements to the ``ncon`` controls
    with at most ``order`` states."""
    if G.nstates > order:
        raise DimensionError(f"initial controller has order {G.nstates} > requested order "
                             f"{order}")
    if G.ninputs != nmeas or G.noutputs != ncon:
        raise DimensionError(f"initial controller is {G.noutputs}x{G.ninputs}, "
                             f"need {ncon}x{nmeas} (ncon x nmeas)")


def _check_reach(parts: Sequence[Partition]) -> None:
    """Refuse, before any work, a plant with a mode that does not decay and that no
    controller moves (the controls do not reach it or the measurements do not see it)."""
    for k, P in enumerate(parts):
        if P.nx == 0:
            continue
        stuck = modes_out_of_reach(P.A, P.B2, P.C2, 0.0)
        if stuck:
            which = f"plant {k}: " if len(parts) > 1 else ""
            raise SynthesisError(
                f"{which}{stuck[0].describe()} does not decay, and no controller of any order "
                "moves it, so none can stabilise the loop; give the plant a control that "
                "reaches it and a measurement that sees it",
                best_spectral_abscissa=float(stuck[0].eigenvalue.real), starts=())


def _initial_gain(prob: Problem, kind: str, rng: np.random.Generator,
                  given=None) -> np.ndarray:
    nu, ny, k = prob.nu, prob.ny, prob.order
    if given is not None:
        G = control.ss(given)           # its sizes checked by _check_initial
        ki = G.nstates
        Ak = -prob.w0 * np.eye(k)
        Bk = np.zeros((k, ny))
        Ck = np.zeros((nu, k))
        if ki:
            Ak[:ki, :ki] = G.A
            Bk[:ki] = G.B
            Ck[:, :ki] = G.C
        K = prob.from_controller(Ak, Bk, Ck, np.asarray(G.D, float).reshape(nu, ny))
        if kind == "given-perturbed":
            scale = 1e-2 * max(np.max(np.abs(K[:nu, :ny]), initial=0.0), 1.0)
            K[nu + ki:, :ny] += scale * rng.standard_normal((k - ki, ny))
            K[:nu, ny + ki:] += scale * rng.standard_normal((nu, k - ki))
        return K
    K = np.zeros((nu + k, ny + k))
    K[nu:, ny:] = -np.eye(k)
    if kind == "random":
        K[:, :ny] = rng.standard_normal((nu + k, ny))
        K[:nu, ny:] = rng.standard_normal((nu, k))
        K[nu:, ny:] += 0.3 * rng.standard_normal((k, k))
        if prob.d22:   # start well posed: shrink the feed-through until det(I - Dk D22) > 0.5
            for _ in range(60):
                if np.all(prob.dets(K) > 0.5):
                    break
                K[:nu, :ny] *= 0.5
    return K


def _shrunk(prob: Problem, K0: np.ndarray) -> np.ndarray | None:
    """``K0`` with its couplings to the loop (``Dk, Bk, Ck``) halved until the worst
    spectral abscissa (scaled time, where the plants' time scale is 1) is at most
    ``max(α0, 0) + 0.05``, ``α0`` the abscissa with those couplings at zero (at most 20
    halvings, keeping the loop well posed); ``None`` if that never happens."""
    Z = K0.copy()
    Z[:prob.nu, :] = 0.0
    Z[:, :prob.ny] = 0.0
    a0 = max(float(np.max(prob.alphas(Z)[0])), 0.0) + 0.05
    if not np.isfinite(a0):        # the loop without couplings has no abscissa
        return None
    K = K0.copy()
    for _ in range(20):
        K = Z + 0.5 * (K - Z)
        if prob.well_posed(K) and float(np.max(prob.alphas(K)[0])) <= a0:
            return K
    return None


_TRIAL_CUTS = 16
"""Most decay-rate cuts kept from rejected trial points (:meth:`_Phase._trial_cuts`)."""


@dataclass
class _Phase:
    """One phase of the bundle iteration (module docstring)."""

    prob: Problem
    qp: CutQP
    opts: SynthesisOptions
    kind: str                   # "stab" or "hinf"
    margin: float               # decay margin of the H∞ plants in the stabilisation phase
    deadline: float
    statuses: list
    abandon_above: float = np.inf   # γ of the best start so far times ``abandon_ratio``

    def value(self, K: np.ndarray) -> tuple[float, Any]:
        if self.kind == "stab":
            return self.prob.stab_objective(K, self.margin), None
        if not self.prob.feasible(K):
            return np.inf, None
        g, gams, peaks = self.prob.gamma(K)
        return g, (gams, peaks)

    def cuts(self, K: np.ndarray, f: float, info, delta: float, memory: list[list[float]]
             ) -> tuple[list[Cut], list[Cut]]:
        prob = self.prob
        if self.kind == "stab":
            allc = prob.eig_cuts(K, self.margin, -np.inf, 0.0, which="all")
            allc += [Cut(c.value - self.opts.min_det * 1e-6, c.grad, c.key)
                     for c in prob.det_cuts(K)]
            top = max(allc, key=lambda c: c.value)
            reach = top.value - (delta * np.sum(np.abs(top.grad)) if top.linear else 0.0)
            obj = [c for c in allc if c.reach(delta) >= reach]
            obj.sort(key=lambda c: -c.reach(delta))
            return obj[:48], []
        gams, peaks = info
        obj: list[Cut] = []
        for j, (gj, wj) in enumerate(zip(gams, peaks)):
            if gj < self.opts.active_ratio * f or gj <= 0.0:   # (γ = 0: nothing to lower)
                continue
            ws = prob.peaks(K, j, gj, wj, self.opts.active_ratio * f / gj)
            if memory[j]:
                # the feed-through piece (ω = ∞) enters only a model that has no other piece
                ws = [w for w in ws if np.isfinite(w)]
            memory[j] = _merge(ws, memory[j])
            obj += prob.sigma_cuts(K, j, memory[j], floor=self.opts.active_ratio * f)
        con = [c for c in prob.eig_cuts(K, 0.0, 0.0, delta, which="stab")]
        con += [c for c in prob.det_cuts(K) if c.reach(delta) >= 0]
        con.sort(key=lambda c: -c.reach(delta))
        return obj, con[:64]

    def done(self, f: float) -> bool:
        return self.kind == "stab" and f <= 0.0

    def _stop(self, it: int, f: float, history: list, history_at: list, label: str) -> bool:
        """The H∞ phase's stall and abandon tests (counted in iterations: deterministic)."""
        opts = self.opts
        if self.kind == "hinf" and len(history) > 1 and it > opts.stall_window and \
                history_at[-1] >= it - 1 and _stalled(history, history_at, it,
                                                      opts.stall_window,
                                                      min(opts.stall_tol, 10 * opts.tol)):
            log.debug("%s: stalled at gamma %.6g (less than %.1e relative decrease in %d "
                      "iterations)", label, f, opts.stall_tol, opts.stall_window)
            return True
        if it > opts.abandon_after and f > self.abandon_above:
            log.debug("%s: abandoned at gamma %.6g (another start is far better)", label, f)
            return True
        return False

    def _curvature(self, fv: np.ndarray, G: np.ndarray, f: float, delta0: float) -> np.ndarray:
        """The first model's curvature, a multiple of the identity.  In the stabilisation
        phase its scale comes from the eigenvalue cuts active now (within 1 % of the top
        value) when a far-away ill-conditioned eigenvalue has a gradient 1e3 times larger,
        which would otherwise shrink every step to nothing."""
        top = float(np.max(fv))
        act = fv >= top - 0.01 * max(abs(f), abs(top), 1e-12) if self.kind == "stab" \
            else np.ones(fv.size, bool)
        with np.errstate(over="ignore"):
            gnorm = np.linalg.norm(G, axis=1)
        if not np.all(np.isfinite(gnorm)):      # squares past the floats: |g| = big |g/big|
            big = np.max(np.abs(G), axis=1)
            gnorm = big * np.linalg.norm(G / np.where(big > 0, big, 1.0)[:, None], axis=1)
            gnorm = np.where(np.isfinite(gnorm), gnorm, 0.0)
        gscale = float(np.max(gnorm))
        if gscale > 1e3 * float(np.max(gnorm[act])):
            gscale = float(np.max(gnorm[act]))
        return max(1e-8, 0.1 * gscale / delta0) * np.eye(self.prob.n)

    def _step(self, H: np.ndarray, fv: np.ndarray, G: np.ndarray, con: list,
              delta: np.ndarray):
        """The trust-region QP's step within the box ``delta`` (its status recorded)."""
        step = self.qp.solve(H, fv, G, np.minimum(np.array([c.value for c in con]), 0.0),
                             np.array([c.grad for c in con]).reshape(len(con), self.prob.n),
                             delta)
        self.statuses.append(step.status)
        return step

    def _updated(self, H: np.ndarray, step, obj: list, con: list, Kn: np.ndarray
                 ) -> tuple[np.ndarray, bool]:
        """The damped BFGS update of the Lagrangian's curvature after an accepted step, and
        whether it changed."""
        y = np.zeros(self.prob.n)
        for lam, c in list(zip(step.mu, obj)) + list(zip(step.nu, con)):
            if lam > 1e-9:
                cn = self.prob.reevaluate(Kn, c, self.margin)
                if cn is not None:
                    y += lam * (cn.grad - c.grad)
        s = step.d
        Hs = H @ s
        sHs, sy = float(s @ Hs), float(s @ y)
        if sHs <= 0:
            return H, False
        if sy < 0.2 * sHs:
            th = 0.8 * sHs / (sHs - sy)
            y = th * y + (1 - th) * Hs
            sy = float(s @ y)
        return H - np.outer(Hs, Hs) / sHs + np.outer(y, y) / sy, True

    def _trial_cuts(self, Kn: np.ndarray, d: np.ndarray) -> list[Cut]:
        """The decay-rate cuts that a rejected trial point ``K + d`` violates, linearised
        there and written in the step from ``K`` (``c(Kn) + gᵀ(d' − d)``): cutting planes for
        the constraints, as the trial's peak frequencies are for the objective.  A step
        that moved an eigenvalue farther than its linear model at ``K`` said is then kept
        out of that direction by the next QPs at ``K``, instead of only by a smaller
        radius."""
        out = []
        for c in self.prob.eig_cuts(Kn, 0.0, 0.0, 0.0, which="stab"):
            if c.linear and c.value > 0.0:
                out.append(Cut(c.value - float(c.grad @ d), c.grad, c.key))
        out.sort(key=lambda c: -c.value)
        return out[:_TRIAL_CUTS]

    def run(self, K: np.ndarray, label: str, max_iter: int) -> "_PhaseResult":
        """The trust-region bundle iteration from ``K`` (module docstring): at most
        ``max_iter`` QP steps, each accepted only when the exact objective decreased."""
        prob, opts = self.prob, self.opts
        free = np.ones(prob.shape)
        if opts.strictly_proper:
            free[:prob.nu, :prob.ny] = 0.0
            K = K.copy()
            K[:prob.nu, :prob.ny] = 0.0
        free = prob.vec(free)
        f, info = self.value(K)
        history, history_at = [f], [0]
        memory: list[list[float]] = [[] for _ in prob.aug]
        delta0 = delta = opts.trust_region * max(1.0, float(np.max(np.abs(K))))
        H, fresh, cuts, trial_cuts = None, True, None, []
        converged, collapsed, it, pred_rel = False, False, 0, np.inf
        extra = opts.extra_outer if self.kind == "hinf" else 0
        for it in range(1, max_iter + extra + 1):
            if self.done(f) or time.perf_counter() > self.deadline or \
                    self._stop(it, f, history, history_at, label):
                break
            if it > max_iter and not _falling(history, history_at, it, opts.extra_rate,
                                              opts.stall_window):
                it -= 1         # the budget's iterations, all of them taken
                break
            if cuts is None:
                cuts = self.cuts(K, f, info, delta, memory)
            obj, con = cuts
            if not obj:
                break
            G = np.array([c.grad for c in obj])
            fv = np.array([c.value for c in obj]) - f
            if H is None:
                H, fresh = self._curvature(fv, G, f, delta0), True
            step = self._step(H, fv, G, con + trial_cuts, delta * free)
            pred = -step.model
            scale = max(abs(f), 1e-12) if self.kind == "hinf" else max(abs(f), self.margin)
            pred_rel = pred / scale
            if pred <= opts.tol * scale:
                if fresh:
                    # a radius that rejected trial points have shrunk far below the first
                    # one predicts little whether or not the model is stationary: converged
                    # only if the model sees no decrease at a tenth of the first radius
                    converged = delta >= 0.1 * delta0 or -self._step(
                        H, fv, G, con, 0.1 * delta0 * free).model <= opts.tol * scale
                    collapsed = not converged
                    if collapsed:
                        log.debug("%s %s it %d: stopped, the trust region collapsed to %.3g "
                                  "(the model predicts a decrease its trial points do not "
                                  "give)", label, self.kind, it, delta)
                    break
                # the quasi-Newton curvature may hide a descent direction (kinks inflate it):
                # decide on a fresh model before stopping
                H, delta = None, max(delta, 0.1 * delta0)
                continue
            Kn = K + prob.mat(step.d)
            fn, info_n = self.value(Kn)
            ratio = (f - fn) / pred if np.isfinite(fn) else -np.inf
            dmax = float(np.max(np.abs(step.d)))
            cuts = None
            if ratio > 1e-2:
                # (the trial points' cuts come last in the step's constraint multipliers and
                # are left out of the curvature update: they are linearised elsewhere)
                H, changed = self._updated(H, step, obj, con, Kn)
                fresh = fresh and not changed
                K, f, info, trial_cuts = Kn, fn, info_n, []
                history.append(f)
                history_at.append(it)
                if ratio > 0.75 and dmax > 0.9 * delta:
                    delta = min(2.0 * delta, opts.max_trust_region * max(1.0, np.max(np.abs(K))))
                elif ratio < 0.25:
                    delta = 0.5 * dmax
                log.debug("%s %s it %d: %s %.6g (ratio %.2f, radius %.3g)", label, self.kind, it,
                          "gamma" if self.kind == "hinf" else "abscissa", f, ratio, delta)
                continue
            delta = 0.5 * dmax
            if self.kind == "hinf" and info_n is not None:
                # the trial point's peaks join the model (cutting planes)
                for j, (gj, w) in enumerate(zip(*info_n)):
                    if gj >= opts.active_ratio * f:
                        memory[j] = _merge([w], memory[j])
            elif self.kind == "hinf":
                trial_cuts = (self._trial_cuts(Kn, step.d) + trial_cuts)[:_TRIAL_CUTS]
            log.debug("%s %s it %d: rejected (ratio %.3g), radius %.3g", label, self.kind, it,
                      ratio, delta)
            if delta < 1e-10 * max(1.0, float(np.max(np.abs(K)))):
                collapsed = True
                break
        return _PhaseResult(K, float(f), tuple(history), converged, it, float(pred_rel),
                            collapsed)


@dataclass(frozen=True)
class _PhaseResult:
    """Where a phase ended: the gain, its objective, the accepted objectives, whether the
    stopping test was met, the iterations, the last model's relative decrease, and whether
    the trust region collapsed (rejected trial points shrank it while the model still
    predicts a decrease)."""

    K: np.ndarray
    f: float
    history: tuple
    converged: bool
    iterations: int
    pred: float
    collapsed: bool = False


def _accepted_by(history: list, at: list, it: int) -> float | None:
    """The last accepted objective at iteration ``it`` or before (``None`` before the
    start)."""
    old = [h for h, a in zip(history, at) if a <= it]
    return old[-1] if old else None


def _falling(history: list, at: list, it: int, rate: float, window: int) -> bool:
    """Whether the objective fell by more than ``rate`` (relative) over the last ``window``
    iterations (the budget's extension, ``SynthesisOptions.extra_outer``)."""
    old = _accepted_by(history, at, it - window - 1)
    return old is not None and old - history[-1] > rate * abs(old)


def _stalled(history: list, at: list, it: int, window: int, tol: float) -> bool:
    """Less than ``tol`` relative decrease of the accepted values over the last ``window``
    iterations."""
    old = _accepted_by(history, at, it - window)
    return old is not None and (old - history[-1]) < tol * abs(old)


def _merge(new: Sequence[float], old: Sequence[float], keep: int = 12) -> list[float]:
    out: list[float] = []
    for w in list(new) + list(old):
        if all(abs(w - v) > 1e-6 * max(abs(v), 1e-9) for v in out):
            out.append(float(w))
    return out[:keep]


def synthesize(plants, nmeas: int, ncon: int, order: int, *, starts: int = 3, seed: int = 0,
               initial: Sequence[control.StateSpace] | control.StateSpace | None = None,
               stability_plants: Sequence[control.StateSpace] = (),
               options: SynthesisOptions | Mapping[str, Any] | None = None) -> SynthesisResult:
    """Fixed-order H∞ synthesis over one plant or the worst case of several (paper §III.C).

    Parameters
    ----------
    plants : control.StateSpace or sequence of them
        Generalised plant(s) in ``control.hinfsyn`` partitioned form (inputs ``[w, u]``,
        outputs ``[z, y]``), e.g. the LFT of eq. (14); all with the same ``w, z, u, y``
        sizes (state dimensions may differ).  ``D22`` may be non-zero: the loop is closed
        exactly and kept well posed (``det(I - Dk D22) >= options.min_det``).
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
    stability_plants : sequence of control.StateSpace
        Further plants (same partition) that the controller must only keep stable with the
        decay rate ``options.decay``, e.g. ΣAE(V) over a range of speeds (eq. 8-9).
    options : SynthesisOptions or dict, optional
        Algorithm settings.

    Returns
    -------
    SynthesisResult
        With the exact γ and the small-gain bound ``1/γ``.

    Raises
    ------
    SynthesisError
        If no start stabilises every plant (``.best_spectral_abscissa`` is the best reached,
        ``.starts`` the record of every start, with why each failed).
    DimensionError
        If the plants do not fit together or with ``nmeas``, ``ncon``, or an initial
        controller does not fit them.
    DataError
        If a plant or an initial controller has a non-finite entry (named).
    ConfigError
        If an option is invalid.

    See Also
    --------
    build_lft : the aeroelastic plant of eq. 14.
    verify_controller : the independent check of the result.

    Examples
    --------
    >>> import control
    >>> import casflutter as cf
    >>> P = control.ss([[1.0]], [[1.0, 1.0]], [[1.0], [1.0]], [[0.0, 0.0], [0.0, 0.0]])
    >>> res = cf.synthesize(P, nmeas=1, ncon=1, order=0, starts=1, seed=0)
    >>> res.success, bool(res.spectral_abscissa < 0)
    (True, True)
    """
    t_start = time.perf_counter()
    if isinstance(options, Mapping):
        options = build_settings(SynthesisOptions, options, "options")
    opts = options or SynthesisOptions()
    if int(order) != order or order < 0:
        raise ConfigError(f"order must be an integer >= 0, got {order!r}")
    if starts < 0:
        raise ConfigError(f"starts must be >= 0, got {starts}")
    order = int(order)
    sys_list = _as_plants(plants)
    if not sys_list:
        raise DimensionError("need at least one plant")
    stab_list = _as_plants(stability_plants)
    parts = [partition(P, nmeas, ncon) for P in sys_list]
    if opts.stable_controller and order > 0:
        nw, nz = parts[0].dims[:2]
        stab_list.append(controller_only(nmeas, ncon, nw, nz).statespace())
    sparts = [partition(P, nmeas, ncon) for P in stab_list]
    if len({P.dims for P in parts + sparts}) != 1:
        raise DimensionError(f"plants differ in (nw, nz, nu, ny): "
                             f"{[P.dims for P in parts + sparts]}; all must share the w, z, "
                             "u, y sizes")
    given = [] if initial is None else (
        [initial] if isinstance(initial, (control.StateSpace, control.TransferFunction))
        else list(initial))
    if not given and starts == 0:
        raise ConfigError("starts=0 needs at least one initial controller")
    _check_finite([("plants", sys_list), ("stability_plants", stab_list),
                   ("initial", [control.ss(G) for G in given])])
    for G in given:
        _check_initial(control.ss(G), order, nmeas, ncon)
    _check_reach(parts + sparts)
    with single_threaded():
        return _synthesize(parts, sparts, sys_list, stab_list, nmeas, ncon, order, starts,
                           seed, given, opts, t_start)


def _synthesize(parts: list[Partition], sparts: list[Partition], sys_list, stab_list, nmeas,
                ncon, order, starts, seed, given, opts: SynthesisOptions, t_start):
    try:
        prob = Problem(parts, sparts, order, decay=opts.decay, min_det=opts.min_det)
    except _NUMERICAL_FAILURES as exc:
        raise SynthesisError(f"the plants could not be scaled for the synthesis "
                             f"({_reason(exc)}); check their entries' magnitudes") from exc
    qp = CutQP(prob.n, {"ipopt.max_iter": opts.max_iter, **dict(opts.ipopt)},
               opts.qp_solver or "ipopt")
    deadline = t_start + opts.time_limit if opts.time_limit else np.inf
    rng = np.random.default_rng(seed)
    plan = [("given", g) for g in given]
    # a lower-order start padded with decoupled states sits on a saddle (zero Bk, Ck for the
    # new states): also start from a slightly perturbed copy
    plan += [("given-perturbed", g) for k, g in plan
             if k == "given" and control.ss(g).nstates < order and starts]
    # with a given controller the zero start would only repeat it (decoupled states)
    plan += [("zero" if i == 0 and opts.zero_start and not given else "random", None)
             for i in range(starts)]
    # last, so that they never make the abandon test stop one of the starts above early: the
    # result is never worse than without them
    full = None
    if opts.full_order_start and len(parts) == 1 and not sparts:
        try:
            full = full_order_controller(parts[0], opts.full_order_gamma_factor,
                                         opts.full_order_regularization)
            reduced = [] if full is None else reduced_controllers(full[0], order)
        except _NUMERICAL_FAILURES as exc:
            log.debug("full-order start: failed (%s), skipped", _reason(exc))
            reduced = []
        # (a static reduction that is zero would only repeat the zero start)
        plan += [("full-order-reduced", Kr) for Kr in reduced
                 if Kr.nstates or np.any(np.asarray(Kr.D) != 0)]
    records, gains = [], []
    best_alpha = np.inf
    log.debug("synthesis: order %d, %d H-inf plant(s) (%d states), %d stability plant(s), "
              "%d start(s)", order, len(parts), parts[0].nx, len(sparts), len(plan))
    descended = False
    while len(records) < len(plan):
        s = len(records)
        kind, g = plan[s]
        t0 = time.perf_counter()
        K0 = _initial_gain(prob, kind, rng, g)
        statuses: list[str] = []
        try:
            rec, K, alpha = _run_start(prob, qp, opts, s, kind, K0, statuses, deadline, records)
        except CasflutterError:
            raise
        except _NUMERICAL_FAILURES as exc:
            # a numerical failure ends this start only (module docstring)
            log.debug("start %d (%s): failed (%s: %s)", s, kind, type(exc).__name__, exc)
            rec = StartRecord(start=s, kind=kind, stabilized=False, spectral_abscissa=np.nan,
                              gamma=np.inf, gamma_history=(), model_decrease=np.inf,
                              statuses=tuple(statuses), stab_iterations=0, outer_iterations=0,
                              converged=False, wall_time=0.0, status="failed",
                              reason=_reason(exc))
            K, alpha = K0, np.inf
        records.append(replace(rec, wall_time=time.perf_counter() - t0))
        gains.append(K)
        best_alpha = min(best_alpha, alpha)
        if time.perf_counter() > deadline and any(r.stabilized for r in records):
            break
        if len(records) == len(plan) and not descended and full is not None and \
                order < full[0].nstates and not any(r.stabilized for r in records) and \
                time.perf_counter() < deadline:
            # every start failed to stabilise, though the full-order controller does: come
            # down to the order from it a few states at a time, for one last start
            descended = True
            Kd = _order_descent(parts, sparts, sys_list, stab_list, nmeas, ncon, order,
                                full[0], opts)
            if Kd is not None:
                plan.append(("order-descent", Kd))
    ok = [r for r in records if r.stabilized and np.isfinite(r.gamma)]
    while ok:
        best = _best_start(ok)
        try:
            controller = realize(*prob.to_controller(gains[best.start]))
            checks = [verify_closed_loop(P, controller, nmeas, ncon) for P in sys_list]
            alpha_s = max((float(verify_closed_loop(P, controller, nmeas, ncon)[2])
                           for P in stab_list), default=-np.inf)
            break
        except CasflutterError:
            raise
        except _NUMERICAL_FAILURES as exc:
            log.debug("start %d: its controller failed the final check (%s)", best.start,
                     _reason(exc))
            records[best.start] = replace(best, status="failed",
                                          reason="final check: " + _reason(exc))
            ok.remove(best)
    if not ok:
        failed = [r for r in records if r.status == "failed"]
        why = f"; {len(failed)} failed numerically ({failed[0].reason})" if failed else ""
        hint = ("Check that the unstable modes are controllable from u and observable from "
                "y, that the plant is scaled sensibly, or try a higher order / more starts"
                if full is None else
                f"The plant can be stabilised: the full-order H-inf controller (order "
                f"{full[0].nstates}) does, but neither its reductions to order {order} nor "
                "a descent to that order a few states at a time led to a stable loop; try a "
                "higher order or more starts")
        raise SynthesisError(
            f"no start stabilised the closed loop (order {order}, {len(records)} starts{why}); "
            f"best spectral abscissa {best_alpha:.4g}. {hint}"
            + (f"; {STABLE_CONTROLLER_NOTE}" if opts.stable_controller else ""),
            best_spectral_abscissa=float(best_alpha), starts=tuple(records))
    gammas = tuple(float(c[0]) for c in checks)
    gamma = max(gammas)
    alpha_v = max(float(c[2]) for c in checks)
    log.info("synthesis: order %d, best of %d starts (start %d): gamma %.6g, the largest "
             "H-inf norm over the %d design plant(s), %.1f s", order, len(records), best.start,
             gamma, len(sys_list), time.perf_counter() - t_start)
    return SynthesisResult(
        controller=controller, gamma=gamma, gammas=gammas,
        delta_bound=float(1.0 / gamma) if np.isfinite(gamma) and gamma > 0 else 0.0,
        omega_peaks=tuple(float(c[1]) for c in checks), spectral_abscissa=alpha_v,
        stability_abscissa=alpha_s, order=order, starts=tuple(records),
        best_start=best.start, statuses=best.statuses, converged=best.converged,
        success=bool(alpha_v < 0 and np.isfinite(gamma) and alpha_s <= -opts.decay * (1 - 1e-6)),
        wall_time=time.perf_counter() - t_start,
        norm_method="casflutter.design Hamiltonian level iteration")


_DESCENT_OUTER = 5
"""H∞ iterations at each intermediate order of :func:`_order_descent` (its aim there is a
stable loop to reduce further, not a low γ)."""


def _order_descent(parts, sparts, sys_list, stab_list, nmeas, ncon, order: int,
                   K: control.StateSpace, opts: SynthesisOptions
                   ) -> control.StateSpace | None:
    """A controller of ``order`` that stabilises the plants, continued down from the
    stabilising controller ``K`` of higher order, or ``None``.

    The order falls by a quarter of the states (at least one) at a time; at each order the
    reductions of the last controller (:func:`._fullorder.reduced_controllers`) are tried
    as starts of a synthesis at that order (with ``_DESCENT_OUTER`` H∞ iterations) until
    one stabilises.  A reduction that leaves the loop slightly unstable is close to one
    that does not, where a random start may be far from any.  The caller runs the result
    as its last start, with its own options.  Deterministic: no random choice.
    """
    sub = replace(opts, max_outer=_DESCENT_OUTER, extra_outer=0, full_order_start=False)
    m = K.nstates
    while m > order:
        m = max(order, m - max(1, m // 4))
        for Kr in reduced_controllers(K, m):
            try:
                res = _synthesize(parts, sparts, sys_list, stab_list, nmeas, ncon, m, 0, 0,
                                  [Kr], sub, time.perf_counter())
            except SynthesisError:
                continue
            K = res.controller
            break
        else:
            log.debug("order descent: no reduction to order %d stabilises", m)
            return None
    log.debug("order descent: a stabilising controller of order %d", order)
    return K


def _run_start(prob: Problem, qp: CutQP, opts: SynthesisOptions, s: int, kind: str,
               K0: np.ndarray, statuses: list, deadline: float, records: list
               ) -> tuple[StartRecord, np.ndarray, float]:
    """Both phases from the gain ``K0``: the start's record, its final gain and the best
    spectral abscissa (rad/s) its stabilisation reached."""
    label = f"start {s} ({kind})"
    m_start = opts.stability_margin
    if kind.startswith("given") or kind == "full-order-reduced":
        # a stable given controller is kept as it is (its γ bounds this order's from above)
        a0 = float(np.max(prob.alphas(K0)[0]))
        if a0 < 0:
            m_start = min(m_start, 0.5 * -a0)
    stab = _Phase(prob, qp, opts, "stab", m_start, deadline, statuses)
    r1 = stab.run(K0, label, opts.max_stab_rounds)
    K, phi = r1.K, r1.f
    a_h = float(np.max(prob.alphas(K)[0])) * prob.w0
    best_alpha = a_h
    # the decay rates reached, or at least a stable, well-posed loop (the H∞ phase then
    # keeps it stable: every accepted step has a finite norm)
    ok = prob.feasible(K) and (phi <= 0.0 or (a_h < 0 and np.isfinite(phi)))
    if not ok and kind == "random":
        # a random gain that moved the loop far right of the zero controller's abscissa
        # can leave the phase crawling at a (nearly) defective rightmost eigenvalue, where
        # the linear cuts mispredict: retry once with the random part shrunk until the
        # loop is no more unstable than with the zero controller (deterministic)
        K1 = _shrunk(prob, K0)
        if K1 is not None:
            log.debug("%s: stabilisation failed (abscissa %.4g rad/s); retried from the "
                     "random gain shrunk towards zero", label, a_h)
            r1b = stab.run(K1, label, opts.max_stab_rounds)
            K, phi = r1b.K, r1b.f
            r1 = replace(r1b, iterations=r1.iterations + r1b.iterations)
            a_h = float(np.max(prob.alphas(K)[0])) * prob.w0
            best_alpha = min(best_alpha, a_h)
            ok = prob.feasible(K) and (phi <= 0.0 or (a_h < 0 and np.isfinite(phi)))
    log.debug("%s: stabilisation %s after %d iterations (abscissa %.4g rad/s)", label,
             "reached the decay rates" if ok else "failed", r1.iterations, a_h)
    status, reason = "not-stabilized", "the stabilisation phase ended with an unstable or " \
        "ill-posed loop"
    if ok:
        best_g = min((r.gamma for r in records if r.stabilized), default=np.inf)
        hinf = _Phase(prob, qp, opts, "hinf", m_start, deadline, statuses,
                      # the reduced full-order starts descend slowly at first from far
                      # above (often unstable), but into a better basin: never abandoned
                      abandon_above=np.inf if kind == "full-order-reduced"
                      else opts.abandon_ratio * best_g)
        r2 = hinf.run(K, label, opts.max_outer)
        K, gam = r2.K, r2.f
        hist, conv, outer, pred = r2.history, r2.converged, r2.iterations, r2.pred
        a_h = float(np.max(prob.alphas(K)[0])) * prob.w0
        log.debug("%s: gamma %.6g after %d H-inf iterations (%s)", label, gam, outer,
                 "converged" if conv else "stopped")
        status, reason = ("converged", "") if conv else (
            "stopped", "the trust region collapsed: trial steps did not give the decrease "
            "the local model predicts (a kink the model does not resolve, as at a nonsmooth "
            "local minimum, or a constraint the step leaves)" if r2.collapsed else
            "iteration or time budget spent, stalled or abandoned")
        if not np.isfinite(gam):
            status, reason = "failed", "no finite norm at the stabilised gain"
    else:
        gam, hist, conv, outer, pred = np.inf, (), False, 0, np.inf
    rec = StartRecord(start=s, kind=kind, stabilized=bool(ok), spectral_abscissa=a_h,
                      gamma=float(gam), gamma_history=tuple(float(h) for h in hist),
                      model_decrease=float(pred), statuses=tuple(statuses),
                      stab_iterations=r1.iterations, outer_iterations=outer,
                      converged=bool(conv), wall_time=0.0, status=status, reason=reason)
    return rec, K, best_alpha


def _reason(exc: BaseException) -> str:
    """``"Class: first line of the message"`` of a numerical failure."""
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__


def _best_start(ok: Sequence[StartRecord]) -> StartRecord:
    """The start whose controller is returned: the lowest γ, where a later start replaces
    an earlier one only when its γ is lower by more than ``GAMMA_TIE_RTOL`` (relative).

    Starts that end in the same local minimum reach it only to the stopping tolerance
    (``tol`` = 1e-5 of predicted relative decrease), and the norm itself is exact to 2e-9: a
    difference of a part in a million is no evidence that one start is better, and a plain
    minimum would choose between such starts by their last bits, which change from machine
    to machine.  The earlier start wins such ties, at a cost in γ of at most one part in 1e6,
    far below the 1 % to which results are promised across machines."""
    best = ok[0]
    for r in ok[1:]:
        if r.gamma < best.gamma * (1.0 - GAMMA_TIE_RTOL):
            best = r
    return best
