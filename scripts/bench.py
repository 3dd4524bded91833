"""Benchmarks (run by hand; figures go into the closing notes, never into timed tests).

    python scripts/bench.py                # all benchmarks (several minutes)
    python scripts/bench.py hybrid         # paper gait and one steady cycle, CPU, against an old
                                             commit
    python scripts/bench.py hybrid --old 3a581df --repeat 20
    python scripts/bench.py hybrid_accuracy  # the paper gait against a refined run, both gravities
    python scripts/bench.py mpcc sweep ocp # MPCC step/cycle, the 37 x 31 map, the OCP solves
    python scripts/bench.py ocp_kernel --repeat 3  # OCP solves: the expanded SX NLP against the
                                                     compiled kernel's map
    python scripts/bench.py ocp_files --repeat 3   # the three OCP problem files whole, and the
                                                     N = 50..400 run (--old REV: against REV)
    python scripts/bench.py ocp_paths --repeat 2   # robust_speed and min_cot on each solver path
                                                     (endgame, ...)
    python scripts/bench.py work --repeat 3        # the work estimates against the runs they bound
    python scripts/bench.py pressure --old REV --repeat 5  # pressure-driven gaits against REV
    python scripts/bench.py --repeat 50

Each benchmark reports the median wall time over repeated calls after one warm-up call (the
warm-up builds or loads the compiled functions, which happens once per process); ``hybrid`` and
``pressure`` report CPU time (min and median) of this tree and of an older commit (``--old``,
exported with ``git archive``) measured in alternating subprocesses of the same run, and their
ratio.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time


def _min_median(fn, repeat: int) -> tuple[float, float, object]:
    """(min, median) seconds of ``repeat`` timed calls after one warm-up call (compiled functions
    are built or loaded once per process), and its output."""
    out = fn()
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), statistics.median(times), out


def _interleaved(runs: dict, repeat: int) -> dict:
    """min and median [ms], status and S [mm] of each simulation in ``runs`` (name: call), timed
    in ``repeat`` rounds that call each once in turn after one warm-up round: the machine's speed
    drifts over seconds, and interleaving gives every run the same share of it."""
    results = {name: run() for name, run in runs.items()}
    times: dict = {name: [] for name in runs}
    for _ in range(repeat):
        for name, run in runs.items():
            t = time.perf_counter()
            results[name] = run()
            times[name].append(time.perf_counter() - t)
    return {name: {"min_ms": round(1e3 * min(times[name]), 2),
                   "median_ms": round(1e3 * statistics.median(times[name]), 2),
                   "status": res.status.label, "S_mm": round(1e3 * res.S, 6)}
            for name, res in results.items()}


def _median_time(fn, repeat: int) -> tuple[float, object]:
    _, median, out = _min_median(fn, repeat)
    return median, out


#: commit whose event-driven stepper ``hybrid`` times against the working tree
OLD_COMMIT = "3a581df"


def hybrid_cpu(repeat: int) -> dict:
    """CPU times [ms] (time.process_time) of the warm paper gait (released start + confirming cycle,
    output, checks: one ``simulate_torque``) and of one steady cycle (one more cycle of the stepper,
    events and checks, from the periodic state), after a warm-up run; lists of ``repeat`` samples
    each.  Uses only names that the old code has too (it runs in a subprocess on an exported old
    tree, see :func:`bench_hybrid`)."""
    from ocp_crawl import Harmonic, Model, ReferenceTorque, Robot, simulate_torque
    from ocp_crawl.sim.event import HybridStepper

    model = Model(Robot.paper(), gravity="paper")
    torque = ReferenceTorque(Harmonic.from_degrees(90, 30, 45), model.robot.k)
    res = simulate_torque(model, torque)
    gait, cycle = [], []
    for _ in range(repeat):
        t = time.process_time()
        simulate_torque(model, torque)
        gait.append(1e3 * (time.process_time() - t))
    st = HybridStepper(model, torque)
    run = st._start_run(st.initial_state(0.0))
    st._run_cycles(run)
    for _ in range(repeat):
        t = time.process_time()
        st._advance_cycle(run)
        cycle.append(1e3 * (time.process_time() - t))
        run.cycle += 1
        run.events_in_cycle = 0
    return {"gait_ms": gait, "cycle_ms": cycle, "S": res.S, "W_plus": res.W_plus, "nfev": res.nfev,
            "events": [e.t for e in res.events]}


def _old_tree(commit: str) -> str:
    """The package ``ocp_crawl`` of ``commit`` exported (git archive) into a temporary directory;
    its path."""
    import subprocess
    import tempfile
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    tmp = tempfile.mkdtemp(prefix="ocp_crawl_old_")
    archive = subprocess.run(["git", "-C", str(root), "archive", commit, "ocp_crawl"],
                             capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", tmp], input=archive, check=True)
    return tmp


def _worker(tree: str, repeat: int, kind: str = "hybrid") -> dict:
    """:func:`hybrid_cpu` (``kind`` "hybrid") or :func:`pressure_cpu` ("pressure") in a fresh
    process with ``tree`` first on the path."""
    import json
    import os
    import subprocess

    env = dict(os.environ, PYTHONPATH=tree)
    out = subprocess.run([sys.executable, __file__, f"--{kind}-worker", str(repeat)], env=env,
                         capture_output=True, text=True, check=True).stdout
    return json.loads(out.splitlines()[-1])


def _against_old(kind: str, repeat: int, old: str, rounds: int) -> dict:
    """The worker ``kind`` (:func:`_worker`) on this tree and on commit ``old`` exported, in
    ``rounds`` alternating pairs of subprocesses: {"new": [outputs], "old": [outputs]}."""
    import shutil
    from pathlib import Path

    new_tree = str(Path(__file__).resolve().parent.parent)
    old_tree = _old_tree(old)
    samples: dict = {"new": [], "old": []}
    try:
        for _ in range(rounds):
            samples["new"].append(_worker(new_tree, repeat, kind))
            samples["old"].append(_worker(old_tree, repeat, kind))
    finally:
        shutil.rmtree(old_tree, ignore_errors=True)
    return samples


def _timing_stats(samples: dict, key: str, prefix: str, digits: int) -> dict:
    """Min and median of the samples ``key`` [ms] of each code (``{prefix}new_ms``,
    ``{prefix}old_ms``) and the ratios old/new (``{prefix}ratio_old_over_new_min``, ...)."""
    stats = {code: {"min": min(v), "median": statistics.median(v)} for code, v in
             ((c, [x for s in samples[c] for x in s[key]]) for c in ("new", "old"))}
    out = {f"{prefix}{code}_ms": {k: round(v, digits) for k, v in st.items()}
           for code, st in stats.items()}
    for stat in ("min", "median"):
        out[f"{prefix}ratio_old_over_new_{stat}"] = round(stats["old"][stat] / stats["new"][stat],
                                                          2)
    return out


#: the pressure-driven gaits of :func:`pressure_cpu`: (p0 [bar], psi [deg], amplitude [bar] or
#: None for the raised sine)
PRESSURE_CASES = [(p0, psi, a) for p0 in (1.2, 1.7) for psi in (20.0, 45.0, 90.0)
                  for a in (None, 0.6)]


def pressure_cpu(repeat: int) -> dict:
    """CPU time [ms] per simulation of the pressure-driven robot (physical gravity, the stored rest
    angle) over :data:`PRESSURE_CASES`, ``repeat`` samples after a warm-up pass, and the S of each
    case.  Uses only names that the old code has too."""
    from ocp_crawl import Model, Robot
    from ocp_crawl.studies.pressure import simulate_pressure

    model = Model(Robot.paper(), "physical")
    runs = [simulate_pressure(model, p0, psi, amplitude_bar=a) for p0, psi, a in PRESSURE_CASES]
    samples = []
    for _ in range(repeat):
        t = time.process_time()
        for p0, psi, a in PRESSURE_CASES:
            simulate_pressure(model, p0, psi, amplitude_bar=a)
        samples.append(1e3 * (time.process_time() - t) / len(PRESSURE_CASES))
    return {"sim_ms": samples, "S": [r.S if r.success else None for r in runs],
            "status": [r.status_name for r in runs]}


#: the commit that ``pressure`` compares against by default (the array form of the pressure inputs;
#: its ``simulate_pressure`` takes ``amplitude_bar``)
PRESSURE_OLD_COMMIT = "1a40791"


def bench_pressure(repeat: int, old: str = PRESSURE_OLD_COMMIT, rounds: int = 2) -> dict:
    """Simulations of the pressure-driven robot (:func:`pressure_cpu`) for the working tree and for
    commit ``old`` in the same run, ``rounds`` alternating pairs of subprocesses: min and median
    [ms] per simulation, their ratio, and the largest relative difference of S."""
    samples = _against_old("pressure", repeat, old, rounds)
    out: dict = {"old_commit": old, **_timing_stats(samples, "sim_ms", "", 2)}
    a, b = samples["new"][0], samples["old"][0]
    out["same_statuses"] = a["status"] == b["status"]
    out["S_max_rel_diff"] = max((abs(x - y) / abs(y) if y else abs(x - y)
                                 for x, y in zip(a["S"], b["S"])
                                 if x is not None and y is not None), default=None)
    return out


def bench_hybrid(repeat: int, old: str = OLD_COMMIT, rounds: int = 3) -> dict:
    """Warm paper gait (Table I robot, gamma 90, A 30, psi 45 deg, torque drive, paper gravity) and
    one steady cycle, CPU time, for the working tree and for commit ``old`` in the same run:
    ``rounds`` alternating pairs of subprocesses of ``repeat`` timed runs each; min and median [ms]
    over all samples, their ratios, and the largest differences of S, W+ and the event phases
    between the two codes."""
    samples = _against_old("hybrid", repeat, old, rounds)
    out = {**_timing_stats(samples, "gait_ms", "gait_", 3),
           **_timing_stats(samples, "cycle_ms", "cycle_", 3)}
    a, b = samples["new"][0], samples["old"][0]
    out["old_commit"] = old
    out["S_abs_diff"] = abs(a["S"] - b["S"])
    out["W_plus_abs_diff"] = abs(a["W_plus"] - b["W_plus"])
    out["event_phase_max_diff"] = max(abs(x - y) for x, y in zip(a["events"], b["events"])) \
        if len(a["events"]) == len(b["events"]) else "event count differs"
    out["nfev_new_old"] = (a["nfev"], b["nfev"])
    out["load_average"] = os.getloadavg()
    return out


def bench_hybrid_accuracy(repeat: int) -> dict:
    """The paper gait (Table I robot, gamma 90, A 30, psi 45 deg, torque drive): median wall time
    and S, W+ against a refined run (max_step 1/512, event_xtol 1e-15, quad_h 1/256), both gravity
    conventions."""
    from ocp_crawl import Harmonic, HybridOptions, Model, ReferenceTorque, Robot, simulate_torque
    from ocp_crawl.model.statics import fast_newton

    out = {}
    for gravity in ("physical", "paper"):
        model = Model(Robot.paper(), gravity=gravity)
        torque = ReferenceTorque(Harmonic.from_degrees(90, 30, 45), model.robot.k)
        med, res = _median_time(lambda: simulate_torque(model, torque), repeat)
        ref = simulate_torque(model, torque,
                              HybridOptions(max_step=1 / 512, event_xtol=1e-15, quad_h=1 / 256))
        out[gravity] = {
            "median_ms": 1e3 * med, "S_m": res.S, "S_rel_diff_vs_refined": abs(res.S / ref.S - 1),
            "W_plus_rel_diff_vs_refined": abs(res.W_plus / ref.W_plus - 1),
            "cycles_run": res.cycles,
            "nfev": res.nfev, "events": len(res.events), "compiled": fast_newton().compiled,
        }
    return out


def bench_prescribed(repeat: int) -> dict:
    from ocp_crawl import Harmonic, Model, Robot
    from ocp_crawl.sim.angles import simulate_angles

    model = Model(Robot.paper())
    med, res = _median_time(lambda: simulate_angles(model, Harmonic.from_degrees(90, 30, 45)),
                            repeat)
    return {"median_ms": 1e3 * med, "S_m": res.S}


def bench_chain(repeat: int) -> dict:
    """The simulators of n-link chains (prescribed angles, torque drive) against the three-link
    ones, in one run: the paper gait at n = 3 through both, and a five-link chain of the same length
    and mass (legs and joints as the paper robot's, the body in three segments of four times the
    stiffness, phases spread over the joints)."""
    import numpy as np

    from ocp_crawl import Harmonic, Model, ReferenceTorque, Robot, simulate
    from ocp_crawl.model import Chain, ChainModel, JointFourier
    from ocp_crawl.sim import ChainReferenceTorque, simulate_chain_angles, simulate_chain_torque
    from ocp_crawl.sim.angles import simulate_angles

    robot = Robot.paper()
    three = Chain.from_robot(robot)
    legs, body = three.lengths[0], three.lengths[1]
    five = Chain(lengths=(legs, body / 3, body / 3, body / 3, legs),
                 masses=(three.masses[0], *(3 * (three.masses[1] / 3,)), three.masses[2]),
                 stiffness=(robot.k, 4 * robot.k, 4 * robot.k, robot.k), mu=three.mu)
    gait5 = JointFourier.harmonic(np.deg2rad([90, 175, 175, 90]), np.deg2rad([30, 3, 3, 30]),
                                  np.deg2rad([22.5, 7.5, -7.5, -22.5]))
    model, m3, m5 = Model(robot), ChainModel(three), ChainModel(five)
    harmonic = Harmonic.from_degrees(90, 30, 45)
    torque3 = ReferenceTorque(harmonic, robot.k)
    torque5 = ChainReferenceTorque(gait5, five)
    runs = {"three_link_angles": lambda: simulate_angles(model, harmonic),
            "chain_n3": lambda: simulate_chain_angles(m3, harmonic),
            "chain_n5": lambda: simulate_chain_angles(m5, gait5),
            "three_link_torque": lambda: simulate(model, torque3),
            "chain_torque_n3": lambda: simulate_chain_torque(m3, torque3),
            "chain_torque_n5": lambda: simulate_chain_torque(m5, torque5)}
    out = _interleaved(runs, repeat)
    for drive, three, chain in (("angles", "three_link_angles", "chain_n"),
                                ("torque", "three_link_torque", "chain_torque_n")):
        base = out[three]["min_ms"]
        for n in (3, 5):
            out[f"{drive}_ratio_n{n}"] = round(out[f"{chain}{n}"]["min_ms"] / base, 2)
    return out


def bench_chain_cycles(repeat: int) -> dict:
    """A cycle of the chain's event-driven solver for n = 3 .. 7 links of equal length (0.123 m and
    0.052 kg in all), the gait shape of ``problems/five_link_chain.toml`` (outer joints 95/90 +-
    20/18 deg, inner ones 175 +- 5 deg, each joint 20 deg behind the previous one): the fastest
    run over its cycles, and per link (the unit cost ``chain_event_cycle`` of
    ``ocp_crawl.problem.work``)."""
    import numpy as np

    from ocp_crawl.model import Chain, ChainModel, JointFourier
    from ocp_crawl.sim import ChainReferenceTorque, simulate_chain_torque

    out: dict = {}
    for n in range(3, 8):
        m = n - 1
        chain = Chain(lengths=(0.123 / n,) * n, masses=(0.052 / n,) * n,
                      stiffness=(0.17, *((0.25,) * (m - 2)), 0.17), mu=(0.35, 0.43))
        mean = np.deg2rad([95.0, *((175.0,) * (m - 2)), 90.0])
        amp = np.deg2rad([20.0, *((5.0,) * (m - 2)), 18.0])
        torque = ChainReferenceTorque(JointFourier.harmonic(mean, amp, -np.deg2rad(20.0)
                                                            * np.arange(m)), chain)
        model = ChainModel(chain)
        low, _, res = _min_median(lambda: simulate_chain_torque(model, torque), repeat)
        cycle = low / max(res.cycles, 1)
        out[f"n{n}"] = {"status": res.status.label, "cycles": res.cycles,
                        "cycle_s": round(cycle, 4), "per_link_s": round(cycle / n, 5)}
    return out


def bench_ocp(repeat: int) -> dict:
    """Periodic-gait OCP on the paper robot: solve time per objective at N = 100 (one solve
    each)."""
    from ocp_crawl import Robot
    from ocp_crawl.ocp import OCPSettings, optimize_gait

    out = {}
    for name, kw in (("max_speed", {}), ("min_cot", {"speed_min": 0.04}), ("robust_speed", {})):
        for nodes in (100,):
            t = time.perf_counter()
            res = optimize_gait(Robot.paper(), "physical",
                                OCPSettings(objective=name, nodes=nodes, **kw))
            out[f"{name}_N{nodes}"] = {
                "wall_s": time.perf_counter() - t, "solve_time_s": res.solve_time_s,
                "status": res.status,
                "value_ocp": res.value_ocp, "value_replay": res.value_replay,
                "rel_diff_replay": res.rel_diff_replay,
                "gain_vs_best_harmonic": res.gain, "stages": len(res.homotopy),
            }
    return out


#: the problem files of ``ocp_kernel`` (beside this script's package, problems/)
KERNEL_PROBLEMS = ("ocp_max_speed",)


def _ocp_run(problem, settings, harm, kernel: str) -> dict:
    """Build the OCP with the step kernel ``kernel`` ("expanded": one SX graph; "compiled": the
    compiled kernel's map in an MX graph) and solve it from the harmonic baseline ``harm``: build
    and solve time, IPOPT's function-evaluation time [s], iterations, optimum."""
    from ocp_crawl.ocp.solve import baseline_gait
    from ocp_crawl.ocp.solver import GaitSolver
    from ocp_crawl.ocp.transcription import GaitOCP

    t = time.perf_counter()
    ocp = GaitOCP(problem.robot, problem.gravity, settings, kernel=kernel)
    build = time.perf_counter() - t
    start = ocp.initial_guess(*baseline_gait(harm, problem.robot, settings))
    x, hist, failed, _ = GaitSolver(ocp).solve(start)
    return {"build_s": build, "ipopt_s": sum(h.time for h in hist),
            "eval_s": sum(h.eval_time for h in hist),
            "iterations": sum(h.iterations for h in hist),
            "status": "ok" if failed is None else failed,
            "value_ocp": ocp.objective(x) if x is not None else float("nan")}


def bench_ocp_kernel(repeat: int) -> dict:
    """The OCP problem files at their default N, one start from the harmonic baseline: build time,
    IPOPT's time and its function-evaluation time with the NLP expanded into one SX graph
    ("expanded", the default) and with the compiled step kernel mapped in an MX graph
    (nlp/codegen.py, "compiled"), alternating in one process, ``min(repeat, 5)`` rounds after a
    warm-up of each: min and median [s], speed-ups compiled/expanded, and whether both found the
    same optimum (iterations, NLP objective)."""
    from pathlib import Path

    from ocp_crawl.ocp.search import best_harmonic
    from ocp_crawl.problem import load_problem, ocp_settings

    root = Path(__file__).resolve().parent.parent
    out = {"load_average_start": os.getloadavg()}
    for name in KERNEL_PROBLEMS:
        problem = load_problem(root / "problems" / f"{name}.toml")
        settings = ocp_settings(problem)
        harm = best_harmonic(problem.robot, problem.gravity, settings)
        runs = {"expanded": [], "compiled": []}
        for k in range(min(repeat, 5) + 1):
            for mode in runs:
                run = _ocp_run(problem, settings, harm, mode)
                # the first round builds and loads (the kernel's library, the simulator's functions)
                if k:
                    runs[mode].append(run)
        row = {}
        for mode, rs in runs.items():
            for key in ("build_s", "ipopt_s", "eval_s"):
                v = [r[key] for r in rs]
                row[f"{mode}_{key}"] = {"min": round(min(v), 3),
                                        "median": round(statistics.median(v), 3)}
        for key in ("build_s", "ipopt_s", "eval_s"):
            row[f"speedup_{key}_median"] = round(row[f"compiled_{key}"]["median"]
                                                 / row[f"expanded_{key}"]["median"], 2)
        a, b = runs["expanded"][0], runs["compiled"][0]
        row["iterations_expanded_compiled"] = (a["iterations"], b["iterations"])
        row["status_expanded_compiled"] = (a["status"], b["status"])
        row["value_rel_diff"] = abs(a["value_ocp"] - b["value_ocp"]) / abs(a["value_ocp"])
        out[name] = row
    out["load_average_end"] = os.getloadavg()
    return out


#: the shipped OCP problem files that ``ocp_files`` solves whole (``ocp-crawl optimize FILE
#: --json``)
OCP_FILES = ("ocp_max_speed", "ocp_min_cot", "ocp_robust")


def _optimize_process(args: list[str], tree: str | None = None) -> tuple[float, dict]:
    """Wall time [s] of one whole ``ocp-crawl optimize`` process and its JSON output (the package
    of ``tree`` first on the path, when given: an old commit's, :func:`_old_tree`)."""
    import json
    import subprocess
    import sys

    env = None if tree is None else dict(os.environ, PYTHONPATH=tree)
    t = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "ocp_crawl.cli", "optimize", *args, "--json"],
                          capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t
    try:
        return wall, json.loads(proc.stdout)
    except ValueError:
        return wall, {"status": f"exit {proc.returncode}: {proc.stderr.strip()[-200:]}"}


