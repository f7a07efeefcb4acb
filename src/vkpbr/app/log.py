"""Diagnostics and results of the command line.

Two streams, as in most Unix tools:

- Results (what was written, how long it took) go to stdout through `say`; users and
  scripts read them. `-q` silences them.
- Diagnostics go to stderr through `logging` (logger "vkpbr" and its children), one line per
  record: "vkpbr: message" for warnings, "vkpbr: error: ..." for errors, "vkpbr: info: ..."
  (`-v`) and "vkpbr: debug: ..." (`-vv`). Python warnings (`warnings.warn` anywhere, e.g. a
  scene loader's) are routed there too, as one line with no source line echoed.

`cli_logging(verbosity)` sets both up for the length of one command and restores the
previous state afterwards, so `main()` can be called many times in one process (tests).
Library users are unaffected: without the CLI, vkpbr's loggers propagate to the root logger
and warnings behave as Python's do.
"""

from __future__ import annotations

import logging
import sys
import warnings
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["LOGGER", "cli_logging", "say", "is_quiet", "format_warning"]

LOGGER = logging.getLogger("vkpbr")

# verbosity -> level: -1 = -q (errors only), 0 = default (warnings), 1 = -v, 2+ = -vv
_LEVELS = {-1: logging.ERROR, 0: logging.WARNING, 1: logging.INFO}
_quiet = False


class _Formatter(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        message = " ".join(record.getMessage().split())  # one record, one line
        if record.exc_info and record.levelno <= logging.DEBUG:
            message += " | " + " ".join(self.formatException(record.exc_info).split())
        if record.levelno >= logging.WARNING:
            return f"vkpbr: {message}"
        return f"vkpbr: {record.levelname.lower()}: {message}"


class _StderrHandler(logging.StreamHandler):
    """Writes to whatever sys.stderr is at the time of the record (pytest's capture, a
    redirected stream), as logging.lastResort does."""

    def __init__(self) -> None:
        logging.Handler.__init__(self)

    @property
    def stream(self):  # noqa: ANN201
        return sys.stderr

    @stream.setter
    def stream(self, _value: object) -> None:  # StreamHandler.setStream; nothing to keep
        pass


def format_warning(message: Warning | str, category: type[Warning], filename: str,
                   lineno: int, verbose: bool = False) -> str:
    """A warning as one line: the message, prefixed by its category unless it is a plain
    UserWarning; with `verbose`, where it was raised."""
    text = " ".join(str(message).split())
    if category is not UserWarning:
        text = f"{category.__name__}: {text}"
    return f"{text} ({filename}:{lineno})" if verbose else text


@contextmanager
def cli_logging(verbosity: int = 0) -> Iterator[None]:
    """Route vkpbr's logging and Python warnings to one-line stderr records at the level
    `verbosity` asks for, and make `say` quiet for verbosity < 0, until the block ends."""
    global _quiet
    level = _LEVELS.get(max(-1, verbosity), logging.DEBUG)
    handler = _StderrHandler()
    handler.setFormatter(_Formatter())
    saved = (LOGGER.level, LOGGER.propagate, warnings.showwarning, _quiet)

    def show(message, category, filename, lineno, file=None, line=None) -> None:  # noqa: ANN001
        LOGGER.warning(format_warning(message, category, filename, lineno, level <= logging.DEBUG))

    LOGGER.addHandler(handler)
    LOGGER.setLevel(level)
    LOGGER.propagate = False  # our handler prints it; the root's would print it again
    warnings.showwarning = show
    _quiet = verbosity < 0
    try:
        yield
    finally:
        LOGGER.removeHandler(handler)
        LOGGER.setLevel(saved[0])
        LOGGER.propagate = saved[1]
        warnings.showwarning = saved[2]
        _quiet = saved[3]


def is_quiet() -> bool:
    """True while a command runs with -q."""
    return _quiet


def say(*parts: object) -> None:
    """Print a result line on stdout (what was written, timings), unless -q."""
    if not _quiet:
        print(*parts, flush=True)
