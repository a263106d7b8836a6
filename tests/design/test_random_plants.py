"""No internal error on any plant: random generalised plants of awkward kinds.

The synthesis must end in one of two ways: a result (every start with a status, the
returned controller's loop checked here by numpy), or one of the package's own exceptions
(:mod:`casflutter.errors`: a :class:`SynthesisError` carrying every start's record, or an
input refused before any work).  Plants: unstable, with integrators, with poles on the
imaginary axis, non-minimal (uncontrollable and unobservable modes), badly scaled (entries
and state coordinates from 1e-8 to 1e8), ``D21 = 0``, ``D12`` rank-deficient, a control
feed-through ``D22``, and static (no state); controller orders 0 to 2.  Small budgets keep
each example short; the examples are derandomised, so the suite is deterministic.
"""

from __future__ import annotations

import json

import control
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from casflutter.design import SynthesisOptions, hinf_norm, synthesize
from casflutter.errors import CasflutterError, DataError, SynthesisError

KINDS = ("unstable", "integrators", "imaginary-axis poles", "non-minimal", "badly scaled",
         "D21 = 0", "D12 rank-deficient", "feed-through D22", "static")
BUDGET = SynthesisOptions(max_outer=6, max_stab_rounds=12, max_iter=40, stall_window=3)
STATUSES = {"converged", "stopped", "not-stabilized", "failed"}
EXAMPLES = settings(max_examples=6, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow])


