"""Figures of the CoT, stiffness and pressure studies (:mod:`ocp_crawl.studies.cot`,
:mod:`ocp_crawl.studies.pressure`), one function per figure: progress and CoT+ against the
amplitude (Fig. CoT), higher friction, stiffness, the two gravity conventions side by side and the
pressure-driven robot (Fig. exp).  The gait studies' figures are
:mod:`ocp_crawl.studies.gait_plots`.

Every function returns a :class:`matplotlib.figure.Figure` on the Agg canvas (no pyplot state).
Where a figure compares with the paper, the vertical axis is the progress per cycle -S: the
paper plots forward progress, and with psi > 0 the robot moves towards foot 1 (S < 0).  Points
at which a run failed are drawn as markers whose shape names the status (fold, lift-off, ...),
so that failures read as data and not as gaps.
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ocp_crawl.studies.common import COT_K_LABELS, MM, SUCCESS
from ocp_crawl.studies.cot import AmplitudeStudy, HigherFriction, StiffnessStudy
from ocp_crawl.studies.marks import (BLUE, PURPLE, _figure, _finish, _gravity_text, mark_failures,
                                     mark_off_axis, plain_log_ticks, stiffness_axis, stiffness_text,
                                     successful)
from ocp_crawl.studies.pressure import PressureStudy

#: colours of the three stiffnesses of the CoT figure (large, realistic, low), as in the paper
K_COLORS = (BLUE, "black", PURPLE)
K_STYLES = ("-", "--", ":")
#: top of the CoT+ axis, as in the paper's Fig. CoT
COT_YMAX = 60.0


def side_legend(ax, handles: list) -> None:
    """The legend of ``ax`` right of it, off the curves."""
    ax.legend(handles=handles, fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0),
              borderaxespad=0.0, handlelength=3.0)


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
    least = ", ".join(f"{COT_K_LABELS[i]} k {s.CoT_min[i]:.1f}"
                      + (f" at {s.A_opt[i]:.0f} deg" if np.isfinite(s.A_opt[i]) else " (grid end)")
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
    a_c.set_title("(b) positive cost of transport (Fig. CoT)"
                  + (" with the paper's values (circles)" if comparison is not None else ""),
                  loc="left", fontsize="medium")
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
        a.plot(h.psi_deg, -MM * h.S[i], color=colors[i % len(colors)], lw=2 if f == 1 else 1.5,
               marker=".", clip_on=False, label=fr"$\mu$ = {f:g} $\times$ 0.389{extra}")
        fails += mark_failures(a, h.psi_deg, np.zeros(len(h.psi_deg)), h.status[i],
                               color=colors[i % len(colors)], seen=seen)
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
    """Progress and CoT+ against k/(M g L); failed points marked by status, the threshold as a line.
    The title gives the friction threshold and the largest progress."""
    fig, ax = _figure((11.0, 7.5), 2, 1, sharex=True)
    a_s, a_c = ax[:, 0]
    prog = -MM * np.asarray(s.S, float)
    best = (f"largest $-S$ = {np.nanmax(prog):.1f} mm" if np.isfinite(prog).any()
            else "no successful point")
    fig.suptitle(r"Stiffness, $\gamma$ = 90, $A$ = 30, $\psi$ = 45 deg "
                 rf"({_gravity_text(s.gravity)})" "\n"
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
            a_s.semilogx(s.k_ratios, -MM * s.S, color=color, ls=ls, lw=2, marker=".",
                         label=f"{gravity}")
            fails += mark_failures(a_s, s.k_ratios,
                                   np.full(len(s.k_ratios), -2.0 if gravity == "physical" else 0.0),
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
    a_s.set_title(r"(a) progress against stiffness ($\gamma$ = 90, $A$ = 30, $\psi$ = 45 deg)",
                  loc="left", fontsize="medium")
    side_legend(a_s, a_s.get_legend_handles_labels()[0] + fails)
    a_c.set_xlabel("amplitude $A$ [deg]")
    a_c.set_ylabel("CoT$^+$ [-]")
    a_c.set_ylim(-3.5 if fails_c else 0.0, COT_YMAX)
    a_c.set_title(r"(b) CoT$^+$ against amplitude ($\gamma$ = 90, $\psi$ = 45 deg)", loc="left",
                  fontsize="medium")
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
    inp = (fr"rest angle $\varphi_\mathrm{{rest}}$ = {c.phi_rest_deg:.1f} deg ({how})"
           if c.amplitude_p0_bar is None else
           fr"$p = p_0 + A_p \sin$, $A_p$ = {c.amplitude_p0_bar:g} bar ($p_0$ curve) / "
           fr"{c.amplitude_psi_bar:.2f} bar ({how}, $\psi$ curve)")
    fig.suptitle(f"Pressure-driven robot: {inp}, {_gravity_text(c.gravity)}\n"
                 fr"RMS error against the paper's simulation: {p.fit.rms_p0:.3f} ($p_0$), "
                 rf"{p.fit.rms_psi:.3f} ($\psi$); best $\psi$ = {p.psi_opt[0]:.1f} deg")
    a0.plot(p.paper_p0["p0_bar"], p.paper_p0["S_over_Smax"], color="0.55", ls="--", lw=1.5,
            label="paper's simulation")
    a0.plot(c.p0_bar, c.progress_p0, color=BLUE, lw=2, marker=".",
            label=f"this model (RMS error {p.fit.rms_p0:.3f})")
    e = p.experiment_p0
    a0.errorbar(e["p0_bar"], e["S_over_Smax"], yerr=[e["err_minus"], e["err_plus"]], color="k",
                ecolor="red", capsize=3, lw=1.5, label="experiment")
    a0.set_xlabel("nominal (mean) pressure $p_0$ [bar]" if c.amplitude_p0_bar is not None else
                  "nominal (peak) pressure $p_0$ [bar]")
    a0.set_ylabel(fr"$S / S(p_0 = 1.7$ bar) [-]  ($\psi$ = {c.psi_for_p0_deg:g} deg)")
    a0.set_title("(a) against nominal pressure", loc="left", fontsize="medium")
    a1.plot(p.paper_psi["psi_deg"], p.paper_psi["S_over_Smax"], color="0.55", ls="--", lw=1.5,
            label="paper's simulation")
    a1.plot(c.psi_deg, c.progress_psi, color=BLUE, lw=2, marker=".",
            label=f"this model (RMS error {p.fit.rms_psi:.3f})")
    e = p.experiment_psi
    a1.errorbar(e["psi_deg"], e["S_over_Smax"], yerr=[e["err_minus"], e["err_plus"]], color="k",
                ecolor="red", capsize=3, lw=1.5, label="experiment")
    a1.set_xlabel(r"phase difference $\psi$ [deg]")
    a1.set_ylabel(fr"$S / \max S$ [-]  ($p_0$ = {c.p0_for_psi_bar:g} bar)")
    a1.set_title("(b) against phase difference", loc="left", fontsize="medium")
    a1.set_xlim(-3, 180)
    for a in (a0, a1):
        a.grid(True, lw=0.3, alpha=0.6)
        a.legend(fontsize="small")
        if any(st != SUCCESS for st in c.status_p0 + c.status_psi):
            a.text(0.02, 0.02, f"{p.fit.failures} failed points", transform=a.transAxes,
                   fontsize="small")
    return _finish(fig)


__all__ = ["plot_amplitude", "plot_higher_friction", "plot_stiffness", "plot_conventions",
           "plot_pressure", "mark_failures"]
