"""Packaging: the declared Python versions are the ones the code runs on, one version source,
a BSD-3-Clause LICENSE and ``py.typed`` in the repository and in the wheel, lower-bounded
documentation dependencies."""

from __future__ import annotations

import importlib.metadata
import re
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.specifiers import SpecifierSet

import casflutter

ROOT = Path(__file__).resolve().parents[2]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
PROJECT = PYPROJECT["project"]


def test_declared_python_versions_have_tomllib():
    # casflutter._resources imports tomllib (standard library from 3.11 on), unconditionally
    assert "import tomllib" in (ROOT / "casflutter" / "_resources.py").read_text()
    spec = SpecifierSet(PROJECT["requires-python"])
    assert "3.10" not in spec and "3.11" in spec
    assert f"{sys.version_info.major}.{sys.version_info.minor}" in spec
    listed = [c.rsplit(" :: ", 1)[1] for c in PROJECT["classifiers"]
              if re.fullmatch(r"Programming Language :: Python :: 3\.\d+", c)]
    assert listed and all(v in spec for v in listed)


def test_one_version_source():
    assert "version" not in PROJECT and "version" in PROJECT["dynamic"]
    attr = PYPROJECT["tool"]["setuptools"]["dynamic"]["version"]["attr"]
    assert attr == "casflutter.__version__"
    assert importlib.metadata.version("casflutter") == casflutter.__version__


def test_license_and_py_typed_are_declared_and_present():
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("BSD 3-Clause License")
    assert "Copyright (c) 2026, the casflutter developers" in text
    assert "Neither the name of the copyright holder" in text  # the third clause
    assert PROJECT["license"] == "BSD-3-Clause" and PROJECT["license-files"] == ["LICENSE"]
    assert not any(c.startswith("License ::") for c in PROJECT["classifiers"])  # PEP 639
    assert (ROOT / "casflutter" / "py.typed").is_file()
    assert "py.typed" in PYPROJECT["tool"]["setuptools"]["package-data"]["casflutter"]
    assert "Typing :: Typed" in PROJECT["classifiers"]
    assert "urls" not in PROJECT  # no invented project pages


def test_docs_dependencies_are_lower_bounded():
    for req in map(Requirement, PROJECT["optional-dependencies"]["docs"]):
        ops = {s.operator for s in req.specifier}
        assert ops == {">="}, f"{req}: give a lower bound, not a pin"
    sphinx = next(Requirement(r) for r in PROJECT["optional-dependencies"]["docs"]
                  if r.startswith("sphinx>"))
    assert "9.0.4" in sphinx.specifier  # the version the site is built and checked with


@pytest.mark.slow
def test_the_wheel_holds_license_py_typed_and_the_problems(tmp_path):
    # build from a copy: an in-tree build would leave build/ and *.egg-info in the checkout
    src = tmp_path / "src"
    shutil.copytree(ROOT, src, symlinks=True, ignore=shutil.ignore_patterns(
        ".venv", ".git", "build", "dist", "docs", "tests", "*.egg-info", "__pycache__"))
    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", "-w",
                           str(tmp_path), str(src)], capture_output=True, text=True,
                          timeout=600)
    if proc.returncode != 0 and "Could not find a version" in proc.stderr:
        pytest.skip("no build backend reachable (offline)")
    assert proc.returncode == 0, proc.stderr
    wheel = next(tmp_path.glob("casflutter-*.whl"))
    assert wheel.name.startswith(f"casflutter-{casflutter.__version__}-")
    names = zipfile.ZipFile(wheel).namelist()
    assert "casflutter/py.typed" in names
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names)
    assert any(n.startswith("casflutter/_problems/typical_section/") for n in names)
    # the seed wing's frozen ROM loop (examples and load_rom_loop) ships; measured records that only an
    # example reads, and the tests' witness controllers, do not
    assert "casflutter/_problems/seed_wing_rom/rom_loop_seed0.npz" in names
    assert not any(n.endswith(".mat") and "/f16gvt/" in n for n in names)
    assert not any("witnesses" in n or n.endswith("_controller.json") for n in names)
    meta = zipfile.ZipFile(wheel).read(next(n for n in names if n.endswith("METADATA"))).decode()
    assert "License-Expression: BSD-3-Clause" in meta and "Requires-Python: >=3.11" in meta
