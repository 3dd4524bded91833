"""The calibration command: fit."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from ocp_crawl.cli.app import register
from ocp_crawl.cli.common import (announce, check_work, finish, force_arg, integer, jobs_type,
                                  out_dir, prepare_out, work_arg, write_out)
from ocp_crawl.model.pressure import PRESSURE_FORMS
from ocp_crawl.problem import load_problem
from ocp_crawl.problem.work import fit_work

#: most least-squares evaluations (each runs every measurement's simulation)
MAX_NFEV = 10000
nfev_type = integer("--max-nfev", 1, " (evaluations of all rows)", high=MAX_NFEV,
                    why="each evaluation simulates every row; more is a runaway, not a fit")
starts_type = integer("--starts", 0, " (points of the sample)", high=MAX_NFEV,
                      why="each point simulates every row; more is a runaway, not a fit")


def _fit_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("problem", metavar="PROBLEM.toml",
                   help="problem file: robot, gait, gravity, solver options")
    p.add_argument("data", metavar="DATA.csv", nargs="+",
                   help="measurement files (docs/guide/calibration.md): e.g. 'psi [deg],S "
                        "[mm],sigma_S [mm]'")
    p.add_argument("--param", dest="params", action="append", default=[], metavar="NAME",
                   required=True,
                   help="a parameter to fit, named by its problem key (robot.k, robot.mu, "
                        "robot.mu1, gait.gamma_deg, ...; a chain's array entry, "
                        "robot.stiffness[1]) or "
                        "pressure.a1/a2/b1/b2/phi_rest_deg/amplitude_bar (repeatable)")
    p.add_argument("--start", action="append", default=[], metavar="NAME=VALUE",
                   help="start value of a fitted parameter (default: the problem's value; for "
                        "pressure.* its [pressure] value, else Table I and the form's)")
    p.add_argument("--bounds", action="append", default=[], metavar="NAME=LOW:HIGH",
                   help="bounds of a fitted parameter (default: start +- 45 deg for angles, "
                        "[start/10, 10 start] otherwise)")
    p.add_argument("--pressure", action="append", default=[], metavar="NAME=VALUE",
                   help="a pressure constant held fixed (a1, a2, b1, b2 [rad/bar^2, rad/bar], "
                        "phi_rest_deg [deg], amplitude_bar [bar]; default the problem's [pressure] "
                        "values, else Table I and the constants of --form)")
    p.add_argument("--form", choices=PRESSURE_FORMS,
                   help="pressure input form (default: the problem's [pressure] form, else "
                        "'paper'): 'paper', the paper's form p0 + A_p sin(2 pi t +- psi/2), p0 the "
                        "nominal pressure, A_p 0.4 bar, rest angle 180 deg; 'raised', the raised "
                        "sine from 0 to the peak p0 with the stored fitted rest angle")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key of the problem (repeatable)")
    p.add_argument("--relative-sigma", action="store_true",
                   help="the sigmas are relative weights: scale the covariance by chi2/dof "
                        "(default: they are standard uncertainties)")
    p.add_argument("--starts", type=starts_type, default=0, metavar="N",
                   help="evaluate N Latin hypercube points of the bounds first and start the "
                        "search at the best of them and the start values (default 0: at the "
                        "start values); for a chi2 that is flat or jumps near the start, as at "
                        "a tie of the feet's friction limits")
    p.add_argument("--max-nfev", type=nfev_type, default=100, metavar="N",
                   help="most least-squares evaluations (default 100)")
    p.add_argument("--jobs", type=jobs_type, default=1, metavar="N",
                   help="worker processes simulating the rows (default 1; a row takes ~20 ms)")
    p.add_argument("--out", metavar="DIR", type=out_dir,
                   help="directory for fitted_problem.toml, fit.json, residuals.csv, fit.png "
                        "(default: ./fit_<problem stem>)")
    p.add_argument("--no-figure", action="store_true", help="do not draw fit.png")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object on stdout instead of the report")
    force_arg(p)
    work_arg(p)


@register("fit",
          "calibrate parameters (k, friction, pressure map, ...) to measurements by weighted least "
          "squares",
          _fit_args)
def cmd_fit(args: argparse.Namespace) -> int:
    # scipy and matplotlib are imported when the command runs, not when the parser is built
    # (start-up time)
    from ocp_crawl.fit import checks, solve
    from ocp_crawl.fit.data import read_measurements
    from ocp_crawl.fit.params import fixed_pressure, resolve_parameters
    from ocp_crawl.fit.report import FIT_FILES, fit_dict, fit_report, write_fit

    problem = load_problem(args.problem, args.overrides)
    params = resolve_parameters(problem, args.params, args.start, args.bounds, args.form)
    pressure = fixed_pressure(args.pressure)
    datasets = [read_measurements(path) for path in args.data]
    # the work first: the rows' checks build a problem per row
    work = check_work(args, fit_work(problem, sum(len(d.y) for d in datasets), args.max_nfev,
                                     len(params), args.jobs, args.starts))
    checks.check_inputs(problem, datasets, params, pressure, args.form)   # before --out is made
    names = [v for k, v in FIT_FILES.items() if k != "figure" or not args.no_figure]
    out = prepare_out(args.out or f"fit_{Path(args.problem).stem}", names, args.force, staged=True)
    announce(work)
    result = solve.fit_measurements(problem, datasets, params, pressure=pressure,
                                    absolute_sigma=not args.relative_sigma, max_nfev=args.max_nfev,
                                    starts=args.starts,
                                    jobs=args.jobs, form=args.form)
    files = write_out(out, lambda d: write_fit(result, d, figure=not args.no_figure), args.force)
    if args.json:
        print(json.dumps(dict(fit_dict(result), written=[str(f) for f in files]), allow_nan=False))
    else:
        print(fit_report(result))
    return finish(args, files, result.success, f"fit failed: {result.message}")
