"""Reproduce the paper's figures and check its statements: ``ocp-crawl reproduce``.

Runs every study of :mod:`ocp_crawl.studies.core` in both gravity conventions (the statements table
needs both), draws the figures in the chosen convention (PNG and PDF), and writes ``report.md``:
each figure with the numbers behind it, the relative difference wherever the paper publishes a
number, and every statement of the paper checked in both conventions.  ``numbers.json`` holds the
same numbers for scripts.

Nothing is lost when a run is killed: every file is written atomically (:func:`ocp_crawl.io.files.atomic_write`:
a temporary file renamed over the target, so a reader sees the previous file or the new one, never a
mix), and every grid is a journaled sweep under ``<out>/sweeps``.  ``resume`` (``--resume``) reuses
the finished grid points there and recomputes the rest (the single gaits, the bisection of the
friction threshold and the pressure curves are not journaled: they are recomputed); figures,
``report.md`` and ``numbers.json`` are always written anew.  A resumed run gives the same numbers,
report and figures as an uninterrupted one, apart from the wall times (``elapsed_s`` in
``numbers.json``; the run time and the Timing section of ``report.md``).  Temporary files of a killed
run are removed by the next run.

The grid sizes of the quick and the full run are the one table :data:`GRIDS`.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ocp_crawl import __version__
from ocp_crawl.io.files import atomic_write, remove_stale_temps, write_json
from ocp_crawl.model.statics import GRAVITY_CONVENTIONS
from ocp_crawl.viz.gait import save_figure
from ocp_crawl.io.paper_data import read_paper_csv
from ocp_crawl.model.pressure import FITTED_REST_DEG
from ocp_crawl.studies.pressure import P0_NORMALISE_BAR, paper_grids
from ocp_crawl.studies.core import (COT_K_LABELS, REALISTIC_K_RATIO, outcome_runs, STUCK_TOL, AmplitudeStudy, FrictionBand,
                      GaitComparison, HigherFriction, PressureStudy, PsiGammaMap, StiffnessStudy, SweepOptions,
                      amplitude_study, friction_band, gait_comparison, higher_friction, pressure_study, psi_gamma_map,
                      stiffness_study)
from ocp_crawl.studies.plots import (plot_amplitude, plot_configuration, plot_conventions, plot_forces, plot_friction_band,
                          plot_higher_friction, plot_parametric, plot_pressure, plot_stiffness)
from ocp_crawl.sweep import SUCCESS

MM = 1e3
#: the paper's critical stiffness below which the robot stops, k/(M g L) (Section II-B)
PAPER_THRESHOLD = 0.1
#: the paper's "realistic" stiffness, k/(M g L) (Section II-B)
PAPER_REALISTIC = 2.7


def _sym(values) -> np.ndarray:
    """Phases -v..v for the given non-negative v (0 once), sorted."""
    v = np.unique(np.abs(np.asarray(values, float)))
    return np.concatenate([-v[::-1][:-1] if v[0] == 0 else -v[::-1], v])


# --------------------------------------------------------------------------------------------
# the grids of the quick and the full run
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Grids:
    """Grids of one run mode (angles in deg, stiffness as k/(M g L), pressure in bar)."""

    gait_samples: int
    """phase samples of the configuration and force figures"""
    map_psi: np.ndarray
    map_gamma: np.ndarray
    band_psi: np.ndarray
    """psi of the friction band (both signs); denser at small psi where the average peaks"""
    band_ratios: int
    """number of mu1/mu2 values in [0.9, 1.1] (odd)"""
    amplitude_A: np.ndarray
    """amplitudes: the paper's points of Fig. CoT (every one in the full run)"""
    friction_psi: np.ndarray
    stiffness_k: np.ndarray
    bisection_steps: int
    """bisections of the friction threshold"""
    pressure_fit: bool
    """fit the rest angle (full) or evaluate the stored fit (quick)"""
    pressure_p0: np.ndarray | None
    """None: the paper's points"""
    pressure_psi: np.ndarray | None

    def rows(self) -> dict[str, str]:
        """Human-readable size of every grid (the report's table)."""
        def axis(a) -> str:
            if a is None:
                return "the paper's points"
            a = np.asarray(a)
            return f"{a.size} ({a.min():g} .. {a.max():g})"
        return {
            "configuration and forces: phase samples": str(self.gait_samples),
            "parametric map: psi x gamma [deg]": f"{axis(self.map_psi)} x {axis(self.map_gamma)}",
            "friction band: psi [deg] x mu1/mu2": f"{axis(self.band_psi)} x {self.band_ratios}",
            "amplitude: A [deg] x 3 stiffnesses": axis(self.amplitude_A),
            "higher friction: psi [deg] x 4 factors": axis(self.friction_psi),
            "stiffness: k/(M g L), bisection steps": f"{axis(self.stiffness_k)}, {self.bisection_steps}",
            "pressure: fit / p0 [bar] / psi [deg]": f"{'fit' if self.pressure_fit else 'stored fit'} / "
                                                     f"{axis(self.pressure_p0)} / {axis(self.pressure_psi)}",
        }


def _paper_A() -> np.ndarray:
    return read_paper_csv("fig_cot_vs_amplitude.csv")["A_deg"]


