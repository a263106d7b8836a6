"""``casflutter run``: a study run of a configuration (default: the paper's study on the seed
wing with its controller designed over speed, ``problems/seed_wing/run.toml``).

Exit status: 0 when the run finished and every check it made passed (the ``verify.required``
interval, and the margins over it with ``verify.require_margins``; the closed-loop
simulations; a ROM loop stable at the start of ``flutter.V_range``),
3 when it finished and wrote its outputs but a check failed (``checks passed: False``;
summary.json says which), 1 or 2 for a run refused or stopped.  A stage named in
``stages`` that cannot run on the problem (``lco`` on a linear ROM, a stage that needs a
simulator on a wing file ...) is refused before any work (1); only a stage of the default
list (``stages`` left out, or spelt out as that list) that cannot run is skipped, with a
note (summary.json ``skipped``), and leaves the status as it is.  On a rig file the keys in
its own units (``data.V0``, ``dt``, ``duration``, ``band``, ``flutter.V_range``) that the
configuration leaves out come from the file's ``[rom]`` table (as ``casflutter flutter``
takes them), not from the seed wing's defaults; one that neither gives, and
``data.coupling_delay`` left out, is refused before any work (1), named."""

from __future__ import annotations

import json
import math
import sys
import tomllib

from ..._format import sig
from ..._outputs import check_output_path
from ...errors import ConfigError


def _speed(block) -> str:
    """``V = 1.2 (speed index), U = 34.68 m/s, q = 736.6 Pa`` of a flutter block."""
    if block is None or block.get("V") is None:
        return "V = None"
    text = f"V = {sig(block['V'])} (speed index)"
    if block.get("airspeed_m_s") is not None:
        text += f", U = {sig(block['airspeed_m_s'])} m/s"
    if block.get("dynamic_pressure_Pa") is not None:
        text += f", q = {sig(block['dynamic_pressure_Pa'], 4)} Pa"
    return text


def _unstable_at_start(block, V_lo: float) -> str:
    """The flutter line of a loop unstable already at the start of ``flutter.V_range``: no
    flutter speed, and its crossing (if any) no flutter onset."""
    text = (f"none: the loop is unstable already at V = {sig(V_lo)}, the start of "
            f"flutter.V_range (spectral abscissa {sig(block['spectral_abscissa_start'], 3)})")
    if block.get("V") is not None:
        text += f"; its crossing at V = {sig(block['V'])} is no flutter onset"
    return text


def _controller_lines(c: dict, res, unit: str) -> list[str]:
    """The controller's design and its certificates, γ said for what it is (eq. 16)."""
    lines = [f"controller order {c['order']} ({c['method']} design, "
             f"{sig(c['design_time_s'], 3)} s)"]
    if c["method"] == "multispeed":
        lines.append(f"  design over {sig(c['interval'])} {unit}: "
                     + ("held" if c["held"] else f"not held ({c['design_message']})"))
    if c.get("hinf_converged") is False:
        lines.append(f"  its H∞ optimisation stopped after {c['hinf_iterations']} iterations "
                     f"(controller.max_outer = {res.config.controller.max_outer}, "
                     f"extra_outer = {res.config.controller.extra_outer}) without "
                     "converging: the controller is the best found; the certificates below "
                     "are its own")
    if c.get("gamma") is not None:
        lines.append(f"  verified γ = {sig(c['gamma'])} (‖T_w̄z‖∞ of the LFT at Vf, eq. 16), "
                     f"small-gain V {sig(c['small_gain_V'])}, exact V {sig(c['lft_stable_V'])}")
    syn = res.synthesis
    if syn is not None and res.config.controller.flap_rate_weight > 0:
        lines.append(f"  the synthesis's γ {sig(syn.gamma)} is of its design plants, which add "
                     "the flap-rate output (controller.flap_rate_weight = "
                     f"{sig(res.config.controller.flap_rate_weight)})")
    gm, pm = res.config.controller.margins
    servo = (f", flap behind a {sig(c['servo_omega'])} rad/s servo"
             if c.get("servo_omega") else "")
    for prefix, label in (("", "design model"), ("truth_", "truth's linearisation")):
        if f"{prefix}stable_interval" not in c:
            continue
        iv, robust = c[prefix + "stable_interval"], c[prefix + "robust_flutter_speed"]
        # a robust flutter speed at the certified interval's start: the margins fail there
        at_start = robust is not None and iv is not None and robust <= iv[0]
        lines.append(f"  on the {label}{servo}: certified stable over "
                     f"{sig(iv, none='no interval')} {unit}; absolute / robust flutter speed "
                     f"{sig(c[prefix + 'absolute_flutter_speed'], none='none')} / "
                     + (f"none: the margins ({gm:g} dB / {pm:g} deg) fail already at "
                        f"{sig(robust)}" if at_start else sig(robust, none='none')))
    for w in (c.get("poles") or {}).get("warnings", ()):
        lines.append(f"  warning: {w}")
    return lines


