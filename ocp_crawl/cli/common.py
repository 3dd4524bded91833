"""What the commands share: argument types, output directories, the exit code of a finished run."""
from __future__ import annotations

import argparse
import importlib.util
import math
import os
import sys
import tempfile
from pathlib import Path
from typing import Iterable

from ocp_crawl.checks import parse_integer, parse_number
from ocp_crawl.cli.app import EXIT_FAILURE, EXIT_OK, PROG, BadInput, UsageError
from ocp_crawl.io.files import write_set
from ocp_crawl.sim.options import STEPS_BOUNDS


def _shown(text: str) -> str:
    """An argument as the user wrote it (quoted only if it is empty or has spaces around it)."""
    return text if text and text.strip() == text else repr(text)


def integer(option: str, low: int, what: str = "", high: int | None = None, why: str = ""):
    """argparse type of ``option``: an integer >= low (and <= high, ``why`` giving the reason of the
    bound).

    A bad value ends parsing with a one-line usage error naming the option and the value as written
    (raised directly: argparse would reword an ArgumentTypeError as "argument OPTION: ...").
    """
    valid = f">= {low}" if high is None else f"in [{low}, {high}]"

    def parse(text: str) -> int:
        try:
            n = parse_integer(text)
        except ValueError:
            n = None
        if n is None or n < low or (high is not None and n > high):
            reason = f": {why}" if why and n is not None and high is not None and n > high else ""
            raise UsageError(f"{option} {_shown(text)} is invalid: must be an integer "
                             f"{valid}{what}{reason}")
        return n
    return parse


def out_dir(text: str) -> str:
    """argparse type of ``--out DIR``: a non-empty path (an empty one would write nothing, or into
    the current directory, silently)."""
    if not text.strip():
        raise UsageError(f"--out {_shown(text)} is invalid: an empty path; give a directory")
    return text


def out_file(suffix: str):
    """argparse type of ``--out FILE``: a non-empty path to a file, not ending in a path separator
    (``x.gif/`` names a directory, which the command would otherwise silently drop)."""
    def parse(text: str) -> str:
        if not text.strip():
            raise UsageError(f"--out {_shown(text)} is invalid: an empty path; give a file name "
                             f"ending in {suffix}")
        if text.endswith(("/", os.sep)) or (os.altsep and text.endswith(os.altsep)):
            raise UsageError(f"--out {text} is invalid: it ends with {text[-1]!r}, which names a "
                             f"directory; give a file name ending in {suffix}")
        return text
    return parse


def real(option: str, low: float, high: float, what: str = "", closed: bool = False):
    """argparse type of ``option``: a finite number in (low, high], or [low, high] when
    ``closed``."""
    def parse(text: str) -> float:
        try:
            x = parse_number(text)
        except ValueError:
            x = math.nan
        if not (math.isfinite(x) and (low <= x if closed else low < x) and x <= high):
            raise UsageError(f"{option} {_shown(text)} is invalid: must be a number in "
                             f"{'[' if closed else '('}{low:g}, {high:g}]{what}")
        return x
    return parse


def address(text: str) -> str:
    """argparse type of --scheduler: a non-empty Dask scheduler address of a known scheme, or
    'local'."""
    usage = "a Dask scheduler address (e.g. tcp://host:8786) or 'local'"
    if not text.strip():
        raise UsageError(f"--scheduler {_shown(text)} is invalid: {usage}")
    if text.strip() == "local":
        return "local"
    try:
        from distributed.comm import parse_address
        from distributed.comm.registry import get_backend
    except ImportError:  # the sweep says what to install
        return text.strip()
    try:
        get_backend(parse_address(text.strip())[0])
    except ValueError as exc:
        raise UsageError(f"--scheduler {_shown(text)} is invalid: {exc}; {usage}") from None
    return text.strip()


steps_type = integer("--steps", STEPS_BOUNDS[0], " (steps per cycle)", high=STEPS_BOUNDS[1],
                     why="each step is an IPOPT solve of about 2 ms")
#: most worker processes (each holds its own compiled functions and solver state)
MAX_JOBS = 256
jobs_type = integer("--jobs", 1, " (worker processes)", high=MAX_JOBS,
                    why="each worker process holds its own compiled functions and solver")


def optional_out(args: argparse.Namespace, names: Iterable[str]) -> Path | None:
    """:func:`prepare_out` of a command whose ``--out`` is optional: None without ``--out`` (nothing
    is written), where ``--force`` has nothing to overwrite and is refused."""
    if args.out is None:
        if args.force:
            raise BadInput("--force without --out: nothing is written, so nothing would be "
                           "overwritten; give --out DIR or drop --force")
        return None
    return prepare_out(args.out, names, args.force, staged=True)


