"""Messages of casflutter go through :mod:`logging`; this module holds the names and the
stderr handler that the command line installs.

Library code logs to ``logging.getLogger(__name__)`` -- a logger under ``casflutter``
(``casflutter.study._runner``, ``casflutter.data._records`` ...) -- and never prints.  The
package logger ``casflutter`` carries a :class:`logging.NullHandler`, so a library user sees
nothing unless the application configures logging; to silence or route the messages::

    import logging
    logging.getLogger("casflutter").setLevel(logging.WARNING)       # progress off
    logging.getLogger("casflutter").addHandler(logging.FileHandler("casflutter.log"))

Progress lines (a sweep's points done and left) are INFO records marked with the attribute
``casflutter_progress`` (``logger.info(line, extra=PROGRESS)``): the command line's handler
redraws them in place on a terminal; any other handler shows them as ordinary lines.

The command line (:func:`configure_cli_logging`) shows INFO and above on stderr by default,
WARNING and above with ``--quiet`` (the result lines on stdout stay), DEBUG with
``--verbose`` or ``--debug``.
"""

from __future__ import annotations

import logging
import sys
import warnings
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

__all__ = ["PACKAGE_LOGGER", "PROGRESS", "PROGRESS_END", "CliHandler", "configure_cli_logging",
           "remove_cli_logging", "cli_level", "own_warnings_logged"]

#: Name of the package logger; every casflutter logger is a child of it.
PACKAGE_LOGGER = "casflutter"

#: ``extra=`` of a progress record (redrawn in place by the command line on a terminal).
PROGRESS = {"casflutter_progress": True}

#: ``extra=`` of the last progress record of a run (the line is then left on the terminal).
PROGRESS_END = {"casflutter_progress": "end"}


def cli_level(*, quiet: bool = False, verbose: bool = False, debug: bool = False) -> int:
    """The level of the ``casflutter`` logger for the command-line flags (``--debug`` and
    ``--verbose`` win over ``--quiet``)."""
    if debug or verbose:
        return logging.DEBUG
    if quiet:
        return logging.WARNING
    return logging.INFO


class _Formatter(logging.Formatter):
    """Plain progress and information lines; ``casflutter: warning: ...`` above INFO;
    the logger name in front of every line with ``--debug``."""

    def __init__(self, debug: bool = False) -> None:
        super().__init__()
        self.debug = debug

    def format(self, record: logging.LogRecord) -> str:
        msg = record.getMessage()
        if record.exc_info and self.debug:
            msg = f"{msg}\n{self.formatException(record.exc_info)}"
        if record.levelno >= logging.WARNING:
            msg = f"casflutter: {record.levelname.lower()}: {msg}"
        if self.debug:
            msg = f"[{record.name}] {msg}"
        return msg


class CliHandler(logging.Handler):
    """Writes records to the *current* ``sys.stderr`` (looked up at every record, so that
    redirections and captured streams are honoured); progress records are redrawn in place
    when stderr is a terminal.  A closed stderr (broken pipe) is ignored."""

    def __init__(self, debug: bool = False) -> None:
        super().__init__()
        self.setFormatter(_Formatter(debug))
        self._line_open = False

    def emit(self, record: logging.LogRecord) -> None:
        try:
            stream = sys.stderr
            msg = self.format(record)
            tty = bool(getattr(stream, "isatty", lambda: False)())
            progress = getattr(record, "casflutter_progress", False)
            if progress and tty:
                end = "\n" if progress == "end" else ""
                stream.write("\r" + msg + "\x1b[K" + end)
                self._line_open = not end
            else:
                if self._line_open:
                    stream.write("\n")
                    self._line_open = False
                stream.write(msg + "\n")
            stream.flush()
        except (BrokenPipeError, ValueError):  # closed or detached stderr: nothing to do
            pass
        except Exception:  # noqa: BLE001 - logging's own convention
            self.handleError(record)

    def close_line(self) -> None:
        """End a progress line left open on a terminal."""
        if self._line_open:
            try:
                sys.stderr.write("\n")
                sys.stderr.flush()
            except (BrokenPipeError, ValueError):
                pass
            self._line_open = False


def configure_cli_logging(*, quiet: bool = False, verbose: bool = False,
                          debug: bool = False) -> CliHandler:
    """Install the command line's stderr handler on the ``casflutter`` logger (replacing
    one installed before) and set the level (:func:`cli_level`).

    Returns
    -------
    CliHandler
        The installed handler; :func:`remove_cli_logging` takes it away again.
    """
    logger = logging.getLogger(PACKAGE_LOGGER)
    for h in list(logger.handlers):
        if isinstance(h, CliHandler):
            logger.removeHandler(h)
    handler = CliHandler(debug=debug)
    logger.addHandler(handler)
    logger.setLevel(cli_level(quiet=quiet, verbose=verbose, debug=debug))
    return handler


def remove_cli_logging(handler: CliHandler, level: int = logging.NOTSET) -> None:
    """Take the command line's handler off the ``casflutter`` logger and restore its
    level (so that an in-process call of :func:`casflutter.cli.main` leaves no trace)."""
    handler.close_line()
    logger = logging.getLogger(PACKAGE_LOGGER)
    logger.removeHandler(handler)
    logger.setLevel(level)


#: the package's own source folder: a warning issued from a file under it is casflutter's own
_PACKAGE = Path(__file__).resolve().parent


def _own_warning(filename: str, text: str) -> bool:
    """A warning issued by casflutter's code, not numpy's floating-point word about it
    (``overflow encountered in matmul``)."""
    if " encountered in " in text:
        return False
    try:
        return Path(filename).resolve().is_relative_to(_PACKAGE)
    except (OSError, ValueError):
        return False


@contextmanager
def own_warnings_logged(logger: logging.Logger) -> Iterator[None]:
    """casflutter's own Python warnings (records used not as meant, an unstable ROM's free
    run, a loop unstable at the start of a search) as one WARNING record each on
    ``logger``, each text once, as every other message (``casflutter: warning: ...`` on
    the command line); numpy's floating-point warnings and other packages' are shown as
    before.

    Nested uses share the outer one's record of what was said, so a warning raised both
    while a command checks its input and again inside :func:`casflutter.run` shows once.
    """
    active = getattr(warnings.showwarning, "_casflutter_said", None)
    if active is not None:          # an outer use routes them already
        yield
        return
    said: set[str] = set()
    with warnings.catch_warnings():
        shown = warnings.showwarning

        def show(message, category, filename, lineno, file=None, line=None):
            text = str(message)
            if not _own_warning(filename, text):
                shown(message, category, filename, lineno, file, line)
            elif text not in said:
                said.add(text)
                logger.warning("%s", text)

        show._casflutter_said = said
        warnings.showwarning = show
        yield


logging.getLogger(PACKAGE_LOGGER).addHandler(logging.NullHandler())
