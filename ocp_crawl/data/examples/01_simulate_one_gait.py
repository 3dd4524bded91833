"""Simulate the paper's gait and plot it.

Shows the basic loop of the Python API: a problem (here the shipped ``paper_gait.toml``, the
paper's Table I robot with gamma = 90 deg, A = 30 deg, psi = 45 deg, torque drive, physical
gravity), :func:`ocp_crawl.run_problem`, the numbers of the steady cycle (S [mm], W+ [mJ], CoT+, the
contact events) and the standard gait figure (joint angles, contact positions, robot snapshots,
tangential force against the friction limits, shaded by contact mode).

Run: ``python examples/01_simulate_one_gait.py [OUT_DIR]``; writes ``OUT_DIR/gait.png``.
"""
from _common import output_dir, save

from ocp_crawl import load_problem, run_problem
from ocp_crawl.problem import shipped_problem
from ocp_crawl.viz import plot_gait


def main() -> None:
    out = output_dir()
    problem = load_problem(shipped_problem("paper_gait"))
    result = run_problem(problem)
    if not result.success:
        raise SystemExit(f"{result.status_name}: {result.message}")
    print(f"S = {1e3 * result.S:.2f} mm per cycle, W+ = {1e3 * result.W_plus:.1f} mJ, "
          f"CoT+ = {result.CoT_plus:.2f}")
    for e in result.steady_events():
        print(f"  phase {e.t - result.t0:.4f}: {e.kind} ({e.mode_before} -> {e.mode_after})")
    fig = plot_gait(result, problem.robot, reference=problem.gait)
    save(fig, out / "gait.png")


if __name__ == "__main__":
    main()
