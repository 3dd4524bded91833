"""Optimise a gait and replay it.

Solves the periodic-gait optimal control problem (objective ``max_speed``: the largest mean speed
v = |S|/T for torques inside the envelope gamma +- 30 deg whose reference angles move at most
180 deg/s) on a coarse transcription (20 nodes, one start, so that the example runs in CI time; the
shipped ``ocp_max_speed.toml`` uses 50), then replays the optimal torques, linear in phase between
the nodes as in the transcription, in the event-driven simulator through the plain Python API,
:func:`ocp_crawl.simulate`, as any other input signal.  The replayed S must match the one
:func:`~ocp_crawl.ocp.optimize_gait` reports for its own replay (the judge); the figure compares the
optimal torques and foot motion with the best gait of the whole harmonic family (gamma1, gamma2, A1,
A2, psi and the period under the same bandwidth).

Run: ``python examples/05_optimise_and_replay.py [OUT_DIR]``; writes
``OUT_DIR/optimise_and_replay.png``.
"""
import math

import numpy as np
from _common import output_dir, save
from matplotlib.figure import Figure

from ocp_crawl import Model, PeriodicLinear, Robot, simulate
from ocp_crawl.ocp import OCPSettings, optimize_gait
from ocp_crawl.viz.ocp import pinned

#: a coarse transcription and a small search of the baselines (harmonic, triangle, pulse),
#: in CI time
SETTINGS = OCPSettings(objective="max_speed", nodes=20, harmonic_psi=12, starts=1,
                       baseline_samples=16, baseline_starts=1, baseline_evaluations=60)


def main() -> None:
    out = output_dir()
    robot = Robot.paper()
    opt = optimize_gait(robot, "physical", SETTINGS)
    print(f"{opt.status.label}: {opt.message}")
    if not opt.success:
        raise SystemExit(1)
    h = opt.harmonic
    # the best harmonic gait, torque drive
    harmonic = simulate(Model(robot), h.torque_signal(robot.k))
    # the optimal torques [N m] as a signal
    mine = simulate(Model(robot), PeriodicLinear(opt.phase, opt.tau))
    if not (mine.success and math.isclose(mine.S, opt.S_replay[0], rel_tol=1e-9)):
        raise SystemExit(f"replay through simulate: {mine.status_name}, S = {mine.S} m, "
                         f"optimize_gait's replay S = {opt.S_replay[0]} m")
    v_h, v_opt = abs(harmonic.S) / h.T, abs(mine.S) / opt.T_ocp   # mean speeds [m/s]
    print(f"best harmonic (gamma {h.gamma1_deg:.1f}/{h.gamma2_deg:.1f} deg, "
          f"A {h.A1_deg:.1f}/{h.A2_deg:.1f} deg, psi {h.psi_deg:.1f} deg, T {h.T:.3f} s): "
          f"v = {1e3 * v_h:.2f} mm/s")
    print(f"optimum: v = {1e3 * opt.v_ocp[0]:.2f} mm/s in the OCP, "
          f"{1e3 * v_opt:.2f} mm/s replayed, T = {opt.T_ocp:.3f} s (gain "
          f"{100 * opt.gains['harmonic']:+.1f} % over the best harmonic), "
          f"solved in {opt.solve_time_s:.1f} s")
    for shape, gain in opt.gains.items():  # a triangle wave in the same bandwidth is nearly as fast
        print(f"  gain over the best {shape} gait: {100 * gain:+.2f} %")

    # both against time: the optimum's and the harmonic gait's periods differ; the harmonic torque
    # is pinned as the optimum's (phase 0 where tau1 is largest), so that the two cycles line up
    fig = Figure(figsize=(10.0, 5.2), layout="constrained")
    ax_tau, ax_x = fig.subplots(1, 2)
    tt = np.linspace(0.0, 1.0, 401)
    tau_opt = PeriodicLinear(opt.phase, opt.tau)(tt)
    tau_h = pinned(h.torque_signal(robot.k), tt)
    for i, (color, lw, marker) in enumerate((("C0", 3.5, "s"), ("C3", 1.2, "o"))):  # tau1 wide
        ax_tau.plot(tt * opt.T_ocp, 1e3 * tau_opt[i], color, lw=lw, alpha=0.8,
                    label=rf"optimal $\tau_{i + 1}$")
        ax_tau.plot(opt.phase * opt.T_ocp, 1e3 * opt.tau[i], color + marker, ms=3,
                    label=rf"OCP nodes, $\tau_{i + 1}$")
        ax_tau.plot(tt * h.T, 1e3 * tau_h[i], color + "--", lw=1,
                    label=rf"best harmonic $\tau_{i + 1}$")
    for r, T, style, name in ((mine, opt.T_ocp, "k-", "optimum (replay)"),
                              (harmonic, h.T, "k--", "best harmonic")):
        phase = np.asarray(r.t) - r.t0
        ax_x.plot(phase * T, 1e3 * (np.asarray(r.x1) - r.x1[0]), style,
                  label=f"{name}: S = {1e3 * r.S:.1f} mm in T = {T:.3f} s, "
                        f"v = S/T = {1e3 * r.S / T:.1f} mm/s")
    ax_tau.set(xlabel="time [s] (one cycle each)", ylabel="joint torque [mN m]",
               title="(a) torques")
    ax_x.set(xlabel="time [s] (one cycle each)", ylabel=r"foot 1 position $x_1 - x_1(0)$ [mm]",
             title="(b) foot 1, event-driven simulator")
    # below the panels: inside, the legends would hide the curves
    ax_tau.legend(fontsize="x-small", ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.18))
    ax_x.legend(fontsize="small", loc="upper center", bbox_to_anchor=(0.5, -0.18))
    for ax in (ax_tau, ax_x):
        ax.grid(True, lw=0.3)
    fig.suptitle(f"max_speed optimum ({SETTINGS.nodes} nodes): v = S/T = "
                 f"{1e3 * mine.S / opt.T_ocp:.1f} mm/s replayed (S < 0: towards foot 1),\n"
                 f"{100 * opt.gains['harmonic']:+.1f} % over the best harmonic gait "
                 f"({1e3 * harmonic.S / h.T:.1f} mm/s)")
    save(fig, out / "optimise_and_replay.png")


if __name__ == "__main__":
    main()
