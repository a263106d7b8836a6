"""casflutter: nonlinear aerodynamic reduced-order models, flutter analysis and
fixed-order robust flutter suppression, centred on CasADi.

Carries out the method of K.-Y. Lum et al., "Reduced-order modeling and flutter
suppression control of an experimental wing", ACC 2016:

``data -> ident (HWL ROM, eq. 1-4) -> realize (ERA, Tustin, eq. 5) ->
aeroelastic (eq. 6-15) -> design (fixed-order H-infinity) -> verify -> report``

The user path is re-exported here (names load on first use, so ``import casflutter`` stays
fast)::

    import casflutter as cf
    truth = cf.load_problem("seed_wing")
    data = cf.truth_records(truth, V0=0.69, coupling_delay=1)
    result = cf.identify(data, (3, 1, 1, 1, 2, 2), regularization=1e-6)
    real = cf.realize(result.model, 15)
    system = cf.AeroelasticSystem.from_parts(real.sigma_f, truth.modal_structure())
    fl = cf.find_flutter(system, (0.3, 2.5))
    lco = cf.simulate_loop(result.model, system.structure, 1.05 * fl.Vf, 5000,
                           xs0=system.structure.displaced_state(fl.flutter_mode, 0.01))
    branch = cf.lco_branch(truth)           # the truth's LCO branch from its Hopf point
    lft = cf.build_lft(system, fl.Vf)
    syn = cf.synthesize(lft.plant_without_d22(), lft.nmeas, lft.ncon, 3)
    rep = cf.verify_controller(lft.P, lft.physical_controller(syn.controller), lft.nmeas,
                               lft.ncon, Vf=fl.Vf, n_delta=lft.n_delta)

or the whole study from a configuration: ``cf.run(cf.load_config())``.
"""

from __future__ import annotations

import importlib as _importlib

from . import _logging  # noqa: F401 - the package logger's NullHandler
from .errors import (CasflutterError, ConfigError, ConvergenceError, DataError,  # noqa: F401
                     DimensionError, OrderError, SynthesisError)

__version__ = "0.1.0"

#: public name -> subpackage that defines it (loaded on first access)
_LAZY = {
    # structure and data
    "ModalStructure": "structure",
    "IOData": "data", "Record": "data", "chirp_excitation": "data", "chirp_motion": "data",
    "analyze_response": "data", "ResponseAnalysis": "data",
    # truth simulators
    "load_problem": "truth", "problem_names": "truth", "truth_records": "truth",
    "RecordSettings": "truth", "frozen_aero_truth": "truth", "truth_lco": "truth",
    "closed_loop_truth": "truth", "suppression_run": "truth", "TypicalSection": "truth",
    "GolandWing": "truth", "SeedWing": "truth",
    # identification
    "identify": "ident", "IdentificationSettings": "ident", "IdentificationResult": "ident",
    "identify_common_denominator": "ident", "HWLModel": "ident", "HWLOrders": "ident",
    "fit_report": "ident", "example_rom": "ident",
    # realisation
    "realize": "realize", "Realization": "realize", "canonical_realization": "realize",
    "ParametricROM": "realize",
    # the loop, flutter, LCO, LFT
    "AeroelasticSystem": "aeroelastic", "ParametricSystem": "aeroelastic",
    "find_flutter": "aeroelastic", "FlutterResult": "aeroelastic",
    "track_eigenvalues": "aeroelastic", "simulate_loop": "aeroelastic",
    "build_lft": "aeroelastic", "AeroelasticLFT": "aeroelastic",
    "speed_following_rom": "aeroelastic",
    "lco_branch": "lco", "rom_lco_branch": "lco", "LCOBranch": "lco", "LCOSettings": "lco",
    # synthesis and verification
    "synthesize": "design", "SynthesisOptions": "design", "SynthesisResult": "design",
    "verify_controller": "verify", "VerificationReport": "verify", "speed_sweep": "verify",
    # the study run
    "run": "pipeline", "RunResult": "pipeline", "RunConfig": "pipeline",
    "load_config": "pipeline",
}

__all__ = ["CasflutterError", "ConfigError", "ConvergenceError", "DataError", "DimensionError",
           "OrderError", "SynthesisError", "__version__", *_LAZY]


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(_importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'casflutter' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(__all__) | {"errors"})
