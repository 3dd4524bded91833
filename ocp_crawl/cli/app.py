"""Command-line interface ``ocp-crawl`` (also ``python -m ocp_crawl``).

Commands live in one registry (:data:`COMMANDS`): a later issue adds a command (sweep, reproduce,
optimize, crosscheck, animate) with :func:`register` and touches nothing else here.  Solvers that
``simulate --solver`` can use live in :data:`SOLVERS` likewise.

Exit codes: 0 success, 1 numerical failure (the result's status message goes to stderr),
2 bad input (one line ``ocp-crawl: error: ...`` on stderr, never a traceback).

Bad input is explicit: it is a :class:`~ocp_crawl.problem.core.ProblemError` (problem files, ``--set``,
``--grid``) or a :class:`BadInput` (arguments, output directories, a robot that cannot stand at
t = 0), raised before any long computation.  Any other exception escaping a command is a bug, not
bad input: it is reported as one line ``ocp-crawl: internal error: <Type>: <message> (set
OCP_CRAWL_TRACEBACK=1 for the traceback)`` with exit code 1; an I/O failure while writing results
(disk full, ...) as ``ocp-crawl: I/O error: ...``, exit code 1.  With the environment variable
``OCP_CRAWL_TRACEBACK=1`` these are re-raised with their traceback.

Commands that write results never overwrite earlier ones without ``--force``
(:func:`prepare_out`, checked before any computation).
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import math
import os
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

from ocp_crawl import __version__
from ocp_crawl.io.files import jsonable, write_json, write_npz
from ocp_crawl.problem.core import Problem, ProblemError, format_value, load_problem, paper_problem, run_problem
from ocp_crawl.sim.result import STATUS_MESSAGES, CrawlResult, Status

PROG = "ocp-crawl"
EXIT_OK, EXIT_FAILURE, EXIT_BAD_INPUT = 0, 1, 2

#: units of the summary's numbers, written with every JSON summary
UNITS = {"S": "m", "W_plus": "J", "W_plus_joint": "J", "CoT_plus": "-", "t": "cycles", "energy": "J"}


class BadInput(Exception):
    """Bad input that is not a ProblemError: arguments, output directories, a robot that cannot stand.

    The message is one line naming the option or file, and the value given.  Only ProblemError and
    BadInput give exit code 2; every other exception escaping a command is an internal error.
    """

    def __init__(self, message: str):
        super().__init__(" ".join(str(message).split()))


class _UsageError(Exception):
    pass


class _Parser(argparse.ArgumentParser):
    """argparse, but usage errors come back as one line and an exit code instead of sys.exit."""

    def error(self, message: str):
        raise _UsageError(f"{message} (see '{self.prog} --help')")


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


COMMANDS: dict[str, Command] = {}


def register(name: str, help: str, arguments: Callable[[argparse.ArgumentParser], None]):
    """Decorator: register ``run(args) -> exit code`` as the subcommand ``name``."""
    def wrap(run: Callable[[argparse.Namespace], int]):
        if name in COMMANDS:
            raise ValueError(f"command {name!r} is already registered")
        COMMANDS[name] = Command(name, help, arguments, run)
        return run
    return wrap


#: solvers of ``simulate --solver``: name -> function(problem, args) -> CrawlResult
def _run_mpcc(problem: Problem, args: argparse.Namespace) -> CrawlResult:
    from ocp_crawl.sim.timestepping import simulate_mpcc

    if problem.drive != "torque":
        raise BadInput(f"{problem.source}: --solver mpcc needs the torque drive, got [gait] drive = "
                       f"{format_value(problem.drive)}")
    return simulate_mpcc(problem.model, problem.torque, steps=args.steps)


SOLVERS: dict[str, Callable[[Problem, argparse.Namespace], CrawlResult]] = {
    "event": lambda problem, args: run_problem(problem),
    "mpcc": _run_mpcc,
}


def _shown(text: str) -> str:
    """An argument as the user wrote it (quoted only if it is empty or has spaces around it)."""
    return text if text and text.strip() == text else repr(text)


def _integer(option: str, low: int, what: str = ""):
    """argparse type of ``option``: an integer >= low.

    A bad value ends parsing with a one-line usage error naming the option and the value as written
    (raised directly: argparse would reword an ArgumentTypeError as "argument OPTION: ...").
    """
    def parse(text: str) -> int:
        try:
            n = int(text)
        except ValueError:
            n = None
        if n is None or n < low:
            raise _UsageError(f"{option} {_shown(text)} is invalid: must be an integer >= {low}{what}")
        return n
    return parse


def _real(option: str, low: float, high: float, what: str = ""):
    """argparse type of ``option``: a finite number in (low, high]."""
    def parse(text: str) -> float:
        try:
            x = float(text)
        except ValueError:
            x = math.nan
        if not (math.isfinite(x) and low < x <= high):
            raise _UsageError(f"{option} {_shown(text)} is invalid: must be a number in ({low:g}, {high:g}]{what}")
        return x
    return parse


def _address(text: str) -> str:
    """argparse type of --scheduler: a non-empty Dask scheduler address or 'local'."""
    if not text.strip():
        raise _UsageError(f"--scheduler {_shown(text)} is invalid: a Dask scheduler address (e.g. tcp://host:8786) "
                          "or 'local'")
    return text.strip()


_steps = _integer("--steps", 4, " (steps per cycle)")
_jobs = _integer("--jobs", 1, " (worker processes)")


# --------------------------------------------------------------------------------------------
# shared helpers
# --------------------------------------------------------------------------------------------
def _err(message: str) -> None:
    print(f"{PROG}: error: " + " ".join(str(message).split("\n")), file=sys.stderr)


def prepare_out(path: str | os.PathLike, names: Iterable[str], force: bool, *, resume: bool = False,
                kind: str | None = None, label: str | None = None) -> Path:
    """Check and create the output directory of a command, before any computation.

    ``names``: the files (or directories) the command writes into ``path``.  If any of them exists,
    the run would overwrite earlier results: refused (BadInput) unless ``force``, or ``resume`` (a
    command that continues an interrupted run in place: its own code checks what it finds).  A
    directory holding none of these names is fine.  Then the directory is created and checked to be
    writable.  ``kind`` (e.g. "a sweep") says what a resumable directory holds; ``label`` replaces
    ``--out PATH`` at the start of the messages (e.g. for a file given as --out).
    """
    out = Path(path)
    label = label or f"--out {out}"
    if not (force or resume):
        existing = [n for n in names if _exists(out / n)]
        if existing:
            shown = ", ".join(existing[:3]) + (", ..." if len(existing) > 3 else "")
            what = f"; it already holds {kind}: continue it with --resume," if kind else ";"
            raise BadInput(f"{label}: would overwrite earlier results ({shown}){what} pass --force to overwrite "
                           "or choose another directory")
    where = label if label == f"--out {out}" else f"{label}: {out}"
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):
            pass
    except FileExistsError:
        raise BadInput(f"{where}: exists and is not a directory") from None
    except OSError as exc:
        raise BadInput(f"{where}: output directory is not writable: {exc.strerror or exc}") from None
    return out


def _exists(path: Path) -> bool:
    try:
        return path.exists()
    except OSError:  # e.g. a path under a regular file: nothing to overwrite there
        return False


def no_start_message(problem: Problem, detail: str) -> str:
    """One line for a torque-driven problem with no equilibrium to start from (bad input, exit 2)."""
    d = problem.to_dict()
    r, g = d.get("robot", {}), d.get("gait", {})
    robot = ", ".join(f"{k} = {format_value(r[k])}" for k in ("k", "M", "L", "g") if k in r)
    gait = ", ".join(f"{k} = {format_value(v)}" for k, v in g.items() if k.endswith("_deg"))
    return (f"{problem.source}: [robot] {robot}; [model] gravity = {format_value(problem.gravity)}; [gait] {gait}: "
            f"{detail}; stiffen the joints (robot.k) or change the gait")


def check_start(problem: Problem) -> None:
    """A torque-driven problem must have a released equilibrium at t = 0 (status no_start otherwise):
    checked before any long run, as bad input (cheap: one equilibrium solve)."""
    if problem.drive != "torque":
        return  # the prescribed-angle contact is checked over the whole cycle when the problem is loaded
    from ocp_crawl.sim.event import HybridStepper

    try:
        HybridStepper(problem.model, problem.torque, problem.hybrid).initial_state(0.0)
    except ValueError as exc:
        raise BadInput(no_start_message(problem, f"{STATUS_MESSAGES[Status.NO_START]}: {exc}")) from None


def _check_scheduler(address: str | None) -> None:
    if address is not None and importlib.util.find_spec("distributed") is None:
        raise BadInput(f"--scheduler {address}: needs dask.distributed: pip install 'ocp-crawl[cluster]'")


def _simulate(problem: Problem, solver: str, args: argparse.Namespace) -> CrawlResult:
    result = SOLVERS[solver](problem, args)
    if result.status == Status.NO_START:
        # check_start has let it through: the same verdict, as bad input
        raise BadInput(no_start_message(problem, result.message))
    return result


def _finish(args: argparse.Namespace, files, success: bool, failure: str) -> int:
    """List the written files (unless --json) and turn success into the exit code, with the failure on stderr."""
    if files and not args.json:
        print("wrote      " + ", ".join(str(f) for f in files))
    if not success:
        print(f"{PROG}: {failure}", file=sys.stderr)
        return EXIT_FAILURE
    return EXIT_OK


def report(result: CrawlResult, problem: Problem, solver: str = "event") -> dict:
    """The JSON report of a run: the result's summary plus the problem and the units."""
    out = result.summary()
    out["solver"] = solver
    out["problem_file"] = problem.source
    out["problem"] = problem.to_dict()
    out["units"] = UNITS
    return jsonable(out)


