"""A controller matched to a plant family's signals by name.

A controller file (``casflutter-controller/1``, :func:`casflutter.verify.controller_from_json`
with the descriptive keys of a run's export) names its inputs and outputs: entries with a
``"name"`` and maybe a ``"signal"`` (or plain strings).  They are matched to the family's
measurements (the controller's inputs) and controls (its outputs) by name, ``"name"`` first,
then ``"signal"``: any subset, in any order.  An optional ``"feedback"`` key
(``"positive"``: ``u = +K y``; ``"negative"``: ``u = -K y``) overrides the family's
convention.  A file without names is accepted only when its sizes equal the family's numbers
of measurements and controls, and then their order is assumed (and said).  Every check runs
before any analysis.
"""

from __future__ import annotations

import difflib
import json
import logging
import os
from dataclasses import dataclass, replace

import control

from .._format import result_repr
from ..aeroelastic import FEEDBACK_SIGNS
from ..errors import ConfigError, DataError, DimensionError
from ._common import as_statespace, check_continuous, ssdata
from ._io import controller_from_json

__all__ = ["FamilyController", "match_controller"]

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class FamilyController:
    """A controller and the family signals it acts on.

    Attributes
    ----------
    K : control.StateSpace
        Continuous controller, inputs in the order of ``measurements``, outputs in the order
        of ``controls``.
    controls : tuple of str
        The family's inputs K drives.
    measurements : tuple of str
        The family's outputs K reads.
    feedback : str
        ``"positive"`` (``u = +K y``) or ``"negative"`` (``u = -K y``).
    notes : tuple of str
        How the match was made (an assumed order, a convention taken from the file).
    """

    __repr__ = result_repr

    K: control.StateSpace
    controls: tuple
    measurements: tuple
    feedback: str
    notes: tuple = ()

    @property
    def sign(self) -> float:
        """``+1`` or ``-1``: ``u = sign · K y``."""
        return FEEDBACK_SIGNS[self.feedback]


def _entry_names(entries, what: str, n: int) -> list | None:
    """The (name, signal) pairs of a file's ``inputs``/``outputs`` list, or None."""
    if entries is None:
        return None
    if not isinstance(entries, list) or len(entries) != n:
        size = len(entries) if isinstance(entries, list) else type(entries).__name__
        raise DimensionError(f"the controller file's {what!r} has {size} entries but the "
                             f"controller has {n} {what}; give one entry per {what[:-1]}")
    out = []
    for i, e in enumerate(entries):
        if isinstance(e, str):
            out.append((e, None))
        elif isinstance(e, dict) and (isinstance(e.get("name"), str)
                                      or isinstance(e.get("signal"), str)):
            out.append((e.get("name"), e.get("signal")))
        else:
            raise DataError(f"the controller file's {what}[{i}] = {e!r:.80} has neither a "
                            "\"name\" nor a \"signal\" string")
    return out


def _match(pairs, pool: tuple, other: tuple, what: str, role: str, family: str) -> tuple:
    """Family signal names for a list of (name, signal) pairs."""
    matched, problems = [], []
    for i, (name, signal) in enumerate(pairs):
        hit = next((x for x in (name, signal) if x is not None and x in pool), None)
        if hit is not None:
            matched.append(hit)
            continue
        given = [x for x in (name, signal) if x is not None]
        wrong_role = [x for x in given if x in other]
        if wrong_role:
            problems.append(f"{what}[{i}] {wrong_role[0]!r} is a signal of {family} but not "
                            f"one of its {role}s")
            continue
        close = sorted({c for x in given for c in difflib.get_close_matches(x, pool, 2, 0.5)})
        problems.append(f"{what}[{i}] ({' / '.join(repr(x) for x in given)}) matches no "
                        f"{role}" + (f" (close: {', '.join(map(repr, close))})" if close
                                     else ""))
    if problems:
        raise ConfigError(f"the controller's {what} do not match {family}: "
                          + "; ".join(problems) + f". The {role}s are {list(pool)}; name "
                          f"each controller {what[:-1]} after one of them")
    dup = sorted({m for m in matched if matched.count(m) > 1})
    if dup:
        raise ConfigError(f"the controller's {what} name {dup} more than once; each "
                          f"{role} may be used by one controller {what[:-1]} only")
    return tuple(matched)


def _side(pairs, size: int, pool: tuple, other: tuple, what: str, role: str, family: str,
          notes: list) -> tuple:
    """The family signals of the controller's inputs (or outputs): matched by name, or, when
    the file names none, the family's own list in its order (if the sizes agree)."""
    if pairs is not None:
        return _match(pairs, pool, other, what, role, family)
    if size != len(pool):
        raise DimensionError(f"the controller has {size} {what} and no names, but {family} "
                             f"has {len(pool)} {role}s {list(pool)}; name the controller's "
                             f"{what} (\"{what}\": [{{\"name\": ...}}]) or give one per {role}")
    notes.append(f"the controller's {what} are unnamed: taken as the {role}s in the family's "
                 f"order {list(pool)}")
    return tuple(pool)


