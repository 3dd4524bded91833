"""Figures of the paper's studies (:mod:`ocp_crawl.studies`), one function per figure.

Every function returns a :class:`matplotlib.figure.Figure` on the Agg canvas (no pyplot state).
Where a figure compares with the paper, the vertical axis is the progress per cycle -S: the
paper plots forward progress, and with psi > 0 the robot moves towards foot 1 (S < 0).  Points
at which a run failed are drawn as markers whose shape names the status (fold, lift-off, ...),
so that failures read as data and not as gaps.
"""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import BoundaryNorm
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Rectangle
from matplotlib.ticker import MaxNLocator

from ocp_crawl.sim.result import CrawlResult
from ocp_crawl.studies.common import COT_K_LABELS, MM, SUCCESS
from ocp_crawl.studies.cot import AmplitudeStudy, HigherFriction, StiffnessStudy
from ocp_crawl.studies.gaits import FrictionBand, GaitComparison, PsiGammaMap
from ocp_crawl.studies.marks import (FAIL_COLOR, mark_failures, mark_off_axis, plain_log_ticks,
                                     stiffness_axis, stiffness_text, successful)
from ocp_crawl.studies.pressure import PressureStudy
from ocp_crawl.viz.gait import mode_legend, mode_runs, plot_friction_limits, robot_points, shade_modes

#: the paper's colours: joint/foot 1 blue, joint/foot 2 purple
BLUE = (0.0, 0.447, 0.741)
PURPLE = (0.494, 0.184, 0.556)
#: line styles of the gait comparison: prescribed angles, realistic stiffness, low stiffness
RUN_STYLES = ("-", "--", ":")
#: colours of the three stiffnesses of the CoT figure (large, realistic, low), as in the paper
K_COLORS = (BLUE, "black", PURPLE)
K_STYLES = ("-", "--", ":")
#: top of the CoT+ axis, as in the paper's Fig. CoT
COT_YMAX = 60.0


def _figure(size: tuple[float, float], rows: int = 1, cols: int = 1, **kw):
    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.subplots(rows, cols, squeeze=False, **kw)


def _finish(fig: Figure) -> Figure:
    # lay out once and freeze: constrained layout would otherwise rerun (slowly) at every save
    fig.draw_without_rendering()
    fig.set_layout_engine("none")
    return fig


def side_legend(ax, handles: list) -> None:
    """The legend of ``ax`` right of it, off the curves."""
    ax.legend(handles=handles, fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0),
              borderaxespad=0.0, handlelength=3.0)


def _gravity_text(gravity: str) -> str:
    return "paper's printed gravity sign" if gravity == "paper" else "physical gravity sign"


def _run_label(name: str, res: CrawlResult) -> str:
    if res.success:
        return f"{name}: $S$ = {MM * res.S:.1f} mm"
    return f"{name}: {res.status_name.replace('_', ' ')} at t = {res.failure_t:.3f}"


def _phase(res: CrawlResult) -> np.ndarray:
    return np.asarray(res.t, float) - res.t0


# --------------------------------------------------------------------------------------------
# Fig. simu_conf and simu_forces
# --------------------------------------------------------------------------------------------
def _comparison_runs(gc: GaitComparison) -> list[tuple[str, CrawlResult, str]]:
    names = ["prescribed angles"] + [f"torque, k = {r:.2f} M g L" for r in gc.k_ratios]
    return list(zip(names, (gc.prescribed,) + gc.torque, RUN_STYLES))


