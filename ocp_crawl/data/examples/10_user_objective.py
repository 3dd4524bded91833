"""An objective of your own: the least joule heating per metre, through the Python hook.

The named objectives (max_speed, min_cot, robust_speed) do not say everything a designer may want.
An electric or pneumatic actuator that holds a torque dissipates power roughly as tau^2 (a motor's
copper loss R tau^2 / k_t^2), so the heat per metre crawled is proportional to
H = mean(tau_1^2 + tau_2^2) T / |S| [N^2 m s].  :class:`~ocp_crawl.ocp.UserObjective` states it
twice: as a CasADi expression of the transcription's symbols (``nlp``: node torques, period, S per
scenario, in physical units) and as the same number on a simulated gait (``value``: a
:class:`~ocp_crawl.ocp.quantities.Cycle`), so that the baselines and the replay judge measure it the
way the optimiser does.  A speed of at least 40 mm/s is required (a constraint of the vocabulary, as
``[[ocp.constraint]]`` in a file).  The optimum is compared with the best harmonic gait that meets
the same requirement; the figure shows both torque profiles.

Run: ``python examples/10_user_objective.py [OUT_DIR]``; writes ``OUT_DIR/user_objective.png``.
"""
import numpy as np
from _common import output_dir, quick, save
from matplotlib.figure import Figure

from ocp_crawl import PeriodicLinear, Robot
from ocp_crawl.ocp import OCPSettings, UserObjective, optimize_gait
from ocp_crawl.viz.ocp import pinned

SPEED_MIN = 0.04    # required mean speed [m/s]


def heat_nlp(q):
    """H = mean(tau^2) T / (direction S) [N^2 m s] in the NLP's symbols (physical units)."""
    return q.mean_torque_sq * q.T / (q.direction * q.S[0])


def heat_value(cycle):
    """The same H of a simulated gait."""
    return cycle.mean_torque_sq * cycle.T / (cycle.direction * cycle.S[0])


HEAT = UserObjective("heat_per_metre", heat_nlp, heat_value, sense="min", unit="N^2 m s", scale=3.0)


def main() -> None:
    out = output_dir()
    robot = Robot.paper()
    settings = OCPSettings(user_objective=HEAT, nodes=20 if quick() else 40, starts=1,
                           baselines="harmonic", harmonic_psi=12,
                           baseline_samples=0 if quick() else 16,
                           baseline_starts=1, baseline_evaluations=60 if quick() else 200,
                           constraints=({"quantity": "speed", "min": SPEED_MIN},))
    opt = optimize_gait(robot, "physical", settings)
    print(f"{opt.status.label}: {opt.message}")
    if not opt.success:
        raise SystemExit(1)
    h = opt.harmonic
    gain = opt.gains["harmonic"]
    print(f"heat per metre: optimum {opt.value_replay:.4g} N^2 m s (replayed; speed "
          f"{1e3 * opt.v_replay[0]:.1f} mm/s, T {opt.T_ocp:.3f} s), best harmonic gait at "
          f">= 40 mm/s {h.value:.4g} N^2 m s ({1e3 * h.v[0]:.1f} mm/s, T {h.T:.3f} s): "
          f"{100 * gain:+.1f} %")

    fig = Figure(figsize=(9.0, 5.0), layout="constrained")
    ax = fig.subplots()
    tt = np.linspace(0.0, 1.0, 401)
    tau_opt = PeriodicLinear(opt.phase, opt.tau)(tt)
    tau_h = pinned(h.torque_signal(robot.k), tt)
    for i, color in enumerate(("C0", "C3")):
        ax.plot(tt * opt.T_ocp, 1e3 * tau_opt[i], color, lw=2, label=rf"optimum, $\tau_{i + 1}$")
        ax.plot(tt * h.T, 1e3 * tau_h[i], color + "--", lw=1,
                label=rf"best harmonic, $\tau_{i + 1}$")
    ax.set(xlabel="time [s] (one cycle each)", ylabel="joint torque [mN m]")
    ax.grid(True, lw=0.3)
    ax.legend(fontsize="small", ncol=2)
    fig.suptitle(f"least heat per metre H = mean(tau^2) T/|S| at v >= {1e3 * SPEED_MIN:.0f} mm/s "
                 f"({settings.nodes} nodes):\noptimum {opt.value_replay:.3g} N^2 m s, best "
                 f"harmonic {h.value:.3g} N^2 m s ({100 * gain:+.1f} %)")
    save(fig, out / "user_objective.png")


if __name__ == "__main__":
    main()
