"""The optimize command: the OCP of a problem file, its summary, the convergence table over N."""
from __future__ import annotations

import argparse
import contextlib
import json
import math
import sys
from dataclasses import replace
from pathlib import Path

from ocp_crawl.cli.app import PROG, BadInput, register
from ocp_crawl.cli.common import (announce, check_work, finish, force_arg, integer, jobs_type,
                                  optional_out, out_dir, work_arg, write_out)
from ocp_crawl.cli.run_commands import check_start
from ocp_crawl.io import units
from ocp_crawl.io.files import jsonable
from ocp_crawl.ocp.asymmetry import asymmetry_text
from ocp_crawl.ocp.dynamic_margin import margin_text
from ocp_crawl.ocp.limits import NODES_BOUNDS
from ocp_crawl.problem import (format_value, load_problem, ocp_settings, optimize_problem,
                               problem_from_dict)
from ocp_crawl.problem.overrides import read_toml
from ocp_crawl.problem.run import check_start_robot
from ocp_crawl.problem.work import optimize_work


def _optimize_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("problem", metavar="PROBLEM.toml",
                   help="problem file with an [ocp] section (see docs/guide/optimal_gaits.md)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key, e.g. --set ocp.nodes=200 (repeatable)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object on stdout instead of the summary")
    p.add_argument("--nodes", nargs="+", metavar="N",
                   type=integer("--nodes", NODES_BOUNDS[0], high=NODES_BOUNDS[1]),
                   help="numbers of nodes (overrides ocp.nodes); up to 6, strictly increasing "
                        "(e.g. --nodes 50 100 200 400): solve at each, warm-started from the "
                        "previous optimum, replay each and print the convergence table "
                        "(objective, change, observed order)")
    p.add_argument("--out", metavar="DIR", type=out_dir,
                   help="write torques.csv, optimal_gait.toml (replays the optimum with simulate; "
                        "over a friction set: also optimal_gait_mu1_mu2_<ratio>.toml per "
                        "scenario), arrays.npz, summary.json and figures to DIR (with several "
                        "--nodes: of the finest N, and convergence.json)")
    p.add_argument("--progress", action="store_true",
                   help="show the homotopy's progress (stage, IPOPT iterations) on stderr even "
                        "when stderr is not a terminal (it is shown on a terminal anyway)")
    p.add_argument("--jobs", type=jobs_type, metavar="N",
                   help="worker processes of the baselines' search (default: the CPUs available; "
                        "the result does not depend on it)")
    p.add_argument("--start", metavar="GAIT.toml",
                   help="start the OCP from this gait instead of the harmonic baseline: a problem "
                        "file of a torque-drive gait with [gait] period, e.g. a previous run's "
                        "optimal_gait.toml")
    p.add_argument("--verbose", action="store_true",
                   help="IPOPT's log of every solve on stdout (not with --json; a log file "
                        "instead: [ocp.ipopt] output_file, file_print_level)")
    force_arg(p)
    work_arg(p)


#: most numbers of nodes of one ``optimize --nodes`` (each is a full solve, warm-started)
MAX_NODE_COUNTS = 6
#: the files ocp_crawl.viz.ocp.write_outputs writes (over a friction set: also one problem file per
#: scenario, ocp_crawl.viz.ocp.scenario_files)
OCP_FILES = ("torques.csv", "optimal_gait.toml", "arrays.npz", "summary.json", "optimal_gait.png",
             "optimal_gait.pdf")


def _each(value, text) -> str:
    """One number, or one per scenario (a list), as text; "-" when missing."""
    if isinstance(value, list):
        return ", ".join(text(v) for v in value) if value else units.MISSING
    return text(value)


def _ocp_replay(s: dict, name: str, text) -> str:
    """The OCP's and the replay's ``name`` (``S``, ``v``, ``W_plus``, ``CoT_plus``): "OCP x, replay
    y", or per friction scenario of a friction set, labelled with its ratio: "mu1/mu2 = 0.9: OCP x,
    replay y; ..."."""
    ocp, replay = s.get(f"{name}_ocp"), s.get(f"{name}_replay")
    if not s.get("scenarios"):
        return f"OCP {_each(ocp, text)}, replay {_each(replay, text)}"
    return "; ".join(f"{_scenario(row)}: OCP {text(row[f'{name}_ocp'])}, "
                     f"replay {text(row[f'{name}_replay'])}"
                     for row in s["scenarios"])


