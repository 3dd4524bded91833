"""Benchmark of the sweep engine (run by hand; the figures go into the closing notes).

    python scripts/bench_sweep.py                     # 37 x 31 psi-gamma map and a 10 x 8 map, jobs
                                                        1 and 2
    python scripts/bench_sweep.py --jobs 1,2,4 --small-only
    python scripts/bench_sweep.py --cli               # also the command line end to end (imports
                                                        included)
    python scripts/bench_sweep.py --repeat 3          # each sweep 3 times, jobs interleaved: min
                                                        and median

The map is the paper robot (Table I) with A = 30 deg, psi 0..180 deg, gamma 60..120 deg,
event-driven stepper.  Each sweep writes its journal and results.csv into a temporary directory, as
the command does.  Times are wall times after a warm-up point in this process (the command pays the
imports and loading the compiled functions once, ~1 s, reported by --cli).
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
PROBLEM = REPO / "problems" / "paper_gait.toml"


def grid(n_psi: int, n_gamma: int) -> dict:
    import numpy as np

    return {"gait.psi_deg": np.linspace(0, 180, n_psi),
            "gait.gamma_deg": np.linspace(60, 120, n_gamma)}


def cpu_seconds() -> float:
    """CPU time of this process and its finished children (the pool's workers are joined at the
    end)."""
    own, kids = (resource.getrusage(resource.RUSAGE_SELF),
                 resource.getrusage(resource.RUSAGE_CHILDREN))
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def time_sweep(problem, n_psi: int, n_gamma: int, jobs: int) -> dict:
    from ocp_crawl.sweep import run_sweep

    with tempfile.TemporaryDirectory() as tmp:
        c, t = cpu_seconds(), time.perf_counter()
        res = run_sweep(problem, grid(n_psi, n_gamma), out_dir=Path(tmp) / "s", jobs=jobs)
        wall, cpu = time.perf_counter() - t, cpu_seconds() - c
    n = res.settings.size
    return {"grid": f"{n_psi} x {n_gamma}", "points": n, "jobs": jobs, "wall_s": wall,
            "ms_per_point": 1e3 * wall / n,
            "cpu_ms_per_point": 1e3 * cpu / n, "counts": res.counts(),
            "S": res.array("S", successful_only=False)}


def _spin(n: int) -> int:
    total = 0
    for i in range(n):
        total += i * i
    return total


def machine_scaling(jobs: int, tasks_per_process: int = 4, n: int = 2_000_000) -> float:
    """Throughput of ``jobs`` processes over one, on busy loops (pure Python, no I/O, nothing
    shared): what the machine itself gives to parallel processes now, the ceiling of a sweep's
    speed-up in the same run."""
    import multiprocessing

    ctx = multiprocessing.get_context("fork")
    rates = []
    for procs in (1, jobs):
        start = time.perf_counter()
        with ctx.Pool(procs) as pool:
            pool.map(_spin, [n] * procs * tasks_per_process)
        rates.append(procs * tasks_per_process / (time.perf_counter() - start))
    return rates[1] / rates[0]


def time_cli(n_psi: int, n_gamma: int, jobs: int) -> tuple[float, dict]:
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "ocp_crawl", "sweep", str(PROBLEM), "--grid",
               f"gait.psi_deg=0:180:{n_psi}",
               "--grid", f"gait.gamma_deg=60:120:{n_gamma}", "--jobs", str(jobs), "--out",
               str(Path(tmp) / "s"), "--no-progress", "--json"]
        t = time.perf_counter()
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
        wall = time.perf_counter() - t
    if proc.returncode != 0:
        raise RuntimeError(f"the command failed ({proc.returncode}): {proc.stderr.strip()}")
    return wall, json.loads(proc.stdout)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", default="1,2", help="comma-separated worker counts (default 1,2)")
    ap.add_argument("--small", default="10x8", help="the smaller grid, PSIxGAMMA (default 10x8)")
    ap.add_argument("--small-only", action="store_true", help="skip the 37 x 31 map")
    ap.add_argument("--cli", action="store_true",
                    help="also time 'ocp-crawl sweep' on the full map (largest --jobs)")
    ap.add_argument("--repeat", type=int, default=1,
                    help="runs of each sweep, the jobs interleaved (default 1)")
    args = ap.parse_args(argv)
    import numpy as np

    from ocp_crawl.problem import load_problem, run_problem

    jobs_list = [int(j) for j in args.jobs.split(",")]
    small = tuple(int(n) for n in args.small.lower().split("x"))
    problem = load_problem(PROBLEM, ["gait.A_deg=30"])
    # warm-up: compiled functions are loaded once per process (forked workers inherit them)
    run_problem(problem)

    grids = [small] + ([] if args.small_only else [(37, 31)])
    # other processes on the machine stretch wall times (CPU times per point stay meaningful)
    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f} at start")
    rows = []
    for n_psi, n_gamma in grids:
        for run in range(args.repeat):
            for jobs in jobs_list:
                r = time_sweep(problem, n_psi, n_gamma, jobs)
                r["run"], r["machine"] = run, machine_scaling(jobs) if jobs > 1 else 1.0
                rows.append(r)
                print(f"{r['grid']:>8} = {r['points']:5d} points, jobs {jobs}: {r['wall_s']:7.2f} "
                      f"s, {r['ms_per_point']:6.2f} ms per point (CPU {r['cpu_ms_per_point']:.2f} "
                      f"ms per point; load {os.getloadavg()[0]:.1f})  "
                      f"({', '.join(f'{k} {v}' for k, v in r['counts'].items())})",
                      flush=True)
    print("\nscaling")
    for n_psi, n_gamma in grids:
        same = [r for r in rows if r["grid"] == f"{n_psi} x {n_gamma}"]
        base = [r for r in same if r["jobs"] == jobs_list[0]]
        for jobs in jobs_list[1:]:
            other = [r for r in same if r["jobs"] == jobs]
            # the ratio within each run (the runs see different loads); min and median over the runs
            ratios = [b["wall_s"] / o["wall_s"] for b, o in zip(base, other)]
            machine = [o["machine"] for o in other]
            walls = {j: [r["wall_s"] for r in same if r["jobs"] == j] for j in (jobs_list[0], jobs)}
            agree = all(np.array_equal(o["S"], base[0]["S"], equal_nan=True) for o in other)
            print(f"{n_psi:>3} x {n_gamma:<3}: jobs {jobs} vs {jobs_list[0]}: speed-up median "
                  f"{statistics.median(ratios):.2f}, max {max(ratios):.2f} over {len(ratios)} runs "
                  f"(ideal {jobs / jobs_list[0]:.0f}; the machine's own, busy loops in {jobs} "
                  f"processes vs 1 in the same runs: median {statistics.median(machine):.2f}); "
                  f"wall jobs {jobs_list[0]} min {min(walls[jobs_list[0]]):.2f} median "
                  f"{statistics.median(walls[jobs_list[0]]):.2f} s, jobs {jobs} min "
                  f"{min(walls[jobs]):.2f} median {statistics.median(walls[jobs]):.2f} s; rows "
                  f"identical: {agree}")
    for jobs in jobs_list:
        by_size = sorted((r for r in rows if r["jobs"] == jobs and r["run"] == 0),
                         key=lambda r: r["points"])
        if len(by_size) == 2:
            a, b = by_size
            per = (b["wall_s"] - a["wall_s"]) / (b["points"] - a["points"])
            fixed = a["wall_s"] - per * a["points"]
            print(f"jobs {jobs}: time ~ {fixed:.2f} s + {1e3 * per:.2f} ms x points (fit through "
                  "the two grids)")
    if args.cli and not args.small_only:
        jobs = max(jobs_list)
        wall, summary = time_cli(37, 31, jobs)
        print(f"\nocp-crawl sweep, 37 x 31, --jobs {jobs}, end to end (imports, journal, "
              f"results.csv): {wall:.2f} s ({summary['counts']})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
