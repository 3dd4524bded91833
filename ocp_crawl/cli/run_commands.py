"""Commands that simulate: simulate, demo, animate, crosscheck."""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

import numpy as np

from ocp_crawl.cli.app import EXIT_FAILURE, EXIT_OK, PROG, BadInput, register
from ocp_crawl.cli.common import (announce, check_work, finish, force_arg, integer, optional_out,
                                  out_dir, out_file,
                                  prepare_out, real, steps_type, work_arg, write_out)
from ocp_crawl.io import units
from ocp_crawl.model.chain import Chain
from ocp_crawl.model.robot import Robot
from ocp_crawl.problem.work import crosscheck_work, simulation_work
from ocp_crawl.io.files import jsonable, write_json, write_npz
from ocp_crawl.problem import (SCHEMA, TORQUE_SOLVERS, Problem, format_value, load_problem,
                               no_start_reason, paper_problem, problem_from_dict, run_problem)
from ocp_crawl.problem.overrides import first_loss, parse_override, read_toml, toml_string
from ocp_crawl.problem.problem import solver_options
from ocp_crawl.problem.waveforms import waveform_text
from ocp_crawl.sim.result import CrawlResult
from ocp_crawl.status import STATUS_MESSAGES, Status
from ocp_crawl.viz import FPS_BOUNDS

#: most step counts of crosscheck (one MPCC run each)
MAX_STEP_COUNTS = 8

#: units of the summary's numbers, written with every JSON summary
UNITS = {**{k: units.UNITS[k] for k in ("S", "W_plus", "W_plus_joint", "CoT_plus", "t", "energy",
                                            "energy.balance_residual")},
         "period": units.UNITS["T"], "speed": units.UNITS["v"]}


def no_start_message(problem: Problem, detail: str) -> str:
    """One line for a torque-driven problem with no equilibrium to start from (bad input, exit
    2)."""
    d = problem.to_dict()
    r, g = d.get("robot", {}), d.get("gait", {})
    robot = ", ".join(f"{k} = {format_value(r[k])}"
                      for k in ("k", "stiffness", "M", "masses", "L", "lengths", "g") if k in r)
    gait = ", ".join(f"{k} = {format_value(v)}" for k, v in g.items() if k.endswith("_deg"))
    return (f"{problem.source}: [robot] {robot}; [model] gravity = "
            f"{format_value(problem.gravity)}; [gait] {gait}: {detail}; stiffen the joints "
            f"(robot.{'stiffness' if problem.is_chain else 'k'}) or change the gait")


def check_start(problem: Problem) -> None:
    """A torque-driven problem must have a released equilibrium at t = 0 (status no_start
    otherwise): checked before any long run, as bad input (cheap: one equilibrium solve)."""
    reason = no_start_reason(problem)
    if reason is not None:
        raise BadInput(no_start_message(problem, f"{STATUS_MESSAGES[Status.NO_START]}: {reason}"))


def _simulate(problem: Problem) -> CrawlResult:
    """``run_problem``, a start the solver could not find being bad input (as check_start's)."""
    result = run_problem(problem)
    if result.status == Status.NO_START:
        # check_start has let it through: the same verdict, as bad input
        raise BadInput(no_start_message(problem, result.message))
    return result


def load_with_shortcuts(args: argparse.Namespace) -> Problem:
    """The command's problem with its shortcut options and ``--set`` overrides (:func:`shortcuts`);
    the file is read once (it may be a named pipe)."""
    data = read_toml(args.problem)
    return problem_from_dict(data, source=str(args.problem), overrides=shortcuts(args, data))


