"""A design map: S over the gait's phase difference psi and nominal angle gamma.

Shows :func:`ocp_crawl.sweep.run_sweep`, the Python face of ``ocp-crawl sweep``: the paper's gait is
evaluated on a small grid of ``gait.psi_deg`` x ``gait.gamma_deg`` (the first key varies slowest),
and ``result.array("S")`` gives S [m] shaped like the grid, NaN where a point failed (its status
says why: fold, lift-off, ...).  The map draws the progress towards foot 1 per cycle, -S [mm], over
psi (x) and gamma (y) with a sequential colour map, as the ``reproduce`` figure parametric.png
does, with failed cells hatched, and marks the best point (largest progress, S < 0).

Run: ``python examples/03_design_map.py [OUT_DIR]``; writes ``OUT_DIR/design_map.png`` and
``OUT_DIR/design_map.csv``.  Use ``jobs=N`` for worker processes on a finer grid.
"""
import numpy as np
from _common import output_dir, save
from matplotlib.figure import Figure
from matplotlib.patches import Patch, Rectangle

from ocp_crawl import paper_problem
from ocp_crawl.sweep import run_sweep

PSI_DEG = np.linspace(0.0, 180.0, 7)      # phase difference [deg]
GAMMA_DEG = np.linspace(60.0, 120.0, 5)   # nominal joint angle [deg]


def edges(centres: np.ndarray) -> np.ndarray:
    """Cell edges around equally spaced centres."""
    h = centres[1] - centres[0]
    return np.append(centres - h / 2, centres[-1] + h / 2)


def main() -> None:
    out = output_dir()
    sweep = run_sweep(paper_problem(), {"gait.psi_deg": PSI_DEG, "gait.gamma_deg": GAMMA_DEG},
                      jobs=1)
    sweep.to_csv(out / "design_map.csv")
    print(f"{sweep.shape[0]} x {sweep.shape[1]} points in {sweep.elapsed:.1f} s; "
          f"statuses {sweep.counts()}")
    progress = -1e3 * sweep.array("S").T          # -S [mm], (gamma, psi): gamma up, psi across
    failed = sweep.status_array().T != "success"
    best = sweep.best()                           # the row of largest |S|

    fig = Figure(figsize=(6.4, 5.2), layout="constrained")
    ax = fig.subplots()
    # one-signed data (progress >= 0 towards foot 1): a sequential colour map from zero
    low = min(0.0, np.nanmin(progress))
    mesh = ax.pcolormesh(edges(PSI_DEG), edges(GAMMA_DEG), progress, cmap="viridis", vmin=low,
                         vmax=np.nanmax(progress))
    fig.colorbar(mesh, ax=ax, label="progress per cycle $-S$ [mm] (towards foot 1)")
    for i, j in zip(*np.nonzero(failed)):
        ax.add_patch(hatched_cell(PSI_DEG, GAMMA_DEG, i, j))
    handles = [Patch(facecolor="white", edgecolor="gray", hatch="///",
                     label="failed point (status in the CSV)")]
    if best is not None:
        at = best["point"]
        label = (f"largest: {-1e3 * best['S']:.1f} mm at $\\psi$ = {at['gait.psi_deg']:g}, "
                 f"$\\gamma$ = {at['gait.gamma_deg']:g} deg")
        handles += ax.plot(at["gait.psi_deg"], at["gait.gamma_deg"], "*", color="orange", mec="k",
                           ms=14, clip_on=False, label=label)
    # below the map: inside it the legend would hide cells
    fig.legend(handles=handles, loc="outside lower center", fontsize="small", ncol=1)
    ax.set(xlabel=r"phase difference $\psi$ [deg]", ylabel=r"nominal joint angle $\gamma$ [deg]")
    title = (r"Paper robot, $A$ = 30 deg (physical gravity sign): progress over $\psi$ and $\gamma$"
             f"\n{failed.sum()} of {failed.size} points failed")
    if best is not None:
        title += f"; largest $-S$ = {-1e3 * best['S']:.1f} mm per cycle"
    ax.set_title(title, fontsize="medium")
    save(fig, out / "design_map.png")


def hatched_cell(x: np.ndarray, y: np.ndarray, i: int, j: int) -> Rectangle:
    """A hatched rectangle over cell (i, j) (row i of y, column j of x)."""
    hx, hy = x[1] - x[0], y[1] - y[0]
    return Rectangle((x[j] - hx / 2, y[i] - hy / 2), hx, hy, facecolor="white", edgecolor="gray",
                     hatch="///")


if __name__ == "__main__":
    main()