def _num(x, scale: float = 1.0, fmt: str = ".3f") -> str:
    x = float(x)
    if math.isnan(x):
        return "-"
    return "inf" if math.isinf(x) else format(scale * x, fmt)


def format_summary(result: CrawlResult, problem: Problem, solver: str = "event") -> str:
    """Readable summary: problem, status, S [mm], W+ [mJ], CoT+, events table, cycles."""
    r = problem.robot
    gait = problem.sections.get("gait", {})
    gait_text = ", ".join(f"{k[:-4]} = {v:g} deg" for k, v in gait.items() if k.endswith("_deg"))
    direction = ""
    if np.isfinite(result.S) and result.S != 0:
        direction = " (towards foot 1)" if result.S < 0 else " (towards foot 2)"
    lines = [
        f"problem    {problem.source}",
        f"drive      {problem.drive} (solver {solver}), gravity {problem.gravity}",
        f"robot      M = {r.M:g} kg, L = {r.L:g} m, beta = {r.beta:g}, k = {r.k:g} N m/rad, "
        f"mu1 = {r.mu1:g}, mu2 = {r.mu2:g}, g = {r.g:g} m/s^2",
        f"gait       {gait_text}",
        f"status     {result.status_name} ({result.status}): {result.message}",
        f"S          {_num(result.S, 1e3)} mm per cycle{direction}",
        f"W+         {_num(result.W_plus, 1e3)} mJ per cycle",
        f"CoT+       {_num(result.CoT_plus)}",
        f"cycles     {result.cycles}" + (f" (steady cycle from t = {result.t0:g})" if result.success else ""),
    ]
    events = result.steady_events() if result.success else result.events
    title = "events in the steady cycle" if result.success else "events"
    lines.append(f"{title}: {len(events)}")
    if events:
        lines.append(f"  {'t [cycles]':>12}  {'phase':>8}  {'kind':<14}  mode before -> after")
        for e in events:
            phase = e.t - result.t0 if result.success else e.t % 1.0
            lines.append(f"  {e.t:12.6f}  {phase:8.5f}  {e.kind:<14}  {e.mode_before} -> {e.mode_after}")
    return "\n".join(lines)


