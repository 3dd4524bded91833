"""Optimise a gait and replay it.

Solves the periodic-gait optimal control problem (objective ``max_speed``: the largest progress per
cycle for torques inside the envelope of the harmonic gaits with A <= 30 deg) on a coarse
transcription (24 nodes, so that the example runs in CI time; the README's ``ocp_max_speed.toml``
uses 100), then replays the optimal torques, interpolated periodically (PCHIP), in the event-driven
simulator through the plain Python API, :func:`ocp_crawl.simulate`, as any other input signal.
The replayed S must match the one :func:`~ocp_crawl.ocp.optimize_gait` reports for its own replay;
the figure compares the optimal torques and foot motion with the best harmonic gait.  On so coarse a
transcription the OCP's own S differs from the replay by about 10 %: the replay is the number that
counts (more nodes close the gap; see README, ``optimize``).

Run: ``python examples/05_optimise_and_replay.py [OUT_DIR]``; writes ``OUT_DIR/optimise_and_replay.png``.
"""
import math

import numpy as np
from _common import output_dir, save
from matplotlib.figure import Figure

from ocp_crawl import Harmonic, Model, PeriodicLinear, ReferenceTorque, Robot, simulate
from ocp_crawl.ocp import OCPSettings, optimize_gait

SETTINGS = OCPSettings(objective="max_speed", nodes=24, harmonic_psi=12)


def main() -> None:
    out = output_dir()
    robot = Robot.paper()
    opt = optimize_gait(robot, "physical", SETTINGS)
    print(f"{opt.status.label}: {opt.message}")
    if not opt.success:
        raise SystemExit(1)
    h = opt.harmonic
    harmonic = simulate(Model(robot), ReferenceTorque(Harmonic.from_degrees(h.gamma_deg, h.A_deg, h.psi_deg), robot.k))
    mine = simulate(Model(robot), PeriodicLinear(opt.phase, opt.tau))   # the optimal torques [N m] as a signal
    if not (mine.success and math.isclose(mine.S, opt.S_replay[0], rel_tol=1e-9)):
        raise SystemExit(f"replay through simulate: {mine.status_name}, S = {mine.S} m, optimize_gait's replay "
                         f"S = {opt.S_replay[0]} m")
    print(f"best harmonic (psi = {h.psi_deg:.1f} deg, A = {h.A_deg:.1f} deg): S = {1e3 * harmonic.S:.2f} mm/cycle")
    print(f"optimum: S = {1e3 * opt.S_ocp[0]:.2f} mm/cycle in the OCP, {1e3 * mine.S:.2f} mm/cycle replayed "
          f"(gain {100 * opt.gain:+.1f} % over the best harmonic), solved in {opt.solve_time_s:.1f} s")

    fig = Figure(figsize=(10.0, 4.0), layout="constrained")
    ax_tau, ax_x = fig.subplots(1, 2)
    tt = np.linspace(0.0, 1.0, 401)
    tau_opt = PeriodicLinear(opt.phase, opt.tau)(tt)
    tau_h = ReferenceTorque(Harmonic.from_degrees(h.gamma_deg, h.A_deg, h.psi_deg), robot.k)(tt)
    for i, (color, lw, marker) in enumerate((("C0", 3.5, "s"), ("C3", 1.2, "o"))):  # tau1 wide: tau2 may cover it
        ax_tau.plot(tt, 1e3 * tau_opt[i], color, lw=lw, alpha=0.8, label=rf"optimal $\tau_{i + 1}$")
        ax_tau.plot(opt.phase, 1e3 * opt.tau[i], color + marker, ms=3, label=rf"OCP nodes, $\tau_{i + 1}$")
        ax_tau.plot(tt, 1e3 * tau_h[i], color + "--", lw=1, label=rf"best harmonic $\tau_{i + 1}$")
    for r, style, name in ((mine, "k-", "optimum (replay)"), (harmonic, "k--", "best harmonic")):
        phase = np.asarray(r.t) - r.t0
        ax_x.plot(phase, 1e3 * (np.asarray(r.x1) - r.x1[0]), style, label=f"{name}: S = {1e3 * r.S:.1f} mm")
    ax_tau.set(xlabel="phase t [cycles]", ylabel="joint torque [mN m]", title="(a) torques")
    ax_x.set(xlabel="phase t [cycles]", ylabel=r"foot 1 position $x_1 - x_1(0)$ [mm]",
             title="(b) foot 1, event-driven simulator")
    ax_tau.legend(fontsize="x-small", ncol=2)
    ax_x.legend(fontsize="small")
    for ax in (ax_tau, ax_x):
        ax.grid(True, lw=0.3)
    fig.suptitle(f"max_speed optimum ({SETTINGS.nodes} nodes): S = {1e3 * mine.S:.1f} mm/cycle replayed, "
                 f"{100 * opt.gain:+.1f} % over the best harmonic gait ({1e3 * harmonic.S:.1f} mm/cycle)")
    save(fig, out / "optimise_and_replay.png")


if __name__ == "__main__":
    main()
