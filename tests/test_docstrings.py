"""The user path's docstrings, checked by numpydoc's own validator.

Every function, class and public method reachable from ``casflutter.__all__`` (the flat
user path) is validated with :func:`numpydoc.validate.validate`.  The checks enforced:

- ``GL08`` a docstring exists; ``SS01``/``SS03`` a one-line summary ending in a period
  (what a reader sees in ``help()`` and in the API tables);
- ``PR02`` no documented parameter that the signature lacks, ``PR07`` every documented
  parameter is described, ``PR10`` the ``name : type`` colon spacing that Sphinx parses;
- on the user-path *functions* also ``PR01`` (every parameter documented) and ``RT01``
  (a Returns section), so a script writer finds every argument and result in the docs.

Not enforced (yet): ``PR01``/``RT01`` on methods and on the dataclasses' generated
constructors (their fields are documented as Attributes, which numpydoc's PR01 does not
read), and the style checks (``SS05`` imperative mood, ``GL02`` quote placement) that do not
change what a reader learns.
"""

from __future__ import annotations

import inspect

import pytest
from numpydoc.validate import validate

import casflutter

ALL_OBJECTS = ("GL08", "SS01", "SS03", "PR02", "PR07", "PR10")
FUNCTIONS = ALL_OBJECTS + ("PR01", "RT01")


def _user_path() -> dict[str, tuple[object, tuple[str, ...]]]:
    out: dict[str, tuple[object, tuple[str, ...]]] = {}
    for name in casflutter.__all__:
        obj = getattr(casflutter, name)
        if inspect.isfunction(obj):
            out[f"{obj.__module__}.{obj.__qualname__}"] = (obj, FUNCTIONS)
        elif inspect.isclass(obj) and obj.__module__.startswith("casflutter"):
            out[f"{obj.__module__}.{obj.__qualname__}"] = (obj, ALL_OBJECTS)
            for attr, value in vars(obj).items():
                if attr.startswith("_"):
                    continue
                if isinstance(value, (classmethod, staticmethod)):
                    value = value.__func__
                if inspect.isfunction(value):
                    out[f"{obj.__module__}.{obj.__qualname__}.{attr}"] = (value, ALL_OBJECTS)
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