def plot_configuration(gc: GaitComparison, snapshots: int = 5) -> Figure:
    """Fig. simu_conf: joint angles, contact positions and robot snapshots over one cycle.

    Prescribed angles solid, torque drive at realistic stiffness dashed and at low stiffness
    dotted; snapshots (gray, darker later) of the prescribed-angle gait as in the paper.
    """
    fig, ax = _figure((8.0, 9.0), 3, 1, gridspec_kw={"height_ratios": [1.0, 1.0, 0.9]})
    ax_a, ax_b, ax_s = ax[:, 0]
    runs = _comparison_runs(gc)
    fig.suptitle(fr"Configuration over a cycle: $\gamma$ = 90, $A$ = 30, $\psi$ = 45 deg ({_gravity_text(gc.gravity)})"
                 "\n$S$ per cycle ($S$ < 0: towards foot 1):\n" + "; ".join(
                     f"{name.replace('torque, ', '')}: "
                     + (f"{MM * res.S:.1f} mm" if res.success
                        else res.status_name.replace("_", " "))
                     for name, res, _ in runs))
    handles = []
    for name, res, ls in runs:
        if res.t.size == 0:
            continue
        t = _phase(res)
        phi = np.degrees(res.phi)
        ax_a.plot(t, phi[0], color=BLUE, ls=ls)
        ax_a.plot(t, phi[1], color=PURPLE, ls=ls)
        origin = res.x1[0]
        ax_b.plot(t, MM * (res.x1 - origin), color=BLUE, ls=ls)
        ax_b.plot(t, MM * (res.x2 - origin), color=PURPLE, ls=ls)
        if not res.success:
            for a in (ax_a, ax_b):
                a.plot([t[-1]] * 2, [phi[0, -1], phi[1, -1]] if a is ax_a else
                       [MM * (res.x1[-1] - origin), MM * (res.x2[-1] - origin)], "X", color="0.2", ms=8)
        handles.append(Line2D([], [], color="0.2", ls=ls, label=_run_label(name, res)))
    handles += [Line2D([], [], color=BLUE, label=r"$\varphi_1$, $x_1$ (joint/foot 1)"),
                Line2D([], [], color=PURPLE, label=r"$\varphi_2$, $x_2$ (joint/foot 2)")]
    if any(not r.success for r in gc.torque):
        handles.append(Line2D([], [], ls="none", marker="X", color="0.2", label="run stops (failure)"))
    for a in (ax_a, ax_b):
        a.set_xlim(0, 1)
        a.set_xlabel("phase t/T [cycles]")
        a.grid(True, lw=0.3, alpha=0.6)
    ax_a.set_ylabel("joint angle [deg]")
    ax_a.set_title("(a) joint angles", loc="left", fontsize="medium")
    ax_b.set_ylabel("contact position [mm]")
    ax_b.set_title("(b) contact positions (from foot 1 at t = 0)", loc="left", fontsize="medium")
    # below the panels: inside (a) the legend would hide the curves
    fig.legend(handles=handles, fontsize="small", loc="outside lower center", ncol=2)
    _snapshots(ax_s, gc.prescribed, gc.robot, snapshots)
    return _finish(fig)