def _scenario(row: dict) -> str:
    """A friction scenario in text: "mu1/mu2 = 0.9", with a level other than the robot's ", level
    0.5"."""
    ratio, _, level = row["label"].partition("_level_")
    if ratio == "own":
        return f"friction level {level}"
    return f"mu1/mu2 = {ratio}" + (f", level {level}" if level else "")


def _value(objective: str, v, digits: int = 3, unit: str = "-") -> str:
    """An objective value with its unit: a speed [m/s] in mm/s, or CoT+ [-] (or another
    objective in its ``unit``) to ``digits + 1`` significant digits."""
    if objective in ("max_speed", "robust_speed"):
        return units.speed(v, digits)
    text = units.significant(v, digits + 1)
    return text if unit == "-" or text == units.MISSING else f"{text} {unit}"


def _gain(s: dict) -> str:
    """The gain by replay over the best baseline, and whether it is significant (beyond
    replay_tol)."""
    if s.get("gain") is None:
        return "-"
    verdict = "significant" if s.get("gain_significant") else "no significant gain"
    best = (s.get("best_baseline") or {}).get("shape", "-")
    tol = units.ratio(s.get("replay_tol"))
    return f"{units.ratio(s['gain'])} over the best ({best}) ({verdict}: replay_tol {tol})"


def _member(h: dict) -> str:
    """A waveform family's best member: its angles [deg], a pulse's rise and duty, its period (a
    chain's travelling wave: its amplitude and phase lead, the envelope's centres)."""
    deg = lambda key: units.significant(h.get(key))  # noqa: E731
    if "A_deg" in h:
        centres = "/".join(units.significant(g) for g in h.get("gamma_joints_deg") or [])
        return (f"travelling wave A {deg('A_deg')} psi {deg('psi_deg')} deg (centres {centres} "
                f"deg), T {units.seconds(h.get('T'))}")
    pulse = ""
    # at rise 0.5 no level is held: a triangle wave, whatever the duty
    if h.get("shape") == "pulse":
        rise, duty = units.significant(h.get("rise")), units.significant(h.get("duty"))
        pulse = (", rise 0.5 cycles (a triangle wave)" if h.get("rise", 0.0) >= 0.5 - 1e-12 else
                 f", rise {rise} cycles, duty {duty}")
    return (f"gamma {deg('gamma1_deg')}/{deg('gamma2_deg')} A {deg('A1_deg')}/{deg('A2_deg')} psi "
            f"{deg('psi_deg')} deg{pulse}, T {units.seconds(h.get('T'))}")


def _baseline_lines(s: dict) -> list[str]:
    """One line per waveform family: its best member's value, the optimum's gain over it, the
    member."""
    obj, rows, gains = s["objective"], s.get("baselines") or [], s.get("gains") or {}
    if not rows:
        h = s.get("best_harmonic")
        rows = [dict(h, shape="harmonic")] if h else []
    out = []
    for row in rows:
        if row.get("value") is None and not row.get("feasible"):
            text = ("no member simulates" if "T" not in row else
                    f"none feasible (nearest: {_member(row)})")
        else:
            gain = units.ratio(gains.get(row["shape"]))
            value = _value(obj, row['value'], unit=s.get("objective_unit", "-"))
            text = f"{value}, gain {gain}: {_member(row)}"
        out.append(f"  {row['shape']:<9} {text}")
    return out


def _pair(value, text) -> str:
    """The peaks of each joint (or foot), or one such list per friction scenario ("a, b; c, d");
    "-" if missing."""
    if not value:
        return units.MISSING
    pairs = value if isinstance(value[0], list) else [value]
    return "; ".join(", ".join(text(v) for v in pair) for pair in pairs)


def _peaks(s: dict) -> str:
    """The replay's peak actual joint rates [deg/s] and foot sliding speeds [mm/s], the bound
    max_joint_rate_deg_s if set, and the harmonic baseline's peaks."""
    deg = lambda v: units.fixed(v, 1)  # noqa: E731
    mm = lambda v: units.fixed(v, 1, 1e3)  # noqa: E731
    bound = s.get("max_joint_rate_deg_s")
    limit = f" (bound {units.significant(bound)})" if bound is not None else ""
    rates = _pair(s.get('peak_joint_rate_deg_s'), deg)
    return (f"joint rate {rates} deg/s{limit}, foot slip speed "
            f"{_pair(s.get('peak_slip_speed_m_s'), mm)} mm/s; harmonic baseline "
            f"{_pair(s.get('harmonic_peak_joint_rate_deg_s'), deg)} deg/s, "
            f"{_pair(s.get('harmonic_peak_slip_speed_m_s'), mm)} mm/s")


