"""The paper's statements (:data:`STATEMENTS`) and their checks on a set of studies, in each gravity
convention.

Each check gives a verdict and the numbers behind it (text for ``report.md`` and ``numbers.json``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ocp_crawl.studies.common import (COT_K_LABELS, MM, REALISTIC_K_RATIO, STUCK_TOL, SUCCESS,
                                      non_increasing, outcome_runs)
from ocp_crawl.studies.cot import AmplitudeStudy, HigherFriction, StiffnessStudy
from ocp_crawl.studies.gaits import FrictionBand, GaitComparison, PsiGammaMap
from ocp_crawl.studies.pressure import PressureStudy
from ocp_crawl.studies.suite import StudySet
from ocp_crawl.studies.text import fmt_mm, runs_text

#: the paper's critical stiffness below which the robot stops, k/(M g L) (Section II-B)
PAPER_THRESHOLD = 0.1
#: the paper's "realistic" stiffness, k/(M g L) (Section II-B)
PAPER_REALISTIC = 2.7

#: the statements: key, where in the paper, the claim
STATEMENTS: tuple[tuple[str, str, str], ...] = (
    ("stick_phases", "Sec. II-B, Fig. simu_conf",
     "With prescribed angles one contact always slips; the hybrid solution adds stick-stick "
     "phases."),
    ("d_max", "Sec. II-B, Fig. simu_conf",
     "The largest distance between the contacts is smaller for the hybrid solution than for "
     "prescribed angles."),
    ("low_k_less", "Sec. II-B, Fig. simu_conf",
     "At lower k/(M g L) the robot slips less and travels less per cycle (k = 0.3 vs 2.74 M g L)."),
    ("S_grows_with_k", "Sec. II-B", "The distance per cycle decreases as the stiffness decreases."),
    ("threshold", "Sec. II-B", "The robot stops below a critical stiffness k ~ 0.1 M g L."),
    ("force_jump", "Sec. II-B, Fig. simu_forces",
     "Prescribed angles make f_t jump at the switching instants; the hybrid f_t is continuous."),
    ("gamma_opt", "Sec. II-C, Fig. parametric",
     "The progression is optimal at gamma = pi/2 (A = pi/6)."),
    ("decreasing_psi", "Sec. II-C, Fig. parametric",
     "S decreases monotonically with psi and vanishes as psi -> pi."),
    ("psi_zero", "Sec. II-C", "At psi = 0 the gait is symmetric and the progression vanishes."),
    ("psi_opt", "Sec. II-C, Fig. d_mu",
     "Averaged over mu1/mu2 in [0.9, 1.1], S has an optimal phase difference psi."),
    ("direction", "Sec. II-C, Fig. d_mu",
     "The robot moves in the direction of the phase-leading joint: sign(S) follows sign(psi)."),
    ("higher_friction", "Supplementary, Fig. s_psi_mu",
     "For higher friction S still decreases monotonically with psi, and stops for a growing range "
     "of psi."),
    ("S_grows_with_A", "Sec. II-C", "S rises monotonically with the amplitude A."),
    ("A_opt", "Sec. II-C, Fig. CoT",
     "CoT+ has an energy-optimal amplitude (large and realistic stiffness)."),
    ("softer_cheaper", "Sec. II-C, Fig. CoT",
     "A softer robot is more energetically efficient (lower CoT+)."),
    ("cot_range", "Fig. CoT",
     "Each of the three stiffnesses crawls at every amplitude at which the paper plots CoT+."),
    ("pressure", "Sec. III, Fig. exp",
     "The pressure-driven robot's S/Smax grows with p0 and peaks at a small phase difference (~10 "
     "deg)."),
)

Checks = dict[str, tuple[bool, str]]


@dataclass(frozen=True)
class Statement:
    """One statement of the paper, checked in each convention with the numbers behind the
    verdict."""

    key: str
    where: str
    """section or figure of the paper"""
    claim: str
    holds: dict[str, bool]
    """convention -> does the statement hold"""
    numbers: dict[str, str]
    """convention -> the numbers behind the verdict"""

    @property
    def changed(self) -> bool:
        """True if the physical convention changes the verdict."""
        return len(set(self.holds.values())) > 1


def _mono(progress: np.ndarray) -> bool:
    """Non-increasing up to round-off (STUCK_TOL of L, in metres or normalised units alike)."""
    return non_increasing(progress, 1e-6)


def stiffness_runs_text(s: StiffnessStudy) -> str:
    """The outcomes along k ("stuck for k = ..; moves for k = ..")."""
    return runs_text(s.ranges(), "k")


def _at(x: np.ndarray, y: np.ndarray, targets) -> str:
    """y at the grid points nearest to each target, as "x: y" pairs."""
    idx = sorted({int(np.argmin(np.abs(x - t))) for t in targets})
    return ", ".join(f"{x[i]:.3g}: {y[i]:.1f}" if np.isfinite(y[i])
                     else f"{x[i]:.3g}: -" for i in idx)


def _gait_checks(gc: GaitComparison) -> Checks:
    out: Checks = {}
    real, low = gc.torque
    fr = [gc.stick_fraction(r) for r in (gc.prescribed, real, low)]
    out["stick_phases"] = (fr[0] == 0.0 and real.success and fr[1] > 0.01,
                           f"stick-stick fraction of the cycle: prescribed {fr[0]:.3f}, hybrid (k "
                           f"= 2.74) {fr[1]:.3f}")
    dm = [gc.d_max(r) for r in (gc.prescribed, real)]
    out["d_max"] = (real.success and dm[1] < dm[0],
                    f"largest foot distance: prescribed {MM * dm[0]:.2f} mm, hybrid "
                    f"{MM * dm[1]:.2f} mm")
    out["low_k_less"] = (real.success and low.success and -low.S < -real.S and fr[2] > fr[1],
                         f"k = 2.74: S = {fmt_mm(real.S)}, stick {fr[1]:.3f}; k = 0.3: "
                         + (f"S = {fmt_mm(low.S)}, stick {fr[2]:.3f}" if low.success else
                            f"{low.status_name} at t = {low.failure_t:.3f} in mode "
                            f"{low.failure_mode}"))
    fj = [gc.force_jump(r) for r in (gc.prescribed, real)]
    out["force_jump"] = (fj[0] > 0.05 and real.success and fj[1] < 1e-4,
                         f"largest f_t jump at an event: prescribed {fj[0]:.4f} N, hybrid "
                         f"{fj[1]:.2e} N")
    return out


def _stiffness_checks(st: StiffnessStudy) -> Checks:
    out: Checks = {}
    ok_k = st.status == SUCCESS
    prog = -st.S
    # above the threshold (all k when there is none)
    above = st.k_ratios > st.threshold if np.isfinite(st.threshold) else np.ones(st.k_ratios.size,
                                                                                 bool)
    mono = bool(np.all(np.diff(prog[above & ok_k]) >= -STUCK_TOL
                       * 0.12)) if (above & ok_k).sum() > 1 else False
    fails_k = int(np.sum(~ok_k & above))
    out["S_grows_with_k"] = (mono and not fails_k,
                             f"-S non-decreasing in k above the threshold: {mono}; failed points "
                             f"above it: {fails_k}; "
                             "-S [mm] at k/(M g L) = "
                             + _at(st.k_ratios, MM * np.where(ok_k, prog, np.nan),
                                                              [0.2, 0.3, 0.5, 1.0,
                                                               REALISTIC_K_RATIO, 10.0]))
    stuck_below = bool(np.all(st.stuck[st.k_ratios
                                       < st.threshold])) if np.isfinite(st.threshold) else False
    near = np.isfinite(st.threshold) and abs(st.threshold
                                             - PAPER_THRESHOLD) <= 0.3 * PAPER_THRESHOLD
    threshold_text = (f"threshold {st.threshold:.4f} M g L (paper ~{PAPER_THRESHOLD}, relative "
                      f"difference {st.threshold / PAPER_THRESHOLD - 1:+.1%})"
                      if np.isfinite(st.threshold) else
                      "no threshold: no grid point where the robot stands still below one where it "
                      "does not")
    out["threshold"] = (bool(near and stuck_below),
                        f"{threshold_text}; all grid points below stuck: {stuck_below}; "
                        f"crawls at every k from {st.onset:.4f} M g L on; outcomes: "
                        f"{stiffness_runs_text(st)}")
    return out


def _map_checks(m: PsiGammaMap) -> Checks:
    cols = (m.psi_deg > 0) & (m.psi_deg <= 150)
    g_opt = m.gamma_opt[cols]
    step = float(np.min(np.diff(m.gamma_deg)))
    return {"gamma_opt": (bool(np.all(np.abs(g_opt - 90.0) <= step / 2)),
                          f"best gamma for psi in (0, 150]: {np.nanmin(g_opt):.1f} .. "
                          f"{np.nanmax(g_opt):.1f} deg; failed points "
                          f"{sum(v for k, v in m.counts.items() if k != SUCCESS)} of "
                          f"{m.status.size}"
                          + "".join(f", {k} {v}" for k, v in m.counts.items() if k != SUCCESS))}


def _band_checks(b: FrictionBand) -> Checks:
    out: Checks = {}
    pos = b.psi_deg > 0
    nominal = -b.nominal
    s180 = float(b.nominal[np.argmin(np.abs(b.psi_deg - 180))])
    mono_psi = _mono(nominal[pos])
    out["decreasing_psi"] = (mono_psi and abs(s180) <= 1e-3 * 0.12,
                             f"progress non-increasing on (0, 180]: {mono_psi}; S(180) = "
                             f"{fmt_mm(s180)}; S(0+) = {fmt_mm(b.nominal[pos][0])} at psi = "
                             f"{b.psi_deg[pos][0]:g}")
    s0 = float(b.nominal[np.argmin(np.abs(b.psi_deg))])
    out["psi_zero"] = (abs(s0) <= STUCK_TOL * 0.12, f"S(0) = {fmt_mm(s0)}")
    psi_opt, prog_opt = b.psi_opt
    interior = bool(np.isfinite(psi_opt) and b.psi_deg[pos][0] < psi_opt < 180)
    out["psi_opt"] = (interior,
                      f"optimal psi of the average {psi_opt:.1f} deg (average -S = "
                      f"{fmt_mm(prog_opt)}); mirror at psi = {b.psi_opt_negative[0]:.1f} deg")
    inner = pos & (b.psi_deg < 180)
    signs = bool(np.all(b.nominal[inner] < 0)
                 and np.all(b.nominal[(b.psi_deg < 0) & (b.psi_deg > -180)] > 0))
    anti = b.antisymmetry()
    out["direction"] = (signs and anti <= 1e-9,
                        f"S < 0 for all psi in (0, 180) and > 0 for psi in (-180, 0): {signs};"
                        f" max |S(psi) + S(-psi)| = {anti:.2e} m")
    return out


def _friction_checks(h: HigherFriction) -> Checks:
    mono_f = h.monotone()
    stops = h.psi_stop
    grows = bool(np.all(np.diff(np.nan_to_num(stops, nan=180.0)) <= 0)
                 and np.nan_to_num(stops[-1], nan=180.0) < np.nan_to_num(stops[0], nan=180.0))
    return {"higher_friction": (bool(np.all(mono_f)) and grows,
                                "monotone per factor: "
                                + ", ".join(f"{f:g}x: {bool(v)}" for f, v in zip(h.factors, mono_f))
                                + "; robot stops from psi = " + ", ".join(
                                    f"{f:g}x: {v:.1f}" if np.isfinite(v)
                                    else f"{f:g}x: -" for f, v in zip(h.factors, stops))
                                + " deg")}


def _failed_runs(a: AmplitudeStudy, i: int) -> str:
    return runs_text([r for r in outcome_runs(a.A_deg, a.status[i]) if r[0] != SUCCESS], "A")


def _cot_range_check(a: AmplitudeStudy) -> tuple[bool, str]:
    comp = a.paper_comparison()
    if comp is None:
        return False, "the amplitude study does not use the paper's three stiffnesses"
    listed = np.isfinite(comp["paper"])
    crawls = np.isfinite(a.CoT_moving)
    missing = [int(np.sum(listed[i] & ~crawls[i])) for i in range(3)]
    return sum(missing) == 0, ("amplitudes with a published CoT+ where the model does not crawl: "
                               + ", ".join(f"{COT_K_LABELS[i]} k {missing[i]} of "
                                           f"{int(listed[i].sum())}" for i in range(3)))


def _amplitude_checks(a: AmplitudeStudy) -> Checks:
    out: Checks = {}
    i_real = int(np.argmin(np.abs(a.k_ratios - REALISTIC_K_RATIO)))
    pr = -a.S[i_real]
    ok_a = a.status[i_real] == SUCCESS
    out["S_grows_with_A"] = (bool(ok_a.all() and _mono(-pr)),
                             f"realistic k: -S from {fmt_mm(-a.S[i_real][0])} (A = "
                             f"{a.A_deg[0]:.1f}) to {fmt_mm(-a.S[i_real][ok_a][-1])} (A = "
                             f"{a.A_deg[ok_a][-1]:.1f} deg); failures: "
                             + (_failed_runs(a, i_real) or "none"))
    A_opt = a.A_opt
    out["A_opt"] = (bool(np.isfinite(A_opt[0]) and np.isfinite(A_opt[1])),
                    "least CoT+ at A = "
                    + ", ".join(f"{COT_K_LABELS[i]} k: {v:.1f} deg" if np.isfinite(v) else
                                f"{COT_K_LABELS[i]} k: none inside the grid"
                                for i, v in enumerate(A_opt)))
    out["cot_range"] = _cot_range_check(a)
    cmin = a.CoT_min
    ordered = bool(np.all(np.isfinite(cmin)) and cmin[2] < cmin[1] < cmin[0])
    out["softer_cheaper"] = (ordered, "least CoT+ over A: " + ", ".join(
        f"{COT_K_LABELS[i]} k {v:.2f}" for i, v in enumerate(cmin)) + "; low k fails: "
                             + (_failed_runs(a, 2) or "none"))
    return out


def _pressure_checks(p: PressureStudy) -> Checks:
    c = p.fit.curves
    inc = _mono(-c.progress_p0[np.isfinite(c.progress_p0)])
    psi_p, _ = p.psi_opt
    return {"pressure": (bool(inc and 5.0 <= psi_p <= 30.0),
                         f"S/Smax increasing in p0: {inc}; best psi {psi_p:.1f} deg (paper's "
                         f"simulation 12.0, experiment 10); fit RMS p0 {p.fit.rms_p0:.3f}, psi "
                         f"{p.fit.rms_psi:.3f}")}


def statement_checks(s: StudySet) -> Checks:
    """Verdict and numbers of every statement in the convention of ``s``: {key: (holds, numbers
    text)}."""
    return {**_gait_checks(s.gait), **_stiffness_checks(s.stiffness), **_map_checks(s.parametric),
            **_band_checks(s.band), **_friction_checks(s.friction),
            **_amplitude_checks(s.amplitude), **_pressure_checks(s.pressure)}


def check_statements(sets: dict[str, StudySet]) -> list[Statement]:
    """Every statement of :data:`STATEMENTS`, checked in each convention of ``sets`` ({gravity:
    StudySet})."""
    checks = {g: statement_checks(s) for g, s in sets.items()}
    return [Statement(key, where, claim, {g: bool(checks[g][key][0]) for g in sets},
                      {g: checks[g][key][1] for g in sets}) for key, where, claim in STATEMENTS]


__all__ = ["STATEMENTS", "Statement", "check_statements", "statement_checks", "PAPER_THRESHOLD",
           "PAPER_REALISTIC"]
