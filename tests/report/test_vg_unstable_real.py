"""The V–g / V–f figure of a plant family shows what is unstable, real modes included.

Truth used: a small gridded family ``A(V) = T M(V) T⁻¹`` (``T`` a fixed, well-conditioned
matrix, ``M`` block diagonal and affine in V, so the linear interpolation between grid speeds
is exact) whose eigenvalues are, by construction,

- a complex pair at 10 rad/s with ``Re λ = 0.004 (V − 150)``: flutter at 150 m/s;
- a real eigenvalue ``0.01 + 10⁻⁴ (V − 100)`` > 0: unstable at every speed (a spiral mode);
- a stable real eigenvalue −5 (a lag: not drawn);
- lightly damped pairs (ζ = 0.02) at 45 rad/s (4.5 × the flutter frequency: drawn) and at
  250 rad/s (25 ×, more than a decade above: left out, and counted);
- a well-damped pair (ζ ≈ 0.7) at 20 rad/s (left out, and counted).

The growth rates on the figure are checked against ``numpy.linalg.eigvals`` of ``A(V)``
assembled here from the arrays, independently of the package's tracking.
"""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from numpy.testing import assert_allclose  # noqa: E402

from casflutter.aeroelastic import GriddedFamily, family_flutter  # noqa: E402
from casflutter.report import family_branches, plot_family_vg_vf  # noqa: E402

SPEEDS = np.linspace(100.0, 200.0, 6)


def _pair(sigma, omega):
    return np.array([[sigma, omega], [-omega, sigma]])


def _blocks(V, spiral=True):
    """Block-diagonal M(V) (affine in V)."""
    blocks = [_pair(0.004 * (V - 150.0), 10.0),
              np.array([[0.01 + 1e-4 * (V - 100.0) if spiral else -0.01]]),
              np.array([[-5.0]]),
              _pair(-0.02 * 45.0, 45.0),
              _pair(-0.02 * 250.0, 250.0),
              _pair(-14.0, 14.0)]
    n = sum(b.shape[0] for b in blocks)
    M, i = np.zeros((n, n)), 0
    for b in blocks:
        k = b.shape[0]
        M[i:i + k, i:i + k] = b
        i += k
    return M


def _family(spiral=True):
    n = _blocks(100.0).shape[0]
    T = np.eye(n) + 0.2 * np.random.default_rng(3).standard_normal((n, n))
    Ti = np.linalg.inv(T)
    A = np.array([T @ _blocks(V, spiral) @ Ti for V in SPEEDS])
    k = SPEEDS.size
    fam = GriddedFamily(SPEEDS, A, np.ones((k, n, 1)), np.ones((k, 1, n)), np.zeros((k, 1, 1)),
                        speed_unit="m/s", time_unit="s", name="toy")
    return fam, A


def _A(A, V):
    """A(V) interpolated elementwise between the grid speeds (independently of the family)."""
    j = int(np.clip(np.searchsorted(SPEEDS, V, side="right") - 1, 0, SPEEDS.size - 2))
    t = (V - SPEEDS[j]) / (SPEEDS[j + 1] - SPEEDS[j])
    return (1.0 - t) * A[j] + t * A[j + 1]


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


@pytest.fixture(scope="module")
def spiral():
    fam, A = _family(spiral=True)
    return fam, A, family_flutter(fam)


def _legend_texts(fig):
    return [t.get_text() for leg in fig.legends + [a.get_legend() for a in fig.axes]
            if leg is not None for t in leg.get_texts()]


