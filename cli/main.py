"""Command line: ``psm-grasp simulate | demo | optimize | verify | train-policy | design``."""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path

from .optimize import add_demo_parser, add_optimize_parser, add_verify_parser
from .policy import add_policy_parsers
from .simulate import add_simulate_parser

__all__ = ["main", "build_parser", "ERROR_EXIT", "BROKEN_PIPE_EXIT"]

ERROR_EXIT = 2  # a refused input (as argparse's own errors)
# the reader of stdout went away (``| head -1``): the status of a program that SIGPIPE ended,
# as the shell reports it; Python ignores SIGPIPE and raises BrokenPipeError instead
BROKEN_PIPE_EXIT = 128 + 13
_ANSI = re.compile(r"\x1b\[[0-9;]*m")  # terminal colours (Gymnasium colours its warnings)


class _Parser(argparse.ArgumentParser):
    """argparse's parser, its errors one line like every refused input (argparse prints the
    usage first: the error, which names the option, scrolls out of sight)."""

    def error(self, message: str):
        self.exit(ERROR_EXIT, f"psm-grasp: error: {message} ({self.prog} --help lists the "
                              "options)\n")


def build_parser() -> argparse.ArgumentParser:
    """The ``psm-grasp`` parser: one sub-command per job."""
    parser = _Parser(prog="psm-grasp", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    add_simulate_parser(sub)
    add_demo_parser(sub)
    add_optimize_parser(sub)
    add_verify_parser(sub)
    add_policy_parsers(sub)
    return parser


def _run(argv: list[str] | None) -> int:
    args = build_parser().parse_args(argv)
    try:
        with _user_warnings():
            return int(args.func(args))
    except ValueError as exc:
        print(f"psm-grasp: error: {exc}", file=sys.stderr)
        return ERROR_EXIT


@contextlib.contextmanager
def _user_warnings() -> Iterator[None]:
    """Warnings as a command-line user should see them: one line ``psm-grasp: warning: ...``
    each (a library's own with its name: ``warning (numpy): ...``), without the source file and
    line a Python programmer needs, and each message once per command (a warning raised in a
    loop, or from several places, is the same news)."""
    shown: set[tuple[type, str]] = set()

    def show(message, category, filename, lineno, file=None, line=None) -> None:
        text = _ANSI.sub("", str(message)).strip()
        if text.startswith("psm-grasp: "):
            text = text[len("psm-grasp: "):]
        if (category, text) in shown:
            return
        shown.add((category, text))
        parts = Path(str(filename)).parts
        library = (parts[parts.index("site-packages") + 1].split(".")[0]
                   if "site-packages" in parts[:-1] else "")
        prefix = f"warning ({library})" if library else "warning"
        try:
            print(f"psm-grasp: {prefix}: {text}", file=sys.stderr if file is None else file)
        except OSError:  # a closed stderr: nothing to tell the user with
            pass

    with warnings.catch_warnings():
        warnings.showwarning = show
        yield


def _silence_stdout() -> None:
    """Send what is left of stdout to the null device: the interpreter flushes stdout again at
    exit, which would raise a second BrokenPipeError (the recipe of Python's ``signal`` docs).
    """
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # stdout without a file descriptor (captured, replaced)
        sys.stdout = open(os.devnull, "w")  # kept open until the process exits


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``psm-grasp`` command.

    Returns the exit code: 0 on success, :data:`ERROR_EXIT` with one line ``psm-grasp: error:
    ...`` on stderr for a refused input (every ``ValueError``), :data:`BROKEN_PIPE_EXIT`
    quietly when the reader of stdout stopped reading; a command's own codes otherwise.
    """
    try:
        try:
            return _run(argv)
        finally:
            # a reader that went away shows here, inside the handler below, not at exit
            sys.stdout.flush()
    except BrokenPipeError:
        _silence_stdout()
        return BROKEN_PIPE_EXIT


if __name__ == "__main__":
    raise SystemExit(main())
