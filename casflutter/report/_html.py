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


_STYLE = """<style>body{font-family:sans-serif;max-width:960px;margin:2em auto;color:#222}
table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:4px 10px}
th{background:#eee}img{max-width:100%}figure{margin:1.5em 0}
figcaption{font-size:90%;color:#555}.flag{color:#a00}</style>"""


def _page(title: str, heading: str, body: str) -> str:
    """The whole HTML page: ``title`` in the head, ``heading`` as its ``<h1>``, then
    ``body`` (HTML)."""
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>
{_STYLE}</head><body>
<h1>{html.escape(heading)}</h1>
{body}
</body></html>
"""


def _figures_html(figures: dict, captions: dict) -> str:
    """The ``Figures`` section: each PNG embedded as base64 with its caption (its file
    name when it has none)."""
    imgs = []
    for name, path in figures.items():
        data = base64.b64encode(Path(path).read_bytes()).decode("ascii")
        caption = captions.get(name) or Path(path).name
        imgs.append(f'<figure><img alt="{html.escape(caption)}" '
                    f'src="data:image/png;base64,{data}">'
                    f"<figcaption>{html.escape(caption)}</figcaption></figure>")
    return "<h2>Figures</h2>\n" + "".join(imgs)


def _timings_html(s: dict) -> str:
    """The ``Timings`` section: seconds per stage."""
    timings = s.get("timings_s", {})
    trows = "\n".join(f"<tr><td>{html.escape(k)}</td><td>{v:.2f}</td></tr>"
                      for k, v in timings.items() if isinstance(v, (int, float)))
    return f"<h2>Timings [s]</h2>\n<table>{trows}</table>"


def html_report(summary: dict, figures: dict[str, Path], *, title: str = "casflutter run",
                captions: dict[str, str] | None = None, config: dict | None = None) -> str:
    """HTML text of the report (figures read from PNG files and embedded as base64).

    A run on a plant family file (``summary["route"] == "family"``) gets the family's
    design report (the family, its open-loop flutter, the controller and its certificate,
    in the family's own units); any other run the reproduction of the paper, its Table I
    beside the truth simulator's and the paper's values.

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
    config : dict, optional
        The run's configuration (``config.json``): the family report reads the
        controller's H∞ objective and margins from it where the summary does not say.

    Returns
    -------
    str
    """
    captions = captions or {}
    if summary.get("route") == "family":
        return _family_report(summary, figures, title, captions, config or {})
    s = summary
    lco, sup, ctrl = s.get("lco") or {}, s.get("suppression") or {}, s.get("controller") or {}
    scale = _airspeed_scale(s)
    ours, truth = _table_i_columns(s, scale)
    ft = s.get("flutter_truth") or {}
    rows = "\n".join(f"<tr><td>{html.escape(k)}</td><td>{ours[k]}</td>"
                     f"<td>{truth.get(k, _fmt(None))}</td>"
                     f"<td>{html.escape(v)}</td></tr>" for k, v in PAPER_TABLE_I.items())
    fit = ", ".join(sig(e, 4) for e in s.get("fit_error_percent") or [])
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
    return _page(title, f"{title}: {s.get('problem')}", f"""<p>Reproduction of K.-Y. Lum et al., ACC 2016, on casflutter's truth simulator
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
{_figures_html(figures, captions)}
{_timings_html(s)}""")


# ---------------------------------------------------------------------- a plant family
#: What the multi-speed design's H∞ plants are, per ``controller.hinf_objective``.
_OBJECTIVES = {
    "sensors": "the family's disturbance inputs to its measurements",
    "sensitivity": ("the loop's output and input sensitivities (in the design's scaled "
                    "signals where the family declares them in different units, else in "
                    "their own units), which bound every loop-at-a-time gain and phase "
                    "margin"),
    "lft": "the LFTs at multiples of the flutter speed (eq. 14-16)",
}


def _speed(x, unit: str) -> str:
    """``139.7 m/s``, ``(60, 193.8) m/s``, ``1.2 (speed index)``: a speed or an interval of
    speeds in the family's unit (an interval's open top, ``None``, as ``∞``)."""
    if x is None:
        return _fmt(None)
    if isinstance(x, (list, tuple)):
        text = "(" + ", ".join("∞" if v is None else _fmt(v) for v in x) + ")"
    else:
        text = _fmt(x)
    unit = str(unit or "")
    if not unit:
        return text
    return f"{text} ({html.escape(unit)})" if unit.startswith("speed index") \
        else f"{text} {html.escape(unit)}"


def _frequency(freq, omega, time_unit: str) -> str:
    """``10.93 Hz (68.69 rad/s)``, or per the family's own time unit when it is not s."""
    if freq is None and omega is None:
        return _fmt(None)
    tu = html.escape(str(time_unit or "s"))
    cycles = "Hz" if tu == "s" else f"cycles per {tu}"
    return f"{_fmt(freq)} {cycles} ({_fmt(omega)} rad/{tu})"