#: the files of one run written by :func:`write_outputs` (after a stem)
RUN_FILES = ("arrays.npz", "summary.json", "gait.png", "gait.pdf")


def write_outputs(out: Path, result: CrawlResult, problem: Problem, data: dict, stem: str = "") -> list[Path]:
    """arrays.npz, summary.json, gait.png and gait.pdf in ``out`` (each written atomically; see RUN_FILES)."""
    from ocp_crawl.viz.gait import plot_gait, save_figure  # matplotlib only when figures are asked for

    arrays, summary, png, pdf = (out / f"{stem}{name}" for name in RUN_FILES)
    files = [write_npz(arrays, result.arrays()), write_json(summary, data)]
    fig = plot_gait(result, problem.robot, reference=problem.gait)
    files += [save_figure(fig, png), save_figure(fig, pdf)]
    return files


def _force_arg(p: argparse.ArgumentParser, what: str = "the results of an earlier run in DIR") -> None:
    p.add_argument("--force", action="store_true",
                   help=f"overwrite {what} (without it the command refuses, before computing anything)")


# --------------------------------------------------------------------------------------------
# simulate
# --------------------------------------------------------------------------------------------
def _simulate_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("problem", metavar="PROBLEM.toml", help="problem file (see README, 'Problem files')")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key, e.g. --set robot.k=0.05 or --set gait.drive=angles (repeatable)")
    p.add_argument("--drive", choices=("torque", "angles"), help="shortcut for --set gait.drive=...")
    p.add_argument("--solver", choices=tuple(SOLVERS), default="event",
                   help="event: event-driven hybrid solver (default); mpcc: MPCC time-stepping (IPOPT)")
    p.add_argument("--steps", type=_steps, default=200, metavar="N",
                   help="--solver mpcc: steps per cycle (default 200)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout instead of the summary")
    p.add_argument("--out", metavar="DIR", help="write arrays.npz, summary.json, gait.png and gait.pdf to DIR")
    _force_arg(p)


