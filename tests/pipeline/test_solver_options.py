"""Solver options are checked against the installed Ipopt's own option list before any work.

The list is read from Ipopt's documentation (``print_options_documentation``); these tests
check it against Ipopt's documented values and against Ipopt's own validation, which refuses
an invalid setting when a solver is built.
"""

import time

import pytest

from casflutter._nlp import _tiny_solver, check_solver_options, ipopt_option_list
from casflutter.errors import ConfigError
from casflutter.pipeline import load_config


def test_list_matches_ipopt_documentation():
    # Ipopt's documented options (https://coin-or.github.io/Ipopt/OPTIONS.html)
    opts = ipopt_option_list()
    assert len(opts) > 200
    tol, lvl, frac = opts["tol"], opts["print_level"], opts["bound_frac"]
    assert (tol.kind, tol.low, tol.low_strict, tol.high) == ("real", 0.0, True, None)
    assert (lvl.kind, lvl.low, lvl.high, lvl.low_strict, lvl.high_strict) == (
        "integer", 0, 12, False, False)
    assert (frac.low, frac.high, frac.low_strict, frac.high_strict) == (0, 0.5, True, False)
    assert opts["mu_strategy"].values == ("monotone", "adaptive")
    assert set(opts["hessian_approximation"].values) == {"exact", "limited-memory"}


def _ipopt_refuses(name, value) -> bool:
    try:
        _tiny_solver({f"ipopt.{name}": value})
    except RuntimeError:
        return True
    return False


def test_list_agrees_with_ipopt_own_validation():
    """At every documented bound and just outside it, the list's verdict is Ipopt's."""
    checked = 0
    for opt in ipopt_option_list().values():
        if opt.kind == "string":
            if opt.values:
                assert _ipopt_refuses(opt.name, "surely-not-a-setting"), opt.name
                assert opt.accepts(opt.values[0]) and not _ipopt_refuses(opt.name,
                                                                         opt.values[0])
                checked += 1
            continue
        for bound in (opt.low, opt.high):
            if bound is None:
                continue
            step = 1 if opt.kind == "integer" else max(abs(bound) * 1e-3, 1e-3)
            for value in (bound, bound - step, bound + step):
                value = int(value) if opt.kind == "integer" else float(value)
                assert opt.accepts(value) != _ipopt_refuses(opt.name, value), (opt, value)
                checked += 1
    assert checked > 200


@pytest.mark.parametrize("options,match", [
    ({"ipopt.foo_bar": 1}, r"^solver.ipopt: unknown Ipopt option 'ipopt.foo_bar' = 1"),
    ({"ipopt.tool": 1e-3}, r"unknown Ipopt option 'ipopt.tool' .*did you mean ipopt.tol\?"),
    ({"ipopt.tol": -1.0}, r"'ipopt.tol' = -1.0 is not allowed: give a real number with 0 < tol"),
    ({"ipopt.tol": "x"}, r"'ipopt.tol' = 'x' is not allowed"),
    ({"ipopt.max_iter": 2.5}, r"'ipopt.max_iter' = 2.5 .*give an integer with 0 <= max_iter"),
    ({"ipopt.print_level": 13}, r"0 <= print_level <= 12"),
    ({"ipopt.mu_strategy": "bogus"}, r"give one of \"monotone\", \"adaptive\""),
    ({"print_tim": False}, r"unknown solver option 'print_tim' .*did you mean print_time"),
    ({"ipopt": {"tol": 0.0}}, r"'ipopt.tol' = 0.0 is not allowed"),
])
def test_bad_options_are_named(options, match):
    with pytest.raises(ConfigError, match=match):
        check_solver_options(options, "solver.ipopt")


def test_valid_options_pass_flat():
    ok = {"ipopt.tol": 1e-9, "ipopt.sb": "yes", "print_time": False, "ipopt.max_iter": 5,
          "ipopt": {"mu_strategy": "adaptive"}}
    assert check_solver_options(ok) == {"ipopt.tol": 1e-9, "ipopt.sb": "yes",
                                        "print_time": False, "ipopt.max_iter": 5,
                                        "ipopt.mu_strategy": "adaptive"}


@pytest.mark.parametrize("text,match", [
    ('[solver.ipopt]\n"ipopt.nonsense" = 3\n', r"^solver.ipopt: unknown Ipopt option"),
    ('[rom]\nipopt_options = {"ipopt.tol" = -1}\n', r"^rom.ipopt_options: Ipopt option"),
    ('[controller]\nipopt = {"ipopt.mu_strategy" = "x"}\n', r"^controller.ipopt: Ipopt option"),
])
def test_run_config_checks_options_at_load(tmp_path, text, match):
    p = tmp_path / "run.toml"
    p.write_text(text)
    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match=match):
        load_config(p)
    assert time.perf_counter() - t0 < 1.0
