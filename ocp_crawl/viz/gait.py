"""Figures of a simulated gait, in the manner of the paper's figures simu_conf and simu_forces.

Library code builds :class:`matplotlib.figure.Figure` objects on the Agg canvas and never touches
pyplot's global state, so plotting works headless, in threads and inside notebooks alike (a
notebook displays a returned Figure directly).
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from ocp_crawl.io import units
from ocp_crawl.io.files import atomic_write
from ocp_crawl.model.chain import Chain
from ocp_crawl.model.inputs import PeriodicSignal
from ocp_crawl.model.statics import Robot
from ocp_crawl.sim.result import CrawlResult, Mode

#: background colour of each contact mode (light, so the curves stay readable)
MODE_COLORS = {
    Mode.STICK: "#e8e8e8",
    Mode.SLIP1_POS: "#fde0c5", Mode.SLIP1_NEG: "#fbc4a0",
    Mode.SLIP2_POS: "#cfe3f7", Mode.SLIP2_NEG: "#a9cbef",
}
_FALLBACK_COLORS = ("#d9f0d3", "#b8e0b0", "#f3d9f0", "#e6ccf0")


def mode_color(code: int) -> str:
    """Background colour of a mode code (modes added later get colours from a fallback list)."""
    try:
        mode = Mode(int(code))
    except ValueError:
        return _FALLBACK_COLORS[int(code) % len(_FALLBACK_COLORS)]
    return MODE_COLORS.get(mode, _FALLBACK_COLORS[int(mode) % len(_FALLBACK_COLORS)])


#: what each contact mode means, for legends (foot i slips along -x or +x while the other foot
#: sticks)
MODE_MEANINGS = {
    Mode.STICK: "both feet stick",
    Mode.SLIP1_POS: "foot 1 slips towards +x", Mode.SLIP1_NEG: "foot 1 slips towards -x",
    Mode.SLIP2_POS: "foot 2 slips towards +x", Mode.SLIP2_NEG: "foot 2 slips towards -x",
    Mode.SLIP_BOTH_POS: "both feet slip apart", Mode.SLIP_BOTH_NEG: "both feet slip together",
}


def mode_label(code: int) -> str:
    """The short name of a mode code (e.g. "slip1-")."""
    try:
        return Mode(int(code)).label
    except ValueError:
        return f"mode {int(code)}"


def mode_legend(codes, alpha: float = 1.0) -> tuple[list[Patch], list[str]]:
    """Legend handles (background patches of opacity ``alpha``) and labels of the contact modes
    ``codes``, each explained, e.g. "mode slip1-: foot 1 slips towards -x"."""
    codes = sorted({int(c) for c in codes})
    labels = []
    for c in codes:
        try:
            meaning = MODE_MEANINGS.get(Mode(c), "")
        except ValueError:
            meaning = ""
        labels.append(f"mode {mode_label(c)}: {meaning}" if meaning else f"mode {mode_label(c)}")
    return [Patch(color=mode_color(c), alpha=alpha) for c in codes], labels


def mode_runs(t: np.ndarray, mode: np.ndarray) -> list[tuple[float, float, int]]:
    """Maximal runs (t_start, t_end, mode) of constant mode over the samples."""
    runs: list[tuple[float, float, int]] = []
    for ti, mi in zip(np.asarray(t, float), np.asarray(mode, int)):
        if runs and runs[-1][2] == mi:
            runs[-1] = (runs[-1][0], ti, mi)
        else:
            # a run starts where the previous one ended: the event phase is shared by both
            start = runs[-1][1] if runs else ti
            runs.append((start, ti, int(mi)))
    return runs


def shade_modes(ax, runs, **kw) -> set[int]:
    """Shade the background of ``ax`` by contact mode over ``runs`` (from :func:`mode_runs`).

    ``kw`` goes to ``axvspan`` (e.g. ``alpha``).  Returns the mode codes drawn (runs of positive
    length).
    """
    drawn: set[int] = set()
    for a, b, m in runs:
        if b > a:
            ax.axvspan(a, b, color=mode_color(m), lw=0, zorder=0, **kw)
            drawn.add(int(m))
    return drawn


def plot_friction_limits(ax, t, robot: Robot | Chain, f_n1, f_n2, *, colors=("C0", "C3"),
                         lw: float | None = None,
                         scale: float = 1.0,
                         labels=(r"$\pm\mu_1 f_{n1}$", r"$\pm\mu_2 f_{n2}$")) -> None:
    """The friction limits +-mu1 f_n1 and +-mu2 f_n2 as dashed lines over ``t``.

    ``f_n1``, ``f_n2``: normal forces [N]; ``scale``: factor of the plotted force (1e3: mN);
    ``lw``: line width (None: matplotlib's default); ``colors``, ``labels``: per foot (the label
    goes to the + line only).
    """
    for mu, fn, color, label in zip((robot.mu1, robot.mu2), (f_n1, f_n2), colors, labels):
        lim = mu * np.asarray(fn, float) * scale
        ax.plot(t, lim, color=color, ls="--", lw=lw, label=label)
        ax.plot(t, -lim, color=color, ls="--", lw=lw)


def robot_points(robot: Robot, x1: float, x2: float, phi1: float, theta: float) -> np.ndarray:
    """Foot 1, joint 1, joint 2, foot 2 in the sagittal plane [m], shape (2, 4).

    J1 = (x1 - l cos a, l sin a) with a = phi1 - theta, J2 = J1 + beta l (cos theta, sin theta),
    foot 2 at (x2, 0).
    """
    l = robot.l
    a = phi1 - theta
    j1 = np.array([x1 - l * np.cos(a), l * np.sin(a)])
    j2 = j1 + robot.beta * l * np.array([np.cos(theta), np.sin(theta)])
    return np.stack([[x1, 0.0], j1, j2, [x2, 0.0]], axis=1)


def chain_points(chain: Chain, x1: float, phi) -> np.ndarray:
    """Foot 1, the joints and foot 2 of a chain in the sagittal plane [m], shape (2, n + 1): from
    foot 1 at (x1, 0) along each link's direction alpha_i (its kinematics at the joint angles
    ``phi`` [rad])."""
    from ocp_crawl.model.chain_model import ChainModel

    kin = ChainModel(chain).kinematics(np.asarray(phi, float))
    alpha = np.array([float(kin[f"alpha{i}"]) for i in range(1, chain.n + 1)])
    steps = np.asarray(chain.lengths) * np.stack([np.cos(alpha), np.sin(alpha)])
    return np.concatenate([[[x1], [0.0]], [[x1], [0.0]] + np.cumsum(steps, axis=1)], axis=1)


def shape_points(robot: Robot | Chain, x1: float, x2: float, phi, theta: float) -> np.ndarray:
    """Foot 1, the joints and foot 2 [m] of either robot, shape (2, joints + 2): the three-link
    robot's from :func:`robot_points`, a chain's from :func:`chain_points` (its joint angles
    ``phi`` [rad]; ``x2`` and ``theta`` follow from them)."""
    if isinstance(robot, Chain):
        return chain_points(robot, x1, phi)
    return robot_points(robot, x1, x2, float(np.asarray(phi)[0]), theta)


def _gait_title(result: CrawlResult) -> str:
    title = f"{result.drive} drive, {result.gravity} gravity: {result.status_name}"
    if np.isfinite(result.S):
        title += (f"\nS = {units.distance(result.S, 2)} per cycle (S < 0: towards foot 1), "
                  f"W$^+$ = {units.work(result.W_plus, 1)}, CoT$^+$ = {units.cot(result.CoT_plus)}")
    if result.failure_t is not None:
        title += f" at t = {result.failure_t:.4f}"
    return title


def plot_gait(result: CrawlResult, robot: Robot | Chain,
              path: str | os.PathLike | None = None, *, reference: PeriodicSignal | None = None,
              snapshots: int = 5, title: str | None = None) -> Figure:
    """Three panels over the phase of the reported cycle, background shaded by contact mode.

    (a) joint angles phi1, phi2 [deg] (a chain: every joint's; and the reference angles if
    ``reference`` is given),
    (b) contact positions x1, x2 [mm], (c) ``snapshots`` robot configurations drawn in gray,
    (d) tangential force f_t [N] with the friction limits +-mu1 f_n1 and +-mu2 f_n2 dashed.
    The title gives S [mm], W+ [mJ] and CoT+; the legend names and explains every contact mode.

    Failed runs are drawn up to the failure.  If ``path`` is given the figure is also saved there
    (format from the suffix, e.g. .png or .pdf; written atomically).  Returns the figure.
    """
    fig = Figure(figsize=(7.0, 9.0), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(4, 1, gridspec_kw={"height_ratios": [1.0, 1.0, 0.8, 1.0]})
    ax_a, ax_b, ax_s, ax_c = axes
    t = np.asarray(result.t, float)
    phase = t - result.t0
    fig.suptitle(_gait_title(result) if title is None else title)
    if t.size == 0:
        for ax in axes:
            ax.text(0.5, 0.5, "no samples", ha="center", va="center", transform=ax.transAxes)
        _save(fig, path)
        return fig

    runs = mode_runs(phase, result.mode)
    for ax in (ax_a, ax_b, ax_c):
        shade_modes(ax, runs)
        ax.set_xlim(phase[0], max(phase[-1], phase[0] + 1e-9))
        ax.set_xlabel("phase t [cycles]")
        ax.grid(True, lw=0.3, alpha=0.6)
    _draw_angles(ax_a, result, phase, reference)
    # positions relative to foot 1 at the start of the plotted cycle, so that x1(end) = S
    origin = float(np.asarray(result.x1, float)[0])
    _draw_positions(ax_b, result, phase, origin)
    _draw_snapshots(ax_s, result, robot, phase, origin, snapshots)
    _draw_forces(ax_c, result, robot, phase)
    handles, labels = ax_c.get_legend_handles_labels()
    patches, names = mode_legend(m for a, b, m in runs if b > a)
    # below the panels: inside (d) the legend would hide the force at the friction limits
    fig.legend(handles + patches, labels + names, loc="outside lower center", fontsize="small",
               ncol=2)
    # lay out once and freeze: constrained layout would otherwise rerun (slowly) at every save
    fig.draw_without_rendering()
    fig.set_layout_engine("none")
    _save(fig, path)
    return fig


def joint_colors(m: int) -> list[str]:
    """A colour per joint: C0 and C3 for the three-link robot's two (as its feet), C0, C1, ... for
    a chain's."""
    return ["C0", "C3"] if m == 2 else [f"C{j % 10}" for j in range(m)]


