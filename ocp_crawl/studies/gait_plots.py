"""Figures of the gait studies (:mod:`ocp_crawl.studies.gaits`), one function per figure: one gait
in detail (Fig. simu_conf, simu_forces), progress over (psi, gamma) (Fig. parametric) and the
friction band (Fig. d_mu).

Every function returns a :class:`matplotlib.figure.Figure` on the Agg canvas (no pyplot state).
Where a figure compares with the paper, the vertical axis is the progress per cycle -S: the
paper plots forward progress, and with psi > 0 the robot moves towards foot 1 (S < 0).  Points
at which a run failed are drawn as markers whose shape names the status (fold, lift-off, ...),
so that failures read as data and not as gaps.
"""
from __future__ import annotations

import numpy as np
from matplotlib.colors import BoundaryNorm
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Rectangle
from matplotlib.ticker import MaxNLocator

from ocp_crawl.sim.result import CrawlResult
from ocp_crawl.studies.common import MM, SUCCESS
from ocp_crawl.studies.gaits import FrictionBand, GaitComparison, PsiGammaMap
from ocp_crawl.studies.marks import (BLUE, FAIL_COLOR, PURPLE, _figure, _finish, _gravity_text,
                                     mark_failures)
from ocp_crawl.viz.gait import (mode_legend, mode_runs, plot_friction_limits, robot_points,
                                shade_modes)