def _snapshots(ax, res: CrawlResult, robot, n: int) -> None:
    ax.set_title("(c) snapshots of the prescribed-angle gait (gray: later is darker)", loc="left", fontsize="medium")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("z [mm]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.axhline(0.0, color="k", lw=0.8)
    t = _phase(res)
    origin = res.x1[0]
    for j, target in enumerate(np.linspace(0.0, 1.0, n)):
        i = int(np.argmin(np.abs(t - target)))
        pts = MM * robot_points(robot, res.x1[i] - origin, res.x2[i] - origin, res.phi[0, i], res.theta[i])
        gray = str(0.8 - 0.65 * j / max(n - 1, 1))
        ax.plot(pts[0], pts[1], "-o", color=gray, lw=1.5, ms=3, label=f"t/T = {t[i]:.2f}")
    # the phases in a legend beside the axes: as text above the robots they overlap, and leave
    # the axes at the top
    ax.legend(title="snapshot at", title_fontsize="x-small", loc="center left",
              bbox_to_anchor=(1.01, 0.5), fontsize="x-small", frameon=False)


def plot_forces(gc: GaitComparison) -> Figure:
    """Fig. simu_forces: f_t and the friction limits, prescribed angles and the hybrid solution.

    Background: contact mode (gray = stick-stick), so the hybrid's intermediate sticking phase
    shows between the slip phases.
    """
    runs = [("prescribed angles", gc.prescribed, gc.robot)] + \
        [(f"hybrid, k = {r:.2f} M g L", res, gc.robot_at(i)) for i, (r, res) in enumerate(zip(gc.k_ratios, gc.torque))]
    fig, ax = _figure((8.0, 3.0 * len(runs)), len(runs), 1, sharex=True)
    jumps = ", ".join(f"{name.split(',')[0]} {gc.force_jump(res):.2g} N" for name, res, _ in runs[:2])
    fig.suptitle(f"Tangential force and friction limits ({_gravity_text(gc.gravity)})\n"
                 f"largest jump of $f_t$ at an event: {jumps}")
    modes_seen: set[int] = set()
    for (name, res, robot), a, letter in zip(runs, ax[:, 0], "abcdef"):
        a.set_title(f"({letter}) {_run_label(name, res)}", loc="left", fontsize="medium")
        a.grid(True, lw=0.3, alpha=0.6)
        a.set_ylabel("force [N]\n($f_t$ on foot 1, along +x)")
        if res.t.size == 0:
            continue
        t = _phase(res)
        modes_seen |= shade_modes(a, mode_runs(t, res.mode))
        a.plot(t, res.f_t, color="k", lw=1.6)
        plot_friction_limits(a, t, robot, res.f_n1, res.f_n2, colors=(BLUE, PURPLE), lw=1.1, labels=(None, None))
        if not res.success:
            a.plot(t[-1], res.f_t[-1], "X", color="0.2", ms=8)
    ax[-1, 0].set_xlabel("phase t/T [cycles]")
    ax[-1, 0].set_xlim(0, 1)
    handles = [Line2D([], [], color="k", label="$f_t$ (on foot 1, along +x)"),
               Line2D([], [], color=BLUE, ls="--", label=r"$\pm\mu_1 f_{n1}$"),
               Line2D([], [], color=PURPLE, ls="--", label=r"$\pm\mu_2 f_{n2}$")]
    patches, names = mode_legend(modes_seen)
    fig.legend(handles=handles + patches, labels=[h.get_label() for h in handles] + names, loc="outside lower center",
               ncol=2, fontsize="small")
    return _finish(fig)


# --------------------------------------------------------------------------------------------
# Fig. parametric
# --------------------------------------------------------------------------------------------
def _cell_edges(v: np.ndarray) -> np.ndarray:
    """Edges of the cells centred on the grid values v (half-way between neighbours)."""
    v = np.asarray(v, float)
    if v.size == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])


