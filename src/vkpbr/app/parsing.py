"""Command-line parsing shared by every command: the parser class and the value parsers.

`Parser` is argparse's ArgumentParser with two changes:

- A value that starts with '-' followed by a digit or '.' ("-5,0.6,-0.9", "-2", "-.5",
  "-1e-3") is a value, not an option, so `--light -5,0.6,-0.9` works as `--light=-5,...`
  does. argparse treats an argument as a value only when it matches its negative-number
  pattern (`^-\\d+$|^-\\d*\\.\\d+$` in 3.11; numbers with exponents or underscores from 3.14);
  comma-separated vectors never match it (CPython issues #53580, #105712, #123945). We widen
  that pattern, argparse's own switch for this, rather than rewrite argv: the parser keeps
  deciding what is an option, and an option that looks like a negative number (vkpbr has
  none) would still turn the rule off, as argparse documents.
- Errors are one line, "vkpbr: error: argument --view: invalid choice: ... (see `vkpbr
  render --help`)", with exit status 2; the usage block is not printed (`--help` shows it).

The value parsers (`parse_size`, `parse_vec3`) raise UsageError; `size_arg` / `vec3_arg`
are their `type=` forms, so a bad value fails while parsing, before any scene is loaded.
"""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Callable
from typing import NoReturn

from vkpbr.errors import UsageError

__all__ = ["Parser", "parse_size", "parse_vec3", "size_arg", "vec3_arg", "light_arg", "finite", "EpilogFormatter",
           "EPILOG_FORMATTER"]

# '-' then a digit, or '-.' then a digit: a negative number or a vector that starts with one.
_NEGATIVE_VALUE = re.compile(r"^-\.?\d")


class EpilogFormatter(argparse.HelpFormatter):
    """Help with example epilogs: a text with line breaks (the examples) is kept as written,
    a one-paragraph text (a description) is filled to the terminal width as usual."""

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        if "\n" in text:
            return "".join(indent + line for line in text.splitlines(keepends=True))
        return super()._fill_text(text, width, indent)


EPILOG_FORMATTER = EpilogFormatter


class Parser(argparse.ArgumentParser):
    """ArgumentParser that takes negative numbers and vectors as values and reports errors
    in one line. Sub-parsers made by `add_subparsers` are of the same class."""

    def __init__(self, *args, **kwargs) -> None:  # noqa: ANN002, ANN003 - argparse's own
        super().__init__(*args, **kwargs)
        # Read by ArgumentParser._parse_optional (and add_argument) since Python 3.2.
        self._negative_number_matcher = _NEGATIVE_VALUE
        self._deferred: list[Callable[[Parser], None]] = []

    def defer(self, add_arguments: Callable[[Parser], None]) -> None:
        """Add arguments when this parser is first used (parse or help), not when it is
        built: the shared options take their choices from the render enums (NumPy), which
        `vkpbr --help` and `vkpbr info` should not pay for."""
        self._deferred.append(add_arguments)

    def _run_deferred(self) -> None:
        while self._deferred:
            self._deferred.pop(0)(self)

    def parse_known_args(self, args=None, namespace=None):  # noqa: ANN001, ANN201
        self._run_deferred()
        return super().parse_known_args(args, namespace)

    def format_usage(self) -> str:
        self._run_deferred()
        return super().format_usage()

    def format_help(self) -> str:
        self._run_deferred()
        return super().format_help()

    def error(self, message: str) -> NoReturn:
        message = " ".join(message.split())
        self.exit(2, f"vkpbr: error: {message} (see `{self.prog} --help`)\n")


def finite(x: float) -> bool:
    return math.isfinite(x)


def parse_size(text: str) -> tuple[int, int]:
    """"WIDTHxHEIGHT" -> (width, height), both positive."""
    parts = text.lower().split("x")
    try:
        w, h = (int(p) for p in parts)
    except ValueError:
        raise UsageError(f"--size {text!r}: expected WIDTHxHEIGHT, e.g. 1920x1080") from None
    if w <= 0 or h <= 0:
        raise UsageError(f"--size {text!r}: width and height must be positive")
    return w, h


def parse_vec3(text: str, option: str) -> tuple[float, float, float]:
    """"x,y,z" -> three finite floats."""
    try:
        values = tuple(float(x) for x in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 3 or not all(map(finite, values)):
        raise UsageError(f"{option} {text!r}: expected three comma-separated finite numbers")
    return values  # type: ignore[return-value]


def _as_type(parse: Callable[[str], object], option: str, name: str) -> Callable[[str], object]:
    """An argparse `type=` from a parser that raises UsageError: argparse then reports
    "argument OPTION: 'VALUE': problem" in its one error line."""

    def convert(text: str) -> object:
        try:
            return parse(text)
        except UsageError as exc:
            message = str(exc)  # "--light '1,2': expected ...": argparse names the option
            raise argparse.ArgumentTypeError(message.removeprefix(f"{option} ")) from None

    convert.__name__ = name  # argparse's fallback message says "invalid <name> value"
    return convert


size_arg = _as_type(parse_size, "--size", "size")


def vec3_arg(option: str) -> Callable[[str], object]:
    """`type=` for an "x,y,z" option named `option`."""
    return _as_type(lambda text: parse_vec3(text, option), option, "vector")


def _parse_light(text: str, option: str) -> object:
    from vkpbr.scene.lights import parse_light_spec

    if ":" not in text and not text.strip().lower().endswith(".json") and text.strip().lower() != "none":
        return parse_vec3(text, option)  # the course's form: a position for the default light
    return parse_light_spec(text)


def light_arg(option: str) -> Callable[[str], object]:
    """`type=` for a `--light` value (vkpbr.scene.lights.parse_light_spec): the course's bare
    "x,y,z" as a position tuple, anything else as the list of Lights it names."""
    return _as_type(lambda text: _parse_light(text, option), option, "light")