def _names(names) -> str:
    names = list(names or [])
    return f"{len(names)}: " + html.escape(", ".join(map(str, names))) if names else "none"


def _rows(rows) -> str:
    """A two-column table of ``(quantity, HTML value)`` pairs."""
    return "<table>" + "\n".join(f"<tr><td>{html.escape(k)}</td><td>{v}</td></tr>"
                                 for k, v in rows) + "</table>"


def _family_config(config: dict, key: str, default=None):
    """``config["controller"][key]`` of a run's ``config.json`` (``default`` without it)."""
    value = (config.get("controller") or {}).get(key)
    return default if value is None else value


def _objective_text(s: dict, config: dict) -> str:
    """What the design's γ is the value of, in words (HTML)."""
    ctrl, fam = s.get("controller") or {}, s.get("family") or {}
    objective = ctrl.get("hinf_objective") or _family_config(config, "hinf_objective")
    if objective == "auto" and isinstance(fam.get("disturbances"), list):
        objective = "sensors" if fam["disturbances"] else "sensitivity"
    n = _family_config(config, "hinf_speeds")
    text = "the largest H∞ norm, over the design's " + (
        f"{n} H∞ speeds spread over the interval held" if n else "H∞ speeds") + ", of "
    if objective in _OBJECTIVES:
        text += f'{_OBJECTIVES[objective]} (controller.hinf_objective = "{objective}")'
    elif objective == "auto":
        text += ('its H∞ plants (controller.hinf_objective = "auto": '
                 f"{_OBJECTIVES['sensors']} when the family names disturbance inputs, else "
                 f"{_OBJECTIVES['sensitivity']})")
    else:
        text += "its H∞ plants"
    weight = _family_config(config, "flap_rate_weight")
    if weight:
        text += (f", each with its control-rate output weighted by {sig(weight)} "
                 "(controller.flap_rate_weight)")
    return html.escape(text)


def _certificates(ctrl: dict) -> list[tuple[str, str]]:
    """``(model, key prefix)`` of each model the controller was certified on: the design
    family (no prefix) and any reference (``truth_`` ...)."""
    out = []
    for key in ctrl:
        if key.endswith("stable_interval") and not key.startswith(("lft", "small")):
            prefix = key[:-len("stable_interval")]
            out.append(("design family" if not prefix else prefix.rstrip("_"), prefix))
    return out


def _margins(s: dict, config: dict) -> tuple | None:
    """The gain [dB] and phase [deg] margin thresholds of the robust flutter speed."""
    m = (s.get("verification") or {}).get("margins") or _family_config(config, "margins")
    return tuple(m) if m else None


