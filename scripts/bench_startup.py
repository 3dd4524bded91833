"""Whole-process benchmarks: start-up of the command and a sweep of 37 gaits (run by hand; figures
go into notes).

    python scripts/bench_startup.py                       # this tree, 7 repeats
    python scripts/bench_startup.py --compare /path/tree  # also another checkout, interleaved in
                                                            the same run
    python scripts/bench_startup.py --repeat 15 --jobs 1,2

Each command runs as a fresh ``python -m ocp_crawl ...`` process (imports, CLI, compiled functions
loaded from the warm cache: ``ocp-crawl warmup`` runs first); wall times over ``--repeat`` runs,
reported as min and median with the load average (the machine may be shared: compare trees within
one run, where the runs are interleaved).  The ``ocp-crawl`` console script adds its own wrapper
(a pyenv shim, for instance) on top of these.

The 37-gait sweep (psi 0..180 deg, the paper gait otherwise) is compared with a MuJoCo simulation of
the same robot with slow actuation: about 24 s of wall time per gait on this machine (T = 12 s,
dt = 5e-5 s to reach 0.3 % in S), i.e. 1/24 gait per second.  Target: 1000 times as many
gaits per second, 37 gaits in under 37 * 24 / 1000 = 0.89 s, whole process.
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
PROBLEM = "problems/paper_gait.toml"

#: wall time of one MuJoCo gait of the same robot [s]
MUJOCO_SECONDS_PER_GAIT = 24.0


def _children_cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def run(tree: Path, args: list[str]) -> tuple[float, float]:
    """Wall and CPU time [s] of ``python -m ocp_crawl ARGS`` with ``tree`` first on the path, from
    ``tree`` (the CPU time of the process and the workers it waited for: robust to other load on the
    machine)."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    env.pop("OCP_CRAWL_NO_COMPILE", None)
    cpu, start = _children_cpu(), time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "ocp_crawl", *args], cwd=tree, env=env,
                          capture_output=True, text=True, check=False)
    wall, cpu = time.perf_counter() - start, _children_cpu() - cpu
    if proc.returncode != 0:
        raise RuntimeError(f"{tree}: ocp-crawl {' '.join(args)} failed ({proc.returncode}): "
                           f"{proc.stderr.strip()}")
    return wall, cpu


def sweep_args(jobs: int, out: Path) -> list[str]:
    return ["sweep", PROBLEM, "--grid", "gait.psi_deg=0:180:37", "--jobs", str(jobs), "--out",
            str(out), "--force", "--no-progress", "--json"]


def commands(jobs_list: list[int], tmp: Path) -> dict[str, list[str]]:
    cmds = {"--version": ["--version"], "simulate --json": ["simulate", PROBLEM, "--json"]}
    for jobs in jobs_list:
        cmds[f"sweep 37 gaits --jobs {jobs}"] = sweep_args(jobs, tmp / f"s{jobs}")
    return cmds


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--compare", metavar="TREE",
                    help="another checkout of the package, timed in the same run")
    ap.add_argument("--repeat", type=int, default=7, help="runs of each command (default 7)")
    ap.add_argument("--jobs", default="1,2",
                    help="worker counts of the 37-gait sweep (default 1,2)")
    args = ap.parse_args(argv)
    trees = {"this": REPO} | ({"compare": Path(args.compare).resolve()} if args.compare else {})
    jobs_list = [int(j) for j in args.jobs.split(",")]
    times: dict[tuple[str, str], list[float]] = {}
    cpus: dict[tuple[str, str], list[float]] = {}
    loads = []
    with tempfile.TemporaryDirectory() as tmp:
        cmds = commands(jobs_list, Path(tmp))
        # warm cache, and a first run of each command (page cache, .pyc files)
        for tree in trees.values():
            if (tree / "ocp_crawl" / "sweep" / "warmup.py").exists():
                run(tree, ["warmup"])
            for cmd in cmds.values():
                run(tree, cmd)
        for _ in range(args.repeat):
            for name, cmd in cmds.items():
                for label, tree in trees.items():  # interleaved: both trees see the same load
                    wall, cpu = run(tree, cmd)
                    times.setdefault((label, name), []).append(wall)
                    cpus.setdefault((label, name), []).append(cpu)
            loads.append(os.getloadavg()[0])
    print(f"# {os.cpu_count()} CPUs, python {sys.version.split()[0]}, {args.repeat} runs each, "
          f"load average {min(loads):.2f}..{max(loads):.2f} (1 min)")
    report = {}
    for name in cmds:
        line = f"{name:<24}"
        for label in trees:
            ts, cs = times[(label, name)], cpus[(label, name)]
            report[f"{label}: {name}"] = {"min_s": min(ts), "median_s": statistics.median(ts),
                                          "cpu_min_s": min(cs),
                                          "cpu_median_s": statistics.median(cs)}
            line += (f"  {label}: wall min {min(ts):.3f} median {statistics.median(ts):.3f} s, CPU "
                     f"min {min(cs):.3f} median {statistics.median(cs):.3f} s")
        if len(trees) == 2:
            line += ("  (median ratio compare/this "
                     f"""{statistics.median(times[('compare', name)])
                          / statistics.median(times[('this', name)]):.2f})""")
        print(line)
    for label in trees:
        for jobs in jobs_list:
            ts = times[(label, f"sweep 37 gaits --jobs {jobs}")]
            rate = 37 / statistics.median(ts)
            print(f"{label}: 37 gaits, --jobs {jobs}, whole process: {rate:.1f} gaits/s (median), "
                  f"{rate * MUJOCO_SECONDS_PER_GAIT:.0f} x MuJoCo's "
                  f"1/{MUJOCO_SECONDS_PER_GAIT:.0f} gait/s (best run "
                  f"{37 / min(ts) * MUJOCO_SECONDS_PER_GAIT:.0f} x; target 1000 x: 37 gaits in "
                  f"{37 * MUJOCO_SECONDS_PER_GAIT / 1000:.2f} s)")
    print(json.dumps(report))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