def _margins_line(res, unit: str) -> str:
    """Whether the loop-at-a-time margins hold over the required interval, in the words
    of ``casflutter verify --require-v`` (which fails a controller whose margins do not),
    and whether the run's checks require them (``verify.require_margins``)."""
    check, (lo, hi) = res.control.checks["design"], res.required_V
    gm, pm = res.config.controller.margins
    head = (f"margins ({gm:g} dB / {pm:g} deg) on the design model over the required "
            f"[{lo:.5g}, {hi:.5g}] {unit}: ")
    if res.robust_ok:
        return head + "held (robust)"
    rfs, reasons = check.robust_flutter_speed, check.robust_reason.split("; ")
    more = f" and {len(reasons) - 1} more" if len(reasons) > 1 else ""
    why = ("" if rfs is None or not check.covers(lo, hi) else
           f" from {rfs:.5g} {unit} ({reasons[0]}{more})")
    return (head + f"not held{why}: stable, not robust; casflutter verify --require-v "
            f"{lo:.5g} {hi:.5g} fails this controller"
            + ("" if res.config.verify.require_margins else
               " (reported, not required: verify.require_margins = true makes it a check)"))


def _model_lines(s: dict) -> list[str]:
    """The model stages: the ROM, the RFA of a GAF wing file, or a plant family."""
    if s.get("family") is not None:
        f = s["family"]
        return [f"problem {s['problem']}: plant family of {f['n_states']} states over "
                f"{sig(f['speed_range'])} {f['speed_unit']}, controls {', '.join(f['controls'])}; "
                f"measurements {', '.join(f['measurements'])} ({f['feedback']} feedback)"]
    if s["orders"] is not None:
        return [
            f"problem {s['problem']}: orders {tuple(s['orders'])}, {s['n_params']} parameters, "
            f"nf = {s['nf']}, ns = {s['ns']}, nae = {s['nae']}",
            "ROM fit error per mode [%]: " + ", ".join(sig(e, 4)
                                                       for e in s["fit_error_percent"])]
    r = s["rfa"]                     # a GAF wing file: the RFA of Q(ik) in place of the ROM
    lines = [f"problem {s['problem']}: {r['method']} RFA, {r['n_lags']} lag roots, fit "
             f"error {r['fit_error']:.3g}, ns = {s['ns']}, nae = {s['nae']}"]
    for key, label in (("flutter", "RFA ΣAE(U)"), ("pk", "p-k")):
        b = r[key]
        if b is not None:
            lines.append(f"flutter ({label}): U = {sig(b['airspeed_m_s'])} m/s, "
                         f"{sig(b['omega_rad_s'])} rad/s, mode {b['mode']}")
    return lines


#: characters that make a ``--set`` value TOML rather than a bare word
_TOML_MARKS = set("[]{}\"'=,#")


def _value(key: str, text: str):
    """A ``--set`` value: a TOML value (``4``, ``0.03``, ``true``, ``[0.05, 2.4]``,
    ``"text"``), or a bare word (``sensitivity``) as a string."""
    try:
        return tomllib.loads(f"value = {text}")["value"]
    except tomllib.TOMLDecodeError:
        if text and not _TOML_MARKS & set(text) and not text[0].isdigit():
            return text
        raise ConfigError(f"--set {key}={text}: {text!r} is not a value; give a number, true "
                          "or false, a list such as [0.05, 2.4], or a word or \"quoted "
                          "text\"") from None


def config_updates(items) -> dict:
    """``--set KEY=VALUE`` items as :func:`casflutter.pipeline.load_config` updates: the
    key dotted (``controller.order``, ``problem.set.zeta``), the value read as in the
    configuration file."""
    from ...truth import parse_sets

    return {key: _value(key, text) for key, text in parse_sets(items).items()}