def prepare_out(path: str | os.PathLike, names: Iterable[str], force: bool, *, resume: bool = False,
                kind: str | None = None, label: str | None = None, staged: bool = False) -> Path:
    """Check and create the output directory of a command, before any computation.

    ``names``: the files (or directories) the command writes into ``path``.  If any of them exists,
    the run would overwrite earlier results: refused (BadInput) unless ``force``, or ``resume`` (a
    command that continues an interrupted run in place: its own code checks what it finds).  A
    directory holding none of these names is fine.  Then the directory is created and checked to be
    writable.  ``kind`` (e.g. "a sweep") says what a resumable directory holds; ``label`` replaces
    ``--out PATH`` at the start of the messages (e.g. for a file given as --out).  ``staged``: the
    command writes its files with :func:`write_out` (all or nothing), so a directory made here only
    for the checks is removed again: a run that fails before its files are complete leaves no
    ``--out`` directory.
    """
    out = Path(path)
    label = label or f"--out {out}"
    if not (force or resume):
        existing = [n for n in names if _exists(out / n)]
        if existing:
            shown = ", ".join(existing[:3]) + (", ..." if len(existing) > 3 else "")
            what = f"; it already holds {kind}: continue it with --resume," if kind else ";"
            raise BadInput(f"{label}: would overwrite earlier results ({shown}){what} pass --force "
                           "to overwrite or choose another directory")
    where = label if label == f"--out {out}" else f"{label}: {out}"
    made = not _exists(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):
            pass
    except FileExistsError:
        raise BadInput(f"{where}: exists and is not a directory") from None
    except OSError as exc:
        raise BadInput(f"{where}: output directory is not writable: "
                       f"{exc.strerror or exc}") from None
    _check_targets(out, names, label)
    if staged and made:
        out.rmdir()   # write_out makes it, complete, at the end (in a parent shown writable)
    return out


def write_out(out: Path, write, force: bool) -> list[Path]:
    """Write a command's files into ``out`` all or nothing (:func:`ocp_crawl.io.files.write_set`):
    ``write(directory)`` writes them into a staging directory and returns their paths; returns
    their final paths.  Without ``force`` a file that appeared in ``out`` since
    :func:`prepare_out` is not overwritten."""
    return write_set(out, write, overwrite=force)


def _check_targets(out: Path, names: Iterable[str], label: str) -> None:
    """BadInput for an output file the directory cannot take: a name longer than the file system
    allows, or a file name (one with a suffix: results.csv, crawl.gif) that is a directory there."""
    try:
        longest = os.pathconf(out, "PC_NAME_MAX")
    except (AttributeError, OSError, ValueError):
        longest = 255
    for name in names:
        if len(os.fsencode(name)) > longest:
            raise BadInput(f"{label}: the file name {name[:40]}... is longer than the {longest} "
                           "bytes a name may have here")
        if Path(name).suffix and (out / name).is_dir():
            raise BadInput(f"{label}: {out / name} is a directory, where the command writes a "
                           "file: remove it or choose another directory")


def _exists(path: Path) -> bool:
    try:
        return path.exists()
    except OSError:  # e.g. a path under a regular file: nothing to overwrite there
        return False


def check_scheduler(address: str | None) -> None:
    """``--scheduler ADDRESS`` needs dask.distributed installed: BadInput otherwise."""
    if address is not None and importlib.util.find_spec("distributed") is None:
        raise BadInput(f"--scheduler {address}: needs dask.distributed: pip install "
                       "'ocp-crawl[cluster]'")


def finish(args: argparse.Namespace, files, success: bool, failure: str) -> int:
    """List the written files (unless --json) and turn success into the exit code, with the failure
    on stderr."""
    if files and not args.json:
        print("wrote      " + ", ".join(str(f) for f in files))
    if not success:
        print(f"{PROG}: {failure}", file=sys.stderr)
        return EXIT_FAILURE
    return EXIT_OK


def force_arg(p: argparse.ArgumentParser,
              what: str = "the results of an earlier run in DIR") -> None:
    """Add ``--force`` (overwrite ``what``) to the parser ``p``."""
    p.add_argument("--force", action="store_true",
                   help=f"overwrite {what} (without it the command refuses, before computing "
                        "anything)")



def work_arg(p: argparse.ArgumentParser) -> None:
    """Add ``--max-hours H``, the limit on the command's estimated work
    (:mod:`ocp_crawl.problem.work`)."""
    from ocp_crawl.problem.work import DEFAULT_MAX_HOURS

    p.add_argument("--max-hours", type=real("--max-hours", 0.0, 1e4), default=None, metavar="H",
                   help="refuse the run, before it starts, when its estimated work is above H "
                        f"hours (default {DEFAULT_MAX_HOURS:g}; the estimate is on stderr above a "
                        "minute)")


def check_work(args: argparse.Namespace, work):
    """Refuse ``work`` (a :class:`~ocp_crawl.problem.work.Work`) above ``--max-hours`` as bad input
    naming the settings that size it; ``work`` otherwise (:func:`announce` it when the run
    starts)."""
    from ocp_crawl.problem.work import WorkLimit

    try:
        work.check(args.max_hours)
    except WorkLimit as exc:
        raise BadInput(str(exc)) from None
    return work


def announce(work) -> None:
    """The estimate of ``work`` on stderr when its typical run is above a minute: after every input
    check (a refusal is one line), as the run starts."""
    from ocp_crawl.problem.work import ANNOUNCE_SECONDS

    if work.typical > ANNOUNCE_SECONDS:
        print(f"{PROG}: estimated {work.text} ({work.detail})", file=sys.stderr, flush=True)
