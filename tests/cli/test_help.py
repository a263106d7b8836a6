"""The command line's help reads as plain text: no reST markup from the docstrings, a help
text for every option, a suggestion for a misspelt problem name, and how to give the typical
section the nonlinearity an LCO needs."""

import argparse
import re

import pytest

from casflutter.cli import build_parser, main
from casflutter.cli._help import plain

MARKUP = re.compile(r"``|:(?:func|class|meth|mod|attr|doc|ref):`|`[^`\s][^`]*`")


def _parsers(parser, path=("casflutter",)):
    yield path, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _parsers(sub, path + (name,))


PARSERS = list(_parsers(build_parser()))


def test_the_walk_finds_every_sub_command():
    names = {" ".join(p) for p, _ in PARSERS}
    for cmd in ("run", "flutter", "lco", "identify", "verify", "problems", "demo",
                "bench identify"):
        assert f"casflutter {cmd}" in names


@pytest.mark.parametrize("path, parser", PARSERS, ids=[" ".join(p) for p, _ in PARSERS])
def test_help_is_plain_text_and_every_option_says_what_it_does(path, parser):
    text = parser.format_help()
    assert not MARKUP.search(text), MARKUP.findall(text)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            continue
        assert action.help, f"{' '.join(path)} {action.option_strings or action.dest}"


def test_plain_reads_roles_literals_and_titles():
    assert plain("``casflutter run`` (:func:`~casflutter.pipeline.run`, "
                 ":class:`casflutter.ident.HWLModel`, :doc:`the gallery <auto_examples/index>`)"
                 " and `V`") == ("casflutter run (run, casflutter.ident.HWLModel, the gallery) "
                                 "and V")


def test_a_misspelt_problem_name_gets_a_suggestion(capsys):
    assert main(["problems", "seedwing"]) == 1
    assert "did you mean 'seed_wing'?" in capsys.readouterr().err


def test_lco_on_the_linear_typical_section_says_how_to_add_a_cubic_term(capsys):
    assert main(["lco", "typical_section"]) == 1
    err = capsys.readouterr().err
    assert "degenerate" in err and "--set kappa2=3" in err
    # and the suggestion works: a supercritical branch
    assert main(["lco", "typical_section", "--set", "kappa2=3", "--max-points", "3",
                 "--json"]) == 0
    assert '"kind": "supercritical"' in capsys.readouterr().out
