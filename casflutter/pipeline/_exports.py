"""What a study run writes: the output folder, its manifest and self-describing exports.

The folder is written beside its target under a name that says it is incomplete and moved
into place at the end (:func:`casflutter._outputs.atomic_folder`), with ``manifest.json``
(configuration hash, version, seed, thread settings, completed stages, start and end time,
a SHA-256 per file).  An existing non-empty folder is refused before any work unless the run
is told to overwrite it (:func:`check_output_folder`).

The controller (``controller.json``, ``controller.mat``) and the plant it was designed on
(``plant.json``, the LFT of eq. 14 at Vf) carry their signal names and units, the sign
convention, the time base, Vf (speed index, and airspeed / dynamic pressure when the problem
has a speed scale), the certified speed intervals (small-gain and exact, eq. 10-16) and the
package version, so that ``casflutter verify OUT/plant.json OUT/controller.json`` reproduces
the run's own verification.  A controller whose poles are faster than the Nyquist frequency
of the identification data, or than the flap actuator's bandwidth, is logged as a warning
and flagged in ``summary.json`` (:func:`controller_pole_check`).
"""

from __future__ import annotations

import json
import logging
import math
from pathlib import Path

import numpy as np
from scipy.io import savemat

from .._outputs import MANIFEST_NAME, atomic_folder
from .._outputs import check_output_folder as _check_folder
from .._outputs import plain_json, provenance, write_manifest
from ..report import figure_captions, write_figures, write_html
from ..verify import controller_to_json, plant_to_json
from ._units import (FLAP_UNIT, interval_values, sensor_units, speed_scale, speed_values,
                     units_block)

__all__ = ["check_output_folder", "controller_pole_check", "controller_document",
           "plant_document", "label_summary", "log_flags", "write_outputs", "SIGN_CONVENTION",
           "DEFAULT_OUT"]

log = logging.getLogger("casflutter.pipeline")

#: The output folder of a run when none is given.
DEFAULT_OUT = "casflutter-run"

#: How the controller closes the loop (the LFT's ``u = K y`` and the truth's flap command).
SIGN_CONVENTION = ("v = K zm: the flap command v is K applied to the sensor readings zm, "
                   "added with a plus sign (positive feedback); with the plant file the loop "
                   "is the lower LFT F_l(P, K) with u = K y (control.hinfsyn convention)")


def _problem(result):
    """The loaded problem: the truth, or a wing file's problem (``result.problem``)."""
    problem = getattr(result, "problem", None)
    return problem if problem is not None else result.truth


def _structure(result):
    """Σs of the run's ROM or RFA loop (``None`` for a family file)."""
    system = result.system if result.system is not None else getattr(result, "rfa_system", None)
    return None if system is None else system.structure


def _time_unit(result) -> str:
    structure = _structure(result)
    return structure.time_unit if structure is not None else result.model.family.time_unit


def check_output_folder(out_dir, *, overwrite: bool = False) -> Path:
    """Check a run's output folder before any work.

    Parameters
    ----------
    out_dir : path or None
        The folder (``None``: :data:`DEFAULT_OUT`).
    overwrite : bool
        Whether an existing non-empty folder may be replaced.

    Returns
    -------
    pathlib.Path
        The folder to write (``out_dir`` or :data:`DEFAULT_OUT`).

    Raises
    ------
    OutputError
        The folder (or the folder that holds it) cannot be created or written, or it exists
        and is not empty without ``overwrite``.
    """
    return _check_folder(out_dir if out_dir is not None else DEFAULT_OUT,
                         what="output folder", overwrite=overwrite)


# ---------------------------------------------------------------------- controller poles
#: a controller pole this many times faster than every pole of the plant it was designed on
#: is flagged (:func:`controller_pole_check`)
FASTER_THAN_PLANT = 100.0


def plant_speed(family, lo: float, hi: float, n: int = 9) -> float:
    """The fastest natural frequency ``max |λ|`` of the family's poles [rad per time unit]
    over ``n`` speeds of ``[lo, hi]`` (and the grid speeds inside it)."""
    grid = family.speed_grid(n, lo, hi) if hi > lo else [lo]
    return float(max(np.max(np.abs(np.linalg.eigvals(family.state_matrix(V))), initial=0.0)
                     for V in grid))


