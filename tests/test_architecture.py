"""The shape of the package: a stage imports only the stages to its left, no import cycle, and
the user path loads from ``import casflutter`` without importing the stages up front.

The imports are read from the source (``ast``), module-level and function-local alike, so a
late import cannot hide an arrow running backwards.
"""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "casflutter"

#: the stages, left to right; a module may import its own stage and those to its left
LAYERS = ["structure", "data", "truth", "ident", "realize", "aeroelastic", "lco", "design",
          "verify", "report", "pipeline", "study", "cli", "__main__"]
#: helpers every stage may use
INFRASTRUCTURE = {"errors", "_nlp", "_resources", "_settings", "_linalg", "_threads", "_logging",
                  "_outputs", "_interrupt", "_format", "_processes", "__init__"}
#: known exceptions (none: design/ computes its own norms and never imports verify/, the
#: layer that must share no code with the optimiser)
KNOWN: set = set()


def _modules():
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT.parent).with_suffix("")
        parts = list(rel.parts)
        is_pkg = parts[-1] == "__init__"
        if is_pkg:
            parts = parts[:-1]
        yield ".".join(parts), path, is_pkg


def _imports(name: str, path: Path, is_pkg: bool):
    """``(imported casflutter module, at module level)`` for every import in ``path``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = name if is_pkg else name.rsplit(".", 1)[0]
    top_level = {id(n) for n in tree.body}
    for node in ast.walk(tree):
        level_ok = id(node) in top_level
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("casflutter"):
                    yield a.name, level_ok
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            if not mod.startswith("casflutter"):
                continue
            if node.module is None or node.level and not node.module:
                for a in node.names:  # from . import x: a submodule, or a name of the package
                    sub = ROOT.parent.joinpath(*f"{mod}.{a.name}".split("."))
                    is_module = sub.is_dir() or sub.with_suffix(".py").is_file()
                    yield (f"{mod}.{a.name}" if is_module else mod), level_ok
            else:
                yield mod, level_ok


def _unit(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def test_a_stage_imports_only_stages_to_its_left():
    bad = []
    for name, path, is_pkg in _modules():
        src = _unit(name)
        if src in INFRASTRUCTURE:
            allowed = INFRASTRUCTURE
        else:
            allowed = INFRASTRUCTURE | set(LAYERS[:LAYERS.index(src) + 1])
        for mod, _ in _imports(name, path, is_pkg):
            dst = _unit(mod)
            if name == "casflutter" or dst in allowed or (src, dst) in KNOWN:
                continue
            bad.append(f"{name} imports {mod}")
    assert not bad, "\n".join(bad)


def test_no_import_cycle_between_modules():
    """The imports between modules form a directed acyclic graph, function-local imports
    included (a cycle hidden in a function is still a cycle)."""
    names = {n for n, _, _ in _modules()}
    graph = {}
    for name, path, is_pkg in _modules():
        deps = set()
        for mod, _ in _imports(name, path, is_pkg):
            while mod and mod not in names:
                mod = mod.rpartition(".")[0]
            # a module importing from its own package's __init__ is not a cycle
            if mod and mod != name and not name.startswith(mod + "."):
                deps.add(mod)
        graph[name] = deps
    state: dict[str, int] = {}

    def visit(node, stack):
        state[node] = 1
        for nxt in graph.get(node, ()):
            if state.get(nxt) == 1:
                cycle = stack[stack.index(nxt):] + [nxt] if nxt in stack else [node, nxt]
                raise AssertionError("import cycle: " + " -> ".join(cycle))
            if nxt not in state:
                visit(nxt, stack + [nxt])
        state[node] = 2

    for n in sorted(graph):
        if n not in state:
            visit(n, [n])


@pytest.mark.parametrize("order", ["forward", "reverse"])
def test_every_module_imports_in_a_fresh_interpreter_in_either_order(order):
    """All modules load in one fresh interpreter, in name order and in reverse name order
    (no hidden order dependency)."""
    names = sorted(n for n, _, _ in _modules())
    if order == "reverse":
        names.reverse()
    code = "import importlib\n" + "".join(f"importlib.import_module({n!r})\n" for n in names)
    subprocess.run([sys.executable, "-c", code], check=True, timeout=300)


def test_the_user_path_loads_from_the_top_lazily():
    code = ("import sys, casflutter as cf\n"
            "assert 'casflutter.design' not in sys.modules and 'casadi' not in sys.modules\n"
            "names = ['identify', 'realize', 'AeroelasticSystem', 'find_flutter',\n"
            "         'simulate_loop', 'build_lft', 'synthesize', 'verify_controller', 'run',\n"
            "         'load_config', 'ModalStructure', 'truth_records', 'load_problem']\n"
            "for n in names:\n"
            "    assert callable(getattr(cf, n)), n\n"
            "    assert n in dir(cf)\n"
            "from casflutter.aeroelastic import find_flutter\n"
            "assert cf.find_flutter is find_flutter\n"
            "try:\n"
            "    cf.no_such_name\n"
            "except AttributeError:\n"
            "    pass\n"
            "else:\n"
            "    raise SystemExit('no AttributeError')\n")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)


def test_realize_stays_the_function_after_its_stage_is_imported():
    """``casflutter.realize`` names both the stage and its function: after anything imports the
    stage (here the loop stage, which uses it), ``cf.realize(model)`` still realises a model
    and ``import casflutter.realize as rz`` still gives the stage's other functions."""
    code = ("import inspect, numpy as np\n"
            "import casflutter.aeroelastic\n"
            "import casflutter as cf\n"
            "import casflutter.realize as rz\n"
            "from casflutter.realize._realize import realize\n"
            "truth = cf.load_problem('typical_section')\n"
            "data = cf.truth_records(truth, V0=1.8, dt=0.1, duration=60.0, band=(0.002, 1))\n"
            "model = cf.identify_common_denominator(data).model\n"
            "a, b = cf.realize(model), realize(model)\n"
            "assert np.array_equal(a.sigma_f.A, b.sigma_f.A) and a.order == b.order == 8\n"
            "assert inspect.signature(cf.realize) == inspect.signature(realize)\n"
            "assert rz.era is casflutter.realize._realize.era\n")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)
