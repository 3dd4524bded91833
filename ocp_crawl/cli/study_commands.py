"""Commands over many problems: sweep, reproduce."""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

from ocp_crawl.cli.app import EXIT_FAILURE, EXIT_OK, PROG, BadInput, err, register
from ocp_crawl.cli.common import (address, announce, check_scheduler, check_work, jobs_type,
                                  out_dir, prepare_out, work_arg)
from ocp_crawl.io import units
from ocp_crawl.problem import SCHEMA, format_value, problem_from_dict
from ocp_crawl.problem.overrides import entry, first_loss, parse_override, read_toml
from ocp_crawl.problem.work import sweep_work
from ocp_crawl.sim import solver_named
from ocp_crawl.sweep import (JOURNAL_FILE, RESULTS_FILE, SETTINGS_FILE, SUMMARY_FILE, SweepError,
                             SweepFailed,
                             check_some_point_valid, default_jobs, grid_from_specs, run_sweep)


# --------------------------------------------------------------------------------------------
# sweep
# --------------------------------------------------------------------------------------------
def _sweep_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("problem", metavar="PROBLEM.toml",
                   help="base problem file (see docs/guide/problem_files.md)")
    p.add_argument("--grid", action="append", required=True, metavar="KEY=START:STOP:NUM",
                   help="an axis: NUM values from START to STOP inclusive, "
                        "KEY=START:STOP:step=STEP (START, START+STEP, ... up to STOP), or a list "
                        "KEY=A,B,C (repeatable; the first axis varies slowest), e.g. --grid "
                        "gait.psi_deg=0:180:37 or gait.psi_deg=0:180:step=5 (the same)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key of the base problem (repeatable)")
    p.add_argument("--jobs", type=jobs_type, metavar="N",
                   help="worker processes (default: the CPUs available)")
    p.add_argument("--out", metavar="DIR", type=out_dir,
                   help="output directory (default: ./sweep_<problem stem>)")
    again = p.add_mutually_exclusive_group()
    again.add_argument("--resume", action="store_true", help="continue an interrupted sweep in DIR")
    again.add_argument("--force", action="store_true",
                       help="overwrite a sweep already in DIR (without it, or --resume, the "
                            "command refuses)")
    p.add_argument("--scheduler", metavar="ADDRESS", type=address,
                   help="run on a Dask cluster (e.g. tcp://host:8786, or 'local'); needs the "
                        "[cluster] extra")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object on stdout instead of the summary")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    work_arg(p)


@register("sweep", "map S, W+ and CoT+ over a grid of problem keys (parallel, resumable)",
          _sweep_args)
def cmd_sweep(args: argparse.Namespace) -> int:
    data = read_toml(args.problem)   # once: the file may be a named pipe
    problem = problem_from_dict(data, source=str(args.problem), overrides=args.overrides)
    grid = grid_from_specs(args.grid)
    _check_grid_keeps_sets(args, data, grid)
    _check_axes_matter(problem, grid)
    check_some_point_valid(problem, grid)
    check_scheduler(args.scheduler)
    work = check_work(args, sweep_work(problem, grid, args.jobs or default_jobs()))
    # --resume: run_sweep checks that the directory's settings.json is this sweep's
    out = prepare_out(args.out or f"sweep_{Path(args.problem).stem}",
                      (SETTINGS_FILE, RESULTS_FILE, JOURNAL_FILE, SUMMARY_FILE), args.force,
                      resume=args.resume, kind="a sweep")
    announce(work)
    try:
        result = run_sweep(problem, grid, out_dir=out, jobs=args.jobs or default_jobs(),
                           resume=args.resume,
                           force=args.force, progress=not args.no_progress and sys.stderr.isatty(),
                           scheduler=args.scheduler)
    except SweepError as exc:
        raise BadInput(str(exc)) from None
    except SweepFailed as exc:
        err(f"sweep incomplete: {exc}")
        return EXIT_FAILURE
    # failed points are data (their status is in results.csv): the command succeeded
    print(json.dumps(result.summary(), allow_nan=False) if args.json else result.format_summary())
    return EXIT_OK


def _simulation_keys(solver: str) -> set[str]:
    """The [simulation] keys the torque solver ``solver`` reads: its options' fields, and
    ``solver``."""
    names = {f.name for f in dataclasses.fields(solver_named(solver).options)}
    return {k.name for k in SCHEMA["simulation"].keys if k.name in names} | {"solver"}


def _check_axes_matter(problem, grid) -> None:
    """BadInput for an axis that no point of the sweep reads (its rows would be copies): an [ocp]
    key (only optimize reads them), a [simulation] key that the points' simulators do not read,
    ``gait.period`` (S, W+, CoT+ per cycle do not depend on it), a [pressure] key without the
    pressure waveform."""
    drives = set(grid.get("gait.drive", [problem.drive]))
    waveforms = set(grid.get("gait.waveform", [problem.sections["gait"]["waveform"]]))
    solvers = set(grid.get("simulation.solver",
                           [problem.sections.get("simulation", {}).get("solver", "event")]))
    # the angles drive reads [simulation] only for MuJoCo (its servos), the torque drive for every
    # solver
    read = solvers if "torque" in drives else solvers & {"mujoco"}
    used = set().union(*(_simulation_keys(s) for s in read))
    for name in grid:
        section, key = name.split(".", 1)
        if section == "ocp":
            raise BadInput(f"--grid {name}: a sweep simulates gaits, and [ocp] keys matter to "
                           "optimize only: every row would be the same")
        if name == "gait.period":
            raise BadInput(f"--grid {name}: a sweep reports S, W+ and CoT+ per cycle, which the "
                           "period does not change: every row would be the same")
        if section == "pressure" and "pressure" not in waveforms:
            raise BadInput(f"--grid {name}: only [gait] waveform = \"pressure\" reads the "
                           "[pressure] section: every row would be the same")
        if section == "simulation" and key not in used:
            who = "the angles drive" if not used else f"solver {' and '.join(sorted(solvers))}"
            raise BadInput(f"--grid {name}: {who} does not read simulation.{key}: every row would "
                           "be the same")


