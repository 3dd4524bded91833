"""Past a fold: where the quasistatic model stops, MuJoCo snaps through and crawls on.

The paper's robot made soft, k = 0.30 M g L (the amplitude study's soft robot), with the paper's
gait gamma = 90 deg, A = 30 deg, psi = 45 deg and physical gravity.  The event-driven solver
tracks the equilibrium until its branch folds (status ``fold``, at a phase it reports): there the
real robot has no nearby equilibrium and must move dynamically.  The same torques played slowly
in MuJoCo (period T = 5 s) run through the fold: joint 1 collapses (to about 15 deg) within a few
hundredths of a cycle, foot 2 hops about 33 mm off the ground (the dynamic solver itself reports
``lift_off``, as its two-contact checks demand), lands, and the robot settles on another periodic
gait that never reaches the fold: S = -29.3 mm in the first cycle, then +29.9 mm per cycle (the
other way).  The example steps MuJoCo directly (the robot of :mod:`ocp_crawl.sim.mujoco_model`)
to follow it past the hop, prints S of each cycle and the largest foot height, and plots the
joint angles against phase for both solvers with the fold marked.  Needs MuJoCo (``pip install
'ocp-crawl[dynamic]'``).

Run: ``python examples/09_past_a_fold.py [OUT_DIR]``; writes ``OUT_DIR/past_a_fold.png``.
"""
import math

import numpy as np
from _common import output_dir, quick, save
from matplotlib.figure import Figure

from ocp_crawl import MujocoOptions, simulate
from ocp_crawl.problem import problem_from_dict
from ocp_crawl.sim.dynamic import require_mujoco
from ocp_crawl.sim.mujoco_model import FOOT_RADIUS, crawler_mjcf, foot_positions, place_on_ground

M, L, G = 0.052, 0.120, 9.81
SOFT = {"robot": {"M": M, "L": L, "beta": 2.0, "k": 0.30 * M * G * L, "mu": 0.389, "g": G},
        "gait": {"drive": "torque", "gamma_deg": 90.0, "A_deg": 30.0, "psi_deg": 45.0},
        "model": {"gravity": "physical"}}
PERIOD = 5.0
"""period of the MuJoCo runs [s]"""
TIMESTEP = 5e-4
"""MuJoCo's integration step [s] (the dynamic solver's default)"""


def mujoco_cycles(problem, cycles: int):
    """Step MuJoCo through ``cycles`` cycles of the problem's torques at :data:`PERIOD`; returns
    the phases [cycles], the joint angles (n, 2) [rad], foot 1's x and the feet's heights above
    their resting height [m]."""
    mujoco = require_mujoco()
    robot, signal = problem.robot, problem.torque
    mjm = mujoco.MjModel.from_xml_string(crawler_mjcf(robot, TIMESTEP))
    data = mujoco.MjData(mjm)
    tau0 = np.asarray(signal(0.0), float)
    place_on_ground(mujoco, mjm, data, math.pi + tau0 / robot.k)
    data.ctrl[:] = tau0
    mujoco.mj_step(mjm, data, nstep=int(0.5 / TIMESTEP))   # settle at the torque of phase 0
    n = int(round(PERIOD / TIMESTEP))
    phases = np.arange(cycles * n + 1) / n
    controls = np.asarray(signal((np.arange(cycles * n) + 0.5) / n), float).T
    qpos = np.empty((len(phases), mjm.nq))
    qpos[0] = data.qpos
    for j, u in enumerate(controls):
        data.ctrl[:] = u
        mujoco.mj_step(mjm, data)
        qpos[j + 1] = data.qpos
    (f1, f2) = foot_positions(robot, qpos)
    height = np.c_[f1[:, 1], f2[:, 1]] - FOOT_RADIUS * robot.l
    return phases, qpos[:, 3:5] + math.pi, f1[:, 0], height


def main() -> None:
    out = output_dir()
    problem = problem_from_dict(SOFT)
    event = simulate(problem.model, problem.torque, "event")
    print(f"event solver: {event.status_name} at phase {event.failure_t:.4f} "
          f"(mode {event.failure_mode})")
    dyn = simulate(problem.model, problem.torque, "mujoco", MujocoOptions(period=PERIOD))
    print(f"mujoco solver, T = {PERIOD:g} s: {dyn.status_name}: {dyn.message}")
    cycles = 2 if quick() else 4
    phase, phi, x1, height = mujoco_cycles(problem, cycles)
    n = int(round(PERIOD / TIMESTEP))
    S = x1[n::n] - x1[:-1:n]
    print("MuJoCo stepped directly: S per cycle [mm] " + ", ".join(f"{1e3 * s:.2f}" for s in S)
          + f"; a foot rises at most {1e3 * height.max():.2f} mm (per cycle "
          + ", ".join(f"{1e3 * height[k * n:(k + 1) * n].max():.2f}" for k in range(cycles)) + ")")
    fig = Figure(figsize=(11, 4.8), constrained_layout=True)
    ax_phi, ax_h = fig.subplots(1, 2)
    first, last = slice(0, n + 1), slice((cycles - 1) * n, cycles * n + 1)
    fold = event.failure_t % 1.0
    for i, colour in ((0, "tab:blue"), (1, "tab:orange")):
        ax_phi.plot(event.t, np.degrees(event.phi[i]), "o", ms=4, color=colour,
                    label=f"phi{i + 1} quasistatic (event solver), up to the fold")
        ax_phi.plot(phase[first], np.degrees(phi[first, i]), color=colour,
                    label=f"phi{i + 1} MuJoCo, cycle 1 (through the snap)")
        ax_phi.plot(phase[last] - (cycles - 1), np.degrees(phi[last, i]), "--", lw=1,
                    color=colour, label=f"phi{i + 1} MuJoCo, cycle {cycles} (steady)")
        ax_h.plot(phase[first], 1e3 * height[first, i], color=colour,
                  label=f"foot {i + 1}, cycle 1")
    for ax in (ax_phi, ax_h):
        ax.axvline(fold, color="tab:red", ls=":", label=f"quasistatic fold, phase {fold:.3f}")
        ax.set_xlabel("phase t/T [cycles]")
        ax.set_xlim(0, 1)
        ax.legend(fontsize=7)
    ax_phi.set_ylabel("joint angle [deg]")
    ax_h.set_ylabel("foot height above rest [mm]")
    fig.suptitle(f"Soft robot k = 0.30 M g L (gamma 90, A 30, psi 45 deg, physical gravity): the "
                 f"quasistatic gait folds at phase {fold:.3f};\nMuJoCo at T = {PERIOD:g} s snaps "
                 f"through, foot 2 hops {1e3 * height[first, 1].max():.0f} mm, then crawls "
                 f"S = {1e3 * S[-1]:+.2f} mm per cycle (cycle 1: {1e3 * S[0]:+.2f} mm)")
    save(fig, out / "past_a_fold.png")


if __name__ == "__main__":
    main()
