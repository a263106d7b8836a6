"""The registry of evaluators: a point (dict of parameter values) -> a dict of outputs.

An evaluator is a plain function ``f(params, settings) -> dict`` where ``params`` are the
swept values of one point and ``settings`` the study's fixed settings.  It raises on
failure (the runner records the error and carries on).  Built-in evaluators:

``truth_flutter``
    Flutter speed, frequency and divergence of a truth problem's full-order linear system
    (:func:`casflutter.aeroelastic.find_flutter` on ``truth.state_matrix``), optionally the
    LCO amplitude of the nonlinear truth above the flutter speed.  Parameters: any truth
    parameter (``casflutter problems`` lists them).
``synthesis``
    Fixed-order H∞ synthesis (:func:`casflutter.design.synthesize`) on a COMPleib-format plant
    file: verified γ vs controller ``order`` (and ``seed``, ``starts``).
``truth_hopf``
    The same flutter speed as the root of the Hopf system, a parametric CasADi NLP built once
    per worker process and reused for every point (:func:`casflutter.study.truth_hopf`).
``pipeline``
    The whole study (``casflutter run``) per point, parameters by dotted path into the run
    configuration (:mod:`casflutter.study._pipeline_eval`).
``rom_flutter``
    The ROM route of ``casflutter flutter`` (a run of ``problems/NAME/flutter.toml``) per
    point, by dotted path as for ``pipeline``.

Further evaluators plug in with :func:`register_evaluator` or as ``"package.module:function"``
in the study file (the form that also reaches spawned and Dask worker processes).

An evaluator may carry a ``check(params, settings)``: the pre-flight check that
:func:`~casflutter.study.run_sweep` calls on every point before any point runs, so that a
misspelt parameter or setting stops the study at once instead of failing point by point
(``pipeline``: the run configuration's validation; ``truth_flutter``: the problem's
parameter names; ``synthesis``: the plant file and the order).  A ``"module:function"``
evaluator gets one from an attribute ``function.check``.
"""

from __future__ import annotations

import importlib
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..aeroelastic import find_flutter
from ..design import load_compleib, synthesize
from ..errors import ConfigError
from ._hopf import truth_hopf
from ._pipeline_eval import (PIPELINE_OUTPUTS, ROM_FLUTTER_OUTPUTS, pipeline_check,
                             pipeline_evaluator, rom_flutter_check, rom_flutter_evaluator)
from ._spec import check_setting
from ._truth_point import load_truth

__all__ = ["Evaluator", "register_evaluator", "get_evaluator", "evaluator_names",
           "truth_flutter_evaluator", "synthesis_gamma"]


@dataclass(frozen=True)
class Evaluator:
    """A registered evaluator.

    Attributes
    ----------
    name : str
        Registry name (``[study] evaluator = NAME``).
    function : callable
        ``function(params: dict, settings: dict) -> dict`` of outputs.
    outputs : tuple of str
        Output names it returns (documentation and default columns).
    description : str
        One line for ``casflutter sweep --list``.
    modules : tuple of str
        Modules a worker imports before its first point (so that start-up is not counted
        as the first point's work).
    check : callable or None
        ``check(params, settings) -> None``: a cheap validation of one point's names and
        values (no work), raising :class:`~casflutter.errors.ConfigError`; the runner
        calls it on every point before submitting any (:meth:`check_point`).
    """

    name: str
    function: Callable[[Mapping[str, Any], Mapping[str, Any]], dict]
    outputs: tuple = ()
    description: str = ""
    modules: tuple = ()
    check: Callable[[Mapping[str, Any], Mapping[str, Any]], Any] | None = None

    def check_point(self, params: Mapping[str, Any], settings: Mapping[str, Any]) -> None:
        """Run :attr:`check` on one point (nothing when the evaluator has none).

        Parameters
        ----------
        params : mapping
            The swept values of the point.
        settings : mapping
            The study's fixed settings (with ``_base_dir``).

        Raises
        ------
        ConfigError
            The point's names or values are invalid for this evaluator.
        """
        if self.check is not None:
            self.check(dict(params), dict(settings))

    def warm_up(self) -> None:
        """Import :attr:`modules` (run once per worker process)."""
        for m in self.modules:
            importlib.import_module(m)


