"""The ``pipeline`` and ``rom_flutter`` evaluators: a study run (:func:`casflutter.pipeline.run`)
at one point.

``pipeline`` runs the whole study (``casflutter run``, default ``problems/seed_wing/run.toml``);
``rom_flutter`` runs the ROM route of ``casflutter flutter`` (``problems/NAME/flutter.toml`` of
the ``problem`` setting).  Every swept parameter and every fixed setting that is not one of
the evaluator's own settings is a change of the run configuration by dotted path (the TOML
tables of :class:`casflutter.pipeline.RunConfig`):

- a stage's key: ``data.V0`` (nominal speed of the records), ``rom.orders`` (HWL orders
  ``[mu, na, nb, r, p, q]``), ``rom.nf`` (order of Σf, eq. 5), ``controller.order``,
  ``controller.starts``, ``lco.speed_factor``, ``suppression.gust_intensity``, ``seed`` ...;
- the accelerometers: ``sensors.rows`` (``Hs`` of eq. 7, a list of rows per value, one
  number per mode; default the problem's own rows, the paper's §IV);
- a truth parameter: ``problem.set.NAME`` (seed wing: ``zeta`` structural damping,
  ``zeta_lateral``, ``rho`` air density and ``U_ref`` the flow's speed scale, ``suction``,
  ``acc1_offset`` (the Acc1 position) ... ``casflutter problems`` lists them).

The changes go through :func:`casflutter.pipeline.load_config` (``updates=``), so a point
with an unknown or invalid name fails before any work with the configuration's own message
(the key and what is allowed); :func:`pipeline_check`, the evaluators' pre-flight check,
does so for every point of a study before the first one runs.  The outputs of ``pipeline``
are ``RunResult.summary()`` (``summary.json``) flattened into columns
(:func:`flatten_summary`).
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from pathlib import Path
from typing import Any, Mapping

from ..errors import ConfigError
from ..pipeline import config_path, default_config_path, load_config, run

__all__ = ["PIPELINE_SETTINGS", "PIPELINE_OUTPUTS", "ROM_FLUTTER_SETTINGS", "ROM_FLUTTER_OUTPUTS",
           "pipeline_config", "pipeline_check", "flatten_summary", "pipeline_evaluator",
           "rom_flutter_check", "rom_flutter_evaluator"]

#: The evaluator's own settings (everything else is a configuration change).
PIPELINE_SETTINGS = {
    "config": "base run configuration (TOML, relative to the study file; default the seed "
              "wing's problems/seed_wing/run.toml, for rom_flutter problems/PROBLEM/flutter.toml)",
    "out_dir": "write each point's files (summary.json, figures, report) to "
               "OUT_DIR/<point>; relative to the working directory (default: no files)",
    "quiet": "no stage progress on stderr (default true)",
}

#: The columns :func:`pipeline_evaluator` returns (``time_<stage>`` for each of the eight
#: stages of the default configuration besides ``time_total``; ``stable_V_lo/hi``: the
#: exact stable interval of the LFT at Vf, eq. 10-15; ``certified_V_lo/hi``: the
#: controller's certified stable interval on the design family, flap behind the servo).
PIPELINE_OUTPUTS = (
    "Vf_rom", "freq_hz_rom", "mode_rom", "Vf_truth", "freq_hz_truth", "mode_truth",
    "lco_V", "lco_kind", "lco_freq_hz", "lco_amplitude", "lco_truth_V", "lco_truth_kind",
    "lco_truth_freq_hz", "lco_truth_amplitude", "controller_order", "gamma",
    "small_gain_V_lo", "small_gain_V_hi", "stable_V_lo", "stable_V_hi", "certified_V_lo",
    "certified_V_hi", "closed_loop_stable",
    "synthesis_success", "synthesis_status", "attenuation_percent", "lco_returns",
    "suppression_V", "fit_error_max", "n_params", "nf", "nae", "time_data", "time_rom",
    "time_realize", "time_structure", "time_flutter", "time_lco", "time_controller",
    "time_suppression", "time_total",
)


#: The ``rom_flutter`` evaluator's own settings besides :data:`PIPELINE_SETTINGS`.
ROM_FLUTTER_SETTINGS = {
    "problem": "the problem whose problems/PROBLEM/flutter.toml is the base configuration "
               "(default typical_section)",
    "parametric": "also the parametric ROM (default false)",
}

#: The columns :func:`rom_flutter_evaluator` returns (and ``time_<stage>``).
ROM_FLUTTER_OUTPUTS = ("Vf_truth", "Vf_rom", "Vf_frozen", "Vf_parametric", "omega_f_rom",
                       "rom_error", "scaling_error", "identification_error",
                       "parametric_error", "rom_stable", "rom_status")


def _split(params: Mapping[str, Any], settings: Mapping[str, Any]):
    merged = {**settings, **params}
    base = Path(str(merged.pop("_base_dir", ".")))
    own = {k: merged.pop(k) for k in list(merged) if k in PIPELINE_SETTINGS}
    return base, own, merged


def pipeline_config(params: Mapping[str, Any], settings: Mapping[str, Any] | None = None):
    """The validated run configuration of one point.

    Parameters
    ----------
    params : mapping
        Swept values by dotted path (module docstring).
    settings : mapping, optional
        ``config`` (base file), ``out_dir``, ``quiet`` and further fixed changes by dotted
        path (a TOML table such as ``[settings.controller]`` is merged key by key).

    Returns
    -------
    RunConfig
        The base file (``config``, default the seed wing's) with the point's values and the
        fixed changes applied.

    Raises
    ------
    ConfigError
        An unknown or invalid name or value (from :func:`casflutter.pipeline.load_config`).
    """
    base, own, updates = _split(params, settings or {})
    path = own.get("config")
    if path is None:
        path = default_config_path()
    else:
        path = Path(str(path))
        if not path.is_absolute():
            path = base / path
    try:
        return load_config(path, updates=updates)
    except ConfigError as exc:
        raise ConfigError(f"pipeline evaluator: {exc} (swept names and [settings] are dotted "
                          f"paths into the run configuration; the evaluator's own settings: "
                          f"{', '.join(PIPELINE_SETTINGS)})") from None


def pipeline_check(params: Mapping[str, Any], settings: Mapping[str, Any]) -> None:
    """The pre-flight check of the ``pipeline`` evaluator: :func:`pipeline_config` (the
    configuration's validation, no work).

    Parameters
    ----------
    params, settings : mapping
        As for :func:`pipeline_evaluator`.

    Raises
    ------
    ConfigError
        An unknown or invalid name or value (the message names the key).
    """
    pipeline_config(params, settings)


def _pair(value, i):
    return None if value is None else value[i]


def _largest(values):
    """The largest entry of a list: ``None`` without one, NaN when an entry is not finite
    (a fit error of a ROM that diverges in free run is not hidden behind the others)."""
    if not values:
        return None
    x = [math.nan if v is None else float(v) for v in values]
    return math.nan if not all(math.isfinite(v) for v in x) else max(x)


def flatten_summary(summary: Mapping[str, Any]) -> dict[str, Any]:
    """One row of columns from ``RunResult.summary()`` (the content of ``summary.json``).

    Parameters
    ----------
    summary : mapping
        The summary of a run.

    Returns
    -------
    dict
        ROM and truth flutter (``Vf_*``, ``freq_hz_*`` [Hz], ``mode_*`` 1-based), LCO of the
        nonlinear ROM and of the truth (``lco_*``; amplitude = largest sensor amplitude),
        the controller (``controller_order``, verified ``gamma``, the small-gain and exact
        stable speed intervals as ``*_lo``/``*_hi``), the suppression (``attenuation_percent``
        ...), the ROM sizes and ``time_<stage>`` [s] for every stage and ``time_total``.
        A value the run does not have is ``None`` (the store's missing value, an empty
        cell of the table): the truth's flutter and LCO of a wing or GAF file (no truth
        simulator), the fit error and ROM sizes of a route without an identified ROM, the
        blocks of the stages that did not run.
    """
    fl, ft = summary.get("flutter") or {}, summary.get("flutter_truth") or {}
    lco = summary.get("lco") or {}
    ctl, sup = summary.get("controller") or {}, summary.get("suppression") or {}
    amp, tamp = lco.get("amplitude"), lco.get("truth_amplitude")
    out = {
        "Vf_rom": fl.get("V"), "freq_hz_rom": fl.get("freq_hz"), "mode_rom": fl.get("mode"),
        "Vf_truth": ft.get("V"), "freq_hz_truth": ft.get("freq_hz"),
        "mode_truth": ft.get("mode"),
        "lco_V": lco.get("V"), "lco_kind": lco.get("kind"), "lco_freq_hz": lco.get("freq_hz"),
        "lco_amplitude": max(amp) if amp else None, "lco_truth_V": lco.get("truth_V"),
        "lco_truth_kind": lco.get("truth_kind"),
        "lco_truth_freq_hz": lco.get("truth_freq_hz"),
        "lco_truth_amplitude": max(tamp) if tamp else None,
        "controller_order": ctl.get("order"), "gamma": ctl.get("gamma"),
        "small_gain_V_lo": _pair(ctl.get("small_gain_V"), 0),
        "small_gain_V_hi": _pair(ctl.get("small_gain_V"), 1),
        "stable_V_lo": _pair(ctl.get("lft_stable_V"), 0),
        "stable_V_hi": _pair(ctl.get("lft_stable_V"), 1),
        "certified_V_lo": _pair(ctl.get("stable_interval"), 0),
        "certified_V_hi": _pair(ctl.get("stable_interval"), 1),
        "closed_loop_stable": ctl.get("stable"),
        "attenuation_percent": sup.get("attenuation_percent"),
        "lco_returns": sup.get("lco_returns"), "suppression_V": sup.get("V"),
        "fit_error_max": _largest(summary.get("fit_error_percent")),
        "n_params": summary.get("n_params"), "nf": summary.get("nf"), "nae": summary.get("nae"),
    }
    out.update({f"time_{k}": v for k, v in (summary.get("timings_s") or {}).items()})
    return out


def _point_dir(params: Mapping[str, Any]) -> str:
    """A readable, unique folder name of a point: ``controller.order=2,zeta=0.03-<hash>``."""
    text = ",".join(f"{k.rsplit('.', 1)[-1]}={params[k]}" for k in sorted(params))
    slug = re.sub(r"[^A-Za-z0-9_.=,+-]", "", text)[:80]
    digest = hashlib.sha256(json.dumps({k: params[k] for k in sorted(params)},
                                       default=str).encode()).hexdigest()[:8]
    return f"{slug}-{digest}" if slug else digest


def pipeline_evaluator(params: Mapping[str, Any], settings: Mapping[str, Any]) -> dict[str, Any]:
    """Run :func:`casflutter.pipeline.run` at one point of a sweep.

    Parameters
    ----------
    params : mapping
        Swept configuration changes by dotted path (``controller.order``,
        ``problem.set.zeta``, ``data.V0``, ``rom.orders`` ...; module docstring).
    settings : mapping
        :data:`PIPELINE_SETTINGS` (``config``, ``out_dir``, ``quiet``) and fixed changes.

    Returns
    -------
    dict
        :func:`flatten_summary` of the run, plus ``synthesis_success`` and
        ``synthesis_status`` (the last Ipopt status of the best start, verbatim).

    Raises
    ------
    ConfigError
        Before any work, for an unknown or invalid name (:func:`pipeline_config`).
    """
    res = _run_point(params, settings)
    out = flatten_summary(res.summary())
    syn = res.synthesis
    out["synthesis_success"] = None if syn is None else bool(syn.success)
    out["synthesis_status"] = syn.statuses[-1] if syn is not None and syn.statuses else None
    return out


def _run_point(params: Mapping[str, Any], settings: Mapping[str, Any]):
    cfg = pipeline_config(params, settings)
    _, own, _ = _split(params, settings)
    out_dir = own.get("out_dir")
    write = out_dir is not None
    # a point computed again (a resumed sweep whose store missed its line) replaces its folder
    return run(cfg, out_dir=Path(str(out_dir)) / _point_dir(params) if write else None,
               quiet=bool(own.get("quiet", True)), write=write, overwrite=True)


def _rom_flutter_settings(settings: Mapping[str, Any]) -> dict:
    """The pipeline settings of a ``rom_flutter`` point: the problem's flutter.toml as the
    base configuration, without the parametric ROM unless asked."""
    settings = dict(settings)
    problem = str(settings.pop("problem", "typical_section"))
    parametric = bool(settings.pop("parametric", False))
    if "config" not in settings:
        settings["config"] = str(config_path(problem, "flutter"))
    if not parametric:
        # the frozen-aero truth beside the ROM where there is a truth (elsewhere the stage
        # would only be skipped, with a note at every point)
        settings["stages"] = ["frozen"] if _has_truth(settings) else []
    return settings


def _has_truth(settings: Mapping[str, Any]) -> bool:
    """Whether the problem of the settings' configuration has a truth simulator (``True``
    when the configuration does not load: the point's own call then names the error)."""
    from ..truth import AeroelasticTruth

    try:
        cfg = pipeline_config({}, {**settings, "stages": []})
    except ConfigError:
        return True
    return isinstance(cfg.problem.load(), AeroelasticTruth)


def rom_flutter_check(params: Mapping[str, Any], settings: Mapping[str, Any]) -> None:
    """The pre-flight check of the ``rom_flutter`` evaluator (:func:`pipeline_check` on the
    problem's flutter configuration).

    Parameters
    ----------
    params, settings : mapping
        As for :func:`rom_flutter_evaluator`.

    Raises
    ------
    ConfigError
        An unknown or invalid name or value (the message names the key).
    """
    pipeline_config(params, _rom_flutter_settings(settings))


def rom_flutter_evaluator(params: Mapping[str, Any],
                          settings: Mapping[str, Any]) -> dict[str, Any]:
    """The ROM route of ``casflutter flutter`` at one point of a sweep.

    Parameters
    ----------
    params : mapping
        Swept configuration changes by dotted path into ``problems/PROBLEM/flutter.toml``
        (``data.V0`` nominal speed, ``rom.na``, ``flutter.n_grid``, ``problem.set.mu`` ...).
    settings : mapping
        :data:`ROM_FLUTTER_SETTINGS`, :data:`PIPELINE_SETTINGS` and fixed changes.

    Returns
    -------
    dict
        ``Vf_truth``, ``Vf_rom``, ``Vf_frozen``, ``Vf_parametric``, ``omega_f_rom``,
        ``rom_error``, ``scaling_error``, ``identification_error``, ``parametric_error``,
        ``rom_stable``, ``rom_status`` and ``time_<stage>`` per stage.

    Raises
    ------
    ConfigError
        Before any work, for an unknown or invalid name (:func:`pipeline_config`).
    """
    res = _run_point(params, _rom_flutter_settings(settings))
    # a wing or GAF file (``config`` of a run on one) has no truth simulator: no Vf_truth
    out = {"Vf_truth": None if res.flutter_truth is None else res.flutter_truth.Vf,
           "Vf_rom": res.flutter.Vf,
           "Vf_frozen": None if res.flutter_frozen is None else res.flutter_frozen.Vf,
           "Vf_parametric": None if res.parametric is None else res.parametric.flutter.Vf,
           "omega_f_rom": res.flutter.omega_f, "rom_error": res.rom_error,
           "scaling_error": res.scaling_error,
           "identification_error": res.identification_error,
           "parametric_error": res.parametric_error, "rom_stable": res.system.rom_stable,
           "rom_status": res.flutter.status}
    out.update({f"time_{k}": v for k, v in res.timings.items()})
    return out