#: line styles of the gait comparison: prescribed angles, realistic stiffness, low stiffness
RUN_STYLES = ("-", "--", ":")


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
    fig.suptitle(r"Configuration over a cycle: $\gamma$ = 90, $A$ = 30, $\psi$ = 45 deg "
                 fr"({_gravity_text(gc.gravity)})"
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
                       [MM * (res.x1[-1] - origin), MM * (res.x2[-1] - origin)], "X", color="0.2",
                       ms=8)
        handles.append(Line2D([], [], color="0.2", ls=ls, label=_run_label(name, res)))
    handles += [Line2D([], [], color=BLUE, label=r"$\varphi_1$, $x_1$ (joint/foot 1)"),
                Line2D([], [], color=PURPLE, label=r"$\varphi_2$, $x_2$ (joint/foot 2)")]
    if any(not r.success for r in gc.torque):
        handles.append(Line2D([], [], ls="none", marker="X", color="0.2",
                              label="run stops (failure)"))
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
    ax.set_title("(c) snapshots of the prescribed-angle gait (gray: later is darker)", loc="left",
                 fontsize="medium")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("z [mm]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.axhline(0.0, color="k", lw=0.8)
    t = _phase(res)
    origin = res.x1[0]
    for j, target in enumerate(np.linspace(0.0, 1.0, n)):
        i = int(np.argmin(np.abs(t - target)))
        pts = MM * robot_points(robot, res.x1[i] - origin, res.x2[i] - origin, res.phi[0, i],
                                res.theta[i])
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
        [(f"hybrid, k = {r:.2f} M g L", res, gc.robot_at(i))
         for i, (r, res) in enumerate(zip(gc.k_ratios, gc.torque))]
    fig, ax = _figure((8.0, 3.0 * len(runs)), len(runs), 1, sharex=True)
    jumps = ", ".join(f"{name.split(',')[0]} {gc.force_jump(res):.2g} N"
                      for name, res, _ in runs[:2])
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
        plot_friction_limits(a, t, robot, res.f_n1, res.f_n2, colors=(BLUE, PURPLE), lw=1.1,
                             labels=(None, None))
        if not res.success:
            a.plot(t[-1], res.f_t[-1], "X", color="0.2", ms=8)
    ax[-1, 0].set_xlabel("phase t/T [cycles]")
    ax[-1, 0].set_xlim(0, 1)
    handles = [Line2D([], [], color="k", label="$f_t$ (on foot 1, along +x)"),
               Line2D([], [], color=BLUE, ls="--", label=r"$\pm\mu_1 f_{n1}$"),
               Line2D([], [], color=PURPLE, ls="--", label=r"$\pm\mu_2 f_{n2}$")]
    patches, names = mode_legend(modes_seen)
    fig.legend(handles=handles + patches, labels=[h.get_label() for h in handles] + names,
               loc="outside lower center", ncol=2, fontsize="small")
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
    interpolation); failed points as hatched cells, marked by status; the best gamma at each psi and
    the largest progress (also in the title)."""
    fig, ax = _figure((8.0, 6.8))
    a = ax[0, 0]
    prog = MM * m.progress
    finite = prog[np.isfinite(prog)]
    xe, ye = _cell_edges(m.psi_deg), _cell_edges(m.gamma_deg)
    levels = (MaxNLocator(14).tick_values(min(0.0, finite.min()), finite.max()) if finite.size
              else np.arange(11.0))
    norm = BoundaryNorm(levels, ncolors=256)
    mesh = a.pcolormesh(xe, ye, np.ma.masked_invalid(prog), cmap="viridis", norm=norm,
                        shading="flat")
    fig.colorbar(mesh, ax=a, label="progress per cycle $-S$ [mm] (towards foot 1)")
    handles = []
    failed = m.status != SUCCESS
    if failed.any():
        for i, j in zip(*np.nonzero(failed)):
            a.add_patch(Rectangle((xe[j], ye[i]), xe[j + 1] - xe[j], ye[i + 1] - ye[i],
                                  facecolor="white", edgecolor="0.45", hatch="///", lw=0.0,
                                  zorder=3))
        handles.append(Patch(facecolor="white", edgecolor="0.45", hatch="///",
                             label="failed point (its cell)"))
        P, G = np.meshgrid(m.psi_deg, m.gamma_deg)
        handles += mark_failures(a, P, G, m.status, color=FAIL_COLOR, size=30)
    a.set_xlim(xe[0], xe[-1])
    a.set_ylim(ye[0], ye[-1])
    a.plot(m.psi_deg, m.gamma_opt, "w--", lw=1.5, zorder=4)
    handles.append(Line2D([], [], color="0.2", ls="--",
                          label=r"best $\gamma$ at each $\psi$ (white)"))
    g, p, s = m.best
    a.plot(p, g, "*", color="orange", ms=14, mec="k", zorder=6)
    handles.append(Line2D([], [], ls="none", marker="*", color="orange", mec="k", ms=10,
                          label=rf"largest: {MM * -s:.1f} mm at $\psi$ = {p:g}, "
                                rf"$\gamma$ = {g:g} deg"))
    a.set_xlabel(r"phase difference $\psi$ [deg]")
    a.set_ylabel(r"nominal joint angle $\gamma$ [deg]")
    n_failed = int(failed.sum())
    fig.suptitle(rf"Progress per cycle over $\psi$ and $\gamma$, $A$ = {m.A_deg:g} deg "
                 rf"({_gravity_text(m.gravity)})"
                 "\n"
                 + rf"largest $-S$ = {MM * -s:.1f} mm at $\psi$ = {p:g}, $\gamma$ = {g:g} deg; "
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
                   label=fr"$\mu_1/\mu_2 \in [{1 - b.eps:g}, {1 + b.eps:g}]$ "
                         f"({len(b.ratios)} ratios)")
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
    best = (fr"best average $-S$ = {MM * prog:.1f} mm at $\psi$ = {psi_opt:.1f} deg"
            if np.isfinite(psi_opt) else "no best average")
    fig.suptitle(r"Friction sensitivity, $\gamma$ = 90, $A$ = 30 deg "
                 fr"({_gravity_text(b.gravity)})" "\n"
                 fr"{best}; $\mu_1/\mu_2 \in [{1 - b.eps:g}, {1 + b.eps:g}]$")
    a.grid(True, lw=0.3, alpha=0.6)
    a.legend(handles=handles + fails, fontsize="small", loc="lower right")
    return _finish(fig)


__all__ = ["plot_configuration", "plot_forces", "plot_parametric", "plot_friction_band"]