def _plant(kind: str, seed: int, nx: int, dims: tuple) -> control.StateSpace:
    """A generalised plant (inputs ``[w, u]``, outputs ``[z, y]``) of the given kind."""
    rng = np.random.default_rng(seed)
    nw, nz, nu, ny = dims
    nx = 0 if kind == "static" else nx
    A = rng.standard_normal((nx, nx))
    B1, B2 = rng.standard_normal((nx, nw)), rng.standard_normal((nx, nu))
    C1, C2 = rng.standard_normal((nz, nx)), rng.standard_normal((ny, nx))
    D11, D12 = rng.standard_normal((nz, nw)), rng.standard_normal((nz, nu))
    D21, D22 = rng.standard_normal((ny, nw)), np.zeros((ny, nu))
    if kind == "unstable" and nx:
        A += (1.0 - np.min(np.linalg.eigvals(A).real)) * np.eye(nx)    # every pole right
    elif kind == "integrators" and nx:
        A[:, : max(1, nx // 2)] = 0.0                                   # poles at 0
    elif kind == "imaginary-axis poles" and nx >= 2:
        A[:2, :] = 0.0
        A[:, :2] = 0.0
        A[:2, :2] = [[0.0, 3.0], [-3.0, 0.0]]                           # ±3j, decoupled
    elif kind == "non-minimal" and nx:
        B1[0], B2[0] = 0.0, 0.0                  # state 0 reached by nothing: uncontrollable
        A[0, 1:] = 0.0
        C1[:, -1], C2[:, -1] = 0.0, 0.0          # the last state seen by nothing
        A[:-1, -1] = 0.0
    elif kind == "badly scaled" and nx:
        s = 10.0 ** rng.uniform(-8, 8, nx)       # state coordinates from 1e-8 to 1e8
        A = A * s[:, None] / s[None, :]
        B1, B2 = B1 * s[:, None], B2 * s[:, None]
        C1, C2 = C1 / s[None, :], C2 / s[None, :]
        B2 *= 10.0 ** rng.uniform(-8, 8)         # and units: actuators, sensors, time
        C2 *= 10.0 ** rng.uniform(-8, 8)
        A *= 10.0 ** rng.uniform(-4, 4)
    elif kind == "D21 = 0":
        D21[:] = 0.0
    elif kind == "D12 rank-deficient":
        D12[:] = 0.0 if nu == 1 else np.outer(D12[:, 0], rng.standard_normal(nu))
    elif kind == "feed-through D22":
        D22 = 0.5 * rng.standard_normal((ny, nu))
    return control.ss(A, np.hstack([B1, B2]), np.vstack([C1, C2]),
                      np.block([[D11, D12], [D21, D22]]))


def _check_outcome(P, ny: int, nu: int, order: int) -> str:
    """Run the synthesis; fail on anything but a result or the package's own errors."""
    try:
        res = synthesize(P, ny, nu, order, starts=2, seed=0, options=BUDGET)
    except SynthesisError as exc:
        if not exc.starts:       # refused before any start: a mode no controller moves, named
            assert "does not decay, and no controller of any order moves it" in str(exc)
            assert exc.best_spectral_abscissa >= 0
            return "no controller"
        assert all(s.status in STATUSES for s in exc.starts)
        assert not any(s.stabilized and np.isfinite(s.gamma) for s in exc.starts)
        assert all(s.reason for s in exc.starts if s.status == "failed")
        return "no controller"
    except CasflutterError:
        return "refused"
    assert all(s.status in STATUSES for s in res.starts)
    best = res.starts[res.best_start]
    assert best.stabilized and best.status != "failed" and np.isfinite(best.gamma)
    K = res.controller
    assert K.nstates == order and K.ninputs == ny and K.noutputs == nu
    assert all(np.all(np.isfinite(np.asarray(M))) for M in (K.A, K.B, K.C, K.D))
    if res.success and not np.any(np.asarray(P.D)[-ny:, -nu:]):
        # independent of the optimiser: the closed loop's poles by numpy
        Pa, Pb, Pc = (np.asarray(M, float) for M in (P.A, P.B, P.C))
        B2, C2 = Pb[:, -nu:], Pc[-ny:, :]
        Acl = np.block([[Pa + B2 @ np.asarray(K.D) @ C2, B2 @ np.asarray(K.C)],
                        [np.asarray(K.B) @ C2, np.asarray(K.A)]])
        assert Acl.size == 0 or np.max(np.linalg.eigvals(Acl).real) < 0
    return "controller"


@pytest.mark.parametrize("kind", KINDS)
@EXAMPLES
@given(seed=st.integers(0, 2 ** 32 - 1), nx=st.integers(1, 4), order=st.integers(0, 2),
       dims=st.tuples(*(st.integers(1, 2),) * 4))
def test_synthesis_ends_in_a_result_or_its_own_error(kind, seed, nx, order, dims):
    P = _plant(kind, seed, nx, dims)
    _check_outcome(P, dims[3], dims[2], order)


@EXAMPLES
@given(seed=st.integers(0, 2 ** 32 - 1), block=st.sampled_from("ABCD"),
       value=st.sampled_from([np.nan, np.inf, -np.inf]))
def test_a_plant_with_a_non_finite_entry_is_refused_naming_it(seed, block, value):
    P = _plant("unstable", seed, 3, (1, 1, 1, 1))
    mats = {name: np.array(getattr(P, name), dtype=float) for name in "ABCD"}
    rng = np.random.default_rng(seed)
    idx = tuple(int(rng.integers(0, n)) for n in mats[block].shape)
    mats[block][idx] = value
    with pytest.raises(DataError, match=rf"plants\[0\]\.{block}\[{idx[0]}, {idx[1]}\]"):
        synthesize(control.ss(*(mats[n] for n in "ABCD")), 1, 1, 1, options=BUDGET)


@pytest.mark.parametrize("scale", [1e-150, 1e150])
def test_norm_of_a_system_whose_hamiltonian_overflows(scale):
    """``C`` of 1e150 squares to 1e300 and beyond in the Hamiltonian: the level set of the
    pencil (no products of the data) still gives the norm, ``|C B / (s + 1)|`` at ω = 0."""
    A, B = -np.eye(2), np.array([[1.0], [0.5]])
    C = scale * np.array([[1.0, 2.0]])
    gamma, omega = hinf_norm(A, B, C, np.zeros((1, 1)))
    np.testing.assert_allclose(gamma, 2.0 * scale, rtol=1e-6)
    assert omega == pytest.approx(0.0, abs=1e-6)


def test_norm_of_a_loop_with_non_finite_entries_is_infinite():
    gamma, _ = hinf_norm(-np.eye(1), [[np.inf]], [[1.0]], [[0.0]])
    assert gamma == np.inf


def test_benchmark_records_a_failing_plant_and_goes_on(tmp_path, capsys):
    """One plant file with a NaN entry, one plant that no controller can stabilise, one that
    works: the JSON holds all three, each failure with its error class and message."""
    from casflutter.cli import main

    plants = tmp_path / "plants"
    plants.mkdir()
    # ẋ = -x + w + u, z = [x; u], y = x: stabilised by any static gain u = -k x, k > -1
    good = {"A": [[-1.0]], "B1": [[1.0]], "B": [[1.0]], "C1": [[1.0], [0.0]], "C": [[1.0]],
            "D12": [[0.0], [1.0]]}
    # the unstable mode +1 is not controllable from u
    unstabilisable = {"A": [[1.0, 0.0], [0.0, -1.0]], "B1": [[1.0], [1.0]],
                      "B": [[0.0], [1.0]], "C1": [[1.0, 0.0]], "C": [[1.0, 1.0]],
                      "D12": [[1.0]], "D21": [[1.0]]}
    broken = dict(good, A=[[float("nan")]])
    for name, doc in (("good", good), ("unstabilisable", unstabilisable), ("broken", broken)):
        (plants / f"{name}.json").write_text(json.dumps(doc))     # (NaN as JSON allows it)
    out = tmp_path / "out.json"
    rc = main(["bench", "synthesis", "--plants", str(plants), "--orders", "0,1",
               "--starts", "1", "--hinfsyn-timeout", "0", "--out", str(out)])
    assert rc == 1                                   # a plant file could not be read
    recs = json.loads(out.read_text())["records"]
    assert sorted((r["plant"], r["order"]) for r in recs) == [
        (name, k) for name in ("broken", "good", "unstabilisable") for k in (0, 1)]
    for r in recs:
        if r["plant"] == "broken":
            assert r["error"]["class"] == "DataError" and "non-finite" in r["error"]["message"]
        elif r["plant"] == "unstabilisable":           # refused before any start, named
            assert r["error"]["class"] == "SynthesisError" and r["stable"] is False
            assert "the mode at λ = 1 (unreached by the controls)" in r["error"]["message"]
        else:
            assert r["stable"] is True and "error" not in r
    assert "broken" in capsys.readouterr().err