def _starts_text(s: dict) -> str | None:
    """Several starts: "4 starts, 3 converged, replayed objective a to b"; None for one."""
    starts, converged, obj = s.get("starts") or [], s.get("starts_converged") or 0, s["objective"]
    if len(starts) < 2:
        return None
    unit = s.get("objective_unit", "-")
    low, high = (_value(obj, s.get(f"objective_value_replay_{e}"), unit=unit)
                 for e in ("min", "max"))
    spread = f"replayed objective {low}" + ("" if low == high else f" to {high}")
    return f"{len(starts)} starts, " + (f"{converged} converged, {spread}" if converged else
                                        "none converged")


def _start_lines(s: dict) -> list[str]:
    """Several starts: one line each, its label, status, replayed objective and IPOPT iterations
    (which start gave the optimum, and how far the others ended from it); none for one."""
    starts, obj, unit = s.get("starts") or [], s["objective"], s.get("objective_unit", "-")
    if len(starts) < 2:
        return []
    return [f"  {r.get('label', '-')}: {r.get('status', '-')}, replay "
            f"{_value(obj, r.get('value_replay'), unit=unit)}, {r.get('iterations', 0)} IPOPT "
            "iterations" for r in starts]


def format_optimize(s: dict) -> str:
    """Readable summary of an optimize run (``OCPResult.summary()`` in SI units) with units: S in
    mm, speeds in mm/s, W+ in mJ, CoT+ to 3 significant digits, times in s; "-" for what was not
    computed (e.g. a failed replay)."""
    obj, unit = s["objective"], s.get("objective_unit", "-")
    spread = _starts_text(s)
    lines = [
        f"status      {s['status']}: {s['message']}",
        f"objective   {obj} ({s['nodes']} nodes, {s['parametrization']} torques), period T "
        f"{units.seconds(s.get('T_ocp'))}",
        f"S           {_ocp_replay(s, 'S', units.distance)}",
        f"speed       {_ocp_replay(s, 'v', units.speed)}",
        f"W+          {_ocp_replay(s, 'W_plus', units.work)}",
        f"CoT+        {_ocp_replay(s, 'CoT_plus', units.cot)}",
        f"value       OCP {_value(obj, s['objective_value_ocp'], unit=unit)}, "
        f"replay {_value(obj, s['objective_value_replay'], unit=unit)} "
        f"(relative difference {units.ratio(s['rel_diff_replay'])})",
        f"baselines   best member of each waveform family at its shortest period; gain of the "
        f"optimum by replay {_gain(s)}",
        *_baseline_lines(s),
        f"peaks       {_peaks(s)}",
        *[f"requirement {r['text']}: "
          f"replay {', '.join(units.significant(v, 6) for v in r['replay'])}"
          for r in s.get("requirements") or []],
        *([f"starts      {spread}"] if spread else []),
        *_start_lines(s),
        *margin_text(s.get("dynamic_margin")),
        *asymmetry_text(s.get("friction_asymmetry")),
        f"residuals   complementarity {units.scientific(s['complementarity_residual'])}, "
        f"periodicity {units.scientific(s['periodicity_residual'])}",
        f"time        {units.seconds(s['solve_time_s'])}",
    ]
    return "\n".join(lines)


#: the convergence table ``optimize --nodes N1 N2 ... --out DIR`` writes next to the finest
#: optimum's files
CONVERGENCE_FILE = "convergence.json"