def _grids() -> dict[str, Grids]:
    A = _paper_A()
    p0, psi = paper_grids()
    small = [0, 1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 35, 40, 45, 50, 55, 60]
    return {
        "quick": Grids(
            gait_samples=201, map_psi=np.arange(0.0, 181.0, 30.0), map_gamma=np.arange(70.0, 151.0, 20.0),
            band_psi=_sym([0, 5, 15, 30, 45, 60, 90, 135, 180]), band_ratios=3, amplitude_A=A[::6].copy(),
            friction_psi=np.array([0.0, 10, 30, 60, 90, 120, 150, 165, 175, 180]),
            stiffness_k=np.geomspace(0.05, 5.0, 10), bisection_steps=6,
            pressure_fit=False, pressure_p0=p0[[0, 6, 13, 18, 26]], pressure_psi=psi[[0, 1, 2, 3, 5, 12, 24, 36, 48]]),
        "full": Grids(
            gait_samples=601, map_psi=np.arange(0.0, 181.0, 5.0), map_gamma=np.arange(50.0, 151.0, 5.0),
            band_psi=_sym(small + list(range(70, 181, 10))), band_ratios=9, amplitude_A=A.copy(),
            friction_psi=np.concatenate([np.arange(0.0, 150.0, 5.0), np.arange(150.0, 181.0, 2.5)]),
            stiffness_k=np.unique(np.concatenate([np.geomspace(0.03, 10.0, 36), np.arange(0.06, 0.2, 0.01)])),
            bisection_steps=14, pressure_fit=True, pressure_p0=None, pressure_psi=None),
    }


#: the one table of grid sizes: "quick" (coarse, for tests and a first look) and "full" (the default)
GRIDS: dict[str, Grids] = _grids()


# --------------------------------------------------------------------------------------------
# all studies in one convention
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class StudySet:
    """Every study in one gravity convention."""

    gravity: str
    gait: GaitComparison
    parametric: PsiGammaMap
    band: FrictionBand
    amplitude: AmplitudeStudy
    friction: HigherFriction
    stiffness: StiffnessStudy
    pressure: PressureStudy
    elapsed: dict[str, float] = field(default_factory=dict)
    """wall time per study [s]"""


def run_studies(gravity: str, grids: Grids, sweep: SweepOptions = SweepOptions(),
                log: Callable[[str], None] | None = None) -> StudySet:
    """Run every study in one convention on the given grids."""
    say = log or (lambda msg: None)
    elapsed: dict[str, float] = {}
    out: dict[str, object] = {}
    steps = (
        ("gait", lambda: gait_comparison(gravity, samples=grids.gait_samples)),
        ("parametric", lambda: psi_gamma_map(gravity, grids.map_psi, grids.map_gamma, sweep=sweep)),
        ("band", lambda: friction_band(gravity, grids.band_psi, n_ratios=grids.band_ratios, sweep=sweep)),
        ("amplitude", lambda: amplitude_study(gravity, grids.amplitude_A, sweep=sweep)),
        ("friction", lambda: higher_friction(gravity, grids.friction_psi, sweep=sweep)),
        ("stiffness", lambda: stiffness_study(gravity, grids.stiffness_k, grids.bisection_steps, sweep=sweep)),
        ("pressure", lambda: pressure_study(gravity, grids.pressure_fit, grids.pressure_p0, grids.pressure_psi,
                                            compare_flat=True)),
    )
    for name, run in steps:
        t = time.perf_counter()
        say(f"{gravity} convention: {name} ...")
        out[name] = run()
        elapsed[name] = time.perf_counter() - t
    return StudySet(gravity=gravity, elapsed=elapsed, **out)


# --------------------------------------------------------------------------------------------
# the paper's statements, checked in both conventions
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Statement:
    """One statement of the paper, checked in each convention with the numbers behind the verdict."""

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


def _num(x: float, fmt: str = ".3f") -> str:
    """A number, or "n/a" when it could not be computed (e.g. the normalising run failed)."""
    return format(x, fmt) if np.isfinite(x) else "n/a"


def _rel(ours: float, paper: float) -> str:
    """ours/paper - 1, or "-" where the paper's value is too small for a ratio to mean anything."""
    return f"{ours / paper - 1:+.1%}" if np.isfinite(ours) and abs(paper) >= 0.05 else "-"


def _fmt_mm(S: float) -> str:
    # + 0.0 turns a rounded -0.00 into 0.00
    return "failed" if not np.isfinite(S) else f"{round(MM * S, 2) + 0.0:.2f} mm"


def _runs_text(runs, var: str) -> str:
    return "; ".join(f"{name} for {var} = {a:.3g}" + (f"..{b:.3g}" if b != a else "") for name, a, b, _ in runs)


def _status_runs(s: StiffnessStudy) -> str:
    return _runs_text(s.ranges(), "k")


def _at(x: np.ndarray, y: np.ndarray, targets) -> str:
    """y at the grid points nearest to each target, as "x: y" pairs."""
    idx = sorted({int(np.argmin(np.abs(x - t))) for t in targets})
    return ", ".join(f"{x[i]:.3g}: {y[i]:.1f}" if np.isfinite(y[i]) else f"{x[i]:.3g}: -" for i in idx)


