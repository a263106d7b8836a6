"""ΣAE(V) kept in a file: Σf, the modal structure and the loop's flutter speed (eq. 5-9).

A run's ROM loop is rebuilt from the identified model in seconds, but benchmarks, tests and
examples that study one fixed loop (e.g. the default run's, ``problems/seed_wing_rom/
rom_loop_seed0.npz``) read it from an ``.npz`` so that they do not depend on the
identification's last digits.
"""

from __future__ import annotations

import os

import numpy as np

from ..errors import DataError
from ..structure import ModalStructure
from ._loop import AeroelasticSystem

__all__ = ["load_rom_loop"]

_KEYS = ("Af", "Bf", "bf", "Cf", "Df", "df", "omega", "zeta", "alpha", "Hs", "sensor", "Vf")


def load_rom_loop(path: str | os.PathLike) -> tuple[AeroelasticSystem, float]:
    """The ROM loop ΣAE(V) and its flutter speed from an ``.npz`` file.

    Parameters
    ----------
    path : str or path-like
        An ``.npz`` with Σf of eq. 5 (``Af, Bf, bf, Cf, Df, df``), the modal structure of
        eq. 6-7 (``omega, zeta, alpha, Hs, sensor``) and the loop's flutter speed ``Vf``.

    Returns
    -------
    system : AeroelasticSystem
        ΣAE(V) of eq. 8-9 (the frozen loop: Σf scaled by V²).
    Vf : float
        The flutter speed index stored with it.

    Raises
    ------
    DataError
        A file that cannot be read as ``.npz``, or one that lacks any of the arrays (all
        missing names are listed).
    """
    try:
        loaded = np.load(path)
    except (OSError, ValueError) as exc:
        raise DataError(f"{path}: not a readable .npz ROM-loop file ({exc})") from None
    if not hasattr(loaded, "files"):     # a single .npy array, not named arrays
        raise DataError(f"{path}: a single array, not an .npz of named arrays")
    with loaded as npz:                   # closes the file; the arrays stay
        d = {k: npz[k] for k in npz.files}
    missing = [k for k in _KEYS if k not in d]
    if missing:
        raise DataError(f"{path}: missing {missing}; the file needs {list(_KEYS)} "
                        "(see problems/seed_wing_rom/rom_loop_seed0.npz)")
    s = ModalStructure(omega=d["omega"], zeta=d["zeta"], alpha=float(d["alpha"]), Hs=d["Hs"],
                       sensor=str(d["sensor"]))
    return (AeroelasticSystem(s, d["Af"], d["Bf"], d["bf"], d["Cf"], d["Df"], d["df"]),
            float(d["Vf"]))