def plot_parametric(m: PsiGammaMap) -> Figure:
    """Fig. parametric: progress -S [mm] over (psi, gamma), one coloured cell per grid point (no
    interpolation); failed points as hatched cells, marked by status; the best gamma at each psi and the
    largest progress (also in the title)."""
    fig, ax = _figure((8.0, 6.8))
    a = ax[0, 0]
    prog = MM * m.progress
    finite = prog[np.isfinite(prog)]
    xe, ye = _cell_edges(m.psi_deg), _cell_edges(m.gamma_deg)
    levels = MaxNLocator(14).tick_values(min(0.0, finite.min()), finite.max()) if finite.size else np.arange(11.0)
    norm = BoundaryNorm(levels, ncolors=256)
    mesh = a.pcolormesh(xe, ye, np.ma.masked_invalid(prog), cmap="viridis", norm=norm, shading="flat")
    fig.colorbar(mesh, ax=a, label="progress per cycle $-S$ [mm] (towards foot 1)")
    handles = []
    failed = m.status != SUCCESS
    if failed.any():
        for i, j in zip(*np.nonzero(failed)):
            a.add_patch(Rectangle((xe[j], ye[i]), xe[j + 1] - xe[j], ye[i + 1] - ye[i], facecolor="white",
                                  edgecolor="0.45", hatch="///", lw=0.0, zorder=3))
        handles.append(Patch(facecolor="white", edgecolor="0.45", hatch="///", label="failed point (its cell)"))
        P, G = np.meshgrid(m.psi_deg, m.gamma_deg)
        handles += mark_failures(a, P, G, m.status, color=FAIL_COLOR, size=30)
    a.set_xlim(xe[0], xe[-1])
    a.set_ylim(ye[0], ye[-1])
    a.plot(m.psi_deg, m.gamma_opt, "w--", lw=1.5, zorder=4)
    handles.append(Line2D([], [], color="0.2", ls="--", label=r"best $\gamma$ at each $\psi$ (white)"))
    g, p, s = m.best
    a.plot(p, g, "*", color="orange", ms=14, mec="k", zorder=6)
    handles.append(Line2D([], [], ls="none", marker="*", color="orange", mec="k", ms=10,
                          label=rf"largest: {MM * -s:.1f} mm at $\psi$ = {p:g}, $\gamma$ = {g:g} deg"))
    a.set_xlabel(r"phase difference $\psi$ [deg]")
    a.set_ylabel(r"nominal joint angle $\gamma$ [deg]")
    n_failed = int(failed.sum())
    fig.suptitle(rf"Progress per cycle over $\psi$ and $\gamma$, $A$ = {m.A_deg:g} deg ({_gravity_text(m.gravity)})"
                 "\n" + rf"largest $-S$ = {MM * -s:.1f} mm at $\psi$ = {p:g}, $\gamma$ = {g:g} deg; "
                 f"{n_failed} of {failed.size} points failed")
    fig.legend(handles=handles, fontsize="small", loc="outside lower center", ncol=2)
    return _finish(fig)


# --------------------------------------------------------------------------------------------
# Fig. d_mu
# --------------------------------------------------------------------------------------------
def plot_friction_band(b: FrictionBand) -> Figure:
    """Fig. d_mu: S against psi (negative psi included) with the friction band and its average."""
    fig, ax = _figure((8.0, 5.0))
    a = ax[0, 0]
    lo, hi = b.band
    a.fill_between(b.psi_deg, -MM * hi, -MM * lo, color=BLUE, alpha=0.25, lw=0,
                   label=fr"$\mu_1/\mu_2 \in [{1 - b.eps:g}, {1 + b.eps:g}]$ ({len(b.ratios)} ratios)")
    a.plot(b.psi_deg, -MM * b.nominal, color=BLUE, lw=2, label=r"$\mu_1 = \mu_2$")
    a.plot(b.psi_deg, -MM * b.average, "k--", lw=2, label="average over the ratios")
    psi_opt, prog = b.psi_opt
    if np.isfinite(psi_opt):
        a.plot([psi_opt], [MM * prog], "o", color="orange", mec="k", zorder=6,
               label=fr"best average: $\psi$ = {psi_opt:.1f} deg, $-S$ = {MM * prog:.1f} mm")
        psi_n, s_n = b.psi_opt_negative
        if np.isfinite(psi_n):
            a.plot([psi_n], [-MM * s_n], "o", color="orange", mec="k", zorder=6)
    handles, labels = a.get_legend_handles_labels()
    fails = mark_failures(a, np.broadcast_to(b.psi_deg, b.S.shape), np.zeros(b.S.shape), b.status)
    a.axhline(0, color="0.4", lw=0.6)
    a.set_xlim(-180, 180)
    a.set_xticks(np.arange(-180, 181, 45))
    a.set_xlabel(r"phase difference $\psi$ [deg]")
    a.set_ylabel("progress towards foot 1 per cycle, $-S$ [mm]")
    best = (fr"best average $-S$ = {MM * prog:.1f} mm at $\psi$ = {psi_opt:.1f} deg" if np.isfinite(psi_opt)
            else "no best average")
    fig.suptitle(fr"Friction sensitivity, $\gamma$ = 90, $A$ = 30 deg ({_gravity_text(b.gravity)})" "\n"
                 fr"{best}; $\mu_1/\mu_2 \in [{1 - b.eps:g}, {1 + b.eps:g}]$")
    a.grid(True, lw=0.3, alpha=0.6)
    a.legend(handles=handles + fails, fontsize="small", loc="lower right")
    return _finish(fig)