@register("simulate", "simulate one problem file and report the gait", _simulate_args)
def cmd_simulate(args: argparse.Namespace) -> int:
    overrides = list(args.overrides) + ([f"gait.drive={args.drive}"] if args.drive else [])
    problem = load_problem(args.problem, overrides)
    out = prepare_out(args.out, RUN_FILES, args.force) if args.out else None
    check_start(problem)
    result = _simulate(problem, args.solver, args)
    data = report(result, problem, args.solver)
    if args.json:
        print(json.dumps(data, allow_nan=False))
    else:
        print(format_summary(result, problem, args.solver))
    files = write_outputs(out, result, problem, data) if out is not None else []
    return _finish(args, files, result.success, f"simulation failed: {result.message}")


# --------------------------------------------------------------------------------------------
# demo
# --------------------------------------------------------------------------------------------
#: the demo's cases: name, description, overrides of the paper problem
DEMO_CASES = (
    ("torque_physical", "torque drive, physical gravity", []),
    ("torque_paper", "torque drive, paper's gravity sign", ["model.gravity=paper"]),
    ("angles", "prescribed angles", ["gait.drive=angles"]),
)


def _demo_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", metavar="DIR", default="ocp_crawl_demo",
                   help="directory for the figures and summaries (default: ./ocp_crawl_demo)")
    _force_arg(p)