def _check_grid_keeps_sets(args: argparse.Namespace, data, grid) -> None:
    """BadInput when a grid value changes or drops a ``--set`` value (the same key, an alternative
    key such as robot.mu for robot.mu1): the --set would be silently ignored.  An axis of
    ``gait.waveform`` drops the keys of the other waveforms by design (only a --set of gait.waveform
    itself is a conflict).  ``data``: the file's sections."""
    if not args.overrides:
        return
    source = str(args.problem)
    sets = [parse_override(text, source) for text in args.overrides]
    for name, values in grid.items():
        section, key = name.split(".", 1)
        if SCHEMA[section].selector == key:
            given = [text for text, (sec, k, _) in zip(args.overrides, sets)
                     if (sec, k) == (section, key)]
            if given:
                raise BadInput(f"--grid {name}=... and --set {given[0]}: the grid gives {name} at "
                               "every point, so drop the --set")
            continue
        for value in dict.fromkeys(v.item() if hasattr(v, "item") else v for v in values):
            loss = first_loss(data, sets, [(section, key, value)])
            if loss is not None:
                given = next(t for t, (sec, k, _) in zip(args.overrides, sets)
                             if f"{sec}.{k}" == loss[1])
                # (an array, the --set of an entry's whole array, is no axis to suggest)
                whole = f"{section}.{entry(key)[0]}"
                also = f" (or sweep {loss[1]})" if loss[1] not in (name, whole) else ""
                raise BadInput(f"--grid {name}={format_value(value)} undoes --set {given}: the "
                               f"grid gives {name} at every point, so drop the --set{also}")


# --------------------------------------------------------------------------------------------
# reproduce
# --------------------------------------------------------------------------------------------
def _reproduce_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", metavar="DIR", default="ocp_crawl_reproduce", type=out_dir,
                   help="directory for the figures, report.md and numbers.json (default: "
                        "./ocp_crawl_reproduce)")
    p.add_argument("--quick", action="store_true",
                   help="coarse grids (about a minute on 2 cores); default: full grids")
    p.add_argument("--gravity", choices=("paper", "physical"), default="paper",
                   help="convention of the figures (default: paper, the sign the published curves "
                        "were computed with); the statements are checked in both")
    p.add_argument("--jobs", type=jobs_type, metavar="N",
                   help="worker processes for the grids (default: the CPUs available)")
    again = p.add_mutually_exclusive_group()
    again.add_argument("--resume", action="store_true",
                       help="reuse the grid points finished by an interrupted run in DIR/sweeps "
                            "(same grids only)")
    again.add_argument("--force", action="store_true",
                       help="overwrite the results of an earlier run in DIR (without it, or "
                            "--resume, the command refuses, before computing anything)")
    p.add_argument("--scheduler", metavar="ADDRESS", type=address,
                   help="run the grids on a Dask cluster (needs the [cluster] extra)")
    p.add_argument("--no-progress", action="store_true",
                   help="no progress bars or step lines on stderr")


@register("reproduce",
          "regenerate the paper's figures and report.md (both gravity conventions checked)",
          _reproduce_args)
def cmd_reproduce(args: argparse.Namespace) -> int:
    from ocp_crawl.studies import reproduce as rp
    from ocp_crawl.studies import SweepOptions

    check_scheduler(args.scheduler)
    names = [f"{stem}.{ext}" for stem in rp.FIGURES for ext in ("png", "pdf")]
    names += ["report.md", "numbers.json", "sweeps"]
    out = prepare_out(args.out, names, args.force, resume=args.resume, kind="a reproduce run")
    quiet = args.no_progress or not sys.stderr.isatty()
    sweep = SweepOptions(jobs=args.jobs or default_jobs(), progress=not quiet,
                         out_dir=out / "sweeps", resume=args.resume, scheduler=args.scheduler)
    log = None if args.no_progress else (lambda msg: print(f"{PROG}: {msg}", file=sys.stderr,
                                                           flush=True))
    try:
        result = rp.reproduce(out, quick=args.quick, gravity=args.gravity, sweep=sweep, log=log)
    except SweepError as exc:
        raise BadInput(str(exc)) from None
    except SweepFailed as exc:
        err(f"reproduce incomplete: {exc}")
        return EXIT_FAILURE
    held = sum(all(s.holds.values()) for s in result.statements)
    changed = [s.key for s in result.statements if s.changed]
    print(f"{result.mode} run in {units.seconds(result.elapsed)}: {len(result.files)} files in "
          f"{result.out_dir}/ (report: {result.report})")
    print(f"statements of the paper: {held} of {len(result.statements)} hold in both conventions; "
          f"changed by the physical convention: {', '.join(changed) if changed else 'none'}")
    return EXIT_OK
