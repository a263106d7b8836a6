"""``casflutter flutter`` on GAF wing files other than the Goland wing: the configuration is
built for the file (no ROM order, the file's own airspeeds), and the p–k cross-check follows
every mode over the speeds where the table holds it, says which modes it leaves out and why,
and never throws the RFA's flutter point away.

The tables are written here from a 3-mode model with rational aerodynamics (eq. 6 with
``Q(p) = A0 + A1 p + A2 p / (p + 0.3)``, ``p = s b / U``, modes at 2, 5 and 12 Hz, the third
weakly coupled); its exact flutter point comes from the eigenvalues of its state matrix.
"""

import json

import numpy as np
import pytest

from casflutter.aeroelastic import pk_flutter
from casflutter.cli import main
from casflutter.truth import load_problem

U_REF, BETA, ALPHA = 10.0, 0.3, 1.0
F_HZ = np.array([2.0, 5.0, 12.0])
ZETA = np.array([0.01, 0.01, 0.02])
# columns: modes 1-3, flap
A0 = np.array([[-20.0, 180.0, 5.0, 30.0], [-60.0, -120.0, 4.0, 60.0], [3.0, 2.0, -30.0, 5.0]])
A1 = np.array([[-25.0, 5.0, 0.0, 2.0], [3.0, -15.0, 0.0, 4.0], [0.0, 0.0, -10.0, 1.0]])
A2 = np.array([[-10.0, 40.0, 0.0, 5.0], [-15.0, -20.0, 0.0, 8.0], [0.0, 0.0, -5.0, 1.0]])

WING = """kind = "gaf"
[problem]
name = "synth"
[modes]
frequencies_hz = {freqs}
damping = {zeta}
alpha = 1.0
[speed]
U_ref = 10.0
[sensors]
kind = "displacement"
rows = {rows}
[gaf]
file = "{table}"
U_range = {U_range}
n_grid = 97
method = "roger"
n_lags = 3
poly_order = 0
"""


def _Q(k, n):
    """``Q(ik)`` of the first ``n`` modes and the flap, ``(nk, n, n + 1)``."""
    p = 1j * np.asarray(k)[:, None, None]
    cols = list(range(n)) + [3]
    return (A0 + A1 * p + A2 * p / (p + BETA))[:, :n][:, :, cols]


def _exact_flutter(n, b=1.0):
    """Airspeed [m/s] and frequency [rad/s] where the model's state matrix first has an
    eigenvalue on the imaginary axis (bisection on the spectral abscissa)."""
    W = 2 * np.pi * F_HZ[:n]

    def abscissa(U, full=False):
        V, c = U / U_REF, BETA * U / b
        q, I, Z = ALPHA * (U / U_REF) ** 2, np.eye(n), np.zeros((n, n))
        A = np.block([[Z, I, Z],
                      [-np.diag(W ** 2) + q * A0[:n, :n],
                       -np.diag(2 * ZETA[:n] * W) + q * A1[:n, :n] * b / U, q * A2[:n, :n]],
                      [Z, I, -c * I]])
        lam = np.linalg.eigvals(A)
        return lam if full else np.max(lam.real)

    lo, hi = 12.0, 50.0
    assert abscissa(lo) < 0 < abscissa(hi)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if abscissa(mid) > 0 else (mid, hi)
    lam = abscissa(hi, full=True)
    return hi, abs(lam[np.argmax(lam.real)].imag)


@pytest.fixture(scope="module")
def gaf_file(tmp_path_factory):
    """``make(n_modes, k, U_range, b=1.0) -> path`` of a GAF wing file and its table."""
    folder = tmp_path_factory.mktemp("gaf_route")
    count = iter(range(100))

    def make(n, k, U_range, b=1.0):
        i = next(count)
        k = np.asarray(k, dtype=float)
        np.savez(folder / f"q{i}.npz", k=k, Q=_Q(k, n), b=np.array(b), U_ref=np.array(U_REF))
        rows = [[1.0, 0.3, 0.1][:n], [0.2, 1.0, 0.1][:n]]
        path = folder / f"wing{i}.toml"
        path.write_text(WING.format(freqs=F_HZ[:n].tolist(), zeta=ZETA[:n].tolist(), rows=rows,
                                    table=f"q{i}.npz", U_range=list(U_range)))
        return path

    return make


def _flutter(path, capsys):
    rc = main(["flutter", str(path), "--json"])
    out = capsys.readouterr()
    return rc, json.loads(out.out) if rc == 0 else None, out.err