def _statement_checks(s: StudySet) -> dict[str, tuple[bool, str]]:
    """Verdict and numbers of every statement in one convention."""
    out: dict[str, tuple[bool, str]] = {}
    gc = s.gait
    real, low = gc.torque
    fr = [gc.stick_fraction(r) for r in (gc.prescribed, real, low)]
    out["stick_phases"] = (fr[0] == 0.0 and real.success and fr[1] > 0.01,
                           f"stick-stick fraction of the cycle: prescribed {fr[0]:.3f}, hybrid (k = 2.74) {fr[1]:.3f}")
    dm = [gc.d_max(r) for r in (gc.prescribed, real)]
    out["d_max"] = (real.success and dm[1] < dm[0],
                    f"largest foot distance: prescribed {MM * dm[0]:.2f} mm, hybrid {MM * dm[1]:.2f} mm")
    out["low_k_less"] = (real.success and low.success and -low.S < -real.S and fr[2] > fr[1],
                         f"k = 2.74: S = {_fmt_mm(real.S)}, stick {fr[1]:.3f}; k = 0.3: "
                         + (f"S = {_fmt_mm(low.S)}, stick {fr[2]:.3f}" if low.success else
                            f"{low.status_name} at t = {low.failure_t:.3f} in mode {low.failure_mode}"))
    st = s.stiffness
    ok_k = st.status == SUCCESS
    prog = -st.S
    # above the threshold (all k when there is none)
    above = st.k_ratios > st.threshold if np.isfinite(st.threshold) else np.ones(st.k_ratios.size, bool)
    mono = bool(np.all(np.diff(prog[above & ok_k]) >= -STUCK_TOL * 0.12)) if (above & ok_k).sum() > 1 else False
    fails_k = int(np.sum(~ok_k & above))
    out["S_grows_with_k"] = (mono and not fails_k,
                             f"-S non-decreasing in k above the threshold: {mono}; failed points above it: {fails_k}; "
                             "-S [mm] at k/(M g L) = " + _at(st.k_ratios, MM * np.where(ok_k, prog, np.nan),
                                                              [0.2, 0.3, 0.5, 1.0, REALISTIC_K_RATIO, 10.0]))
    stuck_below = bool(np.all(st.stuck[st.k_ratios < st.threshold])) if np.isfinite(st.threshold) else False
    near = np.isfinite(st.threshold) and abs(st.threshold - PAPER_THRESHOLD) <= 0.3 * PAPER_THRESHOLD
    threshold_text = (f"threshold {st.threshold:.4f} M g L (paper ~{PAPER_THRESHOLD}, relative difference "
                      f"{st.threshold / PAPER_THRESHOLD - 1:+.1%})" if np.isfinite(st.threshold) else
                      "no threshold: no grid point where the robot stands still below one where it does not")
    out["threshold"] = (bool(near and stuck_below),
                        f"{threshold_text}; all grid points below stuck: {stuck_below}; "
                        f"crawls at every k from {st.onset:.4f} M g L on; outcomes: {_status_runs(st)}")
    fj = [gc.force_jump(r) for r in (gc.prescribed, real)]
    out["force_jump"] = (fj[0] > 0.05 and real.success and fj[1] < 1e-4,
                         f"largest f_t jump at an event: prescribed {fj[0]:.4f} N, hybrid {fj[1]:.2e} N")
    m = s.parametric
    cols = (m.psi_deg > 0) & (m.psi_deg <= 150)
    g_opt = m.gamma_opt[cols]
    step = float(np.min(np.diff(m.gamma_deg)))
    out["gamma_opt"] = (bool(np.all(np.abs(g_opt - 90.0) <= step / 2)),
                        f"best gamma for psi in (0, 150]: {np.nanmin(g_opt):.1f} .. {np.nanmax(g_opt):.1f}"
                        f" deg; failed points {sum(v for k, v in m.counts.items() if k != SUCCESS)} of {m.status.size}"
                        + "".join(f", {k} {v}" for k, v in m.counts.items() if k != SUCCESS))
    b = s.band
    pos = b.psi_deg > 0
    nominal = -b.nominal
    s180 = float(b.nominal[np.argmin(np.abs(b.psi_deg - 180))])
    mono_psi = _mono(nominal[pos])
    out["decreasing_psi"] = (mono_psi and abs(s180) <= 1e-3 * 0.12,
                             f"progress non-increasing on (0, 180]: {mono_psi}; S(180) = {_fmt_mm(s180)}; "
                             f"S(0+) = {_fmt_mm(b.nominal[pos][0])} at psi = {b.psi_deg[pos][0]:g}")
    s0 = float(b.nominal[np.argmin(np.abs(b.psi_deg))])
    out["psi_zero"] = (abs(s0) <= STUCK_TOL * 0.12, f"S(0) = {_fmt_mm(s0)}")
    psi_opt, prog_opt = b.psi_opt
    interior = bool(np.isfinite(psi_opt) and b.psi_deg[pos][0] < psi_opt < 180)
    out["psi_opt"] = (interior, f"optimal psi of the average {psi_opt:.1f} deg (average -S = {_fmt_mm(prog_opt)}); "
                                f"mirror at psi = {b.psi_opt_negative[0]:.1f} deg")
    inner = pos & (b.psi_deg < 180)
    signs = bool(np.all(b.nominal[inner] < 0) and np.all(b.nominal[(b.psi_deg < 0) & (b.psi_deg > -180)] > 0))
    anti = b.antisymmetry()
    out["direction"] = (signs and anti <= 1e-9, f"S < 0 for all psi in (0, 180) and > 0 for psi in (-180, 0): {signs};"
                                                f" max |S(psi) + S(-psi)| = {anti:.2e} m")
    h = s.friction
    mono_f = h.monotone()
    stops = h.psi_stop
    grows = bool(np.all(np.diff(np.nan_to_num(stops, nan=180.0)) <= 0) and np.nan_to_num(stops[-1], nan=180.0)
                 < np.nan_to_num(stops[0], nan=180.0))
    out["higher_friction"] = (bool(np.all(mono_f)) and grows,
                              "monotone per factor: " + ", ".join(f"{f:g}x: {bool(v)}" for f, v in zip(h.factors, mono_f))
                              + "; robot stops from psi = " + ", ".join(
                                  f"{f:g}x: {v:.1f}" if np.isfinite(v) else f"{f:g}x: -" for f, v in zip(h.factors, stops))
                              + " deg")
    a = s.amplitude
    i_real = int(np.argmin(np.abs(a.k_ratios - REALISTIC_K_RATIO)))
    pr = -a.S[i_real]
    ok_a = a.status[i_real] == SUCCESS
    fails_a = _runs_text([r for r in outcome_runs(a.A_deg, a.status[i_real]) if r[0] != SUCCESS], "A")
    out["S_grows_with_A"] = (bool(ok_a.all() and _mono(-pr)),
                             f"realistic k: -S from {_fmt_mm(-a.S[i_real][0])} (A = {a.A_deg[0]:.1f}) to "
                             f"{_fmt_mm(-a.S[i_real][ok_a][-1])} (A = {a.A_deg[ok_a][-1]:.1f} deg); failures: "
                             + (fails_a or "none"))
    A_opt = a.A_opt
    out["A_opt"] = (bool(np.isfinite(A_opt[0]) and np.isfinite(A_opt[1])),
                    "least CoT+ at A = " + ", ".join(f"{COT_K_LABELS[i]} k: {v:.1f} deg" if np.isfinite(v) else
                                                     f"{COT_K_LABELS[i]} k: none inside the grid"
                                                     for i, v in enumerate(A_opt)))
    comp = a.paper_comparison()
    if comp is not None:
        listed = np.isfinite(comp["paper"])
        crawls = np.isfinite(a.CoT_moving)
        missing = [int(np.sum(listed[i] & ~crawls[i])) for i in range(3)]
        out["cot_range"] = (sum(missing) == 0, "amplitudes with a published CoT+ where the model does not crawl: "
                            + ", ".join(f"{COT_K_LABELS[i]} k {missing[i]} of {int(listed[i].sum())}" for i in range(3)))
    else:
        out["cot_range"] = (False, "the amplitude study does not use the paper's three stiffnesses")
    cmin = a.CoT_min
    ordered = bool(np.all(np.isfinite(cmin)) and cmin[2] < cmin[1] < cmin[0])
    low_fail = _runs_text([r for r in outcome_runs(a.A_deg, a.status[2]) if r[0] != SUCCESS], "A")
    out["softer_cheaper"] = (ordered, "least CoT+ over A: " + ", ".join(
        f"{COT_K_LABELS[i]} k {v:.2f}" for i, v in enumerate(cmin)) + "; low k fails: " + (low_fail or "none"))
    p = s.pressure
    c = p.fit.curves
    inc = _mono(-c.progress_p0[np.isfinite(c.progress_p0)])
    psi_p, _ = p.psi_opt
    out["pressure"] = (bool(inc and 5.0 <= psi_p <= 30.0),
                       f"S/Smax increasing in p0: {inc}; best psi {psi_p:.1f} deg (paper's simulation 12.0, "
                       f"experiment 10); fit RMS p0 {p.fit.rms_p0:.3f}, psi {p.fit.rms_psi:.3f}")
    return out