_REGISTRY: dict[str, Evaluator] = {}


def register_evaluator(name: str, function: Callable, outputs=(), description: str = "",
                       modules=(), check: Callable | None = None) -> Evaluator:
    """Add (or replace) an evaluator under ``name`` and return it (fields of
    :class:`Evaluator`, ``check`` the optional pre-flight check)."""
    ev = Evaluator(name=name, function=function, outputs=tuple(outputs),
                   description=description, modules=tuple(modules), check=check)
    _REGISTRY[name] = ev
    return ev


def evaluator_names() -> list[str]:
    """Names of the registered evaluators."""
    return sorted(_REGISTRY)


def get_evaluator(ref: str) -> Evaluator:
    """The evaluator registered as ``ref``, or the function ``"package.module:function"``.

    Raises
    ------
    ConfigError
        Unknown name (the message lists the registered ones) or an import path that does
        not resolve.
    """
    if ref in _REGISTRY:
        return _REGISTRY[ref]
    if ":" in ref:
        mod, _, attr = ref.partition(":")
        try:
            fn = getattr(importlib.import_module(mod), attr)
        except (ImportError, AttributeError) as exc:
            raise ConfigError(f"evaluator {ref!r} cannot be imported ({exc}); give "
                              "'package.module:function' importable on every worker") from None
        return Evaluator(name=ref, function=fn, check=getattr(fn, "check", None))
    raise ConfigError(f"unknown evaluator {ref!r}; registered: {', '.join(sorted(_REGISTRY))} "
                      "(or give 'package.module:function')")


# ----------------------------------------------------------------------- truth flutter

def _lco_amplitude(model, V: float, options: Mapping[str, Any]) -> dict[str, float]:
    """Half peak-to-peak of every physical coordinate over the last quarter of a free run
    of the nonlinear truth at ``V``, and its relative change against the previous quarter
    (small when the oscillation has settled on a limit cycle)."""
    T = float(options.get("lco_time", 600.0))
    n = int(options.get("lco_samples", 6001))
    x0 = float(options.get("lco_x0", 0.01))
    t = np.linspace(0.0, T, n)
    sim = model.simulate(t, model.modal_state(u=np.full(model.n_modes, x0)), V)
    if not sim.success:
        raise RuntimeError(f"LCO simulation failed at V = {V:g}: {sim.message}")
    shapes = model.modal_structure().shapes
    x = sim.u @ shapes.T  # physical coordinates
    q = n // 4
    last, prev = x[-q:], x[-2 * q:-q]
    amp = 0.5 * (last.max(axis=0) - last.min(axis=0))
    amp_prev = 0.5 * (prev.max(axis=0) - prev.min(axis=0))
    names = model.modal_structure().coordinate_names
    out = {f"lco_amplitude_{c.replace('/', '_')}": float(a) for c, a in zip(names, amp)}
    out["lco_amplitude"] = float(np.max(amp))
    out["lco_settling"] = float(np.max(np.abs(amp - amp_prev)) / max(float(np.max(amp)), 1e-300))
    out["lco_V"] = float(V)
    return out