def _document(controller) -> dict | None:
    if isinstance(controller, dict):
        return controller
    if isinstance(controller, (str, os.PathLike)):
        try:
            with open(controller, encoding="utf-8") as fh:
                return json.load(fh)
        except FileNotFoundError:
            raise DataError(f"controller file not found: {controller}") from None
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise DataError(f"{controller} is not a JSON controller file ({exc})") from None
        except OSError as exc:
            raise DataError(f"{controller} cannot be read ({exc.strerror or exc})") from None
    return None


def match_controller(family, controller, *, feedback: str | None = None
                     ) -> FamilyController:
    """Match a controller to a family's measurements and controls.

    Parameters
    ----------
    family : casflutter.aeroelastic.PlantFamily
        The plant family.
    controller : dict, str, path-like, control.StateSpace or FamilyController
        A controller document (``casflutter-controller/1`` or hand-written ``A, B, C, D``
        with optional ``inputs``/``outputs`` names and ``feedback``), its path, or a
        python-control system whose ``input_labels``/``output_labels`` name family signals
        (python-control's default labels ``u[i]``/``y[i]`` count as no names).
    feedback : {"positive", "negative"}, optional
        The convention, overriding the file's and the family's.

    Returns
    -------
    FamilyController

    Raises
    ------
    ConfigError
        Names that match no measurement/control (the close ones are named), a name used
        twice, a discrete-time controller, an unknown feedback value, or a time unit other
        than the family's.
    DimensionError
        Name lists of the wrong length, or (without names) sizes other than the family's.
    DataError
        A file that cannot be read.
    """
    if isinstance(controller, FamilyController):
        if feedback is not None and feedback not in FEEDBACK_SIGNS:
            raise ConfigError(f"feedback = {feedback!r}: 'negative' or 'positive'")
        return controller if feedback is None else replace(controller, feedback=feedback)
    sig, fam = family.signals, family.name
    notes = []
    doc = _document(controller)
    if doc is not None:
        if not isinstance(doc, dict):
            raise DataError(f"a controller file holds a JSON object, got {type(doc).__name__}")
        K = controller_from_json(doc)
        ins = _entry_names(doc.get("inputs"), "inputs", K.ninputs)
        outs = _entry_names(doc.get("outputs"), "outputs", K.noutputs)
        file_fb = doc.get("feedback")
        unit = (doc.get("time_base") or {}).get("time_unit") if isinstance(
            doc.get("time_base"), dict) else None
        if unit is not None and str(unit) != str(family.time_unit):
            raise ConfigError(f"the controller's time unit is {unit!r} but {fam}'s is "
                              f"{family.time_unit!r}: its frequencies would be misread; "
                              "use a controller made for this family's time unit")
    else:
        K = as_statespace(controller, "controller")
        labels_in, labels_out = list(K.input_labels), list(K.output_labels)
        default_in = labels_in == [f"u[{i}]" for i in range(K.ninputs)]
        default_out = labels_out == [f"y[{i}]" for i in range(K.noutputs)]
        ins = None if default_in else [(n, None) for n in labels_in]
        outs = None if default_out else [(n, None) for n in labels_out]
        file_fb = None
    check_continuous(K, "the controller")
    for name, value in (("feedback", feedback), ("the controller file's \"feedback\"",
                                                 file_fb)):
        if value is not None and value not in FEEDBACK_SIGNS:
            raise ConfigError(f"{name} = {value!r}: 'negative' (u = -K y, MATLAB's "
                              "feedback()) or 'positive' (u = +K y, the paper's v = K zm)")
    if feedback is not None:
        fb = feedback
    elif file_fb is not None:
        fb = file_fb
        if file_fb != family.feedback:
            notes.append(f"feedback {file_fb!r} from the controller file (the family says "
                         f"{family.feedback!r})")
    else:
        fb = family.feedback
    others_out = tuple(o for o in sig.outputs if o not in sig.measurements) + sig.inputs
    others_in = tuple(i for i in sig.inputs if i not in sig.controls) + sig.outputs
    measurements = _side(ins, K.ninputs, sig.measurements, others_out, "inputs",
                         "measurement", fam, notes)
    controls = _side(outs, K.noutputs, sig.controls, others_in, "outputs", "control", fam,
                     notes)
    for note in notes:
        _log.info("%s", note)
    K = control.ss(*ssdata(K), inputs=list(measurements), outputs=list(controls))
    return FamilyController(K, tuple(controls), tuple(measurements), fb, tuple(notes))