def _mono(progress: np.ndarray) -> bool:
    """Non-increasing up to round-off (STUCK_TOL of L, in metres or normalised units alike)."""
    y = np.asarray(progress, float)
    y = y[np.isfinite(y)]
    return bool(np.all(np.diff(y) <= 1e-6))


#: the statements: key, where in the paper, the claim
STATEMENTS: tuple[tuple[str, str, str], ...] = (
    ("stick_phases", "Sec. II-B, Fig. simu_conf",
     "With prescribed angles one contact always slips; the hybrid solution adds stick-stick phases."),
    ("d_max", "Sec. II-B, Fig. simu_conf",
     "The largest distance between the contacts is smaller for the hybrid solution than for prescribed angles."),
    ("low_k_less", "Sec. II-B, Fig. simu_conf",
     "At lower k/(M g L) the robot slips less and travels less per cycle (k = 0.3 vs 2.74 M g L)."),
    ("S_grows_with_k", "Sec. II-B", "The distance per cycle decreases as the stiffness decreases."),
    ("threshold", "Sec. II-B", "The robot stops below a critical stiffness k ~ 0.1 M g L."),
    ("force_jump", "Sec. II-B, Fig. simu_forces",
     "Prescribed angles make f_t jump at the switching instants; the hybrid f_t is continuous."),
    ("gamma_opt", "Sec. II-C, Fig. parametric", "The progression is optimal at gamma = pi/2 (A = pi/6)."),
    ("decreasing_psi", "Sec. II-C, Fig. parametric",
     "S decreases monotonically with psi and vanishes as psi -> pi."),
    ("psi_zero", "Sec. II-C", "At psi = 0 the gait is symmetric and the progression vanishes."),
    ("psi_opt", "Sec. II-C, Fig. d_mu",
     "Averaged over mu1/mu2 in [0.9, 1.1], S has an optimal phase difference psi."),
    ("direction", "Sec. II-C, Fig. d_mu",
     "The robot moves in the direction of the phase-leading joint: sign(S) follows sign(psi)."),
    ("higher_friction", "Supplementary, Fig. s_psi_mu",
     "For higher friction S still decreases monotonically with psi, and stops for a growing range of psi."),
    ("S_grows_with_A", "Sec. II-C", "S rises monotonically with the amplitude A."),
    ("A_opt", "Sec. II-C, Fig. CoT", "CoT+ has an energy-optimal amplitude (large and realistic stiffness)."),
    ("softer_cheaper", "Sec. II-C, Fig. CoT", "A softer robot is more energetically efficient (lower CoT+)."),
    ("cot_range", "Fig. CoT", "Each of the three stiffnesses crawls at every amplitude at which the paper plots CoT+."),
    ("pressure", "Sec. III, Fig. exp",
     "The pressure-driven robot's S/Smax grows with p0 and peaks at a small phase difference (~10 deg)."),
)


def check_statements(sets: dict[str, StudySet]) -> list[Statement]:
    """Every statement of :data:`STATEMENTS`, checked in each convention of ``sets``."""
    checks = {g: _statement_checks(s) for g, s in sets.items()}
    return [Statement(key, where, claim, {g: bool(checks[g][key][0]) for g in sets},
                      {g: checks[g][key][1] for g in sets}) for key, where, claim in STATEMENTS]