def truth_flutter_evaluator(params: Mapping[str, Any],
                            settings: Mapping[str, Any]) -> dict[str, Any]:
    """Flutter and divergence of a truth problem's full-order linear system.

    Parameters
    ----------
    params : mapping
        Swept values: any truth parameter of the problem (e.g. ``mu``, ``zeta``, ``a``).
    settings : mapping
        ``problem`` (default ``"typical_section"``), ``V_min``, ``V_max``, ``n_grid`` and,
        for an LCO amplitude, ``lco_speed_ratio`` (simulate at this multiple of Vf; the
        problem needs a nonlinear stiffness, e.g. ``kappa3``), ``lco_time``,
        ``lco_samples``, ``lco_x0``; any truth parameter held fixed.

    Returns
    -------
    dict
        ``flutter_status`` (:class:`FlutterResult` status), ``Vf``, ``omega_f``, ``frequency_hz``,
        ``flutter_mode``, ``divergence_V``, ``n_crossings``, ``flutter_time`` and, with
        ``lco_speed_ratio``, ``lco_amplitude`` (largest coordinate), one
        ``lco_amplitude_<coordinate>`` per coordinate, ``lco_settling``, ``lco_V``.
    """
    model, options = load_truth(params, settings)
    t0 = time.perf_counter()
    res = find_flutter(model.state_matrix, (float(options.get("V_min", 0.02)),
                                            float(options.get("V_max", 4.0))),
                       n_grid=int(options.get("n_grid", 81)),
                       omega=model.modal_structure().omega)
    out: dict[str, Any] = {
        "flutter_status": res.status, "Vf": res.Vf, "omega_f": res.omega_f,
        "frequency_hz": res.frequency_hz, "flutter_mode": res.flutter_mode,
        "divergence_V": None if res.divergence is None else res.divergence.V,
        "n_crossings": len(res.crossings), "flutter_time": time.perf_counter() - t0}
    ratio = options.get("lco_speed_ratio")
    if ratio is not None:
        if res.Vf is None:
            raise RuntimeError("no flutter speed in the range, so no LCO speed "
                               f"(lco_speed_ratio = {ratio}); widen V_min..V_max")
        out.update(_lco_amplitude(model, float(ratio) * res.Vf, options))
    return out


def _truth_flutter_check(params: Mapping[str, Any], settings: Mapping[str, Any]) -> None:
    """Pre-flight check of :func:`truth_flutter_evaluator`: the problem, its parameter names and
    values, the option names and values (builds the truth, no flutter search)."""
    _, options = load_truth(params, settings)
    v_min = check_setting(options, "V_min", 0.02, low=0.0)
    v_max = check_setting(options, "V_max", 4.0, positive=True)
    if not v_min < v_max:
        raise ConfigError(f"V_min = {v_min:g} must be below V_max = {v_max:g}")
    check_setting(options, "n_grid", 81, integer=True, low=3)
    if options.get("lco_speed_ratio") is not None:
        check_setting(options, "lco_speed_ratio", None, positive=True)
    check_setting(options, "lco_time", 600.0, positive=True)
    check_setting(options, "lco_samples", 6001, integer=True, low=8)
    check_setting(options, "lco_x0", 0.01)


# --------------------------------------------------------------------------- synthesis

def synthesis_gamma(params: Mapping[str, Any], settings: Mapping[str, Any]) -> dict[str, Any]:
    """Fixed-order H∞ synthesis on one COMPleib-format plant file (γ vs controller order).

    Parameters
    ----------
    params, settings : mapping
        ``plant`` (path, relative to the study file), ``order`` (controller order),
        ``starts`` (default 2), ``seed`` (default 0), ``time_limit`` [s] (default none),
        any other key is a :class:`casflutter.design.SynthesisOptions` field.

    Returns
    -------
    dict
        ``gamma`` (verified, exact norm), ``delta_bound`` (= 1/γ), ``spectral_abscissa``,
        ``success``, ``converged``, ``n_solves`` / ``n_solve_succeeded`` / ``last_status``
        (Ipopt statuses of the best start, verbatim), ``synthesis_time``.

    Notes
    -----
    :func:`~casflutter.design.synthesize` builds its NLPs inside every call (it does not
    expose them), so this evaluator cannot reuse a solver across points; the study's
    own parametric solvers use :func:`casflutter.study.cached_solver`.
    """
    merged = {**settings, **params}
    base = Path(str(merged.pop("_base_dir", ".")))
    if "plant" not in merged or "order" not in merged:
        raise ConfigError("synthesis needs 'plant' (COMPleib JSON path) and 'order'")
    plant = Path(str(merged.pop("plant")))
    if not plant.is_absolute():
        plant = base / plant
    order = int(merged.pop("order"))
    starts = int(merged.pop("starts", 2))
    seed = int(merged.pop("seed", 0))
    P, nmeas, ncon, _ = load_compleib(plant)
    t0 = time.perf_counter()
    res = synthesize(P, nmeas, ncon, order, starts=starts, seed=seed, options=merged or None)
    return {"gamma": res.gamma, "delta_bound": res.delta_bound,
            "spectral_abscissa": res.spectral_abscissa, "success": res.success,
            "converged": res.converged, "n_solves": len(res.statuses),
            "n_solve_succeeded": sum(st == "Solve_Succeeded" for st in res.statuses),
            "last_status": res.statuses[-1] if res.statuses else None,
            "synthesis_time": time.perf_counter() - t0}