def test_a_two_mode_gaf_file_is_not_checked_against_the_seed_wings_rom_order(gaf_file,
                                                                             capsys):
    """The seed wing's ``rom.nf = 15`` was checked against the file's 2 modes (at most 10):
    the GAF route identifies no ROM."""
    rc, doc, err = _flutter(gaf_file(2, np.linspace(0, 3, 40), [12.0, 50.0]), capsys)
    assert rc == 0, err
    assert "rom.nf" not in err
    U, omega = _exact_flutter(2)                           # 24.040 m/s, 35.163 rad/s
    assert doc["rfa_flutter"]["airspeed_m_s"] == pytest.approx(U, rel=0.01)
    assert doc["pk"]["airspeed_m_s"] == pytest.approx(U, rel=1e-4)
    assert doc["pk"]["omega_rad_s"] == pytest.approx(omega, rel=1e-4)
    assert doc["pk"]["mode"] == doc["rfa_flutter"]["mode"] == 2


def test_the_frozen_loop_is_searched_over_the_files_own_airspeeds(gaf_file, capsys):
    """b = 2 m puts the flutter at Uf / U_ref = 2.61, above the seed wing's flutter.V_range
    (0.3, 2.5) that the frozen ΣAE(V) was searched over; gaf.U_range [12, 50] m/s holds it."""
    rc, doc, err = _flutter(gaf_file(3, np.linspace(0, 3, 40), [12.0, 50.0], b=2.0), capsys)
    assert rc == 0, err
    assert doc["rfa_flutter"]["airspeed_m_s"] / U_REF > 2.5
    assert "flutters nowhere" not in err and "(0.3, 2.5)" not in err


def test_pk_follows_the_flutter_mode_the_table_holds(gaf_file, capsys):
    """Mode 2's in-vacuo k at 12 m/s is 2.6 (> 0.8 k_max = 2.4, where it was left out
    silently): p–k now follows it and finds the flutter point pk_flutter finds on modes 1-2,
    the exact one; mode 3, beyond the table below 27 m/s, is followed from there and named."""
    path = gaf_file(3, np.linspace(0, 3, 40), [12.0, 50.0])
    rc, doc, err = _flutter(path, capsys)
    assert rc == 0, err
    g = load_problem(str(path))
    direct = pk_flutter(g.table, g.structure, np.linspace(12.0, 50.0, 29), modes=(0, 1))
    assert doc["pk"]["airspeed_m_s"] == pytest.approx(direct.flutter_speed, rel=1e-6)
    assert doc["pk"]["omega_rad_s"] == pytest.approx(direct.flutter_omega, rel=1e-6)
    U, omega = _exact_flutter(3)                           # 24.042 m/s, 35.163 rad/s
    assert doc["pk"]["airspeed_m_s"] == pytest.approx(U, rel=1e-4)
    assert doc["pk"]["mode"] == 2 and doc["warnings"] == []
    assert "mode 3 ('mode 3') followed for U in [26.93, 50] m/s only" in err
    assert "beyond the table's k <= 3" in err


def test_pk_starting_outside_the_table_keeps_the_rfa_flutter(gaf_file, capsys):
    """U_range from 2 m/s: mode 1 needs k = 6.3 there, beyond the table's k <= 3.  The
    command failed after the RFA fit; now p–k follows each mode from where the table holds
    it."""
    rc, doc, err = _flutter(gaf_file(3, np.linspace(0, 3, 40), [2.0, 50.0]), capsys)
    assert rc == 0, err
    U, _ = _exact_flutter(3)
    assert doc["rfa_flutter"]["airspeed_m_s"] == pytest.approx(U, rel=0.01)
    assert doc["pk"]["airspeed_m_s"] == pytest.approx(U, rel=1e-4)
    assert "mode 1 ('mode 1') followed for U in [5.429, 50] m/s only" in err


def test_pk_unavailable_on_the_table_is_reported_beside_the_rfa_flutter(gaf_file, capsys):
    """A table up to k = 0.8 only (flutter at k = 1.46): p–k cannot follow either mode, and
    says so, with the reason, instead of failing the command or suggesting other speeds."""
    rc, doc, err = _flutter(gaf_file(3, np.linspace(0, 0.8, 20), [12.0, 50.0]), capsys)
    assert rc == 0, err
    assert doc["rfa_flutter"] is not None and doc["pk"] is None
    (warning,) = [w for w in doc["warnings"] if w.startswith("p-k")]
    assert "unavailable" in warning and "extend the speeds" not in warning
    assert ("modes 1 ('mode 1'), 2 ('mode 2') left out: p–k needs k beyond the table's "
            "k <= 0.8 at every speed") in warning
    assert ("mode 3 ('mode 3') left out: the in-vacuo k = omega b / U lies beyond the table's "
            "k <= 0.8 up to U = 50 m/s") in warning
