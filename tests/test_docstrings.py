"""The user path's docstrings, checked by numpydoc's own validator.

Every function, class and public method reachable from ``casflutter.__all__`` (the flat
user path) is validated with :func:`numpydoc.validate.validate`.  The checks enforced:

- ``GL08`` a docstring exists; ``SS01``/``SS03`` a one-line summary ending in a period
  (what a reader sees in ``help()`` and in the API tables);
- ``PR02`` no documented parameter that the signature lacks, ``PR07`` every documented
  parameter is described, ``PR10`` the ``name : type`` colon spacing that Sphinx parses;
- on the user-path *functions* also ``PR01`` (every parameter documented), ``RT01`` (a
  Returns section), ``SA01`` (See Also: where to go next on the pipeline) and ``EX01`` (an
  Examples section), so a script writer finds every argument, result and a worked call;
- on public methods ``PR01`` and ``RT01`` as well (an override of a documented base-class
  method documents what differs; its parameters and result are the base's);
- the fields of the dataclasses are documented in their Attributes/Parameters section or by
  an attribute docstring (numpydoc's PR01 reads only the generated constructor, so that is
  checked here).

The Examples of the user path run as doctests (:func:`test_examples_run`): each is a worked
call on the typical section or a small plant, with its output checked.

Not enforced: the style checks (``SS05`` imperative mood, ``GL02`` quote placement) that do
not change what a reader learns, and Examples on methods.
"""

from __future__ import annotations

import ast
import dataclasses
import doctest
import importlib
import inspect
import textwrap

import pytest
from numpydoc.docscrape import NumpyDocString
from numpydoc.validate import validate

import casflutter

ALL_OBJECTS = ("GL08", "SS01", "SS03", "PR02", "PR07", "PR10")
CLASSES = ALL_OBJECTS
METHODS = ALL_OBJECTS + ("PR01", "RT01")
FUNCTIONS = METHODS + ("SA01", "EX01")


def _user_path() -> dict[str, tuple[object, tuple[str, ...]]]:
    out: dict[str, tuple[object, tuple[str, ...]]] = {}
    for name in casflutter.__all__:
        # the object the flat name stands for, read from its stage (``casflutter.realize`` is
        # also the stage's module once the stage has been imported)
        stage = casflutter._LAZY.get(name)
        obj = (getattr(importlib.import_module(f"casflutter.{stage}"), name) if stage
               else getattr(casflutter, name))
        if inspect.isfunction(obj):
            out[f"{obj.__module__}.{obj.__qualname__}"] = (obj, FUNCTIONS)
        elif inspect.isclass(obj) and obj.__module__.startswith("casflutter"):
            out[f"{obj.__module__}.{obj.__qualname__}"] = (obj, CLASSES)
            for attr, value in vars(obj).items():
                if attr.startswith("_"):
                    continue
                if isinstance(value, (classmethod, staticmethod)):
                    value = value.__func__
                if inspect.isfunction(value):
                    # an override of a documented base method documents what differs; its
                    # parameters and result are the base method's
                    overrides = any(attr in vars(b) and getattr(b, attr).__doc__
                                    for b in obj.__mro__[1:])
                    out[f"{obj.__module__}.{obj.__qualname__}.{attr}"] = (
                        value, ALL_OBJECTS if overrides else METHODS)
    return out


USER_PATH = _user_path()


def test_the_user_path_is_covered():
    # the flat namespace holds the whole pipeline, the LCO stage included
    for name in ("load_problem", "identify", "realize", "find_flutter", "lco_branch",
                 "build_lft", "synthesize", "verify_controller", "run"):
        assert name in casflutter.__all__, name
    assert len(USER_PATH) > 100
    assert "annotations" not in dir(casflutter) and "importlib" not in dir(casflutter)


@pytest.mark.parametrize("qualname", sorted(USER_PATH))
def test_numpydoc(qualname):
    _, checks = USER_PATH[qualname]
    errors = [f"{code}: {msg}" for code, msg in validate(qualname)["errors"] if code in checks]
    assert not errors, "\n".join(errors)


def _attribute_docstrings(cls) -> set[str]:
    """Fields of ``cls`` documented the ways Sphinx's autodoc shows: a string literal after
    the field, or ``#:`` comment lines before it."""
    source = textwrap.dedent(inspect.getsource(cls))
    lines = source.splitlines()
    body = ast.parse(source).body[0].body
    out = set()
    for stmt, nxt in zip(body, body[1:] + [None]):
        if not (isinstance(stmt, ast.AnnAssign) and isinstance(stmt.target, ast.Name)):
            continue
        after = (isinstance(nxt, ast.Expr) and isinstance(nxt.value, ast.Constant)
                 and isinstance(nxt.value.value, str))
        before = stmt.lineno >= 2 and lines[stmt.lineno - 2].strip().startswith("#:")
        if after or before:
            out.add(stmt.target.id)
    return out


DATACLASSES = sorted(q for q, (obj, _) in USER_PATH.items()
                     if inspect.isclass(obj) and dataclasses.is_dataclass(obj))


@pytest.mark.parametrize("qualname", DATACLASSES)
def test_every_dataclass_field_is_documented(qualname):
    cls = USER_PATH[qualname][0]
    doc = NumpyDocString(inspect.getdoc(cls) or "")
    documented = {name.strip() for section in ("Attributes", "Parameters")
                  for item in doc[section] for name in item.name.split(",")}
    documented |= _attribute_docstrings(cls)
    missing = [f.name for f in dataclasses.fields(cls)
               if not f.name.startswith("_") and f.name not in documented]
    assert not missing, f"fields without documentation: {missing}"


EXAMPLES = sorted(q for q, (obj, checks) in USER_PATH.items() if "EX01" in checks)


@pytest.mark.parametrize("qualname", EXAMPLES)
def test_examples_run(qualname):
    """The Examples section runs and prints what it says (numbers rounded so that they do not
    depend on the BLAS build)."""
    obj = USER_PATH[qualname][0]
    tests = doctest.DocTestFinder(recurse=False).find(obj, qualname, globs={})
    assert tests and any(ex for t in tests for ex in t.examples), "no example"
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for t in tests:
        runner.run(t)
    assert runner.failures == 0, f"{runner.failures} failing example(s) in {qualname}"