def _family_warnings(summary: dict, config: dict | None = None) -> list[str]:
    """The warnings of a run on a plant family file, each in one sentence, read off its
    summary: an open loop unstable already at the range's start, an interval the design did
    not hold, an H∞ phase that did not converge, a certificate that does not cover the
    required interval, margins that fall short inside it, and the controller's pole flags.

    Parameters
    ----------
    summary : dict
        The run's summary (``summary.json``, ``route`` ``"family"``).
    config : dict, optional
        The run's configuration (``config.json``): the margin thresholds where the summary
        does not give them.

    Returns
    -------
    list of str
        Empty when nothing is flagged.
    """
    s, config = summary, config or {}
    fam, ctrl = s.get("family") or {}, s.get("controller") or {}
    ver = s.get("verification") or {}
    unit = fam.get("speed_unit") or (s.get("units") or {}).get("speed", "")
    out = []
    lo_range = (fam.get("speed_range") or [None])[0]
    if fam.get("unstable_at_start"):
        out.append(f"The open-loop family is unstable already at the low end of its range, "
                   f"{sig(lo_range)} {unit} (spectral abscissa "
                   f"{sig(fam.get('spectral_abscissa_start'), 3)}): it has no flutter speed, "
                   "and its crossings are no flutter onsets.")
    if not ctrl:
        return out
    if ctrl.get("method") == "multispeed" and ctrl.get("held") is False:
        out.append(f"The design did not hold the requested interval {sig(ctrl.get('interval'))} "
                   f"{unit}: {ctrl.get('design_message')}.")
    if ctrl.get("hinf_converged") is False:
        out.append(f"The H∞ phase stopped after {ctrl.get('hinf_iterations')} iterations "
                   "without converging: the controller is the best found, not a local minimum "
                   "of its objective; the certificates below are its own.")
    required = ver.get("required_V")
    iv = ctrl.get("stable_interval")
    if ver.get("interval_ok") is False:
        out.append(f"The certified stable interval {sig(iv, none='(none)')} {unit} does not "
                   f"cover the required {sig(required)} {unit}.")
    robust = ctrl.get("robust_flutter_speed")
    margins = _margins(s, config)
    thresholds = "" if margins is None else f" ({sig(margins[0])} dB / {sig(margins[1])} deg)"
    if required and iv is not None and robust is not None:
        top = min(required[1], iv[1] if iv[1] is not None else float("inf"))
        if robust < top:
            reasons = [r for r in str(ctrl.get("robust_flutter_reason") or "").split("; ") if r]
            more = f" and {len(reasons) - 1} more" if len(reasons) > 1 else ""
            why = f" ({reasons[0]}{more})" if reasons else ""
            where = (f"fail already at {sig(robust)} {unit}, the certified interval's start"
                     if robust <= iv[0] else f"hold only to {sig(robust)} {unit}")
            required_too = ("; the run's checks require them (verify.require_margins)"
                            if ver.get("require_margins") else "")
            out.append(f"The loop is certified stable to {sig(iv[1], none='∞')} {unit}, but "
                       f"its loop-at-a-time margins{thresholds} {where}{why}: up to "
                       f"{sig(top)} {unit}, inside the required {sig(required)} {unit}, it is "
                       f"stable, not robustly so{required_too}.")
    for w in (ctrl.get("poles") or {}).get("warnings", ()):
        out.append(f"The controller's poles: {w}.")
    return out


def _family_section(s: dict) -> str:
    """The family: name, size, speeds, signals, feedback, the states left out."""
    fam = s.get("family") or {}
    left = fam.get("left_out_states") or []
    states = f"{_fmt(fam.get('n_states'))} analysed"
    if left:
        states += (f" of the file's {_fmt(fam.get('n_states_file'))}; left out (0-based) "
                   f"{html.escape(str(left))}: poles at the origin that feed no output and no "
                   "other state (rigid-body positions or integrators that no sensor sees); "
                   "every closed loop keeps them, whatever the controller")
    feedback = fam.get("feedback")
    sign = {"negative": "u = −K(s) y", "positive": "u = +K(s) y"}.get(feedback)
    rows = [("family", html.escape(str(fam.get("name"))))]
    if fam.get("description"):
        rows.append(("description", html.escape(str(fam["description"]))))
    rows += [("states", states),
             ("speed range", _speed(fam.get("speed_range"), fam.get("speed_unit"))),
             ("time unit", html.escape(str(fam.get("time_unit")))),
             ("controls (the controller's outputs)", _names(fam.get("controls"))),
             ("measurements (the controller's inputs)", _names(fam.get("measurements")))]
    if fam.get("disturbances"):
        rows.append(("disturbance inputs", _names(fam["disturbances"])))
    rows.append(("feedback sign", html.escape(str(feedback))
                 + (f" (the loop is closed with {sign})" if sign else "")))
    return "<h2>The plant family</h2>\n" + _rows(rows)