def shortcuts(args: argparse.Namespace, data) -> list[str]:
    """The overrides that the command's shortcut options stand for (``--drive``: gait.drive,
    ``--solver``: simulation.solver, ``--steps``: simulation.steps, ``--input``: gait.waveform =
    "samples" with gait.file, the file's path made absolute: relative to the current directory),
    followed by its ``--set`` overrides (so that a ``--set`` key of another waveform than
    ``--input``'s is refused by the schema).  A ``--set`` that changes or drops what a shortcut set
    (another value of its key, an alternative key such as gait.phase for gait.file, another
    waveform) is a conflict: BadInput naming both.  ``data``: the problem file's sections."""
    options = []   # (the option as given, the overrides it stands for)
    if getattr(args, "input", None) is not None:
        options.append((f"--input {args.input}",
                        ["gait.waveform=samples",
                         f"gait.file={toml_string(os.path.abspath(args.input))}"]))
    for name, key in (("drive", "gait.drive"), ("solver", "simulation.solver"),
                      ("steps", "simulation.steps")):
        if getattr(args, name, None) is not None:
            options.append((f"--{name} {getattr(args, name)}", [f"{key}={getattr(args, name)}"]))
    texts = [text for _, items in options for text in items]
    if texts and args.overrides:
        source = str(args.problem)
        loss = first_loss(data, [parse_override(t, source) for t in texts],
                          [parse_override(t, source) for t in args.overrides])
        if loss is not None:
            i, key = loss
            option = next(label for label, items in options
                          if any(t.startswith(key + "=") for t in items))
            raise BadInput(f"{option} sets {key}, and --set {args.overrides[i]} undoes it: give "
                           "one of them")
    return texts + list(args.overrides)


def report(result: CrawlResult, problem: Problem) -> dict:
    """The JSON report of a run: the result's summary, the period and mean speed |S| / period (None
    without a period), the solver, the problem and the units."""
    out = result.summary()
    out["period"] = problem.period
    out["speed"] = problem.speed(result.S)
    out["solver"] = problem.solver
    out["problem_file"] = problem.source
    out["problem"] = problem.to_dict()
    out["units"] = UNITS
    return jsonable(out)


def _per_cycle(text: str) -> str:
    """A per-cycle quantity as text ("-" alone when it was not computed)."""
    return text if text == units.MISSING else f"{text} per cycle"


def _speed_text(speed: float | None, period: float | None) -> str:
    """The mean speed with the period it is over, or "-" (no period, or no S)."""
    if period is None:
        return f"{units.MISSING} (no [gait] period)"
    return f"{units.speed(speed)} (|S| / period, period {period:.6g} s)"


def robot_text(robot: Robot | Chain) -> str:
    """The robot's parameters in one line (a chain: its lists, from foot 1 to foot 2)."""
    tail = f"mu1 = {robot.mu1:g}, mu2 = {robot.mu2:g}, g = {robot.g:g} m/s^2"
    if isinstance(robot, Chain):
        def listed(values, scale=1.0):
            return "[" + ", ".join(f"{scale * v:g}" for v in values) + "]"
        return (f"chain of {robot.n} links: lengths {listed(robot.lengths)} m, masses "
                f"{listed(robot.masses)} kg, stiffness {listed(robot.stiffness)} N m/rad, "
                f"com {listed(robot.com)}, rest {listed(robot.rest, 180 / math.pi)} deg, {tail}")
    return (f"M = {robot.M:g} kg, L = {robot.L:g} m, beta = {robot.beta:g}, k = {robot.k:g} "
            f"N m/rad, {tail}")


