"""Help texts as a terminal shows them: the reST markup of the docstrings the sub-commands
use as descriptions (````code````, ``:func:`name```, ```text```) read as plain text."""

from __future__ import annotations

import argparse
import re

__all__ = ["plain", "plain_help"]

#: a Sphinx role, ``:func:`~casflutter.ident.identify``` or ``:doc:`title <target>```
_ROLE = re.compile(r":(?:py:)?[a-z]+:`([^`]+)`")
#: inline literals and interpreted text
_LITERAL = re.compile(r"``(.+?)``", re.S)
_INTERPRETED = re.compile(r"`([^`]+)`")


def _role(match: re.Match) -> str:
    text = match.group(1)
    if text.endswith(">") and "<" in text:          # an explicit title
        return text[:text.index("<")].strip()
    if text.startswith("~"):                        # the last name only
        return text[1:].rsplit(".", 1)[-1]
    return text


def plain(text: str | None) -> str | None:
    """``text`` with its reST roles, literals and interpreted text as plain words.

    Parameters
    ----------
    text : str or None
        A help text or description.

    Returns
    -------
    str or None
    """
    if not text:
        return text
    text = _ROLE.sub(_role, text)
    text = _LITERAL.sub(r"\1", text)
    return _INTERPRETED.sub(r"\1", text)


def plain_help(parser: argparse.ArgumentParser) -> None:
    """:func:`plain` on the description, epilog and every help text of ``parser`` and its
    sub-commands (in place).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command line's parser.
    """
    parser.description = plain(parser.description)
    parser.epilog = plain(parser.epilog)
    for action in parser._actions:
        if action.help not in (None, argparse.SUPPRESS):
            action.help = plain(action.help)
        if isinstance(action, argparse._SubParsersAction):
            for choice in action._choices_actions:
                choice.help = plain(choice.help)
            for sub in set(action.choices.values()):
                plain_help(sub)