def controller_pole_check(K, *, dt: float | None, actuator_omega: float | None = None,
                          time_unit: str = "s", plant_omega: float | None = None
                          ) -> dict | None:
    """Compare the controller's poles with the data's Nyquist frequency, the actuator and the
    plant.

    A continuous controller pole ``λ`` has the natural frequency ``|λ|`` [rad per time unit].
    Faster than ``π / dt`` (the Nyquist frequency of records sampled every ``dt``) it acts
    where the ROM was never identified; faster than the actuator's natural frequency the
    flap cannot follow it; :data:`FASTER_THAN_PLANT` times faster than the plant's fastest
    pole, the loop's speed is set where the plant's model says nothing (a design that raised
    the gain without bound, on a plant whose abscissa keeps falling with it).

    Parameters
    ----------
    K : control.StateSpace
        The controller (continuous time).
    dt : float or None
        Sample time of the identification records (``None``: no sampled data).
    actuator_omega : float, optional
        Natural frequency of the flap actuator [rad per time unit].
    time_unit : str
        The problem's time unit (``"s"``: frequencies in Hz).
    plant_omega : float, optional
        The fastest natural frequency of the plant's poles over the design's speeds
        (:func:`plant_speed`) [rad per time unit].

    Returns
    -------
    dict or None
        ``None`` for a static gain; else ``poles`` (``[re, im]`` pairs),
        ``natural_frequencies_hz`` (cycles per time unit), ``nyquist_hz``,
        ``faster_than_nyquist`` (bool or ``None`` without ``dt``), ``actuator_bandwidth_hz``
        and ``faster_than_actuator`` (``None`` without an actuator), ``plant_fastest_hz``
        and ``faster_than_plant`` (``None`` without ``plant_omega``), ``unstable`` (a
        controller pole with ``Re >= 0``), and ``warnings`` (one sentence per flag raised).
    """
    A = np.asarray(K.A, dtype=float)
    if A.size == 0:
        return None
    lam = np.linalg.eigvals(A)
    wn = np.abs(lam)
    fast = float(np.max(wn))
    hz = "Hz" if time_unit == "s" else f"cycles per {time_unit}"
    out = {"poles": [[float(p.real), float(p.imag)] for p in lam],
           "natural_frequencies_hz": [float(w / (2 * np.pi)) for w in wn],
           "nyquist_hz": None, "faster_than_nyquist": None, "actuator_bandwidth_hz": None,
           "faster_than_actuator": None, "plant_fastest_hz": None, "faster_than_plant": None,
           "warnings": []}
    # (key of the reference frequency, key of the flag, reference [rad per time unit],
    # limit, the warning with {poles} for the poles above the limit)
    checks = []
    if dt is not None and math.isfinite(dt) and dt > 0:
        nyq = np.pi / dt
        checks.append(("nyquist_hz", "faster_than_nyquist", nyq, nyq,
                       f"controller poles at {{poles}} {hz} are faster than the "
                       f"{nyq / (2 * np.pi):.4g} {hz} Nyquist frequency of the identification "
                       f"data (dt = {dt:g}): the ROM says nothing about the plant there"))
    if actuator_omega is not None:
        checks.append(("actuator_bandwidth_hz", "faster_than_actuator", actuator_omega,
                       actuator_omega,
                       f"controller poles at {{poles}} {hz} are faster than the flap actuator "
                       f"({actuator_omega / (2 * np.pi):.4g} {hz}, closed_loop.actuator_omega)"))
    if plant_omega is not None and math.isfinite(plant_omega) and plant_omega > 0:
        checks.append(("plant_fastest_hz", "faster_than_plant", plant_omega,
                       FASTER_THAN_PLANT * plant_omega,
                       f"controller poles at {{poles}} {hz} are more than "
                       f"{FASTER_THAN_PLANT:g} times faster than the plant's fastest pole "
                       f"({plant_omega / (2 * np.pi):.4g} {hz} over the design's speeds): the "
                       "loop's speed is set where the plant's model says nothing; give a "
                       "controller of lower gain (a slower decay rate, "
                       "controller.interval_decay) or a model valid that fast"))
    for ref_key, flag_key, ref, limit, text in checks:
        out[ref_key] = float(ref / (2 * np.pi))
        out[flag_key] = bool(fast > limit)
        if fast > limit:
            poles = ", ".join(f"{w / (2 * np.pi):.4g}" for w in sorted(wn[wn > limit])[::-1])
            out["warnings"].append(text.format(poles=poles))
    growing = lam[lam.real >= 0]
    out["unstable"] = bool(growing.size)
    if growing.size:
        poles = ", ".join(f"{p.real:.4g}{p.imag:+.4g}j" if p.imag else f"{p.real:.4g}"
                          for p in sorted(growing, key=lambda p: -p.real) if p.imag >= 0)
        out["warnings"].append(
            f"the controller itself is unstable (poles at {poles} rad per {time_unit}): the "
            "loop is stable only while it is closed; a sensor or actuator that drops out, or "
            "the loop opened for a test, leaves the controller's states growing; "
            "[controller] stable_controller = true asks the design for a stable one")
    return out