def _main(args) -> int:
    from ...pipeline import check_requested_stages, load_config, run

    # validated before any work starts
    cfg = load_config(args.config, updates=config_updates(args.sets))
    check_requested_stages(cfg)         # a stage asked for by name that cannot run: refused
    # a path that cannot be a folder is refused before the package's stages are even
    # imported; the driver then refuses a non-empty folder without --overwrite, before any
    # work, and writes the outputs atomically at the end
    check_output_path(args.out, what="--out", kind="dir")
    log_quiet = args.quiet or bool(getattr(args, "log_quiet", False))
    res = run(cfg, out_dir=args.out, seed=args.seed, quiet=log_quiet, overwrite=args.overwrite)
    s = res.summary()
    fl, ft = s["flutter"], s["flutter_truth"]
    lines = _model_lines(s)
    family = s.get("family")
    if family is not None:
        unit = family["speed_unit"]
        lines.append("open loop: " + res.flutter.onsets(unit, family["time_unit"]))
    else:
        unit = "(speed index)"
        lines.append(f"speeds: V is the {s['units']['V']}")
        hz = s["units"].get("freq_hz") or "Hz"     # cycles per time unit in nondimensional time
        if fl is not None:
            what = "ROM" if s["orders"] is not None else "ΣAE(V), Σf frozen at Uf"
            if fl.get("unstable_at_start"):
                lines.append(f"flutter ({what}):   "
                             + _unstable_at_start(fl, res.config.flutter.V_range[0]))
            else:
                lines.append(f"flutter ({what}):   {_speed(fl)}, {sig(fl['freq_hz'])} {hz}, "
                             f"mode {fl['mode']}")
        fc = s.get("flutter_convective")
        if fc is not None:
            lines.append(f"flutter (ROM following the wing over speed): {_speed(fc)}, "
                         f"{sig(fc['freq_hz'])} {hz}, mode {fc['mode']}")
        if ft is not None:
            lines.append(f"flutter (truth): {_speed(ft)}, {sig(ft['freq_hz'])} {hz}, "
                         f"mode {ft['mode']}")
        rev = s.get("control_reversal_V") or {}
        if any(v is not None for v in rev.values()):
            lines.append("flutter mode's control reversal (flap behind the servo): " + ", ".join(
                f"{name.replace('_', '-')} V = {sig(v, 4)}" for name, v in rev.items()
                if v is not None))
        if s["lco"] is not None:
            kind = s["lco"]["kind"]
            lines.append(f"LCO: {sig(s['lco']['freq_hz'])} {hz} ({kind})" if kind == "lco"
                         else f"LCO: none, the ROM loop's response is a {kind}")
            following = s["lco"].get("speed_following") or []
            if following:
                lines.append("speed-following ROM's LCO amplitude vs the truth's: " + "; ".join(
                    f"{c['speed_factor']:g} Vf " + (", ".join(
                        f"{e:+.1f} %" for e in c["amplitude_error_percent"])
                        if None not in c["amplitude_error_percent"] else
                        f"ROM {c['rom_kind']}, truth {c['truth_kind']}")
                    for c in following))
    if s["controller"] is not None:
        lines += _controller_lines(s["controller"], res, unit)
    if s["suppression"] is not None:
        for r in s["suppression"]["runs"]:
            lines.append(f"suppression at {r['speed_factor']:g} Vf (V = {sig(r['V'], 4)}): "
                         f"attenuation {sig(r['attenuation_percent'], 4)} %, flap peak "
                         f"{sig(math.degrees(r['flap_peak']), 3)} deg, rate peak "
                         f"{sig(math.degrees(r['flap_rate_peak']), 3)} deg/s"
                         + (f" (at the rate limit {r['flap_rate_saturated_percent']:.0f} % of "
                            "the hold)" if r.get("flap_rate_saturated_percent") else "")
                         + f", LCO returns on release: {r['lco_returns']}"
                         + ("; the truth's linearised loop is not certified stable at this "
                            "speed" if r.get("linear_loop_certified") is False else ""))
    if log_quiet:                    # otherwise the log said it once already
        lines += res.skipped_notes()
    checked = (res.interval_ok is not None or res.closed_loop is not None
               or res.rom_unstable_at_start)
    if res.robust_ok is not None:
        lines.append(_margins_line(res, unit))
    if checked:
        lines.append(f"checks passed: {res.success}")
    lines.append(f"total {s['timings_s']['total']:.1f} s; outputs in {res.out_dir}/")
    if args.json:
        print(json.dumps(s, indent=2))
    elif not args.quiet:
        print("\n".join(lines))
    if checked and not res.success:
        print(f"casflutter run: a check failed (see {res.out_dir}/summary.json)",
              file=sys.stderr)
        return 3
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("run", help="the paper's study end to end (default: seed wing)",
                              description=__doc__)
    p.add_argument("config", nargs="?", help="TOML configuration (default: the seed wing's)")
    p.add_argument("--out", default="casflutter-run",
                   help="output folder (written beside itself as OUT.incomplete-XXXXXX and "
                        "moved into place at the end)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing non-empty output folder (refused otherwise, "
                        "before any work)")
    p.add_argument("--seed", type=int, help="overrides the configuration's seed")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                   help="change one key of the configuration (repeatable), dotted as "
                        "TABLE.KEY and valued as in the file: --set controller.order=4 "
                        "--set 'controller.interval=[0.05, 2.0]' --set problem.set.zeta=0.03")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.add_argument("--json", action="store_true", help="print summary.json")
    p.set_defaults(func=_main)
