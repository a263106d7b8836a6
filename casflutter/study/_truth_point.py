"""A sweep point of the truth evaluators: problem, truth parameters and evaluator options."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

from ..errors import ConfigError
from ..truth import PROBLEMS, load_problem

__all__ = ["TRUTH_OPTIONS", "load_truth"]

#: Options of the truth evaluators (``truth_flutter``, ``truth_hopf``) besides the parameters.
TRUTH_OPTIONS = {
    "problem": "truth problem name (casflutter problems) or a rig file (kind = pitch_plunge)",
    "V_min": "lowest speed index of the flutter search (default 0.02)",
    "V_max": "highest speed index of the flutter search (default 4.0)",
    "n_grid": "grid points of the eigenvalue tracking (default 81)",
    "lco_speed_ratio": "if given: simulate the nonlinear truth at this multiple of Vf",
    "lco_time": "LCO simulation length in the problem's time unit (default 600)",
    "lco_samples": "output samples of the LCO simulation (default 6001)",
    "lco_x0": "initial modal displacement of every mode for the LCO run (default 0.01)",
}


def load_truth(params: Mapping[str, Any], settings: Mapping[str, Any] | None = None,
               extra_options: tuple = ()):
    """The truth model of a point and the evaluator's options.

    Parameters
    ----------
    params : mapping
        The swept values: truth parameters (and options).
    settings : mapping, optional
        The study's fixed settings: ``problem`` (default ``"typical_section"``), truth
        parameters, options (:data:`TRUTH_OPTIONS`).
    extra_options : tuple of str
        Further option names the calling evaluator accepts.

    Returns
    -------
    (AeroelasticTruth, dict)
        The truth (:func:`casflutter.truth.load_problem`) and the options.

    Raises
    ------
    ConfigError
        Unknown problem, or a name that is neither a parameter nor an option.
    """
    merged = {**(settings or {}), **params}
    base = merged.pop("_base_dir", None)
    name = str(merged.pop("problem", "typical_section"))
    if name in PROBLEMS:
        valid = PROBLEMS[name].Params.parameter_names()
    else:                       # a problem file (a rig section), beside the study file
        path = Path(name)
        if not path.is_absolute() and base is not None and (Path(base) / path).is_file():
            name = str(Path(base) / path)
        try:
            valid = load_problem(name).params.parameter_names()
        except (ConfigError, AttributeError):
            raise ConfigError(f"unknown problem {name!r}: give one of {', '.join(PROBLEMS)} "
                              "or a problem file with simulator parameters (kind = "
                              "\"pitch_plunge\", e.g. \"nata\")") from None
    truth_params = {k: v for k, v in merged.items() if k in valid}
    options = {k: v for k, v in merged.items() if k not in valid}
    allowed = list(TRUTH_OPTIONS) + list(extra_options)
    bad = set(options) - set(allowed)
    if bad:
        raise ConfigError(f"{sorted(bad)} are neither parameters of {name!r} "
                          f"({', '.join(valid)}) nor options ({', '.join(allowed)})")
    return load_problem(name, truth_params), options
