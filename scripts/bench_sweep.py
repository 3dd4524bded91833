"""Benchmark of the sweep engine (run by hand; the figures go into the closing notes).

    python scripts/bench_sweep.py                     # 37 x 31 psi-gamma map and a 10 x 8 map, jobs 1 and 2
    python scripts/bench_sweep.py --jobs 1,2,4 --small-only
    python scripts/bench_sweep.py --cli               # also the command line end to end (imports included)

The map is the paper robot (Table I) with A = 30 deg, psi 0..180 deg, gamma 60..120 deg, event-driven
stepper.  Each sweep writes its journal and results.csv into a temporary directory, as the command
does.  Times are wall times after a warm-up point in this process (the command pays the imports and
loading the compiled functions once, ~1 s, reported by --cli).
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
PROBLEM = REPO / "problems" / "paper_gait.toml"


def grid(n_psi: int, n_gamma: int) -> dict:
    import numpy as np

    return {"gait.psi_deg": np.linspace(0, 180, n_psi), "gait.gamma_deg": np.linspace(60, 120, n_gamma)}


def cpu_seconds() -> float:
    """CPU time of this process and its finished children (the pool's workers are joined at the end)."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def time_sweep(problem, n_psi: int, n_gamma: int, jobs: int) -> dict:
    from ocp_crawl.sweep import run_sweep

    with tempfile.TemporaryDirectory() as tmp:
        c, t = cpu_seconds(), time.perf_counter()
        res = run_sweep(problem, grid(n_psi, n_gamma), out_dir=Path(tmp) / "s", jobs=jobs)
        wall, cpu = time.perf_counter() - t, cpu_seconds() - c
    n = res.settings.size
    return {"grid": f"{n_psi} x {n_gamma}", "points": n, "jobs": jobs, "wall_s": wall, "ms_per_point": 1e3 * wall / n,
            "cpu_ms_per_point": 1e3 * cpu / n, "counts": res.counts(), "S": res.array("S", successful_only=False)}


def time_cli(n_psi: int, n_gamma: int, jobs: int) -> tuple[float, dict]:
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "ocp_crawl", "sweep", str(PROBLEM), "--grid", f"gait.psi_deg=0:180:{n_psi}",
               "--grid", f"gait.gamma_deg=60:120:{n_gamma}", "--jobs", str(jobs), "--out", str(Path(tmp) / "s"),
               "--no-progress", "--json"]
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
    ap.add_argument("--cli", action="store_true", help="also time 'ocp-crawl sweep' on the full map (largest --jobs)")
    args = ap.parse_args(argv)
    import numpy as np

    from ocp_crawl.problem import load_problem, run_problem

    jobs_list = [int(j) for j in args.jobs.split(",")]
    small = tuple(int(n) for n in args.small.lower().split("x"))
    problem = load_problem(PROBLEM, ["gait.A_deg=30"])
    run_problem(problem)  # warm-up: compiled functions are loaded once per process (forked workers inherit them)

    grids = [small] + ([] if args.small_only else [(37, 31)])
    # other processes on the machine stretch wall times (CPU times per point stay meaningful)
    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f} at start")
    rows = []
    for n_psi, n_gamma in grids:
        for jobs in jobs_list:
            r = time_sweep(problem, n_psi, n_gamma, jobs)
            rows.append(r)
            print(f"{r['grid']:>8} = {r['points']:5d} points, jobs {jobs}: {r['wall_s']:7.2f} s, "
                  f"{r['ms_per_point']:6.2f} ms per point (CPU {r['cpu_ms_per_point']:.2f} ms per point; "
                  f"load {os.getloadavg()[0]:.1f})  ({', '.join(f'{k} {v}' for k, v in r['counts'].items())})",
                  flush=True)
    print("\nscaling")
    for n_psi, n_gamma in grids:
        same = [r for r in rows if r["grid"] == f"{n_psi} x {n_gamma}"]
        base = same[0]
        for r in same[1:]:
            agree = np.array_equal(r["S"], base["S"], equal_nan=True)
            print(f"{r['grid']:>8}: jobs {r['jobs']} vs {base['jobs']}: speed-up {base['wall_s'] / r['wall_s']:.2f} "
                  f"(ideal {r['jobs'] / base['jobs']:.0f}); rows identical: {agree}")
    for jobs in jobs_list:
        by_size = sorted((r for r in rows if r["jobs"] == jobs), key=lambda r: r["points"])
        if len(by_size) == 2:
            a, b = by_size
            per = (b["wall_s"] - a["wall_s"]) / (b["points"] - a["points"])
            fixed = a["wall_s"] - per * a["points"]
            print(f"jobs {jobs}: time ~ {fixed:.2f} s + {1e3 * per:.2f} ms x points (fit through the two grids)")
    if args.cli and not args.small_only:
        jobs = max(jobs_list)
        wall, summary = time_cli(37, 31, jobs)
        print(f"\nocp-crawl sweep, 37 x 31, --jobs {jobs}, end to end (imports, journal, results.csv): {wall:.2f} s "
              f"({summary['counts']})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
