"""``casflutter problems``: list the benchmark problems and their parameters."""

from __future__ import annotations

import json

from ...errors import ConfigError

__all__ = ["register", "run"]


def register(subparsers) -> None:
    """Add the ``problems`` sub-command."""
    p = subparsers.add_parser(
        "problems", help="list the problems, their parameters and published reference values",
        description="List the benchmark problems with a truth simulator, every parameter "
                    "(default = published case; change with --set name=value in the "
                    "commands that take a problem) and the published reference values.")
    p.add_argument("name", nargs="?", help="show only this problem (a name or a rig TOML file)")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE",
                   help="show the parameters with these changes applied (validated)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=run)


def _family_info(name: str, record) -> dict:
    """The listing of a gridded plant family (roles checked by building the family)."""
    from ...aeroelastic import load_family

    family = load_family(record)
    sig, v = family.signals, record.speeds
    left_out = [int(i) for i in family.left_out_states]
    return {"name": name, "truth": None, "kind": "plant_family",
            "description": record.description or record.describe(),
            "n_states": family.n_states, "n_states_file": record.n_states,
            "left_out_states": left_out, "speed_unit": record.speed_unit,
            "time_unit": record.time_unit, "feedback": record.feedback,
            "speeds": {"min": float(v[0]), "max": float(v[-1]), "count": int(v.size),
                       "interpolation": record.interpolation},
            "inputs": [{"name": n, "unit": u,
                        "role": "control" if n in sig.controls else "disturbance"}
                       for n, u in zip(sig.inputs, sig.input_units)],
            "outputs": [{"name": n, "unit": u,
                         "role": "measurement" if n in sig.measurements else "other"}
                        for n, u in zip(sig.outputs, sig.output_units)],
            "data_file": str(record.data_path), "reference": record.reference}


def _print_family(info: dict) -> None:
    v = info["speeds"]
    print(f"{info['name']}  (plant family: {info['n_states']} states, {len(info['inputs'])} "
          f"inputs, {len(info['outputs'])} outputs, {v['count']} speeds)")
    if info["left_out_states"]:
        print(f"  the file has {info['n_states_file']} states; states "
              f"{info['left_out_states']} (0-based) are left out: rigid-body positions, which "
              "feed no output or other state and keep a pole at the origin in every loop")
    print(f"  {info['description']}")
    print(f"  speeds {v['min']:g} .. {v['max']:g} {info['speed_unit']} ({v['interpolation']} "
          f"between them);  time unit: {info['time_unit']};  feedback: {info['feedback']}")
    for key in ("inputs", "outputs"):
        print(f"  {key}: " + ", ".join(f"{r['name']} [{r['unit']}]" + (
            f" ({r['role']})" if r["role"] in ("disturbance", "other") else "")
            for r in info[key]))
    print(f"  data file: {info['data_file']}")
    for key, vals in info["reference"].items():
        items = (", ".join(f"{k}={v}" for k, v in vals.items()) if isinstance(vals, dict)
                 else vals)
        print(f"  reference {key} (the file's [reference]): {items}")
    print()


def _info(name: str, sets) -> dict:
    from ...data import FamilyFile
    from ...truth import load_problem, problem_definition, problem_label

    model = load_problem(name, sets)
    if isinstance(model, FamilyFile):
        return _family_info(problem_label(name), model)
    params = model.params
    if getattr(model, "definition", None) is None:   # built-in: values beside the defaults
        rows = [{"name": n, "value": getattr(params, n), "default": d, "unit": u, "doc": doc}
                for n, d, u, doc in params.describe()]
    else:                                            # a problem file: the file is the default
        filed = dict((n, v) for n, v, _, _ in (load_problem(name).params.describe()
                                               if sets else params.describe()))
        rows = [{"name": n, "value": v, "default": filed[n], "unit": u, "doc": doc}
                for n, v, u, doc in params.describe()]
    name = problem_label(name)
    try:
        definition = problem_definition(name)
    except ConfigError:
        definition = {}
    ms = model.modal_structure()
    return {"name": name, "truth": type(model).__name__,
            "description": definition.get("problem", {}).get(
                "description", (type(model).__doc__ or "").strip().splitlines()[0]),
            "speed_index": ms.speed_index, "time_unit": ms.time_unit,
            "modes": list(ms.mode_names), "parameters": rows,
            "reference": definition.get("reference", {})}


def run(args) -> int:
    """Handler: print the listing; unknown problem or parameter names raise ConfigError."""
    from ...truth import file_problem_names, problem_names

    names = [args.name] if args.name else problem_names() + file_problem_names()
    infos = [_info(n, args.sets) for n in names]
    if args.json:
        print(json.dumps(infos, indent=2))
        return 0
    for info in infos:
        if info.get("kind") == "plant_family":
            _print_family(info)
            continue
        print(f"{info['name']}  ({info['truth']})")
        print(f"  {info['description']}")
        print(f"  speed index: {info['speed_index']};  time unit: {info['time_unit']}")
        print(f"  modes: {', '.join(info['modes'])}")
        print("  parameters:")
        w = max(len(r["name"]) for r in info["parameters"])
        for r in info["parameters"]:
            mark = "" if r["value"] == r["default"] else f"  (default {r['default']:g})"
            value = f"{r['value']:<12g}" if isinstance(r["value"], (int, float)) else \
                f"{r['value']!s:<12}"
            print(f"    {r['name']:<{w}} = {value} [{r['unit']}]  {r['doc']}{mark}")
        if info["reference"]:
            print("  published reference values:")
            for key, vals in info["reference"].items():
                items = ", ".join(f"{k}={v}" for k, v in vals.items())
                print(f"    {key}: {items}")
        print()
    return 0