def _open_loop_section(s: dict) -> str:
    """The open loop's flutter (first destabilising crossing) and every crossing."""
    fam, fl = s.get("family") or {}, s.get("flutter") or {}
    unit, tu = fam.get("speed_unit"), fam.get("time_unit")
    crossings = fam.get("crossings") or []
    onset = next((c for c in crossings if c.get("direction") == "destabilizing"
                  and c.get("kind") == "flutter"), None)
    if fam.get("unstable_at_start"):
        text = (f"The open-loop family is unstable already at "
                f"{_speed((fam.get('speed_range') or [None])[0], unit)} (spectral abscissa "
                f"{_fmt(fam.get('spectral_abscissa_start'), 3)}): no flutter speed.")
    elif fl.get("V") is not None:
        freq = onset and onset.get("omega_rad_s")
        text = (f"Open-loop flutter speed {_speed(fl['V'], unit)}, at "
                f"{_frequency(fl.get('freq_hz'), freq, tu)}.")
    else:
        text = (f"No open-loop flutter in the family's range "
                f"{_speed(fam.get('speed_range'), unit)} (status "
                f"{html.escape(str(fam.get('status') or fl.get('status')))}).")
    rows = "\n".join(
        f"<tr><td>{_speed(c.get('speed'), unit)}</td>"
        f"<td>{_frequency(c.get('freq_hz'), c.get('omega_rad_s'), tu)}</td>"
        f"<td>{html.escape(str(c.get('kind')))}</td>"
        f"<td>{html.escape(str(c.get('direction')))}</td><td>{_fmt(c.get('branch'))}</td></tr>"
        for c in crossings)
    table = ("" if not crossings else
             "<table><tr><th>speed</th><th>frequency</th><th>kind</th><th>direction</th>"
             f"<th>branch</th></tr>\n{rows}</table>")
    return f"<h2>Open loop</h2>\n<p>{text}</p>\n{table}"


def _controller_section(s: dict, config: dict) -> str:
    """The controller's design: order, interval, held or reach, γ and its objective, the
    H∞ phase, the poles, the time."""
    ctrl, fam = s.get("controller") or {}, s.get("family") or {}
    if not ctrl:
        return ("<h2>Controller</h2>\n<p>No controller was designed (the run's stages did "
                "not include 'controller').</p>")
    unit, tu = fam.get("speed_unit"), fam.get("time_unit")
    rows = [("order", _fmt(ctrl.get("order"))),
            ("method", html.escape(str(ctrl.get("method"))))]
    if ctrl.get("method") == "multispeed":
        rows.append(("design interval", _speed(ctrl.get("interval"), unit)
                     + (f", closed-loop decay rate {_fmt(ctrl.get('interval_decay'))} rad/"
                        f"{html.escape(str(tu))} at every speed"
                        if ctrl.get("interval_decay") is not None else "")))
        reach = ctrl.get("reach")
        held = ("held: the whole interval" if ctrl.get("held") else
                f"not held: reached up to {_speed(reach, unit)}")
        rows.append(("interval held", held))
    if ctrl.get("start"):
        rows.append(("start controller", html.escape(str(ctrl["start"]))))
    gamma = ctrl.get("design_gamma", ctrl.get("synthesis_gamma"))
    if gamma is None:
        rows.append(("H∞ objective γ", "no H∞ phase (controller.hinf_speeds = 0): the design "
                     "asks only for the decay rate"))
    else:
        rows.append(("H∞ objective γ", f"{_fmt(gamma)}: {_objective_text(s, config)}"))
    conv = ctrl.get("hinf_converged")
    rows.append(("H∞ phase converged", "—" if conv is None else
                 f"yes, after {_fmt(ctrl.get('hinf_iterations'))} iterations" if conv else
                 f"no: stopped after {_fmt(ctrl.get('hinf_iterations'))} iterations; the "
                 "controller is the best found"))
    poles = ctrl.get("poles") or {}
    if poles.get("natural_frequencies_hz"):
        cycles = "Hz" if tu == "s" else f"cycles per {html.escape(str(tu))}"
        rows.append(("controller poles' natural frequencies",
                     f"{_fmt(poles['natural_frequencies_hz'])} {cycles}"
                     + ("; the controller itself is unstable" if poles.get("unstable") else "")))
    rows.append(("design time", f"{_fmt(ctrl.get('design_time_s'))} s"))
    message = ctrl.get("design_message")
    return ("<h2>Controller</h2>\n" + _rows(rows)
            + (f"\n<p>{html.escape(str(message))}.</p>" if message else ""))