# --------------------------------------------------------------------------------------------
# Fig. CoT and S against A
# --------------------------------------------------------------------------------------------
def _k_label(i: int, ratio: float) -> str:
    name = COT_K_LABELS[i] if i < len(COT_K_LABELS) else ""
    return f"{name} k = {ratio:.2f} M g L".strip()


def plot_amplitude(s: AmplitudeStudy, overlay_paper: bool | None = None) -> Figure:
    """S against A, and Fig. CoT: CoT+ against A, for each stiffness.

    ``overlay_paper``: draw the paper's published CoT+ values (default: in the paper's gravity
    convention only, the one they were computed in).
    """
    overlay = (s.gravity == "paper") if overlay_paper is None else overlay_paper
    comparison = s.paper_comparison() if overlay else None
    fig, ax = _figure((11.0, 8.0), 2, 1, sharex=True)
    a_s, a_c = ax[:, 0]
    least = ", ".join(f"{COT_K_LABELS[i]} k {s.CoT_min[i]:.1f}" + (f" at {s.A_opt[i]:.0f} deg"
                                                                   if np.isfinite(s.A_opt[i]) else " (grid end)")
                      for i in range(len(s.k_ratios)) if np.isfinite(s.CoT_min[i]))
    fig.suptitle(rf"Amplitude study, $\gamma$ = 90, $\psi$ = 45 deg ({_gravity_text(s.gravity)})"
                 + (f"\nleast CoT$^+$ over $A$: {least}" if least else ""))
    seen: set = set()
    fails, fails_c, seen_c = [], [], set()
    for i, k in enumerate(s.k_ratios):
        color, ls = K_COLORS[i % 3], K_STYLES[i % 3]
        a_s.plot(s.A_deg, successful(-MM * s.S[i], s.status[i]), color=color, ls=ls, lw=2,
                 marker=".", label=_k_label(i, k))
        a_c.plot(s.A_deg, successful(s.CoT_moving[i], s.status[i]), color=color, ls=ls, lw=2,
                 marker=".", label=_k_label(i, k))
        zeros = np.zeros(len(s.A_deg))
        fails += mark_failures(a_s, s.A_deg, zeros, s.status[i], color=color, seen=seen)
        fails_c += mark_failures(a_c, s.A_deg, zeros, s.status[i], color=color, seen=seen_c)
        if comparison is not None:
            a_c.plot(s.A_deg, comparison["paper"][i], "o", ms=6, mfc="none", mec=color,
                     label=f"paper, {COT_K_LABELS[i]} k")
    a_s.set_ylabel("progress per cycle $-S$ [mm]")
    a_s.set_title("(a) progress against amplitude", loc="left", fontsize="medium")
    side_legend(a_s, a_s.get_legend_handles_labels()[0] + fails)
    a_c.set_ylabel(r"CoT$^+ = W^+/(M g |S|)$ [-]")
    a_c.set_xlabel("amplitude $A$ [deg]")
    a_c.set_title("(b) positive cost of transport (Fig. CoT)" + (" with the paper's values (circles)" if comparison
                                                                is not None else ""), loc="left", fontsize="medium")
    # the paper's axis: CoT+ diverges where the robot barely moves (S -> 0 near the onset of motion)
    a_c.set_ylim(0, COT_YMAX)
    mark_off_axis(a_c, s.A_deg, s.CoT_moving, COT_YMAX, K_COLORS)
    side_legend(a_c, a_c.get_legend_handles_labels()[0] + fails_c)
    for a in (a_s, a_c):
        a.grid(True, lw=0.3, alpha=0.6)
    return _finish(fig)


