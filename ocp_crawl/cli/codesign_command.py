"""The codesign command: the robot parameters of a problem's ``[design]`` and the gait of its
``[ocp]`` objective together, proved by replay and against a scan of designs."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ocp_crawl.cli.app import PROG, BadInput, register
from ocp_crawl.cli.common import (announce, check_work, finish, force_arg, jobs_type, optional_out,
                                  out_dir, work_arg, write_out)
from ocp_crawl.cli.optimize_command import OCP_FILES
from ocp_crawl.cli.run_commands import check_start
from ocp_crawl.io import units
from ocp_crawl.io.files import jsonable, write_json
from ocp_crawl.ocp.judge import value_text
from ocp_crawl.problem import problem_from_dict
from ocp_crawl.problem.overrides import read_toml
from ocp_crawl.problem.work import codesign_work
from ocp_crawl.workers import default_jobs

#: the files of ``codesign --out`` besides those of the chosen design's gait (optimize's)
CODESIGN_FILES = ("codesign.json", "codesign.png", "codesign.pdf")


def _codesign_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("problem", metavar="PROBLEM.toml",
                   help="problem file with [ocp] and [design] sections (see "
                        "problems/codesign_stiffness.toml)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key, e.g. --set design.scan=4 (repeatable)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object on stdout instead of the summary")
    p.add_argument("--out", metavar="DIR", type=out_dir,
                   help="write codesign.json, codesign.png/.pdf and the chosen design's gait "
                        "(torques.csv, optimal_gait.toml of the chosen robot: replays with "
                        "simulate, arrays.npz, summary.json, optimal_gait.png/.pdf) to DIR")
    p.add_argument("--jobs", type=jobs_type, metavar="N",
                   help="worker processes of the scan of designs (default: the CPUs available)")
    work_arg(p)
    force_arg(p)


def _value(objective: str, v) -> str:
    """An objective value with its unit (:func:`~ocp_crawl.ocp.judge.value_text`)."""
    return units.MISSING if v is None else value_text(objective, v)


def format_codesign(data: dict) -> str:
    """The text summary of a co-design's JSON (:meth:`CodesignResult.to_dict`)."""
    obj = data["objective"]
    lines = [f"codesign   {data['status']}: {data['message']}",
             "design     variable: given -> chosen  [low, high]"]
    for name, a, b, lo, hi in zip(data["names"], data["initial"], data["chosen"] or
                                  [None] * len(data["names"]), data["low"], data["high"]):
        lines.append(f"           {name}: {units.significant(a, 5)} -> "
                     f"{units.significant(b, 5) if b is not None else units.MISSING}  "
                     f"[{units.significant(lo, 4)}, {units.significant(hi, 4)}]")
    gains = data["gains"]
    lines += [f"objective  co-design NLP {_value(obj, data['value_nlp'])}, replay at the chosen "
              f"design {_value(obj, data['value_replay'])}",
              f"given      the given robot's optimal gait "
              f"{_value(obj, (data['given'] or {}).get('objective_value_replay'))} (replay)",
              f"gains      {units.ratio(gains['over_given_optimum'])} over the given robot's "
              f"optimal gait; {units.ratio(gains['over_initial'])} over its best harmonic gait, "
              f"{units.ratio(gains['over_scan'])} over the best scanned design's",
              f"scan       {len(data['scan'])} designs, each with its best harmonic travelling "
              f"wave (start: "
              f"{'none' if data['start'] is None else 'design ' + str(data['start'] + 1)}):"]
    for i, d in enumerate(data["scan"]):
        values = ", ".join(units.significant(v, 4) for v in d["values"])
        lines.append(f"           {i + 1:2d}  ({values})  {_value(obj, d['value'])}")
    lines.append(f"time       {units.seconds(data['time_s'])}, {data['iterations']} IPOPT "
                 "iterations")
    return "\n".join(lines)


@register("codesign", "choose robot parameters ([design]) and the gait together, proved by "
          "replay and against a scan of designs", _codesign_args)
def cmd_codesign(args: argparse.Namespace) -> int:
    from ocp_crawl.problem.codesign import (chosen_problem_dict, codesign_inputs,
                                            codesign_problem)
    from ocp_crawl.viz.codesign import codesign_figure
    from ocp_crawl.viz.gait import save_figure
    from ocp_crawl.viz.ocp import scenario_files, write_outputs

    data = read_toml(args.problem)   # once: the file may be a named pipe
    given = {o.split("=", 1)[0].strip().split(".", 1)[0] for o in args.overrides}
    for section in ("ocp", "design"):
        if section not in data and (section == "ocp" or section not in given):
            raise BadInput(f"{args.problem}: no [{section}] section: codesign needs [ocp] (the "
                           "objective) and [design] (the bounds, in the file or as --set "
                           "design.KEY=VALUE); see problems/codesign_stiffness.toml")
    problem = problem_from_dict(data, source=str(args.problem), overrides=args.overrides)
    design, settings = codesign_inputs(problem)   # bad input before any work
    section = problem.sections["design"]
    work = check_work(args, codesign_work(problem, settings, design, int(section["scan"]),
                                          int(section["search_rounds"]),
                                          args.jobs or default_jobs()))
    out = optional_out(args, (*CODESIGN_FILES, *OCP_FILES, *scenario_files(settings)))
    check_start(problem)
    announce(work)
    log = ((lambda text: print(f"{PROG}: {text}", file=sys.stderr, flush=True))
           if sys.stderr.isatty() else None)
    result = codesign_problem(problem, jobs=args.jobs, log=log)
    summary = dict(result.to_dict(), problem_file=problem.source,
                   units={"stiffness": "N m/rad", "lengths": "m", "value": result.unit,
                          "time_s": "s"})
    print(json.dumps(jsonable(summary), allow_nan=False) if args.json
          else format_codesign(summary))

    def write(directory: Path) -> list[Path]:
        files = [write_json(directory / "codesign.json", summary)]
        fig = codesign_figure(result)
        files += [save_figure(fig, directory / f"codesign.{ext}") for ext in ("png", "pdf")]
        if result.result is not None and result.robot is not None:
            gait = dict(result.result.summary(), problem_file=problem.source,
                        problem=chosen_problem_dict(problem, result.robot))
            files += write_outputs(result.result, result.robot, directory, gait)
        return files
    files = [] if out is None else write_out(out, write, args.force)
    return finish(args, files, result.success, f"co-design failed: {result.message}")
