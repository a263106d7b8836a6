"""Figures an engineer can read (issue 12, item 6): sensor axes with units, mode numbers
from 1, the V–g/V–f legend of the structural modes only, the ROM's and the truth's LCO in
their own panels, bifurcation diagrams side by side around the branches, captions."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from casflutter.aeroelastic import find_flutter, simulate_loop  # noqa: E402
from casflutter.lco import LCOSettings, lco_branch  # noqa: E402
from casflutter.report import (html_report, plot_bifurcation_pair, plot_lco,  # noqa: E402
                               plot_rom_fit, plot_vg_vf, sensor_labels)
from casflutter.structure import ModalStructure  # noqa: E402
from casflutter.truth import (SeedWing, TypicalSection, TypicalSectionParams,  # noqa: E402
                              truth_lco)


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_sensor_labels_carry_the_unit_of_what_the_sensor_reads():
    wing = SeedWing()
    ms = wing.modal_structure()
    assert wing.sensor_units() == ("m", "m")
    assert sensor_labels(ms.sensor_names, wing.sensor_units(), "acceleration") == [
        "Acc1 (bending/torsion) [m/s²]", "Acc2 (lateral) [m/s²]"]
    assert sensor_labels(["zm[0]"], [], "velocity", "1/omega") == [
        "sensor 1 [modal units/(1/omega)]"]
    assert sensor_labels(["theta"], ["rad"], "displacement") == ["theta [rad]"]


def test_vg_vf_names_the_structural_modes_from_one_and_keeps_the_lag_states_apart():
    wing = SeedWing()
    res = find_flutter(wing, (0.3, 2.5), n_grid=16, max_refine=0)
    names = wing.modal_structure().mode_names
    fig = plot_vg_vf(res, mode_names=names)
    ag, af = fig.axes[:2]
    texts = [t.get_text() for t in ag.get_legend().get_texts()]
    assert texts[:5] == [f"mode {i + 1} ({n})" for i, n in enumerate(names)]
    assert texts[5:] == ["aerodynamic lag states"]       # one entry, however many states
    # the frequency axis shows every mode (2.19 ... 38.09 Hz) and is scaled to them
    lo, hi = af.get_ylim()
    assert lo == 0.0 and 38.09 < hi < 1.3 * 40.0
    assert "mode 2 (lateral 1)" in ag.get_title()        # the lateral branch, numbered from 1
    grey = [line for line in ag.get_lines() if line.get_color() == "0.6"]
    assert grey and all(line.get_alpha() <= 0.5 for line in grey)
    # the curve the legend calls mode 2 is the one whose damping crosses zero at Vf
    flutter_line = dict(zip(texts, ag.get_legend().legend_handles))["mode 2 (lateral 1)"]
    crossing = [line for line in ag.get_lines() if line.get_label() == "mode 2 (lateral 1)"]
    assert len(crossing) == 1 and crossing[0].get_color() == flutter_line.get_color()
    V, zeta = crossing[0].get_data()
    assert np.interp(res.Vf, V, zeta) == pytest.approx(0.0, abs=2e-3)
    assert zeta[0] > 0 > zeta[-1]


def test_vg_vf_in_the_problems_units_with_the_speed_index_beside():
    """The seed wing in m/s (U = 28.9 V) with a secondary speed-index axis; the typical
    section's frequency in Ω/ω_θ, not Hz; a mode's colour is the same in every panel."""
    wing = SeedWing()
    res = find_flutter(wing, (0.3, 2.5), n_grid=16, max_refine=0)
    fig = plot_vg_vf(res, mode_names=wing.modal_structure().mode_names, speed_scale=28.9,
                     speed_unit="m/s", speed_label="airspeed U [m/s]", index_label="speed index V")
    ag, af = fig.axes[:2]
    assert f"Uf = {res.Vf * 28.9:.4g} m/s" in ag.get_title()
    assert af.get_xlabel() == "airspeed U [m/s]"
    top = [c for c in ag.get_children() if type(c).__name__ == "SecondaryAxis"]
    assert len(top) == 1 and top[0].get_xlabel() == "speed index V"
    lo, hi = ag.get_xlim()
    assert lo < 0.3 * 28.9 + 1 and hi > 2.5 * 28.9 - 1
    ts = TypicalSection()
    rts = find_flutter(ts, (0.5, 3.0), n_grid=30, max_refine=0)
    f2, (a1, a2) = plt.subplots(2, 2)
    plot_vg_vf(rts, hz=False, frequency_unit="Ω/ω_θ", ax=(a1[0], a2[0]))
    plot_vg_vf(rts, hz=False, frequency_unit="Ω/ω_θ", ax=(a1[1], a2[1]))
    assert a2[0].get_ylabel() == "frequency [Ω/ω_θ]" and "Hz" not in a1[0].get_title()
    colours = [{line.get_label(): line.get_color() for line in a.get_lines()} for a in a1]
    assert colours[0]["mode 2 (pitch)" if "mode 2 (pitch)" in colours[0] else "mode 2"] == \
        colours[1]["mode 2 (pitch)" if "mode 2 (pitch)" in colours[1] else "mode 2"]


def test_a_mode_with_several_branches_has_one_legend_entry():
    """A mode whose branches split (the Goland RFA's real roots, several tracked pairs) is
    named once in the legend, all its branches in its colour."""
    ts = TypicalSection()
    res = find_flutter(ts, (0.5, 3.0), n_grid=30, max_refine=0)
    branches = [b for b in range(res.tracking.n_branches) if res.origin[b] >= 0]
    fig = plot_vg_vf(res, branches=branches)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert len(labels) == len(set(labels))
    assert sorted(labels) == sorted({f"mode {res.origin[b] + 1}" for b in branches})


def test_lco_figure_puts_rom_and_truth_in_their_own_panels():
    wing = SeedWing()
    ms = wing.modal_structure()
    tr = truth_lco(wing, 1.2, 1.0, 1, 0.05, dt=0.002, max_extensions=0)

    class Rayleigh:                      # a two-mode stand-in for the ROM loop with an LCO
        n_modes, max_lag, dt = 5, 1, 0.002

        def step(self, y_hist, u_hist, v_hist):
            ud = (u_hist[0] - u_hist[1]) / self.dt
            return 0.9 * ud - 50.0 * ud ** 3

    st = ModalStructure([2 * np.pi * f for f in (2.19, 10.07, 13.55, 16.48, 38.09)],
                        [0.01] * 5, Hs=ms.Hs)
    sim = simulate_loop(Rayleigh(), st, 0.05, 2000, xs0=st.displaced_state(1, 0.05))
    labels = sensor_labels(ms.sensor_names, wing.sensor_units(), "acceleration")
    fig = plot_lco(sim, truth=tr, labels=labels, title="Fig. 9: LCO")
    axes = np.array(fig.axes).reshape(3, 2)
    assert axes[0, 0].get_title().startswith("ROM loop at V = 0.05")
    assert axes[0, 1].get_title().startswith("truth at V = 1.2")
    if tr.kind == "lco":           # the amplitude with its sensor's unit
        assert any(t.get_text().endswith("m/s²") for t in axes[0, 1].texts)
    assert axes[0, 0].get_ylabel() == "Acc1 (bending/torsion) [m/s²]"
    assert axes[1, 0].get_ylabel() == "Acc2 (lateral) [m/s²]"
    # each column draws its own record only (one line per time panel)
    assert len(axes[0, 0].get_lines()) == len(axes[0, 1].get_lines()) == 1
    assert fig._suptitle.get_text() == "Fig. 9: LCO"
    # one vertical scale per row where both are bounded; a divergence (this short truth
    # run's) would flatten the other column, so each is scaled to its own signal then
    bounded = not any(a.get_title().endswith("divergence") for a in axes[0])
    assert axes[0, 1].get_shared_y_axes().joined(axes[0, 0], axes[0, 1]) is bounded
    fig = plot_lco(sim, truth=tr, labels=labels, speed_scale=28.9, speed_unit="m/s")
    assert fig.axes[1].get_title().startswith("truth at V = 1.2 (34.68 m/s)")


def test_rom_fit_error_is_the_tables_definition():
    """The panel's number is ``100 ||y - ŷ|| / ||y||`` after the first max_lag samples
    (the fit table's), recomputed here from the record and the ROM's free run."""
    from casflutter.ident import fit_report, identify
    from casflutter.truth import truth_records

    data = truth_records(TypicalSection(), V0=2.0, dt=0.1, duration=60.0, band=(0.005, 1.0))
    model = identify(data, (2, 1, 1, 0, 1, 1)).model
    fit = fit_report(model, data)
    fig = plot_rom_fit(model, data, fit=fit, mode_names=("plunge", "pitch"))
    for i, ax in enumerate(fig.axes):
        rec = data.records[i]
        y = model.simulate(rec.u, rec.v, y0=rec.y[:model.max_lag])[model.max_lag:, i]
        ref = rec.y[model.max_lag:, i]
        err = 100 * np.linalg.norm(y - ref) / np.linalg.norm(ref)
        title = ax.get_title(loc="right")
        assert title.startswith(f"mode {i + 1} (")
        assert f"error {err:.3f} % on this record" in title
        assert f"{fit.error_percent[i]:.3f} % on all (table)" in title


def test_bifurcation_pair_is_zoomed_on_the_branches():
    settings = LCOSettings(max_points=8)
    a = lco_branch(TypicalSection(TypicalSectionParams(kappa2=3.0)), (0.5, 6.0), settings)
    b = lco_branch(TypicalSection(TypicalSectionParams(kappa2=5.0)), (0.5, 6.0), settings)
    fig = plot_bifurcation_pair(a, b, ["theta"])
    lo, hi = fig.axes[0].get_xlim()
    speeds = [p.V for br in (a, b) for p in br.points] + [a.hopf.V, b.hopf.V]
    assert lo < min(speeds) and hi > max(speeds)
    assert hi - lo < 0.5 * (6.0 - 0.5)          # not the whole search range
    assert "Hopf point at" in fig.axes[0].get_title()
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "Hopf point" in legend and "Neimark–Sacker point" not in legend


def test_a_sampled_data_loops_branch_is_marked_as_a_neimark_sacker_point():
    """The ROM loop is a map: its flutter point is a Neimark–Sacker point, in the title
    and in the legend of its panel (the truth's stays a Hopf point)."""
    from dataclasses import replace

    a = lco_branch(TypicalSection(TypicalSectionParams(kappa2=3.0)), (0.5, 6.0),
                   LCOSettings(max_points=4))
    discrete = replace(a, hopf=replace(a.hopf, discrete=True), problem="ROM loop")
    fig = plot_bifurcation_pair(a, discrete, ["theta"])
    left, right = fig.axes[0], fig.axes[1]          # the top row: truth, ROM loop
    assert "Hopf point at" in left.get_title()
    assert "Neimark–Sacker point at" in right.get_title()
    assert "Neimark–Sacker point" in [t.get_text() for t in right.get_legend().get_texts()]
    assert "Hopf point" not in [t.get_text() for t in right.get_legend().get_texts()]


def test_report_captions_replace_the_file_keys(tmp_path):
    fig, ax = plt.subplots()
    ax.plot([0, 1])
    png = tmp_path / "f.png"
    fig.savefig(png)
    text = html_report({"problem": "p"}, {"fig9_lco": png, "other": png},
                       captions={"fig9_lco": "Fig. 9. The LCO of each model."})
    assert "<figcaption>Fig. 9. The LCO of each model.</figcaption>" in text
    assert "<figcaption>fig9_lco</figcaption>" not in text
    assert "<figcaption>f.png</figcaption>" in text       # no caption: the file's name


def test_mode_labels_number_a_mode_once():
    """A rig names its modes "mode 1 (pitch)": the legend does not number them twice."""
    from casflutter.report._flutter_plots import _mode_label

    assert _mode_label(0, ["mode 1 (pitch)", "mode 2 (heave)"]) == "mode 1 (pitch)"
    assert _mode_label(1, ["bending 1", "torsion 1"]) == "mode 2 (torsion 1)"
    assert _mode_label(0, ["mode 10 (x)"]) == "mode 1 (mode 10 (x))"
