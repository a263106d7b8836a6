"""Every result a user prints fits on one screen: the frozen result dataclasses of the stages
take :func:`casflutter._format.result_repr` (fields by shape, range and dimension, never a
raw array), and a real run's results print in a few lines."""

import dataclasses
import importlib
import inspect
import pkgutil

import control
import numpy as np
import pytest

import casflutter
import casflutter as cf
from casflutter._format import result_repr, sig
from casflutter.ident import HWLModel
from casflutter._resources import problems_dir

#: lines of one screen
SCREEN = 30

#: the stages whose public frozen dataclasses are results (settings and definitions aside)
STAGES = ("ident", "realize", "aeroelastic", "lco", "design", "verify", "data", "truth",
          "pipeline", "structure", "study")
#: public frozen dataclasses that are settings, definitions or configuration, not results
NOT_RESULTS = {"IdentificationSettings", "HWLOrders", "HWLStructure", "RFASettings",
               "LCOSettings", "SynthesisOptions", "Partition", "QPStep", "RecordSettings",
               "SuppressionSettings", "SpeedScale", "Outputs", "Parameter", "Study",
               "Evaluator", "GolandParams", "SeedWingParams", "TypicalSectionParams",
               "PitchPlungeParams", "FlapCoefficients", "StripCoefficients", "AeroMatrices",
               "WingProblem", "GAFProblem",
               # conventions and small values of the structure (a few numbers each)
               "SpeedConvention", "ModalLayout", "ModalState"}


def _public_frozen_dataclasses():
    seen = {}
    for stage in STAGES:
        pkg = importlib.import_module(f"casflutter.{stage}")
        for info in pkgutil.iter_modules(pkg.__path__):
            if info.name == "_config":          # the run configuration's sections
                continue
            mod = importlib.import_module(f"casflutter.{stage}.{info.name}")
            for name, obj in vars(mod).items():
                if (inspect.isclass(obj) and obj.__module__ == mod.__name__
                        and not name.startswith("_") and dataclasses.is_dataclass(obj)
                        and obj.__dataclass_params__.frozen):
                    seen[f"{obj.__module__}.{name}"] = obj
    return seen


CLASSES = _public_frozen_dataclasses()
RESULTS = {k: c for k, c in CLASSES.items() if c.__name__ not in NOT_RESULTS}
#: the results that take the shared one-screen repr (the others write their own)
SHARED = {k: c for k, c in RESULTS.items() if c.__repr__ is result_repr}


def _generated(cls) -> bool:
    """The dataclass's own field-by-field repr (wrapped by reprlib.recursive_repr)."""
    return hasattr(cls.__repr__, "__wrapped__")


def test_every_public_result_class_has_a_one_screen_repr():
    missing = [k for k, c in RESULTS.items() if _generated(c)]
    assert not missing, f"result classes with the raw dataclass repr: {missing}"
    assert len(SHARED) >= 50          # the walk found the stages' results


@pytest.mark.parametrize("key", sorted(SHARED))
def test_a_result_with_huge_fields_prints_on_one_screen(key):
    """Every field a 300 x 300 array, a 300-state system or a 300-item tuple: one short line
    per field at most (a screen for all but the run's 33 stage fields, which a real run
    leaves mostly unset), never the raw values (~10^6 characters)."""
    cls = SHARED[key]
    big = {"array": np.arange(90000.0).reshape(300, 300),
           "system": control.ss(np.eye(300), np.ones((300, 2)), np.ones((3, 300)),
                                np.zeros((3, 2))),
           "tuple": tuple(range(300))}
    for kind, value in big.items():
        obj = object.__new__(cls)
        for f in dataclasses.fields(cls):
            object.__setattr__(obj, f.name, value)
        text = repr(obj)
        lines = text.splitlines()
        assert len(lines) <= max(SCREEN, len(dataclasses.fields(cls)) + 2), text[:300]
        assert max(map(len, lines)) <= 120, (kind, text[:300])
        assert len(text) < 4000 and "89998" not in text      # no raw values


def test_the_seed_wing_realization_and_model_print_in_a_few_lines():
    """``print(realize(model))`` of the seed wing's HWL ROM (230 parameters, 121 Markov
    parameters of 5 x 6) was ~760 lines of arrays."""
    model = HWLModel.load(problems_dir() / "seed_wing_rom" / "rom.npz")
    real = cf.realize(model)
    for obj in (real, model):
        text = repr(obj)
        assert len(text.splitlines()) <= 10, text
    assert "StateSpace(nstates=25, ninputs=6, noutputs=5)" in repr(real)
    assert str(model).count("\n") == 0           # the model's own one-line summary


def _walk(obj, depth=0):
    """The result dataclasses reachable from ``obj`` (fields, tuples of results)."""
    if depth > 3:
        return
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        yield obj
        for f in dataclasses.fields(obj):
            yield from _walk(getattr(obj, f.name), depth + 1)
    elif isinstance(obj, (tuple, list)) and len(obj) < 50:
        for x in obj:
            yield from _walk(x, depth + 1)


def test_a_real_run_and_everything_in_it_print_on_one_screen():
    """The typical section's flutter route (records, ROM, Σf, ΣAE, flutter of the ROM, the
    frozen-aerodynamics truth and the parametric ROM): each result prints within a screen,
    numbers with at most 6 significant digits."""
    from casflutter.pipeline import config_path

    result = cf.run(cf.load_config(config_path("typical_section", "flutter")), write=False,
                    quiet=True)
    shown = 0
    for obj in _walk(result):
        if type(obj).__repr__ is not result_repr:
            continue
        text = repr(obj)
        shown += 1
        assert len(text.splitlines()) <= SCREEN, text
        assert "[[" not in text, text                   # no raw matrix
    assert shown >= 10
    # Vf = 2.258926... printed with 6 significant digits, not 16
    assert f"Vf={sig(result.flutter.Vf, 6)}" in repr(result.flutter)
    assert repr(result.flutter.Vf)[:10] not in repr(result.flutter)


@pytest.mark.parametrize("x, digits, text", [
    (9.153151391264155, 5, "9.1532"), (11.372657800788938, 5, "11.373"),
    (99.99999999999176, 4, "100"), (0.0, 5, "0"), (float("inf"), 5, "inf"), (None, 5, "-"),
    ((0.0, 1.56798155192082), 4, "(0, 1.568)"), (3, 5, "3"), (True, 5, "True"),
    (11410.27, 4, "11410"), (2.5e7, 4, "2.5e+07")])
def test_sig_writes_a_few_significant_digits(x, digits, text):
    assert sig(x, digits) == text


def test_the_flat_namespace_results_are_covered():
    """The results reached from ``casflutter`` itself are among the classes checked."""
    names = {c.__name__ for c in RESULTS.values()}
    for name in ("Realization", "FlutterResult", "OrderSelection", "VerificationReport",
                 "SynthesisResult", "LCOBranch", "RunResult", "IdentificationResult"):
        assert name in names
        assert getattr(casflutter, name, None) is None or \
            getattr(casflutter, name).__repr__ is result_repr