def _pole_check(result) -> dict | None:
    if result.controller is None:
        return None
    cfg = result.config
    model = None if result.identification is None else result.identification.model
    dt = (model.dt if model is not None
          else (result.data.dt if result.data is not None else None))
    act = cfg.closed_loop.actuator_omega if "closed_loop" in cfg.stages else None
    family = getattr(result, "controlled_rom", None)
    plant = None
    if family is not None:
        lo, hi = (cfg.controller.interval if cfg.controller.interval is not None
                  else family.speed_range)
        lo, hi = max(lo, family.speed_range[0]), min(hi, family.speed_range[1])
        if math.isfinite(hi) and hi >= lo:
            plant = plant_speed(family, lo, hi)
    return controller_pole_check(result.controller, dt=dt, actuator_omega=act,
                                 time_unit=_time_unit(result), plant_omega=plant)


def log_flags(result) -> None:
    """Log a warning per flag of the controller's poles (:func:`controller_pole_check`)."""
    check = _pole_check(result)
    for text in (check or {}).get("warnings", ()):
        log.warning("%s", text)


# ---------------------------------------------------------------------- exports
def _time_base(sys, time_unit: str) -> dict:
    dt = sys.dt
    discrete = dt not in (None, 0) and dt is not False
    return {"domain": "discrete" if discrete else "continuous",
            "dt": (None if dt is True else float(dt)) if discrete else None,
            "time_unit": time_unit,
            "frequency_unit": f"rad/{time_unit}"}


def _certified(ver, scale) -> dict:
    """γ and the speed intervals of the LFT at Vf (eq. 10-16) in ``ver``."""
    def num(x):
        return None if x is None or not math.isfinite(float(x)) else float(x)
    return {"stable": bool(ver.stable), "gamma": num(ver.gamma),
            "gamma_delta": None if ver.hinf_delta is None else num(ver.hinf_delta.gamma),
            "small_gain_V": interval_values(ver.small_gain_V, scale),
            "small_gain_V_delta": interval_values(ver.small_gain_V_delta, scale),
            "exact_V": interval_values(ver.exact_V if ver.stable else None, scale),
            "note": "speed intervals over which the LFT at Vf (eq. 14, Σf frozen at Vf, flap "
                    "ideal) is certified stable: small-gain (eq. 16, from gamma) and exact "
                    "(eq. 10-15); each in every unit the problem has"}


def _families_certified(result, scale) -> dict:
    """The verification layer's certificate on each model (design family, truth)."""
    out = {}
    for name, check in result.control.checks.items():
        iv = check.stable_interval
        out[name] = {"family": check.family, "speed_unit": check.speed_unit,
                     "stable_interval": interval_values(iv, scale) if scale is not None
                     else (None if iv is None else list(iv)),
                     "absolute_flutter_speed": check.absolute_flutter_speed,
                     "robust_flutter_speed": check.robust_flutter_speed,
                     "margins_thresholds": [check.gain_margin_db, check.phase_margin_deg]}
    return out


def _family_signals(result) -> tuple[list, list]:
    """``inputs`` / ``outputs`` of a controller designed on a family file: its measurements
    and controls, by name, with their units."""
    fam = result.control.family
    sig = fam.signals
    units_out = dict(zip(sig.outputs, sig.output_units))
    units_in = dict(zip(sig.inputs, sig.input_units))
    return ([{"name": n, "unit": units_out[n]} for n in sig.measurements],
            [{"name": n, "unit": units_in[n]} for n in sig.controls])


