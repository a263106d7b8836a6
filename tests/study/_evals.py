"""Evaluators for the sweep tests (importable as ``module:function`` by worker processes)."""

from __future__ import annotations

import os
import time
from pathlib import Path


def square(params, settings):
    """``y = x**2``; sleeps ``settings['sleep']``; raises for ``x`` in ``settings['fail']``."""
    x = params["x"]
    time.sleep(float(settings.get("sleep", 0.0)))
    if x in settings.get("fail", []):
        raise ValueError(f"x = {x} is not allowed here")
    return {"y": x * x, "pid": os.getpid()}


def crash_once(params, settings):
    """Kill the worker process the first time ``x == settings['crash_x']`` (marker file)."""
    marker = Path(settings["marker"])
    if params["x"] == settings["crash_x"] and not marker.exists():
        marker.write_text("crashed")
        os._exit(1)
    return square(params, settings)


def crash_always(params, settings):
    """Kill the worker process whenever ``x == settings['crash_x']``."""
    if params["x"] == settings["crash_x"]:
        os._exit(1)
    return square(params, settings)


def first_order_plant(params):
    """ẋ = a x + w + u, z = [x; ρu], y = x (closed-form static optimum for a < 0)."""
    import control

    return control.ss([[params["a"]]], [[1.0, 1.0]], [[1.0], [0.0], [1.0]],
                      [[0.0, 0.0], [0.0, params["rho"]], [0.0, 0.0]])
