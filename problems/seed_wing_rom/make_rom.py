"""Regenerate ``rom.npz``: the seed-wing HWL ROM of ``casflutter run`` (stages 1-2).

The ROM of the default run configuration (``problems/seed_wing/run.toml``): chirp records
of the seed-wing truth at ``V0 = 0.69`` with the one-step coupling delay, the paper's orders
(3, 1, 1, 1, 2, 2), identified by :func:`casflutter.ident.identify`.  It is an *input* of
the LCO tests of the sampled-data ROM loop (``tests/lco/test_rom_loop.py``), which check the
invariant circles against :func:`casflutter.aeroelastic.simulate_loop` run on this same ROM.

Run from the repository root: ``python problems/seed_wing_rom/make_rom.py``.
"""

from pathlib import Path

from casflutter.ident import identify
from casflutter.pipeline import load_config
from casflutter.pipeline._rom_data import truth_records
from casflutter.pipeline._run import delayed
from casflutter.truth import load_problem

HERE = Path(__file__).resolve().parent


def main() -> None:
    cfg = load_config(HERE.parent / "seed_wing" / "run.toml")
    truth = load_problem(cfg.problem.name, [f"{k}={v}" for k, v in cfg.problem.set.items()])
    d = cfg.data
    data = delayed(truth_records(truth, d.V0, dt=d.dt, duration=d.duration,
                                 band=tuple(d.band_hz), amplitude=d.amplitude),
                   d.coupling_delay)
    ident = identify(data, tuple(cfg.rom.orders), criterion=cfg.rom.criterion,
                     regularization=cfg.rom.regularization,
                     ipopt_options=dict(cfg.solver.ipopt))
    ident.model.save(HERE / "rom.npz")
    print(ident.model, "fit error %", ident.fit.error_percent)


if __name__ == "__main__":
    main()