def _synthesis_check(params: Mapping[str, Any], settings: Mapping[str, Any]) -> None:
    """Pre-flight check of :func:`synthesis_gamma`: ``plant`` names an existing file and
    ``order`` is a non-negative integer."""
    merged = {**settings, **params}
    base = Path(str(merged.pop("_base_dir", ".")))
    if "plant" not in merged or "order" not in merged:
        raise ConfigError("synthesis needs 'plant' (COMPleib JSON path) and 'order'")
    plant = Path(str(merged["plant"]))
    if not plant.is_absolute():
        plant = base / plant
    if not plant.is_file():
        raise ConfigError(f"plant = {merged['plant']!r}: no file {plant} (paths are relative "
                          "to the study file)")
    order = merged["order"]
    if isinstance(order, bool) or not isinstance(order, (int, float)) or order < 0 \
            or int(order) != order:
        raise ConfigError(f"order = {order!r}: a non-negative integer")
    check_setting(merged, "starts", 2, integer=True, low=1)
    check_setting(merged, "seed", 0, integer=True, low=0)
    if merged.get("time_limit") is not None:
        check_setting(merged, "time_limit", None, positive=True)


register_evaluator("truth_flutter", truth_flutter_evaluator,
                   outputs=("flutter_status", "Vf", "omega_f", "frequency_hz", "flutter_mode",
                            "divergence_V", "n_crossings", "flutter_time", "lco_amplitude",
                            "lco_settling", "lco_V"),
                   description="truth flutter speed/frequency/divergence (and LCO amplitude)",
                   modules=("casflutter.truth", "casflutter.aeroelastic"),
                   check=_truth_flutter_check)
register_evaluator("synthesis", synthesis_gamma,
                   outputs=("gamma", "delta_bound", "spectral_abscissa", "success",
                            "converged", "n_solves", "n_solve_succeeded", "last_status",
                            "synthesis_time"),
                   description="fixed-order H-infinity synthesis on a COMPleib plant (gamma vs order)",
                   modules=("casflutter.design",), check=_synthesis_check)



register_evaluator("truth_hopf", truth_hopf,
                   outputs=("Vf", "omega_f", "frequency_hz", "return_status", "iterations",
                            "solve_time", "solver_builds", "pid", "hopf_time"),
                   description="truth flutter speed by the Hopf-point NLP (one cached "
                               "parametric CasADi solver per worker)",
                   modules=("casflutter.truth", "casflutter.study._hopf"))


register_evaluator("pipeline", pipeline_evaluator, outputs=PIPELINE_OUTPUTS,
                   description="the whole study (casflutter run) per point: sweep run-config "
                               "keys by dotted path (controller.order, rom.orders, data.V0, "
                               "problem.set.zeta ...)",
                   modules=("casflutter.pipeline", "casflutter.study._pipeline_eval"),
                   check=pipeline_check)
register_evaluator("rom_flutter", rom_flutter_evaluator, outputs=ROM_FLUTTER_OUTPUTS,
                   description="ROM route (chirp data, linear ROM, ERA/Tustin, V^2-scaled "
                               "loop) vs the truth flutter speed: casflutter flutter per point",
                   modules=("casflutter.pipeline", "casflutter.study._pipeline_eval"),
                   check=rom_flutter_check)
