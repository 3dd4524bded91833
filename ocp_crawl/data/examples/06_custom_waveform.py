"""A custom (non-sinusoidal) input through the Python API.

Soft pneumatic actuators are often driven by pressure steps, not sines.  Here each joint's
reference angle follows a trapezoid between gamma - A and gamma + A (gamma = 90 deg, A = 30 deg:
the paper's range) with rise and fall taking a quarter cycle each, joint 1 leading joint 2 by
psi = 90 deg: a sequential actuation, one joint moves while the other holds.  The trapezoid is
sampled at 40 phases and interpolated periodically with :class:`~ocp_crawl.PeriodicPchip` (shape
preserving: no overshoot at the corners); a 3rd-order :class:`~ocp_crawl.FourierSeries` fit of
the same samples gives a smoothed version.  Each reference drives the robot through the torque law
tau = k (phi_ref - pi) (:class:`~ocp_crawl.ReferenceTorque`) in the event-driven simulator, next to
the paper's harmonic gait of the same range and phase lead.

Run: ``python examples/06_custom_waveform.py [OUT_DIR]``; writes ``OUT_DIR/custom_waveform.png``.
"""
import numpy as np
from _common import output_dir, save
from matplotlib.figure import Figure

from ocp_crawl import (FourierSeries, Harmonic, Model, PeriodicPchip, ReferenceTorque, Robot,
                       simulate)

GAMMA_DEG, A_DEG, PSI_DEG = 90.0, 30.0, 90.0
RISE = 0.25         # rise (and fall) time [cycles]
KNOTS = 40          # samples per cycle


def trapezoid(t: np.ndarray) -> np.ndarray:
    """A 1-periodic trapezoid in [-1, 1]: rise over RISE from t = 0, hold, fall from t = 0.5,
    hold."""
    t = np.mod(t, 1.0)
    up = np.clip(t / RISE, 0.0, 1.0)
    down = np.clip((t - 0.5) / RISE, 0.0, 1.0)
    return 2.0 * (up - down) - 1.0


def main() -> None:
    out = output_dir()
    robot = Robot.paper()
    t = np.arange(KNOTS) / KNOTS
    # joint 1 leads by psi/2, joint 2 lags by psi/2 (as the harmonic gait)
    lead = PSI_DEG / 360.0 / 2.0
    # (2, N) [rad]
    samples = np.radians(GAMMA_DEG + A_DEG * np.vstack([trapezoid(t + lead), trapezoid(t - lead)]))
    references = {
        "harmonic (the paper's gait)": Harmonic.from_degrees(GAMMA_DEG, A_DEG, PSI_DEG),
        "trapezoid (PCHIP)": PeriodicPchip(t, samples),
        "trapezoid, Fourier order 3": FourierSeries.fit(samples, order=3),
    }
    results = {}
    for name, ref in references.items():
        r = simulate(Model(robot, gravity="physical"), ReferenceTorque(ref, robot.k))
        print(f"{name:>28}: {r.status_name}, S = {1e3 * r.S:.2f} mm/cycle, "
              f"W+ = {1e3 * r.W_plus:.1f} mJ, CoT+ = {r.CoT_plus:.2f}")
        if not r.success:
            raise SystemExit(r.message)
        results[name] = r

    fig = Figure(figsize=(10.0, 5.2), layout="constrained")
    ax_ref, ax_x = fig.subplots(1, 2)
    tt = np.linspace(0.0, 1.0, 401)
    for (name, ref), style in zip(references.items(), ("-", "--", ":")):
        phi = np.degrees(ref(tt))
        ax_ref.plot(tt, phi[0], "C0" + style, label=rf"$\varphi_{{ref,1}}$, {name}")
        ax_ref.plot(tt, phi[1], "C3" + style, label=rf"$\varphi_{{ref,2}}$, {name}")
        r = results[name]
        ax_x.plot(np.asarray(r.t) - r.t0, 1e3 * (np.asarray(r.x1) - r.x1[0]), "k" + style,
                  label=f"{name}: S = {1e3 * r.S:.1f} mm")
    ax_ref.plot(t, np.degrees(samples[0]), "C0.", ms=3, label="samples (40 per cycle)")
    ax_ref.plot(t, np.degrees(samples[1]), "C3.", ms=3)
    ax_ref.set(xlabel="phase t [cycles]", ylabel="reference angle [deg]",
               title="(a) reference angles")
    ax_x.set(xlabel="phase t [cycles]", ylabel=r"foot 1 position $x_1 - x_1(0)$ [mm]",
             title="(b) foot 1 over the steady cycle")
    ax_ref.legend(fontsize="x-small", loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2)
    ax_x.legend(fontsize="small")
    for ax in (ax_ref, ax_x):
        ax.grid(True, lw=0.3)
    S = {name: 1e3 * r.S for name, r in results.items()}
    fig.suptitle("Paper robot, gamma 90 deg, A 30 deg, psi 90 deg, "
                 "torque drive tau = k (phi_ref - pi):\nS = "
                 + ", ".join(f"{v:.1f} mm/cycle ({k})" for k, v in S.items()), fontsize="medium")
    save(fig, out / "custom_waveform.png")


if __name__ == "__main__":
    main()
