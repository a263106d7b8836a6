"""Every option of every command is reachable by its full name, and understood.

The parsers are enumerated from :func:`casflutter.cli.build_parser` itself (top level, each
sub-command, each ``bench`` sub-command), so an option added later is covered without
editing this file.  For each option a command line is built with a value of the option's
own type (one that differs from its default) and the parsed namespace must hold exactly that
value; a prefix of a long option must be refused (no abbreviations: a prefix could be taken
by another parser, as ``identify --v`` was by the top-level ``--version``/``--verbose``).
Then ``casflutter identify`` runs on small files with a flap column (``--y/--u/--v/--time``
on a CSV, ``--fs`` on a .mat) and the identified model has the flap input.
"""

from __future__ import annotations

import argparse
import functools

import numpy as np
import pytest
import scipy.io

from casflutter.cli import build_parser, main
from casflutter.ident import HWLModel, random_hwl_model, synthetic_data

#: values tried, in turn, for an option of a custom type (the first it accepts is used)
_CANDIDATES = ("2", "3", "0.5", "1,2", "x", "a=1")
_SKIP = (argparse._HelpAction, argparse._VersionAction, argparse._SubParsersAction)


@functools.lru_cache(maxsize=1)
def _top() -> argparse.ArgumentParser:
    """The command's parser, built once (parsing does not change it)."""
    return build_parser()


def _parsers(parser: argparse.ArgumentParser, path=()):
    """``(path, parser)`` of ``parser`` and of every sub-command below it."""
    yield path, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _parsers(sub, path + (name,))


def _convert(action: argparse.Action, text: str):
    if action.type is None:
        return text
    return action.type(text)


def _value(action: argparse.Action, avoid=None) -> tuple[list[str], object]:
    """Command-line words for ``action`` and the value the namespace should then hold."""
    if action.choices is not None:
        choices = [c for c in action.choices if c != avoid] or list(action.choices)
        text = str(choices[-1])
        words, value = [text], _convert(action, text)
    else:
        words = value = None
        for text in _CANDIDATES:
            try:
                converted = _convert(action, text)
            except Exception:  # noqa: BLE001 - the type refuses this candidate; try another
                continue
            if converted != avoid:
                words, value = [text], converted
                break
        assert words is not None, f"no candidate value fits {action.option_strings or action.dest}"
    nargs = action.nargs
    if isinstance(nargs, int):
        return words * nargs, [value] * nargs
    if nargs in ("+", "*"):
        return words * 2, [value] * 2
    return words, value


def _base(parser: argparse.ArgumentParser, path, skip: argparse.Action | None = None):
    """A valid command line for ``parser`` with every positional and required option, but
    ``skip``."""
    words: list[str] = list(path)
    for action in parser._actions:
        if action is skip or isinstance(action, _SKIP):
            continue
        if not action.option_strings:
            words += _value(action)[0]
        elif action.required:
            words += [action.option_strings[0]] + _value(action)[0]
    return words


def _options():
    for path, parser in _parsers(_top()):
        for action in parser._actions:
            if action.option_strings and not isinstance(action, _SKIP):
                for flag in action.option_strings:
                    yield pytest.param(path, flag, id=" ".join(path + (flag,)) or flag)


def _find(path, flag):
    top = _top()
    parser = dict(_parsers(top))[path]
    action = parser._option_string_actions[flag]
    return top, parser, action


@pytest.mark.parametrize("path, flag", list(_options()))
def test_each_option_is_understood_by_its_full_name(path, flag):
    top, parser, action = _find(path, flag)
    words = _base(parser, path, skip=action)
    if isinstance(action, argparse.BooleanOptionalAction):
        extra, expected = [flag], not flag.startswith("--no-")
    elif isinstance(action, (argparse._StoreConstAction, argparse._CountAction)):
        extra = [flag]
        expected = 1 if isinstance(action, argparse._CountAction) else action.const
    else:
        value_words, expected = _value(action, avoid=action.default)
        extra = [flag] + value_words
        if isinstance(action, argparse._AppendAction):
            expected = [expected]
    args = top.parse_args(words + extra)
    assert getattr(args, action.dest) == expected, (flag, words + extra)
    if action.nargs == "?" and action.const is not None:     # the bare flag gives the const
        assert getattr(top.parse_args(words + [flag]), action.dest) == action.const