def _verification_section(s: dict, config: dict) -> str:
    """The certified stable interval(s), the absolute and robust flutter speeds, the
    required interval, and the margins."""
    ctrl, fam = s.get("controller") or {}, s.get("family") or {}
    ver = s.get("verification") or {}
    if not ctrl:
        return ""
    unit = fam.get("speed_unit")
    top = (fam.get("speed_range") or [None, None])[1]
    rows = []
    for name, prefix in _certificates(ctrl):
        iv = ctrl.get(prefix + "stable_interval")
        text = ("none: the closed loop is unstable already at the range's start" if iv is None
                else _speed(iv, unit))
        if iv is not None and top is not None and iv[1] is not None and iv[1] >= top:
            text += " (to the top of the family's range)"
        rows.append((f"certified stable interval ({name})", text))
        absolute = ctrl.get(prefix + "absolute_flutter_speed")
        robust = ctrl.get(prefix + "robust_flutter_speed")
        rows.append((f"absolute / robust flutter speed ({name})",
                     ("none (stable over the whole range)" if absolute is None
                      else _speed(absolute, unit)) + " / "
                     + ("none (the margins hold over the whole range)" if robust is None
                        else _speed(robust, unit))))
    if ver.get("required_V"):
        ok = ver.get("interval_ok")
        rows.append(("required interval", _speed(ver["required_V"], unit)
                     + ("" if ok is None else ": covered" if ok else ": not covered")))
    if ver.get("success") is not None:
        rows.append(("checks passed", "yes" if ver["success"] else "no"))
    margins = _margins(s, config)
    reasons = [r for r in str(ctrl.get("robust_flutter_reason") or "").split("; ") if r]
    text = ("<p>The absolute flutter speed is where the closed loop loses stability, the "
            "robust flutter speed where its loop-at-a-time gain and phase margins"
            + ("" if margins is None else f" ({sig(margins[0])} dB / {sig(margins[1])} deg)")
            + " are lost.")
    if ver.get("robust_ok") is not None:
        text += (" Over the required interval the margins "
                 + ("hold." if ver["robust_ok"] else "do not hold")
                 + ("" if ver["robust_ok"] else
                    " (required by the run's checks)." if ver.get("require_margins") else
                    " (reported, not required: verify.require_margins = true makes it a "
                    "check)."))
    text += "</p>"
    if reasons:
        text += ("\n<p>What fails at the robust flutter speed (design family):</p>\n<ul>" + "".join(f"<li>{html.escape(r)}</li>" for r in reasons)
                 + "</ul>")
    for name, m in (ctrl.get("model_error") or {}).items():
        worst = m.get("worst_relative_error") or []
        text += (f"\n<p>Response error of the design family against the {html.escape(name)}: "
                 f"worst relative error {_fmt(max(worst) if worst else None)} over the "
                 f"speeds {_speed(m.get('speeds'), unit)}.</p>")
    return "<h2>Verification</h2>\n" + _rows(rows) + "\n" + text


def _family_report(s: dict, figures: dict, title: str, captions: dict, config: dict) -> str:
    """The design report of a run on a plant family file (:func:`html_report`)."""
    fam = s.get("family") or {}
    name, problem = str(fam.get("name") or s.get("problem")), str(s.get("problem"))
    heading = (f"{title}: controller design on the plant family {name}"
               + ("" if problem in (name, "None") else f" ({problem})"))
    unit = fam.get("speed_unit") or (s.get("units") or {}).get("speed", "")
    warnings = _family_warnings(s, config)
    warn = ("" if not warnings else "<h2>Warnings</h2>\n<ul>" + "".join(
        f'<li class="flag">{html.escape(w)}</li>' for w in warnings) + "</ul>")
    skipped = s.get("skipped") or {}
    notes = ("" if not skipped else "<h2>Not run</h2>\n<ul>" + "".join(
        f"<li>{html.escape(str(v))}</li>" for v in skipped.values()) + "</ul>")
    intro = (f"<p>A fixed-order controller designed on the plant family {html.escape(name)}: "
             f"linear state-space models at a grid of speeds, read from the family file, and "
             f"certified on them by the verification. Speeds in {html.escape(str(unit))}, "
             f"time in {html.escape(str(fam.get('time_unit')))}. Seed {_fmt(s.get('seed'))}; "
             f"casflutter {_fmt(s.get('casflutter_version'))}.</p>")
    body = "\n".join(part for part in (
        intro, warn, _family_section(s), _open_loop_section(s), _controller_section(s, config),
        _verification_section(s, config), _figures_html(figures, captions), notes,
        _timings_html(s)) if part)
    return _page(heading, heading, body)
