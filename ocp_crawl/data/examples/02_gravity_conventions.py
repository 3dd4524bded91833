"""The two gravity conventions side by side.

The paper's printed statics carry the gravity term with the opposite sign of the virtual-work
derivation (see docs/guide/model.md, "Gravity conventions"). This example runs the paper's gait
under both conventions (``model.gravity = "physical"`` and ``"paper"``) and plots, over the steady
cycle, the joint angles phi1, phi2 [deg] and the position of foot 1 [mm], with S of each in the
title, so that the size of the difference is visible at a glance.

Run: ``python examples/02_gravity_conventions.py [OUT_DIR]``; writes
``OUT_DIR/gravity_conventions.png``.
"""
import numpy as np
from _common import output_dir, save
from matplotlib.figure import Figure

from ocp_crawl import paper_problem, run_problem

STYLES = {"physical": "-", "paper": "--"}


def main() -> None:
    out = output_dir()
    results = {}
    for gravity in STYLES:
        result = run_problem(paper_problem([f"model.gravity={gravity}"]))
        if not result.success:
            raise SystemExit(f"{gravity}: {result.status_name}: {result.message}")
        results[gravity] = result
        print(f"{gravity:>8} gravity: S = {1e3 * result.S:.2f} mm per cycle, "
              f"W+ = {1e3 * result.W_plus:.1f} mJ, CoT+ = {result.CoT_plus:.2f}")
    S = {g: 1e3 * r.S for g, r in results.items()}
    fig = Figure(figsize=(9.0, 3.8), layout="constrained")
    ax_phi, ax_x = fig.subplots(1, 2)
    for gravity, r in results.items():
        phase = np.asarray(r.t) - r.t0
        phi = np.degrees(np.asarray(r.phi))
        ls = STYLES[gravity]
        ax_phi.plot(phase, phi[0], "C0" + ls, label=rf"$\varphi_1$, {gravity} gravity")
        ax_phi.plot(phase, phi[1], "C3" + ls, label=rf"$\varphi_2$, {gravity} gravity")
        ax_x.plot(phase, 1e3 * (np.asarray(r.x1) - r.x1[0]), "k" + ls, label=f"{gravity} gravity")
    ax_phi.set(xlabel="phase t [cycles]", ylabel="joint angle [deg]", title="(a) joint angles")
    ax_x.set(xlabel="phase t [cycles]", ylabel=r"foot 1 position $x_1 - x_1(0)$ [mm]",
             title="(b) foot 1 over the steady cycle")
    ax_phi.legend(fontsize="small")
    ax_x.legend(fontsize="small")
    for ax in (ax_phi, ax_x):
        ax.grid(True, lw=0.3)
    diff = 100 * (abs(S["paper"]) - abs(S["physical"])) / abs(S["physical"])
    fig.suptitle(f"Paper gait: S = {S['physical']:.2f} mm/cycle (physical gravity), "
                 f"{S['paper']:.2f} mm/cycle (paper's sign: |S| {diff:+.1f} %)")
    save(fig, out / "gravity_conventions.png")


if __name__ == "__main__":
    main()
