"""Command-line interface ``ocp-crawl`` (also ``python -m ocp_crawl``).

Commands live in one registry (:data:`COMMANDS`), filled with :func:`register` by the command
modules (:mod:`~ocp_crawl.cli.run_commands`: simulate, demo, animate, crosscheck;
:mod:`~ocp_crawl.cli.study_commands`: sweep, reproduce; :mod:`~ocp_crawl.cli.optimize_command`:
optimize), which the package imports.
Commands parse arguments, call a library function and print; solvers are chosen by the problem's
``[simulation] solver`` through the registry :data:`ocp_crawl.sim.SOLVERS`.

Exit codes: 0 success, 1 numerical failure (the result's status message goes to stderr),
2 bad input (one line ``ocp-crawl: error: ...`` on stderr, never a traceback).

Bad input is explicit: it is a :class:`~ocp_crawl.problem.ProblemError` (problem files, ``--set``,
``--grid``) or a :class:`BadInput` (arguments, output directories, a robot that cannot stand at
t = 0), raised before any long computation.  Any other exception escaping a command is a bug, not
bad input: it is reported as one line ``ocp-crawl: internal error: <Type>: <message> (set
OCP_CRAWL_TRACEBACK=1 for the traceback)`` with exit code 1; an I/O failure while writing results
(disk full, ...) as ``ocp-crawl: I/O error: ...``, exit code 1.  With the environment variable
``OCP_CRAWL_TRACEBACK=1`` these are re-raised with their traceback.

Commands that write results never overwrite earlier ones without ``--force``
(:func:`~ocp_crawl.cli.common.prepare_out`, checked before any computation).
"""
from __future__ import annotations

import argparse
import os
import sys
import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ocp_crawl.version import __version__
from ocp_crawl.problem import ProblemError
from ocp_crawl.io.tables import TableError

PROG = "ocp-crawl"
EXIT_OK, EXIT_FAILURE, EXIT_BAD_INPUT = 0, 1, 2


class BadInput(Exception):
    """Bad input that is not a ProblemError: arguments, output directories, a robot that cannot
    stand.

    The message is one line naming the option or file, and the value given.  Only ProblemError and
    BadInput give exit code 2; every other exception escaping a command is an internal error.
    """

    def __init__(self, message: str):
        super().__init__(" ".join(str(message).split()))


class UsageError(Exception):
    """A malformed command line (argparse's verdict, or an option's type): exit code 2."""


class _Parser(argparse.ArgumentParser):
    """argparse, but usage errors come back as one line and an exit code instead of sys.exit."""

    def error(self, message: str):
        raise UsageError(f"{message} (see '{self.prog} --help')")


# --------------------------------------------------------------------------------------------
# registries
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Command:
    """A subcommand: its name, one-line help, argument setup and the function that runs it."""

    name: str
    help: str
    arguments: Callable[[argparse.ArgumentParser], None]
    run: Callable[[argparse.Namespace], int]


#: the commands of ``ocp-crawl`` by name, in the order of its help (each module of the
#: command line registers its own)
COMMANDS: dict[str, Command] = {}


def register(name: str, help: str, arguments: Callable[[argparse.ArgumentParser], None]):
    """Decorator: register ``run(args) -> exit code`` as the subcommand ``name``."""
    def wrap(run: Callable[[argparse.Namespace], int]):
        if name in COMMANDS:
            raise ValueError(f"command {name!r} is already registered")
        COMMANDS[name] = Command(name, help, arguments, run)
        return run
    return wrap


def err(message: str) -> None:
    """Print ``ocp-crawl: error: MESSAGE`` (one line) on stderr."""
    print(f"{PROG}: error: " + " ".join(str(message).split("\n")), file=sys.stderr)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog=PROG,
                     description="Hybrid-quasistatic simulation of a soft three-link inchworm "
                                 "crawler.",
                     epilog="exit codes: 0 success, 1 numerical failure (or an internal error), 2 "
                            "bad input")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for cmd in COMMANDS.values():
        p = sub.add_parser(cmd.name, help=cmd.help, description=cmd.help)
        cmd.arguments(p)
    return parser


def _run(args: argparse.Namespace) -> int:
    """Run the parsed command with numpy's floating-point warnings silenced: a result carries its
    status, and stderr holds one line at most (an overflow warning before an error message would
    break that)."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return COMMANDS[args.command].run(args)


def io_message(exc: OSError) -> str:
    """An I/O failure in one line naming the file: ``PATH: reason``
    (``cannot write PATH: No space left on device``)."""
    reason = exc.strerror or " ".join(str(exc).split()) or type(exc).__name__
    if exc.filename is None:
        return reason
    files = f"{exc.filename} -> {exc.filename2}" if exc.filename2 is not None else f"{exc.filename}"
    return f"{files}: {reason}"


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit code (never calls sys.exit itself)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except UsageError as exc:
        err(str(exc))
        return EXIT_BAD_INPUT
    except SystemExit as exc:  # --help and --version end argparse this way
        return int(exc.code or 0) if isinstance(exc.code, (int, type(None))) else EXIT_BAD_INPUT
    try:
        return _run(args)
    except (ProblemError, BadInput, TableError) as exc:
        err(str(exc))
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        err("interrupted")
        return 130
    except BrokenPipeError:
        # the reader (e.g. `| head`) went away: silence the interpreter's flush at exit
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_FAILURE
    except Exception as exc:
        # not bad input (that is ProblemError or BadInput, raised on purpose): a bug or a failing
        # environment, reported in one line; exit 1 so that a script never mistakes it for bad input
        if os.environ.get("OCP_CRAWL_TRACEBACK", "").strip().lower() not in ("", "0", "false", "no",
                                                                             "off"):
            raise
        text = " ".join(str(exc).split())
        if isinstance(exc, OSError):
            print(f"{PROG}: I/O error: {io_message(exc)}", file=sys.stderr)
        else:
            print(f"{PROG}: internal error: {type(exc).__name__}: {text} (set "
                  "OCP_CRAWL_TRACEBACK=1 for the traceback)", file=sys.stderr)
        return EXIT_FAILURE


if __name__ == "__main__":
    raise SystemExit(main())