def _file_runs(runs: list) -> dict:
    """min and median wall time [s] of (wall, JSON) runs of one file, the first run's status,
    replayed objective, gain and IPOPT split."""
    walls = [w for w, _ in runs]
    data = runs[0][1]
    return {"wall_s": {"min": round(min(walls), 2), "median": round(statistics.median(walls), 2)},
            "status": data.get("status"), "value_replay": data.get("objective_value_replay"),
            "rel_diff_replay": data.get("rel_diff_replay"), "gain": data.get("gain"),
            **_ipopt_split(data.get("homotopy", []))}


def bench_ocp_files(repeat: int, old: str | None = None) -> dict:
    """Each shipped OCP problem file solved whole at its default N and starts (baselines, solve,
    replay; one process each, ``min(repeat, 3)`` runs: min and median wall time [s], status,
    objective by replay, and the first run's IPOPT iterations, seconds and milliseconds per
    iteration), then the convergence run
    ``optimize problems/ocp_max_speed.toml --nodes 50 100 200 400`` once (wall time and the table).
    With ``old`` (a commit): each file's runs alternate with those of that commit's package, and
    the ratios old/new of the minima and medians are reported (the convergence run of this tree
    only).  Targets: <= 20 s per file, <= 60 s for the convergence run, on 2 cores."""
    import shutil
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent / "problems"
    out: dict = {"load_average_start": os.getloadavg()}
    old_tree = None if old is None else _old_tree(old)
    try:
        for name in OCP_FILES:
            runs: dict = {"new": [], "old": []}
            for _ in range(min(repeat, 3)):
                runs["new"].append(_optimize_process([str(root / f"{name}.toml")]))
                if old_tree is not None:
                    runs["old"].append(_optimize_process([str(root / f"{name}.toml")], old_tree))
            out[name] = _file_runs(runs["new"])
            if old_tree is not None:
                before = out[name]["old"] = {"commit": old, **_file_runs(runs["old"])}
                for stat in ("min", "median"):
                    out[name][f"ratio_old_over_new_{stat}"] = round(
                        before["wall_s"][stat] / out[name]["wall_s"][stat], 3)
    finally:
        if old_tree is not None:
            shutil.rmtree(old_tree, ignore_errors=True)
    wall, data = _optimize_process([str(root / "ocp_max_speed.toml"), "--nodes", "50", "100", "200",
                                    "400"])
    rows = data.get("rows", [])
    out["convergence_max_speed"] = {"wall_s": round(wall, 1), "rows": [
        {k: r.get(k) for k in ("nodes", "status", "value_ocp", "value_replay", "rel_change",
                               "order", "solve_time_s")}
        for r in rows]}
    out["load_average_end"] = os.getloadavg()
    return out


