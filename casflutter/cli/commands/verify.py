"""``casflutter verify PLANT.json CONTROLLER.json``: independent check of a controller.

Prints the :class:`casflutter.verify.VerificationReport` (or its JSON with ``--json``):
closed-loop poles, exact H∞ norm and peak frequency, and for an LFT in ΔV (``--vf``,
``--n-delta`` or the plant file's ``Vf``/``n_delta``) the small-gain and the exact
speed-index intervals (Lum et al. 2016, eq. 10-16).
"""

from __future__ import annotations

import json

from ...errors import ConfigError

__all__ = ["register", "run"]


def register(subparsers) -> None:
    """Add the ``verify`` sub-command."""
    p = subparsers.add_parser(
        "verify", help="verify a controller on a plant: poles, H-inf norm, V intervals",
        description="Independent check of a controller on a plant: closed-loop poles, exact "
                    "H-inf norm and peak frequency, small-gain and exact speed-index intervals "
                    "(Lum et al. 2016, eq. 10-16).")
    p.add_argument("plant", help="plant JSON (casflutter format or COMPleib keys "
                                 "A, B1, B, C1, D11, D12, C, D21, D22)")
    p.add_argument("controller", help="controller JSON with A, B, C, D (only D for a static "
                                      "gain)")
    p.add_argument("--nmeas", type=int, default=None,
                   help="number of measurements (last plant outputs); default from the file")
    p.add_argument("--ncon", type=int, default=None,
                   help="number of controls (last plant inputs); default from the file")
    p.add_argument("--vf", type=float, default=None,
                   help="nominal speed index Vf (eq. 10); default from the file")
    p.add_argument("--n-delta", type=int, default=None, dest="n_delta",
                   help="size of the ΔV channel (first inputs/outputs); default from the file")
    p.add_argument("--method", choices=("auto", "slycot", "scipy"), default="auto",
                   help="H-inf norm implementation (default: slycot if installed)")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    """Handler of ``casflutter verify``."""
    from ...verify import load_controller, load_plant, verify_controller

    plant = load_plant(args.plant)
    K = load_controller(args.controller)
    nmeas = args.nmeas if args.nmeas is not None else plant.nmeas
    ncon = args.ncon if args.ncon is not None else plant.ncon
    if nmeas is None or ncon is None:
        raise ConfigError(f"{args.plant} does not say how many measurements/controls the "
                          "plant has; pass --nmeas N --ncon N")
    Vf = args.vf if args.vf is not None else plant.Vf
    n_delta = args.n_delta if args.n_delta is not None else plant.n_delta
    if Vf is None or n_delta is None:
        if Vf is not None or n_delta is not None:
            raise ConfigError("the ΔV intervals need both Vf and n_delta: pass --vf and "
                              "--n-delta (or put Vf and n_delta in the plant file)")
    report = verify_controller(plant.sys, K, nmeas, ncon, Vf=Vf, n_delta=n_delta,
                               method=args.method)
    if args.json:
        print(json.dumps(report.to_dict(), indent=1))
    else:
        print(report.format())
    return 0