def format_convergence(table: dict) -> str:
    """The convergence table (``ConvergenceTable.to_dict()``, SI units) as text: per N the status,
    the period, the OCP's and the replay's objective (speeds in mm/s, CoT+ to 6 significant digits),
    their relative difference, the change of the replayed objective from the previous N and the
    observed order p."""
    obj, unit = table["objective"], table.get("unit", "-")
    own = obj not in ("max_speed", "robust_speed", "min_cot") and unit != "-"
    in_unit = f", in {unit}" if own else ""  # a user objective's unit, once (speeds say mm/s)
    head = (f"{'N':>5}  {'status':<16} {'T':>9}  {'OCP':>14}  {'replay':>14}  {'diff':>11}  "
            f"{'change':>14}  {'change':>10}  {'p':>6}  {'time':>7}")
    lines = [f"convergence in N: {obj}{in_unit} (T: period; OCP and replay: the objective; diff: "
             f"|OCP - replay| / |replay|; change: replay minus the previous N's, absolute and "
             f"relative; p: observed order)", head]
    for r in table["rows"]:
        lines.append(f"{r['nodes']:>5}  {r['status']:<16} {units.seconds(r['T']):>9}  "
                     f"{_value(obj, r['value_ocp'], 5):>14}  "
                     f"{_value(obj, r['value_replay'], 5):>14}  "
                     f"{units.ratio(r['rel_diff_replay']):>11}  "
                     f"{_value(obj, r['change'], 5):>14}  "
                     f"{units.ratio(r['rel_change']):>10}  {units.fixed(r['order'], 2):>6}  "
                     f"{units.seconds(r['solve_time_s']):>7}")
    return "\n".join(lines)


def _progress_bar(wanted: bool):
    """A context manager showing the homotopy's IPOPT calls on stderr (tqdm: stage, sigma, IPOPT
    iterations), or doing nothing unless ``wanted``."""
    if not wanted:
        return contextlib.nullcontext()
    from tqdm import tqdm

    from ocp_crawl.nlp.homotopy import observe

    @contextlib.contextmanager
    def shown():
        # no monitor thread: the workers fork (mp_context)
        interval, tqdm.monitor_interval = tqdm.monitor_interval, 0
        try:
            bar = tqdm(desc="optimize", unit=" IPOPT it", file=sys.stderr, dynamic_ncols=True)
        finally:
            tqdm.monitor_interval = interval
        with bar:
            bar.set_postfix_str("best gait of each waveform family (the harmonic one: the start)")
            calls = []

            def update(stage) -> None:
                calls.append(stage)
                sigma = "" if math.isnan(stage.sigma) else f" sigma {units.scientific(stage.sigma)}"
                bar.set_postfix_str(f"{stage.kind} stage {len(calls)}{sigma}, "
                                    f"{stage.return_status}", refresh=False)
                bar.update(stage.iterations)
            with observe(update):
                yield
    return shown()


@register("optimize", "design an optimal periodic torque profile (OCP) and prove it by replay",
          _optimize_args)
def cmd_optimize(args: argparse.Namespace) -> int:
    from ocp_crawl.viz.ocp import scenario_files, write_outputs as write_ocp_outputs

    if args.nodes and len(args.nodes) > MAX_NODE_COUNTS:
        raise BadInput(f"--nodes: {len(args.nodes)} numbers of nodes given, at most "
                       f"{MAX_NODE_COUNTS}: each is a full solve (minutes at N = 400); e.g. "
                       "--nodes 50 100 200 400")
    if args.nodes and any(text.split("=", 1)[0].strip() == "ocp.nodes" for text in args.overrides):
        raise BadInput(f"--nodes {' '.join(map(str, args.nodes))} and --set ocp.nodes both set the "
                       f"nodes: give one")
    # the first N of --nodes is the problem's ocp.nodes (so the reports name the N solved)
    data = read_toml(args.problem)   # once: the file may be a named pipe
    if "ocp" not in data:
        raise BadInput(f"{args.problem}: no [ocp] section: optimize needs one (objective, nodes, "
                       "...; see docs/guide/optimal_gaits.md and problems/ocp_max_speed.toml)")
    problem = problem_from_dict(data, source=str(args.problem),
                                overrides=[*args.overrides,
                                           *([f"ocp.nodes={args.nodes[0]}"] if args.nodes else [])])
    if problem.drive != "torque":
        raise BadInput(f"{problem.source}: optimize designs joint torques: it needs [gait] drive = "
                       f"\"torque\", got {format_value(problem.drive)}")
    settings = ocp_settings(problem)
    if args.verbose and args.json:
        raise BadInput("--verbose with --json: IPOPT's log would mix into the JSON on stdout; give "
                       "one, or write the log to a file with [ocp.ipopt] output_file and "
                       "file_print_level")
    settings = replace(settings, verbose=bool(args.verbose))
    if args.start and args.nodes and len(args.nodes) > 1:
        raise BadInput(f"--start with --nodes {' '.join(map(str, args.nodes))}: the convergence "
                       "run starts each N from the previous optimum; give --start with one N")
    nodes = args.nodes or [settings.nodes]
    if any(b <= a for a, b in zip(nodes, nodes[1:])):
        raise BadInput(f"--nodes {' '.join(str(n) for n in nodes)} is invalid: the numbers of "
                       "nodes must increase strictly (each N is warm-started from the "
                       "previous one)")
    settings = replace(settings, nodes=nodes[0])
    work = check_work(args, optimize_work(problem, settings, nodes))
    if len(nodes) > 1:
        return _optimize_nodes(args, problem, settings, nodes, work)
    out = optional_out(args, (*OCP_FILES, *scenario_files(settings)))
    check_start(problem)
    start = None if args.start is None else load_problem(args.start)
    if start is not None:
        check_start_robot(problem, start)
    if start is not None and (start.drive != "torque" or start.period is None):
        raise BadInput(f"--start {args.start}: needs a torque-drive gait with a [gait] period [s] "
                       f"(as the optimal_gait.toml that optimize --out writes); got drive "
                       f"{format_value(start.drive)}, period {format_value(start.period)}")
    announce(work)
    with _progress_bar(args.progress or sys.stderr.isatty()):
        result = optimize_problem(problem, jobs=args.jobs, start=start, verbose=bool(args.verbose))
    data = _optimize_data(result, problem)
    if args.json:
        print(json.dumps(data, allow_nan=False))
    else:
        print(format_optimize(data))
    files = [] if out is None else write_out(
        out, lambda d: write_ocp_outputs(result, problem.robot, d, data), args.force)
    return finish(args, files, result.success, f"optimisation failed: {result.message}")