@register("demo", "run the paper's gait (torque drive, both gravity signs, prescribed angles)", _demo_args)
def cmd_demo(args: argparse.Namespace) -> int:
    names = [f"{case}_{name}" for case, _, _ in DEMO_CASES for name in RUN_FILES] + ["demo_summary.json"]
    out = prepare_out(args.out, names, args.force)
    print("The paper's gait (Table I robot; gamma = 90 deg, A = 30 deg, psi = 45 deg)\n")
    header = f"{'case':<36} {'status':<10} {'S [mm]':>9} {'W+ [mJ]':>9} {'CoT+':>8} {'events/cycle':>12}"
    print(header)
    print("-" * len(header))
    reports, failed = {}, []
    for name, text, overrides in DEMO_CASES:
        problem = paper_problem(overrides)
        result = _simulate(problem, "event", args)
        n_events = len(result.steady_events()) if result.success else len(result.events)
        print(f"{text:<36} {result.status_name:<10} {_num(result.S, 1e3):>9} {_num(result.W_plus, 1e3):>9} "
              f"{_num(result.CoT_plus, fmt='.2f'):>8} {n_events:>12}")
        reports[name] = data = report(result, problem)
        write_outputs(out, result, problem, data, stem=f"{name}_")
        if not result.success:
            failed.append(f"{text}: {result.message}")
    write_json(out / "demo_summary.json", reports)
    print(f"\nfigures and summaries in {out}/ (<case>_gait.png, <case>_gait.pdf, <case>_summary.json, "
          "<case>_arrays.npz)")
    print("S < 0: the robot moves towards foot 1, the joint that leads in phase. The two gravity signs "
          "differ by a few percent in S (see README, 'Gravity conventions').")
    for f in failed:
        print(f"{PROG}: simulation failed: {f}", file=sys.stderr)
    return EXIT_FAILURE if failed else EXIT_OK


# --------------------------------------------------------------------------------------------
# sweep
# --------------------------------------------------------------------------------------------
def _sweep_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("problem", metavar="PROBLEM.toml", help="base problem file (see README, 'Problem files')")
    p.add_argument("--grid", action="append", required=True, metavar="KEY=START:STOP:NUM",
                   help="an axis: NUM values from START to STOP inclusive, or a list KEY=A,B,C (repeatable; "
                        "the first axis varies slowest), e.g. --grid gait.psi_deg=0:180:37")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key of the base problem (repeatable)")
    p.add_argument("--jobs", type=_jobs, metavar="N", help="worker processes (default: the CPUs available)")
    p.add_argument("--out", metavar="DIR", help="output directory (default: ./sweep_<problem stem>)")
    again = p.add_mutually_exclusive_group()
    again.add_argument("--resume", action="store_true", help="continue an interrupted sweep in DIR")
    again.add_argument("--force", action="store_true",
                       help="overwrite a sweep already in DIR (without it, or --resume, the command refuses)")
    p.add_argument("--scheduler", metavar="ADDRESS", type=_address,
                   help="run on a Dask cluster (e.g. tcp://host:8786, or 'local'); needs the [cluster] extra")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout instead of the summary")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")


@register("sweep", "map S, W+ and CoT+ over a grid of problem keys (parallel, resumable)", _sweep_args)
def cmd_sweep(args: argparse.Namespace) -> int:
    from ocp_crawl.sweep.core import JOURNAL_FILE, RESULTS_FILE, SETTINGS_FILE, SUMMARY_FILE, SweepError, SweepFailed, \
        check_some_point_valid, default_jobs, grid_from_specs, run_sweep

    problem = load_problem(args.problem, args.overrides)
    grid = grid_from_specs(args.grid)
    check_some_point_valid(problem, grid)
    _check_scheduler(args.scheduler)
    # --resume: run_sweep checks that the directory's settings.json is this sweep's
    out = prepare_out(args.out or f"sweep_{Path(args.problem).stem}",
                      (SETTINGS_FILE, RESULTS_FILE, JOURNAL_FILE, SUMMARY_FILE), args.force, resume=args.resume,
                      kind="a sweep")
    try:
        result = run_sweep(problem, grid, out_dir=out, jobs=args.jobs or default_jobs(), resume=args.resume,
                           force=args.force, progress=not args.no_progress and sys.stderr.isatty(),
                           scheduler=args.scheduler)
    except SweepError as exc:
        raise BadInput(str(exc)) from None
    except SweepFailed as exc:
        _err(f"sweep incomplete: {exc}")
        return EXIT_FAILURE
    # failed points are data (their status is in results.csv): the command succeeded
    print(json.dumps(result.summary(), allow_nan=False) if args.json else result.format_summary())
    return EXIT_OK