@pytest.mark.parametrize("path, flag", [p for p in _options() if p.values[1].startswith("--")
                                        and len(p.values[1]) > 3])
def test_a_prefix_of_an_option_is_refused(path, flag, capsys):
    top, parser, action = _find(path, flag)
    prefix = flag[:-1]
    if prefix in parser._option_string_actions or (
            not path and prefix in top._option_string_actions):
        pytest.skip(f"{prefix} is an option of its own")
    words = _base(parser, path, skip=action)
    extra = [prefix] if action.nargs == 0 else [prefix] + _value(action)[0]
    with pytest.raises(SystemExit) as info:
        top.parse_args(words + extra)
    assert info.value.code == 2
    assert prefix in capsys.readouterr().err


def test_every_parser_refuses_abbreviations():
    for path, parser in _parsers(build_parser()):
        assert parser.allow_abbrev is False, path


def test_the_identify_data_options_are_there():
    """The options that name the columns of a data file (the paper's input ``v`` is the
    flap or shaker force): present and parsed as given, also written ``--v=COL``."""
    top = build_parser()
    args = top.parse_args(["identify", "d.csv", "--y", "f1,f2", "--u", "q1,q2", "--v", "flap",
                           "--time", "time_s", "--fs", "Fs", "--dt", "0.01"])
    assert (args.y, args.u, args.v, args.time, args.fs, args.dt) == (
        "f1,f2", "q1,q2", "flap", "time_s", "Fs", 0.01)
    assert top.parse_args(["identify", "d.csv", "--v=flap"]).v == "flap"
    # the global flags still work before and after the command
    assert top.parse_args(["--verbose", "identify", "d.csv", "--v", "v"]).verbose
    assert top.parse_args(["identify", "d.csv", "--v", "v", "-v"]).verbose


@pytest.fixture(scope="module")
def flap_records():
    """Records of a random HWL model with modal inputs and a flap input."""
    model = random_hwl_model(2, (2, 1, 1, 1, 2, 2), has_v=True, seed=1)
    return synthetic_data(model, 1500, seed=2, noise=0.02)


def test_identify_a_csv_with_a_flap_column(flap_records, tmp_path, capsys):
    rec = flap_records.records[0]
    t = np.arange(rec.y.shape[0]) * flap_records.dt
    path = tmp_path / "rec.csv"
    np.savetxt(path, np.column_stack([t, rec.y, rec.u, rec.v]), delimiter=",",
               header="time_s,f1,f2,q1,q2,flap", comments="")
    out = tmp_path / "model.npz"
    rc = main(["identify", str(path), "--y", "f1,f2", "--u", "q1,q2", "--v", "flap",
               "--time", "time_s", "--orders", "2,1,1,1,2,2", "--out", str(out)])
    assert rc == 0, capsys.readouterr().err
    model = HWLModel.load(out)
    assert model.has_u and model.has_v                       # the flap column was used
    assert model.dt == pytest.approx(flap_records.dt, rel=1e-9)   # read from --time
    assert "inputs u+v" in capsys.readouterr().out


def test_identify_a_mat_file_with_its_sampling_frequency(flap_records, tmp_path, capsys):
    rec = flap_records.records[0]
    path = tmp_path / "rec.mat"
    scipy.io.savemat(path, {"force": rec.y, "disp": rec.u, "shaker": rec.v,
                            "Fs": 1.0 / flap_records.dt})
    out = tmp_path / "model.npz"
    rc = main(["identify", str(path), "--y", "force", "--u", "disp", "--v", "shaker",
               "--fs", "Fs", "--orders", "2,1,1,1,2,2", "--out", str(out)])
    assert rc == 0, capsys.readouterr().err
    model = HWLModel.load(out)
    assert model.has_v and model.dt == pytest.approx(flap_records.dt, rel=1e-9)