#: the peaks of optimize's JSON summary (their units in their names, and in units.UNITS)
PEAK_KEYS = ("peak_joint_rate_deg_s", "peak_slip_speed_m_s", "harmonic_peak_joint_rate_deg_s",
             "harmonic_peak_slip_speed_m_s")


def _optimize_data(result, problem) -> dict:
    """The JSON summary of an optimize result, with the problem and the units of its numbers."""
    return jsonable(dict(result.summary(), problem_file=problem.source, problem=problem.to_dict(),
                         units=dict({k: units.UNITS[k]
                                     for k in ("S", "W_plus", "CoT_plus", "tau", "solve_time_s")},
                                    T_ocp=units.UNITS["T"], v_ocp=units.UNITS["v"],
                                    v_replay=units.UNITS["v"],
                                    **{k: units.UNITS[k] for k in PEAK_KEYS})))


def _optimize_nodes(args: argparse.Namespace, problem, settings, nodes: list[int], work) -> int:
    """``optimize --nodes N1 N2 ...``: the convergence table (and the finest optimum's summary and
    files)."""
    from ocp_crawl.io.files import write_json
    from ocp_crawl.ocp.convergence import converge_in_nodes
    from ocp_crawl.viz.ocp import scenario_files, write_outputs as write_ocp_outputs

    out = optional_out(args, (*OCP_FILES, *scenario_files(settings), CONVERGENCE_FILE))
    check_start(problem)
    announce(work)
    shown = args.progress or sys.stderr.isatty()
    log = (lambda text: print(f"{PROG}: {text}", file=sys.stderr, flush=True)) if shown else None
    with _progress_bar(shown):
        table = converge_in_nodes(problem.robot, problem.gravity, settings, nodes, log=log,
                                  jobs=args.jobs)
    finest = table.rows[-1].result
    data = _optimize_data(finest, problem)
    conv = table.to_dict()
    if args.json:
        print(json.dumps(jsonable(dict(conv, finest=data, problem_file=problem.source)),
                         allow_nan=False))
    else:
        print(format_convergence(conv) + f"\n\nfinest N = {nodes[-1]}:\n" + format_optimize(data))
    def write(directory: Path) -> list[Path]:
        return [*write_ocp_outputs(finest, problem.robot, directory, data),
                write_json(directory / CONVERGENCE_FILE, dict(conv, problem_file=problem.source))]
    files = [] if out is None else write_out(out, write, args.force)
    bad = [r for r in table.rows if r.status.label != "success"]
    failure = "" if not bad else (f"optimisation not confirmed at N = "
                                  f"{', '.join(str(r.nodes) for r in bad)}: "
                                  f"{bad[0].message}")
    return finish(args, files, table.success, failure)
