"""Benchmark of the MPCC step and the MPCC time-stepping (run by hand; numbers go into the notes).

    python scripts/bench_mpcc.py                      # paper gait, N = 200, physical gravity
    python scripts/bench_mpcc.py --steps 400 --gravity paper --psi 90 --formulation l1_penalty

Reports the median wall time of a warm-started step solve (IPOPT calls included, the previous step's
solution as warm start) over two cycles, the median over ``--repeat`` runs of one full cycle
(``simulate``-style run from the released start, ``cycles=1``), and the one-off NLP build time.
CPU times (process time) and the load average are reported too: on a shared machine the wall times
grow with the load, the CPU times much less.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time


def bench(steps: int, gravity: str, psi: float, formulation: str, repeat: int) -> dict:
    import numpy as np

    from ocp_crawl import Harmonic, Model, ReferenceTorque, Robot
    from ocp_crawl.sim.event import HybridStepper
    from ocp_crawl.sim.mpcc import MPCCOptions, MPCCStep
    from ocp_crawl.sim.step import StepState
    from ocp_crawl.sim.timestepping import TimeStepper

    model = Model(Robot.paper(), gravity=gravity)
    torque = ReferenceTorque(Harmonic.from_degrees(90, 30, psi), model.robot.k)
    options = MPCCOptions(formulation=formulation)

    t = time.perf_counter()
    step = MPCCStep(model, options)
    build = time.perf_counter() - t

    start = HybridStepper(model, torque).initial_state(0.0)
    state = StepState(start.x[:2], 0.0, float(model.kinematics(start.x[:2])["d"]), 0.0)
    warm, warm_cpu, cold, calls, iters, retried = [], [], [], [], [], 0
    prev = None
    for n in range(1, 2 * steps + 1):
        cpu = time.process_time()
        res = step.solve(state, torque(n / steps), warm_start=prev)
        cpu = time.process_time() - cpu
        if not res.success:
            raise RuntimeError(f"step {n} failed: {res.message}")
        (cold if prev is None else warm).append(res.solve_time)
        if prev is not None:
            warm_cpu.append(cpu)
        if prev is not None:
            calls.append(len(res.homotopy))
            iters.append(res.iterations)
            retried += res.attempts > 1
        prev, state = res, res.next_state()

    stepper = TimeStepper(model, torque, steps, options)
    cycle_times, cycle_cpu = [], []
    for _ in range(repeat):
        t, cpu = time.perf_counter(), time.process_time()
        out = stepper.run(cycles=1)
        cycle_times.append(time.perf_counter() - t)
        cycle_cpu.append(time.process_time() - cpu)
        if not out.success:
            raise RuntimeError(out.message)
    return {
        "cores": os.cpu_count(), "steps_per_cycle": steps, "gravity": gravity, "psi_deg": psi,
        "formulation": formulation,
        "nlp_build_ms": 1e3 * build,
        "warm_step_median_ms": 1e3 * statistics.median(warm),
        "warm_step_p90_ms": 1e3 * float(np.percentile(warm, 90)),
        "warm_step_mean_ms": 1e3 * statistics.fmean(warm),
        "warm_step_median_cpu_ms": 1e3 * statistics.median(warm_cpu),
        "cold_step_ms": 1e3 * cold[0],
        "warm_step_ipopt_calls_mean": statistics.fmean(calls),
        "warm_step_ipopt_iterations_mean": statistics.fmean(iters),
        "warm_steps_retried": retried,
        "full_cycle_median_s": statistics.median(cycle_times),
        "full_cycle_min_s": min(cycle_times),
        "full_cycle_median_cpu_s": statistics.median(cycle_cpu),
        "load_average_1min": os.getloadavg()[0],
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=200, help="steps per cycle N")
    ap.add_argument("--gravity", choices=("physical", "paper"), default="physical")
    ap.add_argument("--psi", type=float, default=45.0,
                    help="phase difference [deg] of the harmonic gait")
    ap.add_argument("--formulation", choices=("scholtes", "l1_penalty", "fischer_burmeister"),
                    default="scholtes")
    ap.add_argument("--repeat", type=int, default=5, help="timed full-cycle runs")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args(argv)
    result = bench(args.steps, args.gravity, args.psi, args.formulation, args.repeat)
    if args.json:
        print(json.dumps(result))
    else:
        print(f"# python {sys.version.split()[0]}")
        for key, value in result.items():
            print(f"{key:34s} {value:.4g}" if isinstance(value, float) else f"{key:34s} {value}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