# --------------------------------------------------------------------------------------------
# supplementary figure: higher friction
# --------------------------------------------------------------------------------------------
def plot_higher_friction(h: HigherFriction) -> Figure:
    """Supplementary figure: progress against psi for mu = factor x 0.389."""
    fig, ax = _figure((10.5, 5.0))
    a = ax[0, 0]
    colors = [BLUE, "tab:orange", "tab:green", "tab:red", "tab:brown", "tab:gray"]
    seen: set = set()
    fails = []
    for i, f in enumerate(h.factors):
        stop = h.psi_stop[i]
        extra = fr", stops from $\psi$ = {stop:.0f} deg" if np.isfinite(stop) else ""
        # markers at psi = 0 and 180 sit on the frame: not clipped
        a.plot(h.psi_deg, -MM * h.S[i], color=colors[i % len(colors)], lw=2 if f == 1 else 1.5, marker=".",
               clip_on=False, label=fr"$\mu$ = {f:g} $\times$ 0.389{extra}")
        fails += mark_failures(a, h.psi_deg, np.zeros(len(h.psi_deg)), h.status[i], color=colors[i % len(colors)],
                               seen=seen)
    a.set_xlim(0, 180)
    a.set_xticks(np.arange(0, 181, 30))
    a.set_xlabel(r"phase difference $\psi$ [deg]")
    a.set_ylabel("progress per cycle $-S$ [mm]")
    largest = ", ".join(f"{f:g}x {np.nanmax(-MM * h.S[i]):.1f}" for i, f in enumerate(h.factors)
                        if np.isfinite(h.S[i]).any())
    fig.suptitle(fr"Higher friction, $\gamma$ = 90, $A$ = 30 deg ({_gravity_text(h.gravity)})" "\n"
                 fr"largest $-S$ [mm] per friction factor: {largest or 'none'}")
    a.grid(True, lw=0.3, alpha=0.6)
    side_legend(a, a.get_legend_handles_labels()[0] + fails)
    return _finish(fig)


# --------------------------------------------------------------------------------------------
# stiffness
# --------------------------------------------------------------------------------------------
def plot_stiffness(s: StiffnessStudy) -> Figure:
    """Progress and CoT+ against k/(M g L); failed points marked by status, the threshold as a line.  The
    title gives the friction threshold and the largest progress."""
    fig, ax = _figure((11.0, 7.5), 2, 1, sharex=True)
    a_s, a_c = ax[:, 0]
    prog = -MM * np.asarray(s.S, float)
    best = f"largest $-S$ = {np.nanmax(prog):.1f} mm" if np.isfinite(prog).any() else "no successful point"
    fig.suptitle(rf"Stiffness, $\gamma$ = 90, $A$ = 30, $\psi$ = 45 deg ({_gravity_text(s.gravity)})" "\n"
                 f"friction threshold {stiffness_text(s.threshold)}; {best}")
    a_s.semilogx(s.k_ratios, prog, color=BLUE, lw=2, marker=".", label="$-S$")
    fails = mark_failures(a_s, s.k_ratios, np.zeros(len(s.k_ratios)), s.status)
    a_c.loglog(s.k_ratios, np.where(s.stuck, np.nan, s.CoT_plus), color="k", lw=2, marker=".",
               label="CoT$^+$ (moving points)")
    lines = []
    if np.isfinite(s.threshold):
        for a in (a_s, a_c):
            a.axvline(s.threshold, color="tab:red", ls="--", lw=1.2)
        lines.append(Line2D([], [], color="tab:red", ls="--",
                            label=f"friction threshold {stiffness_text(s.threshold)}"))
    if np.isfinite(s.onset) and not abs(s.onset - s.threshold) < 1e-3:
        for a in (a_s, a_c):
            a.axvline(s.onset, color="tab:green", ls=":", lw=1.5)
        lines.append(Line2D([], [], color="tab:green", ls=":",
                            label=f"crawls at every stiffness from {stiffness_text(s.onset)}"))
    a_s.set_ylabel("progress per cycle $-S$ [mm]")
    a_s.set_title("(a) progress", loc="left", fontsize="medium")
    side_legend(a_s, a_s.get_legend_handles_labels()[0] + lines + fails)
    a_c.set_ylabel("CoT$^+$ [-]")
    a_c.set_xlabel("stiffness $k/(M g L)$ [-]")
    a_c.set_title("(b) positive cost of transport", loc="left", fontsize="medium")
    side_legend(a_c, a_c.get_legend_handles_labels()[0] + lines)
    for a in (a_s, a_c):
        a.grid(True, which="both", lw=0.3, alpha=0.6)
        plain_log_ticks(a.xaxis)
    plain_log_ticks(a_c.yaxis)
    stiffness_axis(a_s)
    return _finish(fig)