#: the solver paths that ``ocp_paths`` compares on each shipped OCP file (``--set`` overrides)
OCP_PATHS = {"homotopy": [], "perturbation always": ["ocp.perturbation=always"],
             "endgame 1e-3": ["ocp.endgame_sigma=1e-3"],
             "endgame 1e-3, perturbation "
             "always": ["ocp.endgame_sigma=1e-3", "ocp.perturbation=always"]}


def bench_ocp_paths(repeat: int) -> dict:
    """robust_speed's and min_cot's files whole (``ocp-crawl optimize FILE --json``) on each path of
    :data:`OCP_PATHS` where the file's schedule has the stage, alternating in one run,
    ``min(repeat, 2)`` rounds: wall time [s] (min, median), status, replayed objective, IPOPT
    iterations and seconds, and what the endgame did."""
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent / "problems"
    out = {"load_average_start": os.getloadavg()}
    for name in ("ocp_robust", "ocp_min_cot"):
        runs: dict = {path: [] for path in OCP_PATHS}
        for _ in range(min(repeat, 2)):
            for path, sets in OCP_PATHS.items():
                if name != "ocp_robust" and "endgame" in path:
                    continue  # (the default schedule, 1e-4 and 1e-6, has no stage at 1e-3)
                runs[path].append(_optimize_process([str(root / f"{name}.toml"),
                                                     *[a for x in sets for a in ("--set", x)]]))
        out[name] = {path: {"wall_s": {"min": round(min(w for w, _ in r), 1),
                                       "median": round(statistics.median(w for w, _ in r), 1)},
                            "status": r[0][1].get("status"),
                            "value_replay": r[0][1].get("objective_value_replay"),
                            "endgame": r[0][1].get("endgame"),
                            **_ipopt_split(r[0][1].get("homotopy", []))}
                     for path, r in runs.items() if r}
    out["load_average_end"] = os.getloadavg()
    return out


