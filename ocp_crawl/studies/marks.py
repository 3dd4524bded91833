"""What the study figures share (:mod:`ocp_crawl.studies.gait_plots`,
:mod:`ocp_crawl.studies.plots`): a figure on the Agg canvas whose layout is frozen once drawn, the
paper's two colours, the name of a gravity convention; failed points as markers whose shape names
the status, values above an axis's top as arrows, curves broken at failed points, log axes with
plain tick labels, and stiffnesses k/(M g L) of the paper's robot in N m/rad."""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from ocp_crawl.studies.common import PAPER_ROBOT, SUCCESS

#: marker of each failure status (others: FALLBACK_MARKER)
STATUS_MARKERS = {"fold": "X", "lift_off": "^", "joint_on_ground": "v", "no_start": "s",
                  "bad_input": "d", "no_consistent_mode": "D", "feet_crossed": "P",
                  "no_convergence": "*", "not_periodic": "p", "error": "h", "unstable": "<",
                  "snap_through": ">", "energy_imbalance": "H", "set_valued": "8"}
FALLBACK_MARKER = "o"
#: legend text of statuses whose name alone would mislead
STATUS_LABELS = {"no_start": "no equilibrium to start from", "unstable": "unstable equilibrium",
                 "snap_through": "snap-through (state jumps)",
                 "set_valued": "set-valued (friction tie)"}
#: colour of failure markers on maps
FAIL_COLOR = "#b2182b"
#: the paper's colours: joint/foot 1 blue, joint/foot 2 purple
BLUE = (0.0, 0.447, 0.741)
PURPLE = (0.494, 0.184, 0.556)


def _figure(size: tuple[float, float], rows: int = 1, cols: int = 1, **kw):
    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.subplots(rows, cols, squeeze=False, **kw)


def _finish(fig: Figure) -> Figure:
    # lay out once and freeze: constrained layout would otherwise rerun (slowly) at every save
    fig.draw_without_rendering()
    fig.set_layout_engine("none")
    return fig


def _gravity_text(gravity: str) -> str:
    return "paper's printed gravity sign" if gravity == "paper" else "physical gravity sign"


def plain_log_ticks(axis) -> None:
    """Ticks of a log ``axis`` (``ax.xaxis``/``ax.yaxis``) at 1, 2 and 5 per decade, labelled as
    plain numbers (0.5, 2, 40) instead of matplotlib's 2x10^0 ... 4x10^1."""
    axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())


def mark_failures(ax, x, y, status, *, color="0.3", size=36,
                  seen: set | None = None) -> list[Line2D]:
    """Markers at the failed points (x, y) of ``status``; returns legend handles for the statuses
    not in ``seen`` yet (and adds them to it)."""
    x, y, status = np.asarray(x, float), np.asarray(y, float), np.asarray(status)
    handles = []
    seen = set() if seen is None else seen
    for name in sorted(set(status.ravel()) - {SUCCESS}):
        sel = status == name
        marker = STATUS_MARKERS.get(str(name), FALLBACK_MARKER)
        face = color if marker in "X*" else "none"
        ax.scatter(x[sel], y[sel], marker=marker, s=size, facecolor=face, edgecolor=color,
                   linewidths=1.0, zorder=5, clip_on=False)
        if name not in seen:
            seen.add(name)
            text = STATUS_LABELS.get(str(name), str(name).replace("_", " "))
            handles.append(Line2D([], [], ls="none", marker=marker, color=color, mfc=face,
                                  label=f"{text} ({int(sel.sum())})"))
    return handles


def successful(y, status) -> np.ndarray:
    """``y`` with NaN at the failed points: a curve breaks there instead of joining the points
    either side."""
    return np.where(np.asarray(status) == SUCCESS, np.asarray(y, float), np.nan)


def mark_off_axis(ax, x, y, top: float, colors, below: dict | None = None, tag: str = "") -> None:
    """An arrow with the value at every point of ``y`` (rows: the curves, coloured ``colors`` in
    turn) above ``top``, the top of the axis; the values at one x are stacked downwards (``below``:
    how many are there already at each x, shared by the calls for one axes), the first with the
    arrow; ``tag`` follows each value (e.g. " (paper)")."""
    y = np.atleast_2d(np.asarray(y, float))
    below = {} if below is None else below
    for i, j in zip(*np.nonzero(np.isfinite(y) & (y > top))):
        color = colors[i % len(colors)]
        below[x[j]] = below.get(x[j], 0) + 1
        arrow = {"arrowstyle": "->", "color": color} if below[x[j]] == 1 else None
        ax.annotate(f"{y[i, j]:.0f}{tag}", (x[j], top), xytext=(0, -12 * below[x[j]]),
                    textcoords="offset points", ha="center", va="top", fontsize="x-small",
                    color=color, arrowprops=arrow)


def stiffness_text(ratio: float) -> str:
    """A stiffness k/(M g L) as a stiffness of the paper's robot, "k = 0.00614 N m/rad (0.100 M g
    L)", or "none found" when it is NaN."""
    if not np.isfinite(ratio):
        return "none found"
    return f"k = {ratio * PAPER_ROBOT.MgL:.3g} N m/rad ({ratio:.3f} M g L)"


def stiffness_axis(ax) -> None:
    """A top axis of ``ax`` (whose x is k/(M g L)) in the paper robot's stiffness k [N m/rad]."""
    mgl = PAPER_ROBOT.MgL
    top = ax.secondary_xaxis("top", functions=(lambda r: r * mgl, lambda k: k / mgl))
    top.set_xlabel(f"stiffness k [N m/rad] (M g L = {mgl:.4f} N m)")
    plain_log_ticks(top.xaxis)


__all__ = ["STATUS_MARKERS", "STATUS_LABELS", "FAIL_COLOR", "BLUE", "PURPLE", "plain_log_ticks",
           "mark_failures", "successful", "mark_off_axis", "stiffness_text", "stiffness_axis"]