def _draw_angles(ax, result: CrawlResult, phase, reference: PeriodicSignal | None) -> None:
    phi = np.degrees(np.asarray(result.phi, float))
    colors = joint_colors(phi.shape[0])
    for j, color in enumerate(colors):
        ax.plot(phase, phi[j], color=color, label=rf"$\varphi_{j + 1}$")
    # the angles drive prescribes phi = phi_ref: the reference would only hide under the angles
    if reference is not None and result.drive != "angles":
        ref = np.degrees(np.asarray(reference(np.asarray(result.t, float)), float))
        ref = ref.reshape(len(colors), -1)
        for j, color in enumerate(colors):
            ax.plot(phase, ref[j], color=color, ls=":",
                    label=rf"$\varphi_{{{j + 1},\mathrm{{ref}}}}$")
    ax.set_ylabel("joint angle [deg]")
    ax.set_title("(a) joint angles", loc="left", fontsize="medium")
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize="small", frameon=False)


def _draw_positions(ax, result: CrawlResult, phase, origin: float) -> None:
    ax.plot(phase, 1e3 * (np.asarray(result.x1, float) - origin), color="C0",
            label="$x_1$ (foot 1)")
    ax.plot(phase, 1e3 * (np.asarray(result.x2, float) - origin), color="C3",
            label="$x_2$ (foot 2)")
    ax.set_ylabel("contact position [mm]")
    ax.set_title("(b) contact positions", loc="left", fontsize="medium")
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize="small", frameon=False)