def _ipopt_split(stages: list) -> dict:
    """IPOPT's share of a solve (the first run's ``homotopy`` records): iterations, seconds inside
    IPOPT calls and milliseconds per iteration (the machine's speed on these KKT systems, apart from
    the iteration count)."""
    its = sum(int(h.get("iterations", 0)) for h in stages)
    secs = sum(float(h.get("time", 0.0)) for h in stages)
    return {"ipopt_iterations": its, "ipopt_s": round(secs, 2),
            "ms_per_iteration": round(1e3 * secs / its, 1) if its else None}


def bench_paper(repeat: int) -> dict:
    """Accuracy checks behind the notes: stiff limit vs prescribed angles, CoT+ vs the published
    curve."""
    import csv

    import numpy as np

    from ocp_crawl import Harmonic, Model, ReferenceTorque, Robot, simulate_torque
    from ocp_crawl.sim.angles import simulate_angles
    from ocp_crawl.io.paper_data import paper_data_dir

    out = {}
    gait = Harmonic.from_degrees(90, 30, 45)
    for gravity in ("paper", "physical"):
        robot = Robot.paper().with_stiffness_ratio(1e4)
        model = Model(robot, gravity=gravity)
        s_t = simulate_torque(model, ReferenceTorque(gait, robot.k)).S
        s_a = simulate_angles(model, gait).S
        out[f"stiff_limit_rel_diff_{gravity}"] = abs(s_t / s_a - 1)
    with open(paper_data_dir() / "fig_cot_vs_amplitude.csv") as fh:
        rows = list(csv.DictReader(fh))
    amps = np.array([float(r["A_deg"]) for r in rows])
    for col, ratio in (("CoT_plus_large_k", 5.0), ("CoT_plus_realistic_k", 2.74),
                       ("CoT_plus_low_k", 0.3)):
        for target in (20.0, 50.0):
            j = int(np.argmin(np.abs(amps - target)))
            robot = Robot.paper().with_stiffness_ratio(ratio)
            res = simulate_torque(Model(robot, gravity="paper"),
                                  ReferenceTorque(Harmonic.from_degrees(90, amps[j], 45), robot.k))
            out[f"{col}_A{amps[j]:.1f}_rel_diff"] = res.CoT_plus / float(rows[j][col]) - 1
    return out


