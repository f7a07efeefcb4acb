"""The `vkpbr` command line: builds the parser from the command modules and maps errors to
exit statuses. Nothing else lives here.

Every failure a user can cause ends as one line on stderr ("vkpbr: error: ...") and a
non-zero exit status: 2 for bad usage (argparse's errors and UsageError), 1 for everything
else a VkpbrError or the OS reports. Diagnostics go through `logging` (app/log.py): `-q`
keeps only errors (and silences the result lines on stdout), `-v` adds info lines, `-vv`
debug lines. Heavy modules are imported inside the commands, so `vkpbr --help` is instant.

SIGTERM is handled like SIGINT: it raises `Terminated` in the main thread, so every `with`
block unwinds (atomic writes remove their temporary files, the GPU objects are destroyed)
and the CLI exits 143 (128 + SIGTERM) after one line, "vkpbr: terminated".

Commands, one module each: render_cmd, view_cmd, info_cmd, bench_cmd, bake_cmd, batch_cmd.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import logging
import signal
import sys
import threading
from collections.abc import Iterator, Sequence
from typing import Any

from vkpbr.app.log import cli_logging
from vkpbr.app.parsing import EPILOG_FORMATTER, Parser
from vkpbr.errors import UsageError, VkpbrError

__all__ = ["main", "build_parser", "Terminated", "sigterm_raises"]

log = logging.getLogger("vkpbr")

EPILOG = """\
examples:
  vkpbr render --out chart.png            the built-in PBR chart
  vkpbr render scene.gltf --view d        one BRDF term of a glTF scene
  vkpbr -v view scene.gltf                the interactive viewer, with info lines
  vkpbr COMMAND --help                    each command's options and examples
"""


def _add_verbosity(p: argparse.ArgumentParser, suffix: str = "") -> None:
    """-q / -v, before the command (`vkpbr -v render`) or after it (`vkpbr render -v`)."""
    # After the command, other names and no defaults: the sub-parser's values would
    # otherwise overwrite those given before it.
    after = {"default": argparse.SUPPRESS} if suffix else {}
    p.add_argument("-q", "--quiet", dest="quiet" + suffix, action="store_true",
                   help="only errors: no warnings, no result lines on stdout",
                   **({"default": False} | after))
    p.add_argument("-v", "--verbose", dest="verbose" + suffix, action="count",
                   help="more diagnostics on stderr (-vv: debug)", **({"default": 0} | after))


def build_parser() -> argparse.ArgumentParser:
    from vkpbr import __version__
    from vkpbr.app import batch_cmd, bench_cmd, info_cmd, render_cmd, view_cmd

    parser = Parser(prog="vkpbr", description="Physically based rendering on Vulkan.",
                    epilog=EPILOG, formatter_class=EPILOG_FORMATTER)
    parser.add_argument("--version", action="version", version=f"vkpbr {__version__}")
    _add_verbosity(parser)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    render_cmd.add_parser(sub)
    view_cmd.add_parser(sub)
    info_cmd.add_parser(sub)
    bench_cmd.add_parser(sub)
    batch_cmd.add_parser(sub)
    try:
        from vkpbr.app import bake_cmd
    except ImportError:  # pragma: no cover - a build without the bake layer
        bake_cmd = None
    if bake_cmd is not None:
        bake_cmd.add_parser(sub)
    for command in sub.choices.values():
        _add_verbosity(command, "_after")
    return parser


class Terminated(BaseException):
    """SIGTERM arrived (see `sigterm_raises`). A BaseException, as KeyboardInterrupt is, so
    that `except Exception` blocks let it through and only cleanup code runs."""


def _raise_terminated(signum: int, frame: Any) -> None:
    raise Terminated()


@contextlib.contextmanager
def sigterm_raises() -> Iterator[None]:
    """Within the block, SIGTERM raises `Terminated` in the main thread (as SIGINT raises
    KeyboardInterrupt); the previous handler comes back afterwards. Off the main thread,
    where Python cannot install handlers, it does nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _verbosity(args: argparse.Namespace) -> int:
    if args.quiet or getattr(args, "quiet_after", False):
        return -1
    return args.verbose + getattr(args, "verbose_after", 0)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status (0 success, 1 failure, 2 bad usage,
    130 interrupted, 143 terminated by SIGTERM)."""
    with sigterm_raises():
        try:
            parser = build_parser()
            try:
                args = parser.parse_args(argv)
            except SystemExit as exc:  # --help, --version, or argparse's one-line error
                return exc.code if isinstance(exc.code, int) else int(exc.code is not None)
            with cli_logging(_verbosity(args)):
                return _run(args)
        except Terminated:  # before the logging was set up (or after it was torn down)
            print("vkpbr: terminated", file=sys.stderr)
            return 143


def _run(args: argparse.Namespace) -> int:
    try:
        command = getattr(args, "run", None) or args.func
        return int(command(args) or 0)
    except UsageError as exc:
        log.error("error: %s", exc)
        return 2
    except VkpbrError as exc:
        log.error("error: %s", exc)
        return 1
    except KeyboardInterrupt:
        log.error("interrupted")
        return 130
    except Terminated:
        log.error("terminated")
        return 143
    except MemoryError:
        log.error("error: out of memory (try a smaller --size)")
        return 1
    except OSError as exc:
        # Name the file involved: the OS's filename(s), else the command's output or scene
        # (an OSError from a bare write has none: "File too large" under `ulimit -f`).
        files = [str(f) for f in (exc.filename, exc.filename2) if f is not None]
        if not files:
            files = [f"while {verb} {v}" for verb, key in (("writing", "out"), ("reading", "scene"))
                     if (v := getattr(args, key, None)) is not None][:1]
        hints = {errno.EFBIG: "the file size limit (ulimit -f) is too low",
                 errno.ENOSPC: "the disk is full", errno.EDQUOT: "the disk quota is full",
                 errno.EACCES: "check the permissions", errno.EPERM: "check the permissions",
                 errno.ENAMETOOLONG: "use a shorter path", errno.EROFS: "write elsewhere"}
        hint = hints.get(exc.errno)  # type: ignore[arg-type]
        log.error("error: %s%s%s", " -> ".join(files) + ": " if files else "",
                  exc.strerror or exc, f" ({hint})" if hint else "")
        return 1


if __name__ == "__main__":
    sys.exit(main())