def controller_document(result) -> dict:
    """``controller.json`` of a run: the matrices and what they mean.

    Parameters
    ----------
    result : RunResult
        A run with a controller.

    Returns
    -------
    dict
        ``A, B, C, D`` (:func:`casflutter.verify.controller_to_json`), ``format``,
        ``casflutter_version``, ``time_base``, ``inputs`` / ``outputs`` (name, signal,
        unit), ``sign_convention``, ``design`` (problem, order, Vf in every unit, the
        speed-index definition, seed), ``certified`` (γ and the small-gain and exact speed
        intervals) and ``poles`` (:func:`controller_pole_check`).
    """
    K, ver, cfg = result.controller, result.verification, result.config
    problem, structure = _problem(result), _structure(result)
    feedback = result.control.family.feedback
    doc = {"format": "casflutter-controller/1",
           "casflutter_version": provenance()["casflutter_version"],
           **controller_to_json(K), "feedback": feedback}
    if structure is None:     # a family file: its own signal names, units and speed unit
        fam = result.control.family
        inputs, outputs = _family_signals(result)
        doc.update({"time_base": _time_base(K, fam.time_unit), "inputs": inputs,
                    "outputs": outputs,
                    "sign_convention": f"u = {'+' if feedback == 'positive' else '-'}K y: the "
                                       "controls are K applied to the measurements, with the "
                                       f"family's {feedback} feedback",
                    "design": {"problem": cfg.problem.name, "order": int(K.nstates),
                               "speed_unit": fam.speed_unit, "seed": cfg.seed},
                    "certified": _families_certified(result, None),
                    "poles": _pole_check(result)})
        return doc
    scale = speed_scale(problem)
    names = tuple(structure.sensor_names)
    units = sensor_units(problem, structure, bool(cfg.sensors.rows))
    if len(names) != K.ninputs:   # pragma: no cover - K acts on the structure's sensors
        names = tuple(f"zm[{j}]" for j in range(K.ninputs))
        units = ("",) * K.ninputs
    servo = cfg.controller.servo_omega
    doc.update({
        "time_base": _time_base(K, scale.time_unit),
        "inputs": [{"name": n, "signal": f"zm[{j}]", "unit": u, "kind": structure.sensor}
                   for j, (n, u) in enumerate(zip(names, units))],
        "outputs": [{"name": "v", "signal": "v", "unit": FLAP_UNIT,
                     "description": "flap deflection command" + (
                         f" (to the flap servo, {servo:g} rad/{scale.time_unit})"
                         if servo > 0 else "")}],
        "sign_convention": SIGN_CONVENTION,
        "design": {"problem": cfg.problem.name, "order": int(K.nstates),
                   "speed_index_definition": scale.definition,
                   "Vf": speed_values(ver.Vf if ver is not None else result.Vf, scale),
                   "seed": cfg.seed},
        "certified": {**({} if ver is None else {"lft": _certified(ver, scale)}),
                      **_families_certified(result, scale)},
        "poles": _pole_check(result)})
    return doc


def plant_document(result) -> dict:
    """``plant.json`` of a run: the LFT of eq. 14 at Vf that the controller was verified on.

    ``casflutter verify plant.json controller.json`` reads ``nmeas``, ``ncon``, ``Vf`` and
    ``n_delta`` from it and so repeats the run's verification.

    Parameters
    ----------
    result : RunResult
        A run with the controller stage.

    Returns
    -------
    dict
        :func:`casflutter.verify.plant_to_json` of the LFT, plus ``format``,
        ``casflutter_version``, ``time_base``, ``inputs`` / ``outputs`` (name, role, unit),
        ``speed_index_definition``, ``Vf_speeds`` (Vf in every unit), ``sign_convention``
        and ``verification`` (what the run found: stability, γ, the intervals).
    """
    lft, ver, cfg = result.lft, result.verification, result.config
    problem, structure = _problem(result), _structure(result)
    scale = speed_scale(problem)
    P = lft.P
    Vf = ver.Vf if ver is not None and ver.Vf is not None else lft.Vf
    doc = plant_to_json(P, lft.nmeas, lft.ncon, Vf=Vf, n_delta=lft.n_delta,
                        name=f"{cfg.problem.name}: LFT of Sigma_AE in dV = V^2 - Vf^2 (eq. 14)")
    nd, nu, ny = lft.n_delta, lft.ncon, lft.nmeas
    m, p = P.ninputs, P.noutputs
    in_labels = list(getattr(P, "input_labels", [])) or [f"u[{i}]" for i in range(m)]
    out_labels = list(getattr(P, "output_labels", [])) or [f"y[{i}]" for i in range(p)]
    sens = sensor_units(problem, structure, bool(cfg.sensors.rows))
    names = tuple(structure.sensor_names)
    inputs = []
    for i, lab in enumerate(in_labels):
        if i < nd:
            role, unit = "wf: the dV channel's input (eq. 13)", "-"
        elif i < m - nu:
            role, unit = "w: disturbance input (eq. 14)", "-"
        else:
            role, unit = "v: the flap deflection (control)", FLAP_UNIT
        inputs.append({"signal": str(lab), "role": role, "unit": unit})
    outputs = []
    for i, lab in enumerate(out_labels):
        if i < nd:
            outputs.append({"signal": str(lab), "role": "zf: the dV channel's output (eq. 13)",
                            "unit": "-"})
        elif i < p - ny:
            outputs.append({"signal": str(lab), "role": "z: performance output", "unit": "-"})
        else:
            j = i - (p - ny)
            outputs.append({"signal": str(lab), "role": "zm: measurement (eq. 7)",
                            "name": names[j] if j < len(names) else str(lab),
                            "unit": sens[j] if j < len(sens) else ""})
    doc.update({"format": "casflutter-plant/1",
                "casflutter_version": provenance()["casflutter_version"],
                "time_base": _time_base(P, scale.time_unit),
                "inputs": inputs, "outputs": outputs,
                "speed_index_definition": scale.definition,
                "Vf_speeds": speed_values(Vf, scale),
                "sign_convention": SIGN_CONVENTION,
                "verification": None if ver is None else _certified(ver, scale)})
    return doc