# --------------------------------------------------------------------------------------------
# the report
# --------------------------------------------------------------------------------------------
def _table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c).replace("|", "/") for c in r) + " |" for r in rows]
    return "\n".join(lines)


def _counts_text(counts: dict[str, int]) -> str:
    return ", ".join(f"{k} {v}" for k, v in counts.items())


def _fig(name: str, caption: str) -> str:
    return f"![{caption}]({name}.png)\n\n*{caption}* ([PDF]({name}.pdf))"


def _report(sets: dict[str, StudySet], gravity: str, mode: str, statements: list[Statement], elapsed: float,
            sweep: SweepOptions) -> str:
    s = sets[gravity]
    other = "physical" if gravity == "paper" else "paper"
    o = sets.get(other)
    out: list[str] = []
    w = out.append
    w("# Reproduction of \"Understanding Inchworm Crawling for Soft-Robotics\"\n")
    w(f"`ocp-crawl reproduce` ({mode} run, ocp_crawl {__version__}, {elapsed:.0f} s with {sweep.jobs} worker(s)). "
      f"Figures in the **{gravity}** gravity convention "
      f"({'the sign printed in eq. (intEq), which the paper computed its curves with' if gravity == 'paper' else 'the virtual-work sign'}); "
      f"the statements table checks both conventions. Robot: Table I (M = 52 g, L = 120 mm, k = 0.1677 N m/rad "
      f"= {REALISTIC_K_RATIO:.3f} M g L, mu = 0.389); reference gait gamma 90, A 30, psi 45 deg, torque "
      "tau = k (phi_ref - pi).\n")
    w("**Sign convention.** S is the displacement per cycle along +x, from foot 1 to foot 2. With psi > 0 joint 1 "
      "leads and the robot moves towards foot 1, so S < 0; the figures plot the progress -S where they compare with "
      "the paper, whose figures show the magnitude of forward progress.\n")
    w("**Failed points are data.** A point whose run stops (a fold of the equilibrium branch, a foot lifting off, a "
      "joint touching the ground, no equilibrium at the start = `no_start`, ...) is drawn as a marker whose shape "
      "names the status and is counted below; derived numbers use the successful points only.\n")
    w("## Grids\n")
    w(_table(["grid", "quick", "full"], [[k, v, GRIDS["full"].rows()[k]] for k, v in GRIDS["quick"].rows().items()]))
    w(f"\nThis run: **{mode}**.\n")

    # ---- statements
    w("## The paper's statements in both conventions\n")
    conv = list(sets)
    rows = []
    for st in statements:
        rows.append([f"{st.claim} ({st.where})"] + [("yes" if st.holds[c] else "**no**") + ": " + st.numbers[c]
                                                    for c in conv])
    w(_table(["statement (where)"] + [f"{c} convention" for c in conv], rows))
    changed = [st for st in statements if st.changed]
    w("\n### Statements the physical convention changes\n")
    if not changed or "physical" not in sets:
        w("None on these grids.\n")
    for st in changed:
        w(f"- **{st.claim}** ({st.where}) holds with the paper's sign: {st.holds.get('paper')}, with the physical "
          f"sign: {st.holds.get('physical')}. Paper's sign: {st.numbers.get('paper')}. Physical sign: "
          f"{st.numbers.get('physical')}.")
    if "paper" in sets and "physical" in sets:
        sp, sq = sets["paper"].gait.torque[0].S, sets["physical"].gait.torque[0].S
        w(f"- Every number shifts a little: S of the reference gait is {_fmt_mm(sp)} (paper's sign) vs "
          f"{_fmt_mm(sq)} (physical), {sq / sp - 1:+.1%}.")
    w("")
    w(_fig("conventions", "Both conventions: progress against stiffness, and CoT+ against amplitude "
                          "(paper's sign solid, physical dashed)"))
    w("")

    # ---- simu_conf, simu_forces
    gc = s.gait
    w("## Fig. simu_conf: configuration and contact positions over a cycle\n")
    w(_fig("simu_conf", "Joint angles, contact positions and snapshots: prescribed angles (solid), torque drive at "
                        "realistic (dashed) and low (dotted) stiffness"))
    rows = []
    for name, r in (("prescribed angles", gc.prescribed), ("torque, k = 2.74 M g L", gc.torque[0]),
                    ("torque, k = 0.3 M g L", gc.torque[1])):
        rows.append([name, r.status_name, _fmt_mm(r.S) if r.success else f"at t = {r.failure_t:.4f} ({r.failure_mode})",
                     f"{gc.stick_fraction(r):.3f}" if r.success else "-", f"{MM * gc.d_max(r):.2f}",
                     f"{r.W_plus * MM:.2f}" if r.success else "-", f"{r.CoT_plus:.2f}" if r.success else "-"])
    w(_table(["run", "status", "S", "stick-stick fraction", "largest d [mm]", "W+ [mJ]", "CoT+"], rows))
    w("\n## Fig. simu_forces: tangential force and friction limits\n")
    w(_fig("simu_forces", "f_t (black) and +-mu_i f_ni (dashed), background by contact mode"))
    w(f"\nLargest jump of f_t across an event: prescribed {gc.force_jump(gc.prescribed):.4f} N, hybrid "
      f"(k = 2.74) {gc.force_jump(gc.torque[0]):.2e} N.\n")

    # ---- parametric
    m = s.parametric
    w("## Fig. parametric: S over the psi-gamma plane, A = 30 deg\n")
    w(_fig("parametric", "Progress -S [mm] over psi and gamma; hatched/marked: failed points"))
    gb, pb, sb = m.best
    w(f"\nLargest progress {_fmt_mm(-sb)} at gamma {gb:g}, psi {pb:g} deg. Points: {_counts_text(m.counts)}.\n")
    w(_table(["psi [deg]"] + [f"{p:g}" for p in m.psi_deg],
             [["best gamma [deg]"] + [f"{v:.1f}" if np.isfinite(v) else "-" for v in m.gamma_opt],
              ["-S at gamma 90 [mm]"] + [f"{MM * v:.2f}" if np.isfinite(v) else "-" for v in
                                         -m.S[int(np.argmin(np.abs(m.gamma_deg - 90)))]]]))
    if o is not None:
        w(f"\n{other} convention: points {_counts_text(o.parametric.counts)}; largest progress "
          f"{_fmt_mm(-o.parametric.best[2])} at gamma {o.parametric.best[0]:g}, psi {o.parametric.best[1]:g} deg.\n")

    # ---- d_mu
    b = s.band
    w("## Fig. d_mu: friction sensitivity and S against psi, negative psi included\n")
    w(_fig("d_mu", "Progress against psi: mu1 = mu2 (solid), mu1/mu2 in [0.9, 1.1] (band), average (dashed)"))
    po, pv = b.psi_opt
    w(f"\nOptimal psi of the average: **{po:.1f} deg** (average progress {_fmt_mm(pv)}); mirror at "
      f"{b.psi_opt_negative[0]:.1f} deg. max |S(psi) + S(-psi)| = {b.antisymmetry():.2e} m. mu1/mu2 = "
      + ", ".join(f"{r:.3f}" for r in b.ratios) + f" at sqrt(mu1 mu2) = 0.389. Points: {_counts_text(b.counts)}.\n")
    lo, hi = b.band
    sel = b.psi_deg >= 0
    w(_table(["psi [deg]", "-S, mu1 = mu2 [mm]", "-S band [mm]", "-S average [mm]"],
             [[f"{p:g}", f"{-MM * n:.2f}", f"{-MM * h:.2f} .. {-MM * l:.2f}", f"{-MM * a:.2f}"]
              for p, n, l, h, a in zip(b.psi_deg[sel], b.nominal[sel], lo[sel], hi[sel], b.average[sel])]))
    if o is not None:
        w(f"\n{other} convention: optimal psi of the average {o.band.psi_opt[0]:.1f} deg "
          f"({_fmt_mm(o.band.psi_opt[1])}).\n")

    # ---- amplitude / CoT
    a = s.amplitude
    w("## Fig. CoT and S against the amplitude\n")
    w(_fig("cot", "Progress and CoT+ against A for k = 5, 2.74, 0.3 M g L (gamma 90, psi 45 deg)"
                  + (", with the paper's values" if gravity == "paper" else "")))
    w(f"\nPoints: {_counts_text(a.counts)}. Least CoT+: " + ", ".join(
        f"{COT_K_LABELS[i]} k {a.CoT_min[i]:.2f}" + (f" at A = {a.A_opt[i]:.1f} deg" if np.isfinite(a.A_opt[i]) else
                                                     " (at the end of the grid)") for i in range(len(a.k_ratios))) + ".\n")
    for label, study in ((gravity, a),) + (((other, o.amplitude),) if o is not None else ()):
        comp = study.paper_comparison()
        if comp is None:
            continue
        rd = comp["rel_diff"]
        w(f"\nCoT+ against the paper's published values ({label} convention): relative difference ours/paper - 1 "
          "(median |.| and largest |.| over the amplitudes where both exist):\n")
        w(_table(["stiffness", "points", "median |rel. diff.|", "largest |rel. diff.|", "at A [deg]"],
                 [[f"{COT_K_LABELS[i]} ({study.k_ratios[i]:.2f} M g L)", str(int(np.isfinite(rd[i]).sum())),
                   f"{np.nanmedian(np.abs(rd[i])):.2%}" if np.isfinite(rd[i]).any() else "-",
                   f"{np.nanmax(np.abs(rd[i])):.2%}" if np.isfinite(rd[i]).any() else "-",
                   f"{study.A_deg[int(np.nanargmax(np.abs(rd[i])))]:.1f}" if np.isfinite(rd[i]).any() else "-"]
                  for i in range(3)]))
        w("")
    comp = a.paper_comparison()
    rows = []
    for j, A in enumerate(a.A_deg):
        row = [f"{A:.2f}"]
        for i in range(len(a.k_ratios)):
            row.append(f"{-MM * a.S[i, j]:.2f}" if np.isfinite(a.S[i, j]) else a.status[i, j])
            cell = f"{a.CoT_plus[i, j]:.2f}" if np.isfinite(a.CoT_plus[i, j]) else (
                "inf (no motion)" if a.status[i, j] == SUCCESS else a.status[i, j])
            if comp is not None and np.isfinite(comp["paper"][i, j]):
                cell += f" (paper {comp['paper'][i, j]:.2f}, {comp['rel_diff'][i, j]:+.1%})" \
                    if np.isfinite(comp["rel_diff"][i, j]) else f" (paper {comp['paper'][i, j]:.2f})"
            row.append(cell)
        rows.append(row)
    w(_table(["A [deg]"] + [h for i in range(len(a.k_ratios)) for h in
                            (f"-S {COT_K_LABELS[i]} k [mm]", f"CoT+ {COT_K_LABELS[i]} k")], rows))

    # ---- higher friction
    h = s.friction
    w("\n## Supplementary figure: higher friction\n")
    w(_fig("s_psi_mu", "Progress against psi for mu = 1, 2, 3, 4 x 0.389"))
    w(f"\nPoints: {_counts_text(h.counts)}.\n")
    w(_table(["mu", "largest -S [mm]", "progress non-increasing in psi", "stops from psi [deg]"],
             [[f"{f:g} x 0.389", f"{np.nanmax(-MM * h.S[i]):.2f}", str(bool(h.monotone()[i])),
               f"{h.psi_stop[i]:.1f}" if np.isfinite(h.psi_stop[i]) else "moves up to 180"]
              for i, f in enumerate(h.factors)]))

    # ---- stiffness
    st = s.stiffness
    w("\n## Stiffness and the friction threshold\n")
    w(_fig("stiffness", "Progress and CoT+ against k/(M g L); the dashed line is the friction threshold"))
    w(f"\nFriction threshold: **k = {st.threshold:.4f} M g L** (bisection bracket {st.threshold_bracket[0]:.5f} .. "
      f"{st.threshold_bracket[1]:.5f}); the robot crawls at every k from {st.onset:.4f} M g L on. The paper says ~{PAPER_THRESHOLD} M g L: relative difference "
      f"{st.threshold / PAPER_THRESHOLD - 1:+.1%}. The realistic stiffness of Table I is {REALISTIC_K_RATIO:.3f} M g L "
      f"(the paper rounds it to {PAPER_REALISTIC}: {REALISTIC_K_RATIO / PAPER_REALISTIC - 1:+.1%}).\n")
    w("Outcomes along k: " + _status_runs(st) + f". Points: {_counts_text(st.counts)}.\n")
    if o is not None:
        w(f"{other} convention: threshold {o.stiffness.threshold:.4f} M g L, crawls at every k from "
          f"{o.stiffness.onset:.4f} M g L on; outcomes: {_status_runs(o.stiffness)}.\n")
    w(_table(["k/(M g L)", "status", "-S [mm]", "CoT+"],
             [[f"{k:.4g}", stt, f"{-MM * v:.2f}" if np.isfinite(v) else "-", f"{c:.2f}" if np.isfinite(c) else "-"]
              for k, stt, v, c in zip(st.k_ratios, st.status, st.S, st.CoT_plus)]))

    # ---- pressure
    p = s.pressure
    c = p.fit.curves
    e_p0, e_psi = p.experiment_rms()
    w("\n## Fig. exp: the pressure-driven robot\n")
    w(_fig("exp", "S/Smax against p0 and psi: this model (blue), the paper's simulation (gray dashed), "
                  "experiments (black, red error bars)"))
    w("\n**Assumptions** (the paper does not state the waveform): pressures are raised sines from 0 to the peak p0, "
      "p_i(t) = p0 (1 + sin(2 pi t +- psi/2))/2; the calibrated bending a_i p^2 + b_i p (Table I) lowers the joint's "
      "reference angle from a rest angle phi_rest, phi_ref,i = phi_rest - bending_i(p_i), with tau_i = k (phi_ref,i - pi). "
      "phi_rest is the one fitted parameter: with a flat rest shape (180 deg) the robot stays nearly flat and S grows "
      "like p0^3 instead of the paper's ~p0^1.8"
      + (f" (flat rest shape on the same grids: RMS error {_num(p.flat.rms_p0)} on the p0 curve, {_num(p.flat.rms_psi)} "
         f"on the psi curve, {p.flat.failures} failed points)" if p.flat is not None else "")
      + ". The p0 curve is assumed computed at psi = "
      f"{c.psi_for_p0_deg:g} deg and normalised at p0 = {P0_NORMALISE_BAR:g} bar (as the paper's), the psi curve at "
      f"p0 = {c.p0_for_psi_bar:g} bar and normalised by its maximum.\n")
    w(f"Rest angle: **{c.phi_rest_deg:.2f} deg** ({'fitted in this run' if p.fit.fitted else 'stored fit'}, "
      f"{c.gravity} convention; stored fits: " + ", ".join(f"{k} {v:g}" for k, v in FITTED_REST_DEG.items())
      + f"). Fit error in S/Smax (model - paper's simulation): RMS {p.fit.rms_p0:.4f} on the p0 curve (largest "
      f"{p.fit.max_p0[0]:.4f} at p0 = {p.fit.max_p0[1]:g} bar), RMS {p.fit.rms_psi:.4f} on the psi curve (largest "
      f"{p.fit.max_psi[0]:.4f} at psi = {p.fit.max_psi[1]:g} deg); failed points {p.fit.failures}. "
      f"Against the experiments: RMS {e_p0:.3f} (p0), {e_psi:.3f} (psi). Best psi {p.psi_opt[0]:.1f} deg "
      "(paper's simulation: 12.0 deg; experiment: 10 deg).\n")
    w("The two features of the paper's psi curve this waveform does not give: S/Smax = 0.33 already at psi = 1 deg "
      "and 0.08 at psi = 180 deg (here both ends are near 0: only the small difference between the two segments' "
      "maps breaks the mirror symmetry).\n")
    w(_table(["p0 [bar]", "model S/Smax", "paper's simulation", "difference", "relative difference", "status"],
             [[f"{x:g}", f"{v + 0.0:.4f}", f"{r:.4f}", f"{v - r:+.4f}", _rel(v, r), stt] for x, v, r, stt in
              zip(c.p0_bar, c.progress_p0, p.fit.ref_p0, c.status_p0)]))
    w("")
    w(_table(["psi [deg]", "model S/Smax", "paper's simulation", "difference", "relative difference", "status"],
             [[f"{x:.2f}", f"{round(v, 4) + 0.0:.4f}", f"{r:.4f}", f"{v - r:+.4f}", _rel(v, r), stt] for x, v, r, stt in
              zip(c.psi_deg, c.progress_psi, p.fit.ref_psi, c.status_psi)]))

    # ---- failures and timing
    w("\n## Failed points by study\n")
    rows = []
    for conv_name, ss in sets.items():
        for name, counts in (("parametric", ss.parametric.counts), ("d_mu", ss.band.counts),
                             ("amplitude", ss.amplitude.counts), ("higher friction", ss.friction.counts),
                             ("stiffness", ss.stiffness.counts)):
            fails = {k: v for k, v in counts.items() if k != SUCCESS}
            rows.append([conv_name, name, str(sum(counts.values())), str(sum(fails.values())),
                         _counts_text(fails) or "-"])
    w(_table(["convention", "study", "points", "failed", "by status"], rows))
    w("\n## Timing\n")
    w(_table(["convention"] + list(s.elapsed), [[cn] + [f"{v:.1f} s" for v in ss.elapsed.values()]
                                                for cn, ss in sets.items()]))
    w("")
    return "\n".join(out) + "\n"