def _draw_forces(ax, result: CrawlResult, robot: Robot | Chain, phase) -> None:
    ax.plot(phase, np.asarray(result.f_t, float), color="k", label="$f_t$")
    plot_friction_limits(ax, phase, robot, result.f_n1, result.f_n2, lw=1.0)
    ax.set_ylabel("tangential force [N]\n($f_t$ on foot 1, along +x)")
    ax.set_title("(d) tangential force and friction limits", loc="left", fontsize="medium")


def _draw_snapshots(ax, result: CrawlResult, robot: Robot | Chain, phase, origin: float,
                    n: int) -> None:
    ax.set_title("(c) robot snapshots (later is darker)", loc="left", fontsize="medium")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("z [mm]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.axhline(0.0, color="k", lw=0.8)
    if n <= 0:
        return
    span = phase[-1] - phase[0]
    # equally spaced phases including both ends: the last snapshot repeats the first shape shifted
    # by S
    targets = phase[0] + span * np.arange(n) / max(n - 1, 1) if span > 0 else phase[:1]
    idx = sorted({int(np.argmin(np.abs(phase - s))) for s in targets})
    phi = np.asarray(result.phi, float)
    for j, i in enumerate(idx):
        pts = 1e3 * shape_points(robot, result.x1[i] - origin, result.x2[i] - origin, phi[:, i],
                                 result.theta[i])
        gray = 0.75 - 0.6 * j / max(len(idx) - 1, 1)
        ax.plot(pts[0], pts[1], "-o", color=str(gray), lw=1.5, ms=2.5, label=f"t = {phase[i]:.2f}")
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize="x-small", frameon=False)


def save_figure(fig: Figure, path: str | os.PathLike) -> Path:
    """Save atomically; the format follows the suffix (.png, .pdf, .svg; none: png)."""
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower() or "png"
    return atomic_write(path, lambda fh: fig.savefig(fh, format=fmt, dpi=150))


def _save(fig: Figure, path) -> None:
    if path is not None:
        save_figure(fig, path)