def format_summary(result: CrawlResult, problem: Problem) -> str:
    """Readable summary: problem, status, S [mm], the mean speed [mm/s] ("-" without a period), W+
    [mJ], CoT+, events table, cycles."""
    gait = problem.sections.get("gait", {})
    gait_text = waveform_text(gait)
    direction = ""
    if np.isfinite(result.S) and result.S != 0:
        direction = " (towards foot 1)" if result.S < 0 else " (towards foot 2)"
    lines = [
        f"problem    {problem.source}",
        f"drive      {problem.drive} (solver {problem.solver}), gravity {problem.gravity}",
        f"robot      {robot_text(problem.robot)}",
        f"gait       {gait_text}",
        f"status     {result.status_name} ({result.status}): {result.message}",
        f"S          {_per_cycle(units.distance(result.S))}{direction}",
        f"speed      {_speed_text(problem.speed(result.S), problem.period)}",
    ]
    if np.isfinite(result.S_error):
        ex = result.extra
        bound = ex.get("S_error_bound", np.nan) * 1e3
        lines.append(f"S error    {result.S_error * 1e3:.2g} mm (estimate |S_N - S_M|, the steady "
                     f"cycle re-run with M = {ex.get('steps_check')} steps; bound {bound:.2g} mm)")
    lines += [
        f"W+         {_per_cycle(units.work(result.W_plus))}",
        f"CoT+       {units.cot(result.CoT_plus)}",
        f"cycles     {result.cycles}"
        + (f" (steady cycle from t = {result.t0:g})" if result.success else ""),
    ]
    events = result.steady_events() if result.success else result.events
    title = "events in the steady cycle" if result.success else "events"
    lines.append(f"{title}: {len(events)}")
    if events:
        lines.append(f"  {'t [cycles]':>12}  {'phase':>8}  {'kind':<14}  mode before -> after")
        for e in events:
            phase = e.t - result.t0 if result.success else e.t % 1.0
            lines.append(f"  {e.t:12.6f}  {phase:8.5f}  {e.kind:<14}  {e.mode_before} -> "
                         f"{e.mode_after}")
    return "\n".join(lines)


#: the files of one run written by :func:`write_outputs` (after a stem)
RUN_FILES = ("arrays.npz", "summary.json", "gait.png", "gait.pdf")


def write_outputs(out: Path, result: CrawlResult, problem: Problem, data: dict,
                  stem: str = "") -> list[Path]:
    """arrays.npz, summary.json, gait.png and gait.pdf in ``out`` (each written atomically; see
    RUN_FILES)."""
    # matplotlib only when figures are asked for
    from ocp_crawl.viz.gait import plot_gait, save_figure

    arrays, summary, png, pdf = (out / f"{stem}{name}" for name in RUN_FILES)
    files = [write_npz(arrays, result.arrays()), write_json(summary, data)]
    fig = plot_gait(result, problem.robot, reference=problem.gait)
    files += [save_figure(fig, png), save_figure(fig, pdf)]
    return files


# --------------------------------------------------------------------------------------------
# simulate
# --------------------------------------------------------------------------------------------
def _simulate_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("problem", metavar="PROBLEM.toml",
                   help="problem file (see docs/guide/problem_files.md)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key, e.g. --set robot.k=0.05 or --set gait.drive=angles "
                        "(repeatable)")
    p.add_argument("--drive", choices=("torque", "angles"),
                   help="shortcut for --set gait.drive=...")
    p.add_argument("--input", metavar="FILE.csv",
                   help="drive the problem's robot with a table of torques or reference angles "
                        "over one cycle, e.g. the torques.csv of optimize --out (columns 'phase "
                        "[-]' and 'tau1 [N m]', 'tau2 [N m]' or 'phi1_ref [deg]', 'phi2_ref "
                        "[deg]'): shortcut for --set gait.waveform=samples --set "
                        "gait.file=FILE.csv")
    p.add_argument("--solver", choices=TORQUE_SOLVERS,
                   help="shortcut for --set simulation.solver=...: event (event-driven hybrid "
                        "solver, the default), mpcc (MPCC time-stepping, IPOPT) or mujoco "
                        "(dynamic, at simulation.period [s]; needs pip install "
                        "'ocp-crawl[dynamic]'); the angles drive has its own solver, or mujoco "
                        "(servos hold the angles)")
    p.add_argument("--steps", type=steps_type, metavar="N",
                   help="shortcut for --set simulation.steps=N: steps per cycle of --solver mpcc "
                        f"(default {SCHEMA['simulation'].key_map['steps'].default})")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object on stdout instead of the summary")
    p.add_argument("--out", metavar="DIR", type=out_dir,
                   help="write arrays.npz, summary.json, gait.png and gait.pdf to DIR")
    force_arg(p)
    work_arg(p)