def plot_conventions(stiff: dict[str, StiffnessStudy], amp: dict[str, AmplitudeStudy]) -> Figure:
    """The two gravity conventions side by side: progress against k, and CoT+ against A."""
    fig, ax = _figure((11.0, 8.0), 2, 1)
    a_s, a_c = ax[:, 0]
    thresholds = "; ".join(f"{g} {stiffness_text(st.threshold)}" for g, st in stiff.items())
    fig.suptitle("Gravity conventions: paper's printed sign (solid) vs physical sign (dashed)"
                 + (f"\nfriction thresholds: {thresholds}" if thresholds else ""))
    seen: set = set()
    fails, fails_c, seen_c, below = [], [], set(), {}
    for gravity, ls, color in (("paper", "-", BLUE), ("physical", "--", "tab:red")):
        if gravity in stiff:
            s = stiff[gravity]
            a_s.semilogx(s.k_ratios, -MM * s.S, color=color, ls=ls, lw=2, marker=".", label=f"{gravity}")
            fails += mark_failures(a_s, s.k_ratios, np.full(len(s.k_ratios), -2.0 if gravity == "physical" else 0.0),
                                   s.status, color=color, seen=seen)
        if gravity in amp:
            am = amp[gravity]
            for i, k in enumerate(am.k_ratios):
                c = K_COLORS[i % 3]
                a_c.plot(am.A_deg, successful(am.CoT_moving[i], am.status[i]), color=c, ls=ls,
                         lw=1.8, marker=".", label=f"{gravity}, {_k_label(i, k)}")
                # failures at zero, the physical sign's just below, as in (a)
                at = np.full(len(am.A_deg), -2.0 if gravity == "physical" else 0.0)
                fails_c += mark_failures(a_c, am.A_deg, at, am.status[i], color=c, seen=seen_c)
            mark_off_axis(a_c, am.A_deg, am.CoT_moving, COT_YMAX, K_COLORS, below, f" ({gravity})")
    a_s.set_xlabel("stiffness $k/(M g L)$ [-]")
    a_s.set_ylabel("progress per cycle $-S$ [mm]")
    plain_log_ticks(a_s.xaxis)
    a_s.set_title(r"(a) progress against stiffness ($\gamma$ = 90, $A$ = 30, $\psi$ = 45 deg)", loc="left",
                  fontsize="medium")
    side_legend(a_s, a_s.get_legend_handles_labels()[0] + fails)
    a_c.set_xlabel("amplitude $A$ [deg]")
    a_c.set_ylabel("CoT$^+$ [-]")
    a_c.set_ylim(-3.5 if fails_c else 0.0, COT_YMAX)
    a_c.set_title(r"(b) CoT$^+$ against amplitude ($\gamma$ = 90, $\psi$ = 45 deg)", loc="left", fontsize="medium")
    side_legend(a_c, a_c.get_legend_handles_labels()[0] + fails_c)
    for a in (a_s, a_c):
        a.grid(True, which="both", lw=0.3, alpha=0.6)
    return _finish(fig)


