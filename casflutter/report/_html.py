"""A self-contained HTML report: the figures embedded, Table I beside the paper's values."""

from __future__ import annotations

import base64
import html
from pathlib import Path

from .._format import sig

__all__ = ["html_report", "PAPER_TABLE_I", "VF_FLAG_FRACTION", "flutter_speed_flags"]

#: Paper Table I and §IV figures, for the comparison column.
PAPER_TABLE_I = {
    "nominal speed index V0": "0.69",
    "number of modes N": "5",
    "(mu, na, nb, r, p, q)": "(3, 1, 1, 1, 2, 2)",
    "order of Σf nf": "15",
    "order of Σs": "10",
    "order of ΣAE": "25",
    "flutter speed index Vf": "1.20",
    "flutter mode": "2 (lateral)",
    "LCO fundamental frequency [Hz]": "8.5",
    "order of controller K(s)": "3",
    "number of sensors": "2",
    "stable speed range (controller)": "(0, 2.4)",
    "LCO attenuation": "> 90 %",
}


#: A ROM flutter speed that differs from the truth's by more than this fraction is flagged
#: in the report (unconservative when above the truth's: a clearance read off the ROM would
#: admit speeds at which the wing flutters).
VF_FLAG_FRACTION = 0.02


def _fmt(x, digits=4):
    if x is None:
        return "—"
    if isinstance(x, bool) or not isinstance(x, (int, float, list, tuple)):
        return html.escape(str(x))
    return html.escape(sig(x, digits))


def _airspeed_scale(s: dict) -> float | None:
    """Metres per second per speed index, read off a flutter block that has both."""
    for key in ("flutter", "flutter_truth"):
        b = s.get(key) or {}
        if b.get("V") and b.get("airspeed_m_s") is not None:
            return float(b["airspeed_m_s"]) / float(b["V"])
    return None


def _with_airspeed(V, scale: float | None) -> str:
    """``1.2 (34.68 m/s)``, ``(0, 1.568) = (0, 45.31) m/s``: a speed index (or an interval of
    them) and, where the problem has a scale, its airspeed."""
    if V is None:
        return "—"
    if scale is None:
        return _fmt(V)
    if isinstance(V, (list, tuple)):
        return f"{_fmt(V)} = {_fmt([None if v is None else v * scale for v in V])} m/s"
    return f"{_fmt(V)} ({_fmt(V * scale)} m/s)"


def flutter_speed_flags(summary: dict, threshold: float = VF_FLAG_FRACTION) -> list[str]:
    """The ROM flutter speeds of a run that differ from the truth's by more than
    ``threshold``, each said in one sentence (unconservative above the truth's).

    Parameters
    ----------
    summary : dict
        The run's summary (``summary.json``): ``flutter_truth`` and the ROMs' blocks
        ``flutter`` (the paper's route), ``flutter_parametric``.
    threshold : float
        Relative difference above which a speed is flagged (0.02: 2 %).

    Returns
    -------
    list of str
        Empty when the truth has no flutter speed or every ROM is within the threshold.
    """
    truth = (summary.get("flutter_truth") or {}).get("V")
    if not truth:
        return []
    scale = _airspeed_scale(summary)
    out = []
    for key, what in (("flutter", "The ROM's flutter speed (the paper's route)"),
                      ("flutter_parametric", "The parametric ROM's flutter speed")):
        V = (summary.get(key) or {}).get("V")
        if V is None:
            continue
        rel = V / truth - 1.0
        if abs(rel) <= threshold:
            continue
        side = ("above the truth's, {t}: unconservative, a clearance read off the ROM would "
                "admit speeds at which the wing flutters" if rel > 0 else
                "below the truth's, {t}: conservative")
        out.append(f"{what}, V = {_with_airspeed(V, scale)}, is {100 * abs(rel):.3g} % "
                   + side.format(t=_with_airspeed(truth, scale))
                   + f" (flagged when the difference exceeds {100 * threshold:g} %).")
    return out