@register("simulate", "simulate one problem file and report the gait", _simulate_args)
def cmd_simulate(args: argparse.Namespace) -> int:
    problem = load_with_shortcuts(args)
    if args.steps is not None and problem.solver != "mpcc":
        raise BadInput(f"--steps {args.steps} is invalid with solver "
                       f"{format_value(problem.solver)}: it sets the steps of --solver mpcc (the "
                       "event-driven and prescribed-angle solvers place their own)")
    work = check_work(args, simulation_work(problem))
    out = optional_out(args, RUN_FILES)
    check_start(problem)
    announce(work)
    result = _simulate(problem)
    data = report(result, problem)
    if args.json:
        print(json.dumps(data, allow_nan=False))
    else:
        print(format_summary(result, problem))
    files = [] if out is None else write_out(
        out, lambda d: write_outputs(d, result, problem, data), args.force)
    return finish(args, files, result.success, f"simulation failed: {result.message}")


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
    p.add_argument("--out", metavar="DIR", default="ocp_crawl_demo", type=out_dir,
                   help="directory for the figures and summaries (default: ./ocp_crawl_demo)")
    force_arg(p)


@register("demo", "run the paper's gait (torque drive, both gravity signs, prescribed angles)",
          _demo_args)
def cmd_demo(args: argparse.Namespace) -> int:
    names = ([f"{case}_{name}" for case, _, _ in DEMO_CASES for name in RUN_FILES]
             + ["demo_summary.json"])
    out = prepare_out(args.out, names, args.force, staged=True)
    print("The paper's gait (Table I robot; gamma = 90 deg, A = 30 deg, psi = 45 deg)\n")
    header = (f"{'case':<36} {'status':<10} {'S [mm]':>9} {'W+ [mJ]':>9} {'CoT+':>8} "
              f"{'events/cycle':>12}")
    print(header)
    print("-" * len(header))
    reports, failed, runs = {}, [], []
    for name, text, overrides in DEMO_CASES:
        problem = paper_problem(overrides)
        result = _simulate(problem)
        n_events = len(result.steady_events()) if result.success else len(result.events)
        print(f"{text:<36} {result.status_name:<10} {units.fixed(result.S, scale=1e3):>9} "
              f"{units.fixed(result.W_plus, scale=1e3):>9} {units.cot(result.CoT_plus):>8} "
              f"{n_events:>12}")
        reports[name] = data = report(result, problem)
        runs.append((name, result, problem, data))
        if not result.success:
            failed.append(f"{text}: {result.message}")

    def write(directory: Path) -> list[Path]:
        files = [f for name, *run in runs for f in write_outputs(directory, *run, stem=f"{name}_")]
        return files + [write_json(directory / "demo_summary.json", reports)]
    write_out(out, write, args.force)
    print(f"\nfigures and summaries in {out}/ (<case>_gait.png, <case>_gait.pdf, "
          "<case>_summary.json, <case>_arrays.npz)")
    print("S < 0: the robot moves towards foot 1, the joint that leads in phase. The two gravity "
          "signs differ by a few percent in S (see docs/guide/model.md, 'Gravity conventions').")
    for f in failed:
        print(f"{PROG}: simulation failed: {f}", file=sys.stderr)
    return EXIT_FAILURE if failed else EXIT_OK


# --------------------------------------------------------------------------------------------
# animate
# --------------------------------------------------------------------------------------------
def _animate_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("problem", metavar="PROBLEM.toml",
                   help="problem file (see docs/guide/problem_files.md)")
    p.add_argument("--out", metavar="FILE.gif", default="crawl.gif", type=out_file(".gif"),
                   help="output GIF (default: ./crawl.gif)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key, e.g. --set robot.k=0.05 (repeatable)")
    p.add_argument("--drive", choices=("torque", "angles"),
                   help="shortcut for --set gait.drive=...")
    p.add_argument("--cycles", type=integer("--cycles", 1), default=2, metavar="N",
                   help="cycles to show, at most 10 (default: 2)")
    p.add_argument("--frames-per-cycle", type=integer("--frames-per-cycle", 2), default=48,
                   metavar="N", help="frames per cycle, at most 100 (default: 48)")
    p.add_argument("--fps",
                   type=real("--fps", *FPS_BOUNDS, " (at most 100 s per frame)", closed=True),
                   default=20.0, help="frames per second (default: 20)")
    force_arg(p, "an existing FILE.gif")
    work_arg(p)


