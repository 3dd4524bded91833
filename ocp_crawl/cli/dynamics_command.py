"""The command ``dynamics``: S, W+ and CoT+ of a gait against its period, in MuJoCo."""
from __future__ import annotations

import argparse
import json

from ocp_crawl.cli.app import BadInput, register
from ocp_crawl.cli.common import (announce, check_work, finish, force_arg, out_dir, prepare_out,
                                  real, work_arg, write_out)
from ocp_crawl.io.files import jsonable
from ocp_crawl.problem import load_problem
from ocp_crawl.problem.work import dynamics_work

#: most periods of one scan (each a MuJoCo run of a few cycles)
MAX_PERIODS = 12
#: the files written into --out
FILES = ("dynamics.csv", "dynamics.png")


def _dynamics_args(p: argparse.ArgumentParser) -> None:
    from ocp_crawl.studies.dynamics import DEFAULT_PERIODS

    p.add_argument("problem", metavar="PROBLEM.toml", help="problem file (torque drive, physical "
                   "gravity)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key, e.g. --set simulation.timestep=2.5e-4 (repeatable)")
    p.add_argument("--periods", nargs="+", type=real("--periods", 0.0, 1e4), metavar="T",
                   default=list(DEFAULT_PERIODS), help="periods of one cycle [s] (default "
                   f"{' '.join(format(t, 'g') for t in DEFAULT_PERIODS)}; at most {MAX_PERIODS})")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    p.add_argument("--out", metavar="DIR", type=out_dir,
                   help=f"write {' and '.join(FILES)} (S, W+, CoT+ against frequency) to DIR")
    force_arg(p)
    work_arg(p)


@register("dynamics", "is it still quasistatic? S, W+ and CoT+ against the period, in MuJoCo",
          _dynamics_args)
def cmd_dynamics(args: argparse.Namespace) -> int:
    from ocp_crawl.studies.dynamics import dynamics_scan, plot_dynamics

    problem = load_problem(args.problem, ["simulation.solver=mujoco", *args.overrides])
    if len(args.periods) > MAX_PERIODS:
        raise BadInput(f"--periods: {len(args.periods)} periods given, at most {MAX_PERIODS} (one "
                       "MuJoCo run each)")
    work = check_work(args, dynamics_work(problem, sorted(set(args.periods))))
    out = None if args.out is None else prepare_out(args.out, FILES, args.force, staged=True)
    announce(work)
    try:
        scan = dynamics_scan(problem, sorted(set(args.periods)))
    except ValueError as exc:
        raise BadInput(str(exc)) from None

    def write(d):
        return [scan.write_csv(d / FILES[0]), plot_dynamics(scan, d / FILES[1])]

    files = [] if out is None else write_out(out, write, args.force)
    if args.json:
        print(json.dumps(jsonable(dict(scan.summary(), files=[str(f) for f in files])),
                         allow_nan=False))
    else:
        print(scan.table())
    failed = [f"T = {t:g} s: {m}" for t, s, m in zip(scan.periods, scan.statuses, scan.messages)
              if s != "success"]
    return finish(args, files, not failed, "; ".join(failed))