def _delegate(script: str, argv: list[str]):
    """Run another benchmark script's main(argv) (they live beside this file)."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).with_name(script)
    spec = importlib.util.spec_from_file_location(path.stem, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.main(argv)


def bench_mpcc(repeat: int) -> str:
    """MPCC step and time-stepping cycle (scripts/bench_mpcc.py)."""
    _delegate("bench_mpcc.py", [])
    return "see above"


def bench_sweep(repeat: int) -> str:
    """37 x 31 psi-gamma map, jobs 1 and 2 (scripts/bench_sweep.py)."""
    _delegate("bench_sweep.py", [])
    return "see above"


def bench_baselines(repeat: int) -> dict:
    """The baselines: (1) a triangle wave's simulation (the paper robot, gamma 87.5, A 27.5, psi 9
    deg) with the input's linear pieces taken whole (the default for an input linear between its
    knots) against steps of 1/1024 cycle (the cap its Fourier content would set), alternating in one
    run, ``repeat`` times each: min and median [ms], steps, and S of both;
    (2) the search of max_speed's baselines (the shipped envelope and bandwidth) with the harmonic
    family alone and with every family, ``min(repeat, 2)`` times each: min and median [s] and the
    members simulated."""
    from ocp_crawl import Model, Robot
    from ocp_crawl.ocp.family import WaveParams
    from ocp_crawl.ocp.search import best_baselines
    from ocp_crawl.ocp.settings import OCPSettings
    from ocp_crawl.sim.event import HybridOptions, simulate_torque

    robot = Robot.paper()
    model, torque = Model(robot), WaveParams(87.5, 87.5, 27.5, 27.5, 9.0,
                                             "triangle").torque(robot.k)
    out = {"load_average_start": os.getloadavg()}
    times, results = {"whole_pieces": [], "fine_steps": []}, {}
    for _ in range(repeat):
        for name, opt in (("whole_pieces", HybridOptions()),
                          ("fine_steps", HybridOptions(max_step=1 / 1024))):
            t = time.perf_counter()
            results[name] = simulate_torque(model, torque, opt)
            times[name].append(time.perf_counter() - t)
    for name, ts in times.items():
        out[f"triangle_{name}_ms"] = {"min": round(1e3 * min(ts), 2),
                                      "median": round(1e3 * statistics.median(ts), 2),
                                      "samples": len(results[name].t), "S": results[name].S}
    settings = OCPSettings(gamma_deg=90.0, A_max_deg=30.0, max_rate_deg_s=180.0, direction=-1)
    for label, shapes in (("harmonic", ("harmonic",)), ("all", None)):
        walls, base = [], None
        for _ in range(min(repeat, 2)):
            t = time.perf_counter()
            base = best_baselines(robot, "physical", settings, shapes=shapes)
            walls.append(time.perf_counter() - t)
        out[f"search_{label}_s"] = {
            "min": round(min(walls), 2), "median": round(statistics.median(walls), 2),
            "members": {s: c.evaluated for s, c in base.choices.items()},
            "value_mm_s": {s: round(1e3 * c.value, 3) for s, c in base.choices.items()}}
    out["load_average_end"] = os.getloadavg()
    return out


#: the requests of ``work``: a shipped file and overrides whose run the estimate must bound
WORK_CASES = (("paper_gait.toml", []), ("pulse_gait.toml", []),
              ("paper_gait.toml", ["simulation.max_step=1e-4"]),
              ("paper_gait.toml", ["simulation.solver=mpcc", "simulation.steps=50"]),
              ("paper_gait.toml", ["simulation.solver=mpcc", "simulation.steps=400"]),
              ("pulse_gait.toml", ["simulation.solver=mpcc", "simulation.steps=200"]),
              ("paper_gait.toml", ["simulation.solver=mujoco", "simulation.period=5"]),
              ("five_link_chain.toml", []),
              ("five_link_chain.toml", ["simulation.solver=mpcc", "simulation.steps=100"]))


def bench_work(repeat: int) -> dict:
    """The work estimates of ``ocp_crawl.problem.work`` against the runs they bound: for each
    request of WORK_CASES, the estimate (an upper bound: every cycle up to max_cycles run), the
    typical one (three cycles) and the measured wall time (min and median of ``repeat`` runs after a
    warm-up) and steps; ratio = estimate / median."""
    from pathlib import Path

    import ocp_crawl
    from ocp_crawl.problem.work import simulation_work

    problems = Path(__file__).resolve().parent.parent / "problems"
    out = {}
    for name, overrides in WORK_CASES:
        problem = ocp_crawl.load_problem(problems / name, overrides=overrides)
        estimate = simulation_work(problem)
        ocp_crawl.run_problem(problem)
        times, result = [], None
        for _ in range(max(1, repeat)):
            t = time.perf_counter()
            result = ocp_crawl.run_problem(problem)
            times.append(time.perf_counter() - t)
        median = statistics.median(times)
        out[" ".join([name, *overrides])] = {
            "estimate_s": round(estimate.seconds, 3), "typical_s": round(estimate.typical, 3),
            "min_s": round(min(times), 3),
            "median_s": round(median, 3), "ratio": round(estimate.seconds / median, 1),
            "cycles": result.cycles, "steps": result.nsteps, "detail": estimate.detail}
    return out


BENCHMARKS = {"hybrid": bench_hybrid, "hybrid_accuracy": bench_hybrid_accuracy,
              "prescribed": bench_prescribed, "chain": bench_chain,
              "chain_cycles": bench_chain_cycles, "paper": bench_paper,
              "mpcc": bench_mpcc, "sweep": bench_sweep, "ocp": bench_ocp,
              "ocp_kernel": bench_ocp_kernel, "ocp_files": bench_ocp_files,
              "ocp_paths": bench_ocp_paths, "baselines": bench_baselines, "work": bench_work,
              "pressure": bench_pressure}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("which", nargs="*", metavar="NAME", default=[],
                    help=f"benchmarks to run: {', '.join(BENCHMARKS)} (default: all)")
    ap.add_argument("--repeat", type=int, default=30, help="timed repetitions per benchmark")
    ap.add_argument("--old", default=None,
                    help=f"commit that `hybrid` and `pressure` compare against (default: "
                         f"{OLD_COMMIT} and {PRESSURE_OLD_COMMIT}), and `ocp_files` (default: "
                         f"none)")
    ap.add_argument("--hybrid-worker", type=int, metavar="REPEAT", help=argparse.SUPPRESS)
    ap.add_argument("--pressure-worker", type=int, metavar="REPEAT", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.repeat < 1:
        ap.error("--repeat must be >= 1")
    for worker, fun in ((args.hybrid_worker, hybrid_cpu), (args.pressure_worker, pressure_cpu)):
        if worker is not None:
            import json
            print(json.dumps(fun(worker)))
            return 0
    names = args.which or list(BENCHMARKS)
    unknown = [n for n in names if n not in BENCHMARKS]
    if unknown:
        ap.error(f"unknown benchmark(s) {unknown}; choose from {list(BENCHMARKS)}")
    print(f"# {os.cpu_count()} cores, python {sys.version.split()[0]}")
    for name in names:
        result = (BENCHMARKS[name](args.repeat, args.old)
                  if name in ("hybrid", "pressure", "ocp_files") and args.old
                  else BENCHMARKS[name](args.repeat))
        print(f"{name}: {result}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