@register("animate", "animate the robot crawling (GIF; feet coloured by contact state)",
          _animate_args)
def cmd_animate(args: argparse.Namespace) -> int:
    from ocp_crawl.viz.animate import FRAME_BOUNDS, animate_problem

    for option, value in (("--cycles", args.cycles), ("--frames-per-cycle", args.frames_per_cycle)):
        low, high = FRAME_BOUNDS[option]
        if not low <= value <= high:
            raise BadInput(f"{option} {value} is invalid: must be an integer in [{low}, {high}]: "
                           "every frame is an image held in memory until the GIF is written")
    path = Path(args.out)
    if path.suffix.lower() != ".gif" or not path.stem:
        raise BadInput(f"--out {args.out}: the animation is a GIF; give a file name ending in .gif")
    problem = load_with_shortcuts(args)
    twice = simulation_work(problem).times(2, "a run for the cycle, one for the frames")
    work = check_work(args, twice)
    prepare_out(path.parent, [path.name], args.force, label=f"--out {args.out}")
    check_start(problem)
    announce(work)
    result, written = animate_problem(problem, path, args.cycles, args.frames_per_cycle, args.fps)
    if written is not None:
        print(f"wrote {written}: {result.status_name}, "
              + (f"S = {units.distance(result.S, 2)} per cycle" if result.success
                 else result.message))
    if not result.success:
        what = ("animated up to the failure" if written is not None
                else "no samples to animate: nothing written")
        print(f"{PROG}: simulation failed: {result.message} ({what})", file=sys.stderr)
        return EXIT_FAILURE
    return EXIT_OK


# --------------------------------------------------------------------------------------------
# crosscheck
# --------------------------------------------------------------------------------------------
def _crosscheck_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("problem", metavar="PROBLEM.toml", help="problem file (torque drive)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key (repeatable)")
    p.add_argument("--steps", type=steps_type, nargs="+", default=[50, 100, 200, 400],
                   metavar="N", help="increasing steps per cycle of the MPCC time-stepping "
                                     f"(default 50 100 200 400; at most {MAX_STEP_COUNTS} counts)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object on stdout instead of the table")
    work_arg(p)


@register("crosscheck", "compare the event-driven and the MPCC time-stepping simulators",
          _crosscheck_args)
def cmd_crosscheck(args: argparse.Namespace) -> int:
    from ocp_crawl.sim.crosscheck import crosscheck

    problem = load_problem(args.problem, args.overrides)
    if problem.drive != "torque":
        raise BadInput(f"{problem.source}: crosscheck needs the torque drive, got [gait] drive = "
                       f"{format_value(problem.drive)}")
    steps = list(args.steps)
    given = " ".join(map(str, args.steps))
    if len(steps) < 2 or any(b <= a for a, b in zip(steps, steps[1:])):
        raise BadInput(f"--steps {given} is invalid: give at least two different step counts, "
                       "increasing strictly (the error is checked to decrease with N)")
    if len(steps) > MAX_STEP_COUNTS:
        raise BadInput(f"--steps {given}: {len(steps)} step counts, at most "
                       f"{MAX_STEP_COUNTS} (one MPCC run each)")
    work = check_work(args, crosscheck_work(problem, steps))
    check_start(problem)
    announce(work)
    # the file's [simulation] options (cycles, periodicity, event location) for both simulators;
    # --steps the steps
    sim = problem.sections.get("simulation", {})
    result = crosscheck(problem.model, problem.torque, steps=steps, hybrid_options=problem.hybrid,
                        mpcc_options=solver_options("mpcc", sim))
    if args.json:
        print(json.dumps(jsonable(dict(result.summary(), problem_file=problem.source)),
                         allow_nan=False))
    else:
        print(result.table())
    # the criteria decide, each named with its value and bound; the information does not
    failed = [f"'{name}': {c.text()}" for name, c in result.checks.items() if not c.passed]
    if failed:
        print(f"{PROG}: crosscheck FAIL, criteria not met: {'; '.join(failed)}", file=sys.stderr)
    return EXIT_FAILURE if failed or not result.passed else EXIT_OK