# --------------------------------------------------------------------------------------------
# reproduce
# --------------------------------------------------------------------------------------------
def _reproduce_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", metavar="DIR", default="ocp_crawl_reproduce",
                   help="directory for the figures, report.md and numbers.json (default: ./ocp_crawl_reproduce)")
    p.add_argument("--quick", action="store_true", help="coarse grids (about a minute on 2 cores); default: full grids")
    p.add_argument("--gravity", choices=("paper", "physical"), default="paper",
                   help="convention of the figures (default: paper, the sign the published curves were computed "
                        "with); the statements are checked in both")
    p.add_argument("--jobs", type=_jobs, metavar="N", help="worker processes for the grids (default: the CPUs available)")
    again = p.add_mutually_exclusive_group()
    again.add_argument("--resume", action="store_true",
                       help="reuse the grid points finished by an interrupted run in DIR/sweeps (same grids only)")
    again.add_argument("--force", action="store_true",
                       help="overwrite the results of an earlier run in DIR (without it, or --resume, the command "
                            "refuses, before computing anything)")
    p.add_argument("--scheduler", metavar="ADDRESS", type=_address,
                   help="run the grids on a Dask cluster (needs the [cluster] extra)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars or step lines on stderr")


@register("reproduce", "regenerate the paper's figures and report.md (both gravity conventions checked)",
          _reproduce_args)
def cmd_reproduce(args: argparse.Namespace) -> int:
    from ocp_crawl.studies import reproduce as rp
    from ocp_crawl.studies.core import SweepOptions
    from ocp_crawl.sweep.core import SweepError, SweepFailed, default_jobs

    _check_scheduler(args.scheduler)
    names = [f"{stem}.{ext}" for stem in rp.FIGURES for ext in ("png", "pdf")]
    names += ["report.md", "numbers.json", "sweeps"]
    out = prepare_out(args.out, names, args.force, resume=args.resume, kind="a reproduce run")
    quiet = args.no_progress or not sys.stderr.isatty()
    sweep = SweepOptions(jobs=args.jobs or default_jobs(), progress=not quiet, out_dir=out / "sweeps",
                         resume=args.resume, scheduler=args.scheduler)
    log = None if args.no_progress else (lambda msg: print(f"{PROG}: {msg}", file=sys.stderr, flush=True))
    try:
        result = rp.reproduce(out, quick=args.quick, gravity=args.gravity, sweep=sweep, log=log)
    except SweepError as exc:
        raise BadInput(str(exc)) from None
    except SweepFailed as exc:
        _err(f"reproduce incomplete: {exc}")
        return EXIT_FAILURE
    held = sum(all(s.holds.values()) for s in result.statements)
    changed = [s.key for s in result.statements if s.changed]
    print(f"{result.mode} run in {result.elapsed:.0f} s: {len(result.files)} files in {result.out_dir}/ "
          f"(report: {result.report})")
    print(f"statements of the paper: {held} of {len(result.statements)} hold in both conventions; "
          f"changed by the physical convention: {', '.join(changed) if changed else 'none'}")
    return EXIT_OK