# --------------------------------------------------------------------------------------------
# Fig. exp: the pressure-driven robot
# --------------------------------------------------------------------------------------------
def plot_pressure(p: PressureStudy) -> Figure:
    """Fig. exp: S/S_max against p0 and psi: this model, the paper's simulation, the experiments."""
    fig, ax = _figure((11.0, 4.8), 1, 2)
    a0, a1 = ax[0]
    c = p.fit.curves
    how = "fitted" if p.fit.fitted else "stored fit"
    inp = (fr"rest angle $\varphi_\mathrm{{rest}}$ = {c.phi_rest_deg:.1f} deg ({how})" if c.amplitude_p0_bar is None else
           fr"$p = p_0 + A_p \sin$, $A_p$ = {c.amplitude_p0_bar:g} bar ($p_0$ curve) / {c.amplitude_psi_bar:.2f} bar ({how}, $\psi$ curve)")
    fig.suptitle(f"Pressure-driven robot: {inp}, {_gravity_text(c.gravity)}\n"
                 fr"RMS error against the paper's simulation: {p.fit.rms_p0:.3f} ($p_0$), {p.fit.rms_psi:.3f} ($\psi$); "
                 fr"best $\psi$ = {p.psi_opt[0]:.1f} deg")
    a0.plot(p.paper_p0["p0_bar"], p.paper_p0["S_over_Smax"], color="0.55", ls="--", lw=1.5, label="paper's simulation")
    a0.plot(c.p0_bar, c.progress_p0, color=BLUE, lw=2, marker=".", label=f"this model (RMS error {p.fit.rms_p0:.3f})")
    e = p.experiment_p0
    a0.errorbar(e["p0_bar"], e["S_over_Smax"], yerr=[e["err_minus"], e["err_plus"]], color="k", ecolor="red",
                capsize=3, lw=1.5, label="experiment")
    a0.set_xlabel("nominal (mean) pressure $p_0$ [bar]" if c.amplitude_p0_bar is not None else
                  "nominal (peak) pressure $p_0$ [bar]")
    a0.set_ylabel(fr"$S / S(p_0 = 1.7$ bar) [-]  ($\psi$ = {c.psi_for_p0_deg:g} deg)")
    a0.set_title("(a) against nominal pressure", loc="left", fontsize="medium")
    a1.plot(p.paper_psi["psi_deg"], p.paper_psi["S_over_Smax"], color="0.55", ls="--", lw=1.5, label="paper's simulation")
    a1.plot(c.psi_deg, c.progress_psi, color=BLUE, lw=2, marker=".", label=f"this model (RMS error {p.fit.rms_psi:.3f})")
    e = p.experiment_psi
    a1.errorbar(e["psi_deg"], e["S_over_Smax"], yerr=[e["err_minus"], e["err_plus"]], color="k", ecolor="red",
                capsize=3, lw=1.5, label="experiment")
    a1.set_xlabel(r"phase difference $\psi$ [deg]")
    a1.set_ylabel(fr"$S / \max S$ [-]  ($p_0$ = {c.p0_for_psi_bar:g} bar)")
    a1.set_title("(b) against phase difference", loc="left", fontsize="medium")
    a1.set_xlim(-3, 180)
    for a in (a0, a1):
        a.grid(True, lw=0.3, alpha=0.6)
        a.legend(fontsize="small")
        if any(st != SUCCESS for st in c.status_p0 + c.status_psi):
            a.text(0.02, 0.02, f"{p.fit.failures} failed points", transform=a.transAxes, fontsize="small")
    return _finish(fig)


__all__ = ["plot_configuration", "plot_forces", "plot_parametric", "plot_friction_band", "plot_amplitude",
           "plot_higher_friction", "plot_stiffness", "plot_conventions", "plot_pressure", "mark_failures"]