def test_the_unstable_real_mode_is_drawn_by_its_growth_rate(spiral):
    fam, A, res = spiral
    assert res.unstable_at_start and res.status == "flutter"
    assert_allclose(res.Vf, 150.0, rtol=1e-6)
    fig = plot_family_vg_vf(res, fam)
    ag, af = fig.axes[0], fig.axes[1]
    twins = [a for a in fig.axes[2:] if a.bbox.bounds == ag.bbox.bounds]
    assert len(twins) == 1
    real_lines = [ln for ln in twins[0].get_lines()
                  if ln.get_label().startswith("real mode, unstable")]
    assert len(real_lines) == 1
    V, y = (np.asarray(d, dtype=float) for d in real_lines[0].get_data())
    assert V[0] == SPEEDS[0] and V[-1] == SPEEDS[-1]
    # the growth rate at each speed drawn, from numpy's eigenvalues of A(V)
    grow = []
    for v in V:
        lam = np.linalg.eigvals(_A(A, v))
        real = lam[np.abs(lam.imag) < 1e-9]
        grow.append(real[np.argmax(real.real)].real)
    grow = np.array(grow)
    assert np.all(grow > 0)
    assert_allclose(grow, 0.01 + 1e-4 * (V - 100.0), rtol=1e-9)     # the construction
    assert_allclose(-y, grow, rtol=1e-8, atol=1e-12)   # drawn as −Re λ (damping convention)
    # below the zero line, which is level with ζ = 0 on the damping axis
    (a, b), (c, d) = ag.get_ylim(), twins[0].get_ylim()
    assert a < 0 < b and c < 0 < d
    assert_allclose(-a / (b - a), -c / (d - c), rtol=1e-9)
    assert np.all((y > c) & (y < d))
    # and at frequency 0, in the same style, on the frequency panel
    zero = [ln for ln in af.get_lines() if ln.get_linestyle() == real_lines[0].get_linestyle()
            and ln.get_color() == real_lines[0].get_color()]
    assert len(zero) == 1 and np.all(np.asarray(zero[0].get_ydata()) == 0.0)


def test_the_title_and_legend_say_unstable_at_the_start_and_what_was_left_out(spiral):
    fam, A, res = spiral
    fig = plot_family_vg_vf(res, fam)
    title = fig.axes[0].get_title()
    assert "flutter at 150 m/s" in title
    assert "unstable already at 100 m/s" in title and "real mode" in title
    assert f"{0.01:+.3g} /s" in title
    texts = _legend_texts(fig)
    assert any(t.startswith("real mode, unstable") for t in texts)
    note = next(t for t in texts if t.startswith("drawn:"))
    assert "1 real, stable" in note
    assert "1 well damped (ζ ≥ 0.5 throughout)" in note
    assert "1 lightly damped above" in note and "10 × the highest crossing frequency" in note
    # the drawn oscillatory branches: the flutter one and the one at 4.5 × its frequency
    branches = [t for t in texts if not t.startswith(("drawn:", "real mode"))]
    assert sorted(branches) == sorted(
        [f"{10 / (2 * np.pi):.3g} Hz (crosses)", f"{45 / (2 * np.pi):.3g} Hz"])


def test_family_branches_keep_the_unstable_real_one_and_cut_a_decade_above(spiral):
    fam, A, res = spiral
    lam = res.tracking.eigenvalues
    bs = family_branches(res)
    real_unstable = [b for b in range(lam.shape[1])
                     if np.all(lam[:, b].imag == 0) and np.all(lam[:, b].real > 0)]
    assert len(real_unstable) == 1 and real_unstable[0] in bs
    freqs = sorted(np.abs(lam[0, b].imag) for b in bs)
    assert_allclose(freqs, [0.0, 10.0, 45.0], atol=0.5)
    # a tighter cut given by hand leaves the 45 rad/s branch out, never the unstable ones
    tight = family_branches(res, omega_max=20.0)
    assert_allclose(sorted(np.abs(lam[0, b].imag) for b in tight), [0.0, 10.0], atol=0.5)
    assert set(family_branches(res, max_branches=0)) == {res.flutter.branch,
                                                         real_unstable[0]}


def test_a_family_stable_at_the_start_has_no_growth_axis_and_no_warning():
    fam, A = _family(spiral=False)
    res = family_flutter(fam)
    assert not res.unstable_at_start
    fig = plot_family_vg_vf(res, fam)
    assert len(fig.axes) == 2
    assert "unstable already" not in fig.axes[0].get_title()
    assert "2 real, stable" in next(t for t in _legend_texts(fig) if t.startswith("drawn:"))


def test_on_given_axes(spiral):
    fam, A, res = spiral
    fig, (a1, a2) = plt.subplots(2, 1)
    assert plot_family_vg_vf(res, fam, ax=(a1, a2)) is fig
    assert any(t.startswith("real mode, unstable") for t in _legend_texts(fig))