def _mat_interval(pair) -> np.ndarray:
    return np.zeros((0, 2)) if pair is None else np.array([[float(pair[0]), float(pair[1])]])


def _controller_mat(result, doc: dict) -> dict:
    """``controller.mat``: A, B, C, D, Ts and the same names, units and speeds as the JSON."""
    K, ver = result.controller, result.verification
    tb = doc["time_base"]
    mat = {k: np.asarray(getattr(K, k), dtype=float) for k in "ABCD"}
    mat.update({
        "Ts": 0.0 if tb["domain"] == "continuous" else float(tb["dt"] or -1.0),
        "time_unit": tb["time_unit"],
        "input_names": np.array([d["name"] for d in doc["inputs"]], dtype=object),
        "input_units": np.array([d["unit"] for d in doc["inputs"]], dtype=object),
        "output_names": np.array([d["name"] for d in doc["outputs"]], dtype=object),
        "output_units": np.array([d["unit"] for d in doc["outputs"]], dtype=object),
        "sign_convention": doc["sign_convention"],
        "speed_index_definition": doc["design"].get("speed_index_definition",
                                                    doc["design"].get("speed_unit", "")),
        "feedback": doc["feedback"],
        "casflutter_version": doc["casflutter_version"]})
    vf = doc["design"].get("Vf") or {}
    for key, value in vf.items():
        mat[f"Vf_{key}"] = np.nan if value is None else float(value)
    exact = result.rom_stable_V
    mat["certified_V"] = _mat_interval(exact)
    if ver is not None:
        mat["small_gain_V"] = _mat_interval(ver.small_gain_V)
        scale = speed_scale(_problem(result))
        if scale.has_airspeed:
            for name, pair in (("small_gain", ver.small_gain_V), ("exact", exact)):
                iv = interval_values(pair, scale)
                mat[f"{name}_airspeed_m_s"] = (np.zeros((0, 2)) if iv is None else np.array(
                    [[np.inf if x is None else x for x in iv["airspeed_m_s"]]]))
    return mat