def _numbers(sets: dict[str, StudySet], statements: list[Statement]) -> dict:
    out: dict = {"statements": {st.key: {"claim": st.claim, "holds": st.holds, "numbers": st.numbers}
                                for st in statements}}
    for g, s in sets.items():
        a = s.amplitude
        comp = a.paper_comparison()
        out[g] = {
            "S_reference_gait_m": s.gait.torque[0].S,
            "S_prescribed_m": s.gait.prescribed.S,
            "S_low_k_m": s.gait.torque[1].S, "low_k_status": s.gait.torque[1].status_name,
            "parametric_best": dict(zip(("gamma_deg", "psi_deg", "S_m"), s.parametric.best)),
            "parametric_counts": s.parametric.counts,
            "psi_opt_deg": s.band.psi_opt[0], "psi_opt_average_S_m": -s.band.psi_opt[1],
            "A_opt_deg": dict(zip(COT_K_LABELS, a.A_opt.tolist())),
            "CoT_min": dict(zip(COT_K_LABELS, a.CoT_min.tolist())),
            "CoT_rel_diff_median": None if comp is None else dict(zip(COT_K_LABELS, [
                float(np.nanmedian(np.abs(r))) if np.isfinite(r).any() else None for r in comp["rel_diff"]])),
            "friction_psi_stop_deg": dict(zip((f"{f:g}" for f in s.friction.factors), s.friction.psi_stop.tolist())),
            "threshold_k_over_MgL": s.stiffness.threshold,
            "stiffness_outcomes": [list(r) for r in s.stiffness.ranges()],
            "pressure": {"phi_rest_deg": s.pressure.fit.phi_rest_deg, "fitted": s.pressure.fit.fitted,
                         "rms_p0": s.pressure.fit.rms_p0, "rms_psi": s.pressure.fit.rms_psi,
                         "psi_opt_deg": s.pressure.psi_opt[0]},
            "elapsed_s": s.elapsed,
        }
    return out