# --------------------------------------------------------------------------------------------
# animate
# --------------------------------------------------------------------------------------------
def _animate_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("problem", metavar="PROBLEM.toml", help="problem file (see README, 'Problem files')")
    p.add_argument("--out", metavar="FILE.gif", default="crawl.gif", help="output GIF (default: ./crawl.gif)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key, e.g. --set robot.k=0.05 (repeatable)")
    p.add_argument("--drive", choices=("torque", "angles"), help="shortcut for --set gait.drive=...")
    p.add_argument("--cycles", type=_integer("--cycles", 1), default=2, metavar="N", help="cycles to show (default: 2)")
    p.add_argument("--frames-per-cycle", type=_integer("--frames-per-cycle", 2), default=48, metavar="N",
                   help="frames per cycle (default: 48)")
    p.add_argument("--fps", type=_real("--fps", 0.0, 100.0), default=20.0, help="frames per second (default: 20)")
    _force_arg(p, "an existing FILE.gif")


@register("animate", "animate the robot crawling (GIF; feet coloured by contact state)", _animate_args)
def cmd_animate(args: argparse.Namespace) -> int:
    from ocp_crawl.viz.animate import animate_problem

    path = Path(args.out)
    if path.suffix.lower() != ".gif" or not path.stem:
        raise BadInput(f"--out {args.out}: the animation is a GIF; give a file name ending in .gif")
    overrides = list(args.overrides) + ([f"gait.drive={args.drive}"] if args.drive else [])
    problem = load_problem(args.problem, overrides)
    prepare_out(path.parent, [path.name], args.force, label=f"--out {args.out}")
    check_start(problem)
    result, written = animate_problem(problem, path, args.cycles, args.frames_per_cycle, args.fps)
    print(f"wrote {written}: {result.status_name}, "
          + (f"S = {1e3 * result.S:.2f} mm per cycle" if result.success else result.message))
    if not result.success:
        print(f"{PROG}: simulation failed: {result.message} (animated up to the failure)", file=sys.stderr)
        return EXIT_FAILURE
    return EXIT_OK


# --------------------------------------------------------------------------------------------
# crosscheck
# --------------------------------------------------------------------------------------------
def _crosscheck_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("problem", metavar="PROBLEM.toml", help="problem file (torque drive)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key (repeatable)")
    p.add_argument("--steps", type=_steps, nargs="+", default=[50, 100, 200, 400], metavar="N",
                   help="increasing steps per cycle of the MPCC time-stepping (default 50 100 200 400)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout instead of the table")


@register("crosscheck", "compare the event-driven and the MPCC time-stepping simulators", _crosscheck_args)
def cmd_crosscheck(args: argparse.Namespace) -> int:
    from ocp_crawl.sim.crosscheck import crosscheck

    problem = load_problem(args.problem, args.overrides)
    if problem.drive != "torque":
        raise BadInput(f"{problem.source}: crosscheck needs the torque drive, got [gait] drive = "
                       f"{format_value(problem.drive)}")
    steps = sorted(set(args.steps))
    if len(steps) < 2:
        raise BadInput(f"--steps {' '.join(map(str, args.steps))}: give at least two different step counts")
    check_start(problem)
    result = crosscheck(problem.model, problem.torque, steps=steps)
    if args.json:
        print(json.dumps(jsonable(dict(result.summary(), problem_file=problem.source)), allow_nan=False))
    else:
        print(result.table())
    return EXIT_OK if result.summary()["passed"] else EXIT_FAILURE


# --------------------------------------------------------------------------------------------
# optimize
# --------------------------------------------------------------------------------------------
def _optimize_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("problem", metavar="PROBLEM.toml", help="problem file with an [ocp] section (see README)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key, e.g. --set ocp.nodes=200 (repeatable)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout instead of the summary")
    p.add_argument("--out", metavar="DIR", help="write torques.csv, arrays.npz, summary.json and figures to DIR")
    _force_arg(p)


#: the files ocp_output.write_outputs writes
OCP_FILES = ("torques.csv", "arrays.npz", "summary.json", "optimal_gait.png", "optimal_gait.pdf")


