"""A self-contained HTML report: the figures embedded, Table I beside the paper's values."""

from __future__ import annotations

import base64
import html
from pathlib import Path

__all__ = ["html_report", "PAPER_TABLE_I"]

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


def _fmt(x, digits=4):
    if x is None:
        return "—"
    if isinstance(x, float):
        return f"{x:.{digits}g}"
    if isinstance(x, (list, tuple)):
        return "(" + ", ".join(_fmt(v, digits) for v in x) + ")"
    return html.escape(str(x))


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
    fl, ctrl = s.get("flutter") or {}, s.get("controller") or {}
    lco, sup = s.get("lco") or {}, s.get("suppression") or {}
    ours = {
        "nominal speed index V0": s.get("V0"),
        "number of modes N": s.get("ns", 0) // 2,
        "(mu, na, nb, r, p, q)": tuple(s.get("orders") or []),
        "order of Σf nf": s.get("nf"),
        "order of Σs": s.get("ns"),
        "order of ΣAE": s.get("nae"),
        "flutter speed index Vf": fl.get("V"),
        "flutter mode": fl.get("mode"),
        "LCO fundamental frequency [Hz]": lco.get("freq_hz"),
        "order of controller K(s)": ctrl.get("order"),
        "number of sensors": s.get("n_sensors"),
        "stable speed range (controller)": ctrl.get("stable_V"),
        "LCO attenuation": (None if sup.get("attenuation_percent") is None
                            else f"{sup['attenuation_percent']:.1f} %"),
    }
    ft = s.get("flutter_truth") or {}
    truth = {   # the truth simulator's own values, where it has one
        "flutter speed index Vf": ft.get("V"),
        "stable speed range (controller)": ctrl.get("truth_stable_V"),
        "flutter mode": ft.get("mode"),
        "LCO fundamental frequency [Hz]": (lco.get("truth_freq_hz")
                                           if lco.get("truth_kind") == "lco" else None),
    }
    rows = "\n".join(f"<tr><td>{html.escape(k)}</td><td>{_fmt(ours.get(k))}</td>"
                     f"<td>{_fmt(truth.get(k))}</td>"
                     f"<td>{html.escape(v)}</td></tr>" for k, v in PAPER_TABLE_I.items())
    fit = ", ".join(f"{e:.3f}" for e in s.get("fit_error_percent") or [])
    imgs = []
    for name, path in figures.items():
        data = base64.b64encode(Path(path).read_bytes()).decode("ascii")
        caption = captions.get(name) or Path(path).name
        imgs.append(f'<figure><img alt="{html.escape(caption)}" '
                    f'src="data:image/png;base64,{data}">'
                    f"<figcaption>{html.escape(caption)}</figcaption></figure>")
    lco_text = ""
    if lco.get("amplitude") is not None and lco.get("truth_amplitude") is not None:
        lco_text = (f"<p>LCO amplitude per sensor (half peak to peak), each model a little "
                    f"above its own flutter speed: ROM {_fmt(lco['amplitude'])} at "
                    f"V = {_fmt(lco.get('V'))}, truth {_fmt(lco['truth_amplitude'])} at "
                    f"V = {_fmt(lco.get('truth_V'))}.</p>")
    timings = s.get("timings_s", {})
    trows = "\n".join(f"<tr><td>{html.escape(k)}</td><td>{v:.2f}</td></tr>"
                      for k, v in timings.items() if isinstance(v, (int, float)))
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>
<style>body{{font-family:sans-serif;max-width:960px;margin:2em auto;color:#222}}
table{{border-collapse:collapse;margin:1em 0}}td,th{{border:1px solid #bbb;padding:4px 10px}}
th{{background:#eee}}img{{max-width:100%}}figure{{margin:1.5em 0}}
figcaption{{font-size:90%;color:#555}}</style></head><body>
<h1>{html.escape(title)}: {html.escape(str(s.get('problem')))}</h1>
<p>Reproduction of K.-Y. Lum et al., ACC 2016, on casflutter's truth simulator
(the paper's CFD and wind tunnel are not available). Seed {_fmt(s.get('seed'))}.</p>
<h2>Table I</h2>
<table><tr><th>quantity</th><th>this run (ROM)</th><th>truth simulator</th><th>paper</th></tr>
{rows}</table>
<p>ROM fit error per mode [%]: {fit}. Truth flutter: V = {_fmt(ft.get('V'))},
{_fmt(ft.get('freq_hz'))} Hz. Controller: verified γ = {_fmt(ctrl.get('gamma'))},
small-gain interval of V {_fmt(ctrl.get('small_gain_V'))}, exact stable interval {_fmt(ctrl.get('stable_V'))}
on the ROM loop and {_fmt(ctrl.get('truth_stable_V'))} on the truth's own linearisation (flap
behind a servo of {_fmt(ctrl.get('truth_servo_omega'))} rad/s).</p>
{lco_text}
<h2>Figures</h2>
{''.join(imgs)}
<h2>Timings [s]</h2>
<table>{trows}</table>
</body></html>
"""
