"""``load_rom_loop``: ΣAE(V) from the ``.npz`` a benchmark keeps, and clear errors for files
that are not one.  Truth used: the loop built here directly from the file's arrays."""

from __future__ import annotations

import numpy as np
import pytest

from casflutter._resources import problems_dir
from casflutter.aeroelastic import AeroelasticSystem, load_rom_loop
from casflutter.errors import DataError
from casflutter.structure import ModalStructure

FILE = problems_dir() / "seed_wing_rom" / "rom_loop_seed0.npz"


def test_the_loop_is_the_one_the_arrays_describe():
    system, Vf = load_rom_loop(FILE)
    d = np.load(FILE)
    s = ModalStructure(omega=d["omega"], zeta=d["zeta"], alpha=float(d["alpha"]), Hs=d["Hs"],
                       sensor=str(d["sensor"]))
    ref = AeroelasticSystem(s, d["Af"], d["Bf"], d["bf"], d["Cf"], d["Df"], d["df"])
    assert Vf == float(d["Vf"])
    for V in (0.5, Vf, 2.0):
        assert np.array_equal(system.loop(V).A, ref.loop(V).A)
    # and Vf is the loop's flutter speed: the rightmost eigenvalue crosses there
    a = [np.max(np.linalg.eigvals(system.loop(V).A).real) for V in (0.99 * Vf, 1.01 * Vf)]
    assert a[0] < 0 < a[1]


def test_a_file_that_is_not_an_npz_is_named(tmp_path):
    bad = tmp_path / "loop.npz"
    bad.write_text("not numpy")
    with pytest.raises(DataError, match="loop.npz: not a readable .npz"):
        load_rom_loop(bad)


def test_every_missing_array_is_listed(tmp_path):
    bad = tmp_path / "loop.npz"
    np.savez(bad, Af=np.eye(2), Vf=1.0)
    with pytest.raises(DataError, match=r"missing \['Bf', 'bf', 'Cf'"):
        load_rom_loop(bad)


def test_a_single_npy_array_is_named(tmp_path):
    path = tmp_path / "loop.npy"
    np.save(path, np.zeros(3))
    with pytest.raises(DataError, match="loop.npy: a single array, not an .npz"):
        load_rom_loop(path)
