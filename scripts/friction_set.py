"""What the friction tolerance guarantees: S of gaits at a friction asymmetry mu1/mu2 = 1 +- delta.

    python scripts/friction_set.py             # harmonic gaits of the paper robot (a few seconds)
    python scripts/friction_set.py OUT [OUT2]  # also optima of `ocp-crawl optimize ... --out OUT`

For each gait: its slip-weighted friction margin m at equal feet (:mod:`ocp_crawl.ocp.slip_margin`),
its S [mm per cycle] at mu1/mu2 = 1, and at 1 - delta and 1 + delta (mu1 = mu sqrt(r),
mu2 = mu / sqrt(r): the geometric mean fixed) for delta = 0.5 %, 2.5 % (friction_tol / 2) and 5 %:
the largest relative change of S, (delta/m)^2 and their ratio.  The harmonic gaits are gamma 90 deg,
A 30 deg, psi as listed, physical gravity; an optimum is read from its directory's torques.csv
(replayed linear in phase, as the judge does) and optimal_gait.toml (robot, gravity).
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from ocp_crawl import Robot
from ocp_crawl.model.inputs import Harmonic, ReferenceTorque
from ocp_crawl.model.sampled import PeriodicLinear
from ocp_crawl.model.statics import Model
from ocp_crawl.ocp.slip_margin import result_margins
from ocp_crawl.sim.event import simulate_torque

PSI_DEG = (0.01, 0.5, 2.0, 5.0, 10.0, 20.0, 45.0)
DELTAS = (0.005, 0.025, 0.05)


def at_ratio(robot: Robot, ratio: float) -> Robot:
    """The robot with feet mu1/mu2 = ratio at the same geometric mean sqrt(mu1 mu2)."""
    mu = math.sqrt(robot.mu1 * robot.mu2)
    return robot.replace(mu1=mu * math.sqrt(ratio), mu2=mu / math.sqrt(ratio))


def S_at(robot: Robot, gravity: str, signal, ratio: float) -> float:
    """S [m] of the gait at mu1/mu2 = ratio (NaN when the simulation fails)."""
    res = simulate_torque(Model(at_ratio(robot, ratio), gravity=gravity), signal)
    return res.S if res.success else math.nan


def row(name: str, robot: Robot, gravity: str, signal) -> None:
    """Print the margin, S at equal feet and the relative change of S at 1 +- delta of one gait."""
    ref = simulate_torque(Model(at_ratio(robot, 1.0), gravity=gravity), signal)
    if not ref.success:
        print(f"{name}: {ref.status.name} ({ref.message})")
        return
    m = result_margins(ref, at_ratio(robot, 1.0))[0]
    print(f"{name}: m {m:.4f}, S {1e3 * ref.S:.3f} mm at mu1/mu2 = 1")
    for d in DELTAS:
        S = [S_at(robot, gravity, signal, r) for r in (1 - d, 1 + d)]
        change = max(abs(s - ref.S) for s in S) / abs(ref.S)
        q = (d / m) ** 2 if m > 0 else math.inf
        print(f"    delta {d:.3f}: S {1e3 * S[0]:8.3f} / {1e3 * S[1]:8.3f} mm, "
              f"change {change:6.1%}, (delta/m)^2 {q:8.3g}, ratio {change / q:5.2f}")


def optimum(out: Path) -> tuple[Robot, str, PeriodicLinear]:
    """The robot, gravity and replay signal of an ``optimize --out`` directory."""
    from ocp_crawl.problem.problem import load_problem

    problem = load_problem(out / "optimal_gait.toml")
    table = np.loadtxt(out / "torques.csv", delimiter=",", skiprows=2)
    N = table.shape[0]
    return problem.robot, problem.model.gravity, PeriodicLinear(np.arange(N) / N, table[:, 1:3].T)


def main(argv: list[str]) -> None:
    robot = Robot.paper()
    for psi in PSI_DEG:
        signal = ReferenceTorque(Harmonic.from_degrees(90.0, 30.0, psi), robot.k)
        row(f"harmonic psi {psi:g} deg", robot, "physical", signal)
    for out in argv:
        row(f"optimum {out}", *optimum(Path(out)))


if __name__ == "__main__":
    main(sys.argv[1:])