# --------------------------------------------------------------------------------------------
# the driver
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ReproduceResult:
    """What ``reproduce`` wrote and the numbers behind it."""

    out_dir: Path
    mode: str
    gravity: str
    files: tuple[Path, ...]
    report: Path
    studies: dict[str, StudySet]
    statements: tuple[Statement, ...]
    elapsed: float


#: figure stem -> (function of the chosen convention's studies and all sets)
FIGURES: dict[str, Callable[[StudySet, dict[str, StudySet]], object]] = {
    "simu_conf": lambda s, _: plot_configuration(s.gait),
    "simu_forces": lambda s, _: plot_forces(s.gait),
    "parametric": lambda s, _: plot_parametric(s.parametric),
    "d_mu": lambda s, _: plot_friction_band(s.band),
    "cot": lambda s, _: plot_amplitude(s.amplitude),
    "s_psi_mu": lambda s, _: plot_higher_friction(s.friction),
    "stiffness": lambda s, _: plot_stiffness(s.stiffness),
    "conventions": lambda _, sets: plot_conventions({g: x.stiffness for g, x in sets.items()},
                                                    {g: x.amplitude for g, x in sets.items()}),
    "exp": lambda s, _: plot_pressure(s.pressure),
}


def reproduce(out_dir: str | Path, quick: bool = False, gravity: str = "paper", sweep: SweepOptions | None = None,
              log: Callable[[str], None] | None = None) -> ReproduceResult:
    """Run every study in both conventions, write the figures of ``gravity`` and ``report.md`` to ``out_dir``.

    ``sweep``: how grids are evaluated (workers, progress, journal); by default serially, with the
    sweeps journaled under ``out_dir/sweeps``.  ``log`` receives one line per step (the CLI prints it).
    """
    if gravity not in GRAVITY_CONVENTIONS:
        raise ValueError(f"gravity must be one of {GRAVITY_CONVENTIONS}, got {gravity!r}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    remove_stale_temps(out)  # temporary files of a killed run (the sweeps clean their own directories)
    sweep = sweep or SweepOptions(out_dir=out / "sweeps")
    mode = "quick" if quick else "full"
    grids = GRIDS[mode]
    say = log or (lambda msg: None)
    start = time.perf_counter()
    # the chosen convention first: its figures are the report's subject
    order = [gravity] + [g for g in GRAVITY_CONVENTIONS if g != gravity]
    sets = {g: run_studies(g, grids, sweep, say) for g in order}
    statements = check_statements(sets)
    files: list[Path] = []
    say("figures ...")
    for stem, draw in FIGURES.items():
        fig = draw(sets[gravity], sets)
        for ext in ("png", "pdf"):
            files.append(save_figure(fig, out / f"{stem}.{ext}"))
    elapsed = time.perf_counter() - start
    text = _report(sets, gravity, mode, statements, elapsed, sweep)
    report = atomic_write(out / "report.md", lambda fh: fh.write(text.encode("utf-8")))
    files.append(write_json(out / "numbers.json", _numbers(sets, statements)))
    files.append(report)
    say(f"done in {elapsed:.0f} s")
    return ReproduceResult(out, mode, gravity, tuple(files), report, sets, tuple(statements), elapsed)


__all__ = ["GRIDS", "Grids", "StudySet", "run_studies", "Statement", "STATEMENTS", "check_statements",
           "ReproduceResult", "reproduce", "FIGURES"]