# ---------------------------------------------------------------------- summary.json
def label_summary(summary: dict, result) -> dict:
    """Add the units, the provenance and the flags to a run's summary (in place).

    Every speed index of the flutter blocks and of the controller gets its airspeed [m/s]
    and dynamic pressure [Pa] beside it when the problem has them, the ``units`` entry says
    what each kind of number is in, the LCO amplitudes get their sensors' units
    (``lco.amplitude_units``), and ``casflutter_version``, ``threads`` and ``flags``
    (controller poles faster than the data's Nyquist frequency or the actuator) are added.

    Parameters
    ----------
    summary : dict
        :meth:`RunResult.summary` before its values are made plain JSON.
    result : RunResult

    Returns
    -------
    dict
        ``summary``.
    """
    check = _pole_check(result)
    if _structure(result) is None:        # a family file: its own units
        fam = result.model.family
        summary["units"] = {"speed": fam.speed_unit, "time": fam.time_unit,
                            "frequency": f"rad/{fam.time_unit}"}
        if isinstance(summary.get("controller"), dict):
            summary["controller"]["poles"] = check
        return _provenance_flags(summary, result, check)
    scale = speed_scale(_problem(result))
    summary["units"] = units_block(scale)
    for key in ("flutter", "flutter_truth", "flutter_frozen", "flutter_parametric",
                "flutter_convective"):
        block = summary.get(key)
        if isinstance(block, dict) and block.get("V") is not None:
            sv = speed_values(block["V"], scale)
            for k in ("airspeed_m_s", "dynamic_pressure_Pa"):
                if k in sv:
                    block[k] = sv[k]
    ctl = summary.get("controller")
    ver = result.verification
    if isinstance(ctl, dict):
        if ver is not None:
            ctl["Vf"] = speed_values(ver.Vf if ver.Vf is not None else result.Vf, scale)
        ctl["certified"] = _families_certified(result, scale)
        ctl["poles"] = check
    lco = summary.get("lco")
    if isinstance(lco, dict) and result.lco.rom.sensors is not None:
        # the amplitudes are of the sensor readings: say in what
        lco["amplitude_units"] = list(sensor_units(_problem(result), _structure(result),
                                                   bool(result.config.sensors.rows)))
    return _provenance_flags(summary, result, check)


def _provenance_flags(summary: dict, result, check) -> dict:
    """The version, thread settings and controller-pole flags of a run's summary."""
    info = dict(getattr(result, "provenance", None) or {}) or provenance(seed=result.config.seed)
    summary["casflutter_version"] = info.get("casflutter_version")
    summary["threads"] = info.get("threads")
    summary["flags"] = {
        "controller_faster_than_nyquist": None if check is None else check["faster_than_nyquist"],
        "controller_faster_than_actuator": (None if check is None
                                            else check["faster_than_actuator"])}
    return summary


# ---------------------------------------------------------------------- the folder
def _dump(doc, path: Path) -> Path:
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(doc, fh, indent=2, allow_nan=False)
    return path


def write_outputs(target, result, *, overwrite: bool = False) -> dict:
    """Write a run's output folder atomically (module docstring).

    Files: ``summary.json``, ``rom.npz`` (a run with a ROM), ``controller.json``,
    ``controller.mat`` and ``plant.json`` (a run with a controller), ``config.json``, the
    figures, ``report.html`` and, last, ``manifest.json``.

    Parameters
    ----------
    target : path
        The output folder.
    result : RunResult
    overwrite : bool
        Replace an existing non-empty folder (as a whole).

    Returns
    -------
    dict
        Name -> final path of every file.

    Raises
    ------
    OutputError
        The folder cannot be written, or exists and is not empty without ``overwrite``.
    """
    target = Path(target)
    with atomic_folder(target, overwrite=overwrite, what="output folder") as tmp:
        files = {}
        summary = result.summary()
        files["summary"] = _dump(summary, tmp / "summary.json")
        if result.identification is not None:
            result.identification.model.save(tmp / "rom.npz")
            files["rom"] = tmp / "rom.npz"
        if result.controller is not None:
            doc = controller_document(result)
            files["controller_json"] = _dump(plain_json(doc), tmp / "controller.json")
            savemat(tmp / "controller.mat", _controller_mat(result, doc))
            files["controller_mat"] = tmp / "controller.mat"
            if result.lft is not None:
                files["plant_json"] = _dump(plain_json(plant_document(result)),
                                            tmp / "plant.json")
        config = plain_json(result.config.to_dict())
        files["config"] = _dump(config, tmp / "config.json")
        figs = write_figures(tmp, result)
        files.update(figs)
        files["report"] = write_html(tmp, summary, figs, figure_captions(result))
        info = dict(getattr(result, "provenance", None) or {}) or provenance(
            seed=result.config.seed)
        stages = [k for k in result.timings if k != "total"]
        files["manifest"] = write_manifest(
            tmp, config=config, started=info.get("started"), stages=stages, info=info,
            extra={"flags": summary.get("flags"), "output_folder": str(target)})
        rel = {k: Path(p).relative_to(tmp) for k, p in files.items()}
    assert rel["manifest"].name == MANIFEST_NAME
    return {k: target / p for k, p in rel.items()}