def _table_i_columns(s: dict, scale) -> tuple[dict, dict]:
    """Table I's run column and truth column (the truth simulator's own values, where it has
    one), each row name -> HTML text."""
    fl, ctrl = s.get("flutter") or {}, s.get("controller") or {}
    lco, sup = s.get("lco") or {}, s.get("suppression") or {}
    ours = {
        "nominal speed index V0": _with_airspeed(s.get("V0"), scale),
        "number of modes N": _fmt(s["ns"] // 2 if s.get("ns") else None),
        "(mu, na, nb, r, p, q)": _fmt(tuple(s.get("orders") or [])),
        "order of Σf nf": _fmt(s.get("nf")),
        "order of Σs": _fmt(s.get("ns")),
        "order of ΣAE": _fmt(s.get("nae")),
        "flutter speed index Vf": _with_airspeed(fl.get("V"), scale),
        "flutter mode": _fmt(fl.get("mode")),
        "LCO fundamental frequency [Hz]": _fmt(lco.get("freq_hz")),
        "order of controller K(s)": _fmt(ctrl.get("order")),
        "number of sensors": _fmt(s.get("n_sensors")),
        "stable speed range (controller)": _with_airspeed(ctrl.get("stable_interval"), scale),
        "LCO attenuation": _attenuation(sup),
    }
    ft = s.get("flutter_truth") or {}
    truth = {   # the truth simulator's own values, where it has one
        "flutter speed index Vf": _with_airspeed(ft.get("V"), scale),
        "stable speed range (controller)": _with_airspeed(ctrl.get("truth_stable_interval"),
                                                          scale),
        "flutter mode": _fmt(ft.get("mode")),
        "LCO fundamental frequency [Hz]": _fmt(lco.get("truth_freq_hz")
                                               if lco.get("truth_kind") == "lco" else None),
    }
    return ours, truth


def _attenuation(sup: dict) -> str:
    """The suppression runs' attenuations, ``"1.05 Vf: 91.0 %, 1.2 Vf: 16.2 %"`` (or the
    single run's of a summary without ``runs``)."""
    runs = [r for r in sup.get("runs") or [] if r.get("attenuation_percent") is not None]
    if runs:
        return ", ".join(f"{r['speed_factor']:g} Vf: {r['attenuation_percent']:.1f} %"
                         for r in runs)
    att = sup.get("attenuation_percent")
    return _fmt(None) if att is None else f"{att:.1f} %"


def html_report(summary: dict, figures: dict[str, Path], *, title: str = "casflutter run",
                captions: dict[str, str] | None = None) -> str:
    """HTML text of the report (figures read from PNG files and embedded as base64).

    Parameters
    ----------
    summary : dict
        The run's summary (``summary.json``).
    figures : dict
        Figure name -> PNG path.
    title : str
        Page title.
    captions : dict, optional
        Figure name -> caption; a figure without one is captioned by its file name.

    Returns
    -------
    str
    """
    captions = captions or {}
    s = summary
    lco, sup, ctrl = s.get("lco") or {}, s.get("suppression") or {}, s.get("controller") or {}
    scale = _airspeed_scale(s)
    ours, truth = _table_i_columns(s, scale)
    ft = s.get("flutter_truth") or {}
    rows = "\n".join(f"<tr><td>{html.escape(k)}</td><td>{ours[k]}</td>"
                     f"<td>{truth.get(k, _fmt(None))}</td>"
                     f"<td>{html.escape(v)}</td></tr>" for k, v in PAPER_TABLE_I.items())
    fit = ", ".join(sig(e, 4) for e in s.get("fit_error_percent") or [])
    imgs = []
    for name, path in figures.items():
        data = base64.b64encode(Path(path).read_bytes()).decode("ascii")
        caption = captions.get(name) or Path(path).name
        imgs.append(f'<figure><img alt="{html.escape(caption)}" '
                    f'src="data:image/png;base64,{data}">'
                    f"<figcaption>{html.escape(caption)}</figcaption></figure>")
    lco_text = ""
    if lco.get("amplitude") is not None and lco.get("truth_amplitude") is not None:
        units = lco.get("amplitude_units")
        unit = (f" [{html.escape(units[0])}]" if units and len(set(units)) == 1
                else f" [{html.escape(', '.join(units))}]" if units else "")
        lco_text = (f"<p>LCO amplitude per sensor{unit} (half peak to peak), each model a "
                    f"little above its own flutter speed: ROM {_fmt(lco['amplitude'])} at "
                    f"V = {_with_airspeed(lco.get('V'), scale)}, truth "
                    f"{_fmt(lco['truth_amplitude'])} at "
                    f"V = {_with_airspeed(lco.get('truth_V'), scale)}.</p>")
    flags = flutter_speed_flags(s)
    flag_text = ("" if not flags else "<h2>Flags</h2>\n<ul>" + "".join(
        f'<li class="flag">{html.escape(f)}</li>' for f in flags) + "</ul>")
    timings = s.get("timings_s", {})
    trows = "\n".join(f"<tr><td>{html.escape(k)}</td><td>{v:.2f}</td></tr>"
                      for k, v in timings.items() if isinstance(v, (int, float)))
    version = s.get("casflutter_version")
    gamma = (f"verified γ = {_fmt(ctrl.get('gamma'))} (‖T_w̄z‖∞ of the LFT at Vf, eq. 16, flap "
             f"ideal), small-gain interval of V {_with_airspeed(ctrl.get('small_gain_V'), scale)}; "
             if ctrl.get("gamma") is not None else "")
    design = ""
    if ctrl.get("method") == "multispeed":
        design = (f"order-{_fmt(ctrl.get('order'))} multi-speed design over "
                  f"{_with_airspeed(ctrl.get('interval'), scale)} "
                  f"({'held' if ctrl.get('held') else 'not held: ' + html.escape(str(ctrl.get('design_message')))}, "
                  f"{_fmt(ctrl.get('design_time_s'))} s); ")
    servo = ctrl.get("servo_omega")
    robust = (f" Absolute / robust flutter speed (the closed loop's loss of stability / of "
              f"its gain and phase margins): ROM {_fmt(ctrl.get('absolute_flutter_speed'))} / "
              f"{_fmt(ctrl.get('robust_flutter_speed'))}, truth "
              f"{_fmt(ctrl.get('truth_absolute_flutter_speed'))} / "
              f"{_fmt(ctrl.get('truth_robust_flutter_speed'))}." if ctrl else "")
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>
<style>body{{font-family:sans-serif;max-width:960px;margin:2em auto;color:#222}}
table{{border-collapse:collapse;margin:1em 0}}td,th{{border:1px solid #bbb;padding:4px 10px}}
th{{background:#eee}}img{{max-width:100%}}figure{{margin:1.5em 0}}
figcaption{{font-size:90%;color:#555}}.flag{{color:#a00}}</style></head><body>
<h1>{html.escape(title)}: {html.escape(str(s.get('problem')))}</h1>
<p>Reproduction of K.-Y. Lum et al., ACC 2016, on casflutter's truth simulator
(the paper's CFD and wind tunnel are not available). Seed {_fmt(s.get('seed'))};
casflutter {_fmt(version)}.{'' if scale is None else
f" Speeds as the speed index V with the airspeed U = {_fmt(scale)} V m/s beside it."}</p>
{flag_text}
<h2>Table I</h2>
<table><tr><th>quantity</th><th>this run (ROM)</th><th>truth simulator</th><th>paper</th></tr>
{rows}</table>
<p>ROM fit error per mode [%]: {fit}. Truth flutter: V = {_with_airspeed(ft.get('V'), scale)},
{_fmt(ft.get('freq_hz'))} Hz. Controller: {design}{gamma}certified stable interval
{_with_airspeed(ctrl.get('stable_interval'), scale)} on the ROM loop and
{_with_airspeed(ctrl.get('truth_stable_interval'), scale)} on the truth's own linearisation
(flap behind a servo of {_fmt(servo)} rad/s).{robust}</p>
{lco_text}
<h2>Figures</h2>
{''.join(imgs)}
<h2>Timings [s]</h2>
<table>{trows}</table>
</body></html>
"""