def format_optimize(s: dict) -> str:
    def mm(v):
        return "-" if v is None else f"{1e3 * v:+.3f} mm"

    h = s.get("best_harmonic") or {}
    lines = [
        f"status      {s['status']}: {s['message']}",
        f"objective   {s['objective']} ({s['nodes']} nodes, {s['parametrization']} torques)",
        f"S           OCP {mm(s['S_ocp']) if not isinstance(s['S_ocp'], list) else s['S_ocp']}, "
        f"replay {mm(s['S_replay']) if not isinstance(s['S_replay'], list) else s['S_replay']}",
        f"objective   OCP {s['objective_value_ocp']}, replay {s['objective_value_replay']} "
        f"(relative difference {s['rel_diff_replay']})",
        f"CoT+        replay {s['CoT_plus_replay']}",
        f"harmonic    best of the envelope: psi = {h.get('psi_deg')} deg, A = {h.get('A_deg')} deg, "
        f"objective {h.get('value')}; gain of the optimum (by replay) {s['gain']}",
        f"residuals   complementarity {s['complementarity_residual']}, periodicity {s['periodicity_residual']}",
        f"time        {s['solve_time_s']} s",
    ]
    return "\n".join(lines)


@register("optimize", "design an optimal periodic torque profile (OCP) and prove it by replay", _optimize_args)
def cmd_optimize(args: argparse.Namespace) -> int:
    from ocp_crawl.ocp import optimize_gait
    from ocp_crawl.viz.ocp import write_outputs as write_ocp_outputs
    from ocp_crawl.problem.core import ocp_settings

    problem = load_problem(args.problem, args.overrides)
    settings = ocp_settings(problem)
    out = prepare_out(args.out, OCP_FILES, args.force) if args.out else None
    check_start(problem)
    result = optimize_gait(problem.robot, problem.gravity, settings)
    data = jsonable(dict(result.summary(), problem_file=problem.source, problem=problem.to_dict(),
                         units={"S": "m", "W_plus": "J", "CoT_plus": "-", "tau": "N m", "solve_time_s": "s"}))
    if args.json:
        print(json.dumps(data, allow_nan=False))
    else:
        print(format_optimize(data))
    files = write_ocp_outputs(result, problem.robot, out, data) if out is not None else []
    return _finish(args, files, result.success, f"optimisation failed: {result.message}")


# --------------------------------------------------------------------------------------------
# entry point
# --------------------------------------------------------------------------------------------
def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog=PROG, description="Hybrid-quasistatic simulation of a soft three-link inchworm crawler.",
                     epilog="exit codes: 0 success, 1 numerical failure (or an internal error), 2 bad input")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for cmd in COMMANDS.values():
        p = sub.add_parser(cmd.name, help=cmd.help, description=cmd.help)
        cmd.arguments(p)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit code (never calls sys.exit itself)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except _UsageError as exc:
        _err(str(exc))
        return EXIT_BAD_INPUT
    except SystemExit as exc:  # --help and --version end argparse this way
        return int(exc.code or 0) if isinstance(exc.code, (int, type(None))) else EXIT_BAD_INPUT
    try:
        return COMMANDS[args.command].run(args)
    except (ProblemError, BadInput) as exc:
        _err(str(exc))
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        _err("interrupted")
        return 130
    except BrokenPipeError:
        # the reader (e.g. `| head`) went away: silence the interpreter's flush at exit
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_FAILURE
    except Exception as exc:
        # not bad input (that is ProblemError or BadInput, raised on purpose): a bug or a failing
        # environment, reported in one line; exit 1 so that a script never mistakes it for bad input
        if os.environ.get("OCP_CRAWL_TRACEBACK"):
            raise
        text = " ".join(str(exc).split())
        if isinstance(exc, OSError):
            print(f"{PROG}: I/O error: {text}", file=sys.stderr)
        else:
            print(f"{PROG}: internal error: {type(exc).__name__}: {text} (set OCP_CRAWL_TRACEBACK=1 for the "
                  "traceback)", file=sys.stderr)
        return EXIT_FAILURE


if __name__ == "__main__":
    raise SystemExit(main())
