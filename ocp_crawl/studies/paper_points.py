"""Our numbers at every abscissa the paper publishes, against its published values (``reproduce``).

The paper's curves (``ocp_crawl/data/paper``) are simulations tabulated on their own grids: CoT+
against the amplitude at 40 amplitudes for three stiffnesses (Fig. CoT), and S/max S of the
pressure-driven robot against p0 (27 pressures) and psi (49 phases) (Fig. exp).  Each published
point is evaluated here directly (one run per point, about 20 ms), so that no worst point is missed
by a coarse grid, and reported as the relative error ours/paper - 1 per figure: median |.|, largest
|.| and where.

CoT+ is ill-conditioned near the friction threshold: a published point whose CoT+ changes by more
than :data:`ILL_CONDITIONED_PER_DEG` per degree of amplitude (central difference of +-
:data:`SLOPE_STEP_DEG`) may instead be matched by an amplitude within :data:`MATCH_WINDOW_DEG` of
the published one: :func:`amplitude_match` finds it with a root bracket.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ocp_crawl.io.paper_data import read_paper_csv
from ocp_crawl.model.pressure import FITTED_REST_DEG, FLAT_REST_DEG, PAPER_FORM_AMPLITUDE_BAR
from ocp_crawl.problem import run_problem
from ocp_crawl.studies.common import COT_K_LABELS, COT_K_RATIOS, PAPER_ROBOT, SUCCESS, base_problem
from ocp_crawl.studies.pressure import PSI_CURVE_AMPLITUDE_BAR, evaluate_fit
from ocp_crawl.studies.text import num, table

#: relative tolerance on a published CoT+ value
COT_TOL = 0.02
#: relative change of CoT+ per degree of amplitude above which a point counts as ill-conditioned
ILL_CONDITIONED_PER_DEG = 0.05
#: half-width [deg] of the amplitude window in which an ill-conditioned point may be matched
MATCH_WINDOW_DEG = 0.2
#: amplitude step [deg] of the central difference that measures the conditioning
SLOPE_STEP_DEG = 0.1
#: the columns of ``fig_cot_vs_amplitude.csv`` in the order of COT_K_RATIOS
COT_COLUMNS = ("CoT_plus_large_k", "CoT_plus_realistic_k", "CoT_plus_low_k")
#: phase difference [deg] with which the paper's low-stiffness CoT+ curve was computed, inferred
#: from its 30 points (least squares with k = 0.3 M g L: 42.03 deg; the paper states none, the other
#: two curves are at 45)
LOW_K_PAPER_PSI_DEG = 42.0
#: the paper's gait phase difference [deg]
PAPER_PSI_DEG = 45.0


@dataclass(frozen=True)
class PaperCurve:
    """One published curve: its abscissae, the paper's values and ours there."""

    key: str
    """e.g. "cot_low" or "exp_p0" """
    label: str
    x_name: str
    """abscissa with unit, e.g. "A [deg]" """
    x: np.ndarray
    paper: np.ndarray
    ours: np.ndarray
    """NaN where the run failed or the robot did not move"""
    status: tuple[str, ...]
    k_ratio: float = math.nan
    """k/(M g L) of a CoT+ curve (NaN for the pressure curves)"""
    psi_deg: float = PAPER_PSI_DEG
    """phase difference [deg] of a CoT+ curve's runs"""

    @property
    def rel(self) -> np.ndarray:
        """ours/paper - 1 at each published point (NaN where ours is missing)."""
        return self.ours / self.paper - 1.0

    @property
    def median(self) -> float:
        r = np.abs(self.rel)
        return float(np.nanmedian(r)) if np.isfinite(r).any() else math.nan

    @property
    def worst(self) -> tuple[float, float]:
        """(signed relative error of largest |.|, abscissa there); NaN if nothing is finite."""
        r = self.rel
        if not np.isfinite(r).any():
            return math.nan, math.nan
        j = int(np.nanargmax(np.abs(r)))
        return float(r[j]), float(self.x[j])

    @property
    def missing(self) -> int:
        """published points without a value of ours (failed or stuck runs)"""
        return int(np.sum(~np.isfinite(self.ours)))

    def beyond(self, tol: float) -> int:
        return int(np.sum(np.abs(np.nan_to_num(self.rel, nan=np.inf)) > tol))

    def summary(self) -> dict:
        w, at = self.worst
        return {"label": self.label, "x": self.x_name, "points": int(self.x.size),
                "median_abs_rel": self.median,
                "worst_rel": w, "worst_at": at, "beyond_2pc": self.beyond(COT_TOL),
                "missing": self.missing}


def cot_at(gravity: str, k_ratio: float, A_deg: float,
           psi_deg: float = PAPER_PSI_DEG) -> tuple[float, str]:
    """CoT+ [-] of the paper's gait (gamma 90 deg, phase difference ``psi_deg`` [deg]) at k/(M g
    L) = ``k_ratio`` and amplitude ``A_deg`` [deg], and the run's status (CoT+ NaN unless the run
    succeeds and the robot moves)."""
    r = run_problem(base_problem(gravity,
                                 {"robot.k": float(k_ratio * PAPER_ROBOT.MgL),
                                  "gait.A_deg": float(A_deg), "gait.psi_deg": float(psi_deg)}))
    ok = r.status_name == SUCCESS and math.isfinite(r.CoT_plus)
    return (float(r.CoT_plus) if ok else math.nan), r.status_name


def cot_curves(gravity: str = "paper") -> list[PaperCurve]:
    """CoT+ at every published point of Fig. CoT, one :class:`PaperCurve` per stiffness
    (``gravity``: "paper" or "physical"); in the paper's convention also the low-stiffness curve at
    the inferred :data:`LOW_K_PAPER_PSI_DEG` (key ``cot_low_psi<deg>``)."""
    data = read_paper_csv("fig_cot_vs_amplitude.csv")
    rows = [(ratio, label, col, PAPER_PSI_DEG) for ratio, label, col in zip(COT_K_RATIOS,
                                                                            COT_K_LABELS,
                                                                            COT_COLUMNS)]
    if gravity == "paper":
        rows.append((COT_K_RATIOS[2], COT_K_LABELS[2], COT_COLUMNS[2], LOW_K_PAPER_PSI_DEG))
    out = []
    for ratio, label, col, psi in rows:
        keep = np.isfinite(data[col])
        A, paper = data["A_deg"][keep], data[col][keep]
        runs = [cot_at(gravity, ratio, a, psi) for a in A]
        tag = "" if psi == PAPER_PSI_DEG else f"_psi{psi:g}"
        how = "" if psi == PAPER_PSI_DEG else f", psi {psi:g} deg (inferred)"
        out.append(PaperCurve(f"cot_{label}{tag}", f"CoT+ {label} k ({ratio:.3g} M g L){how}",
                              "A [deg]", A, paper,
                              np.array([r[0] for r in runs]), tuple(r[1] for r in runs), ratio,
                              psi))
    return out


def relative_slope(gravity: str, k_ratio: float, A_deg: float, h: float = SLOPE_STEP_DEG,
                   psi_deg: float = PAPER_PSI_DEG) -> float:
    """|d CoT+/d A| / CoT+ [1/deg] at ``A_deg`` by a central difference of +-h [deg] (NaN if a run
    fails)."""
    lo, _ = cot_at(gravity, k_ratio, A_deg - h, psi_deg)
    mid, _ = cot_at(gravity, k_ratio, A_deg, psi_deg)
    hi, _ = cot_at(gravity, k_ratio, A_deg + h, psi_deg)
    return abs(hi - lo) / (2 * h * mid)


def amplitude_match(gravity: str, k_ratio: float, A_deg: float, target: float,
                    window: float = MATCH_WINDOW_DEG, psi_deg: float = PAPER_PSI_DEG) -> float:
    """An amplitude [deg] within +-``window`` of ``A_deg`` at which CoT+ equals ``target`` (brentq
    on a bracket; the window is split in four so that a sign change inside it is found); NaN if
    none."""
    edges = np.linspace(A_deg - window, A_deg + window, 5)
    vals = [cot_at(gravity, k_ratio, a, psi_deg)[0] - target for a in edges]
    for a, b, fa, fb in zip(edges[:-1], edges[1:], vals[:-1], vals[1:]):
        if np.isfinite(fa) and np.isfinite(fb) and fa * fb <= 0:
            return float(brentq(lambda x: cot_at(gravity, k_ratio, x, psi_deg)[0] - target, a, b,
                                xtol=1e-4))
    return math.nan


def point_verdicts(curve: PaperCurve, gravity: str) -> list[dict]:
    """For each published point of a CoT+ curve beyond :data:`COT_TOL`: its conditioning and, if
    ill-conditioned, the matching amplitude within the window (runs at the curve's ``k_ratio`` and
    ``psi_deg``).  Returns dicts (A, paper, ours, rel, slope, match_A, verdict)."""
    k_ratio, psi = curve.k_ratio, curve.psi_deg
    rows = []
    for A, p, o, r in zip(curve.x, curve.paper, curve.ours, curve.rel):
        if abs(r) <= COT_TOL or not np.isfinite(r):
            continue
        slope = relative_slope(gravity, k_ratio, A, psi_deg=psi)
        ill = bool(slope > ILL_CONDITIONED_PER_DEG)
        match = amplitude_match(gravity, k_ratio, A, p, psi_deg=psi) if ill else math.nan
        verdict = ("matched at A " + f"{match:.3f} deg" if math.isfinite(match) else
                   ("ill-conditioned, no match within " + f"{MATCH_WINDOW_DEG:g} deg" if ill
                    else "beyond 2 %"))
        rows.append({"A_deg": float(A), "paper": float(p), "ours": float(o), "rel": float(r),
                     "slope_per_deg": slope, "match_A_deg": match, "verdict": verdict})
    return rows


def pressure_points(gravity: str, phi_rest_deg: float,
                    amplitudes: tuple[float, float] | None = None,
                    tag: str = "") -> list[PaperCurve]:
    """S/max S of the pressure-driven robot (rest angle ``phi_rest_deg`` [deg]) at every point of
    the paper's simulated curves of Fig. exp (:func:`~ocp_crawl.studies.pressure.evaluate_fit` on
    the paper's grids).

    ``amplitudes``: None for the raised sine, else the pressure amplitudes [bar] of the paper's form
    (ref) on the p0 and the psi curve; ``tag``: appended to the curves' keys and labels.
    """
    a0, a1 = (None, None) if amplitudes is None else amplitudes
    fit = evaluate_fit(phi_rest_deg, gravity, amplitude_p0_bar=a0, amplitude_psi_bar=a1)
    c = fit.curves
    how = (f", raised sine, rest {phi_rest_deg:g} deg" if amplitudes is None else
           f", form (ref), A_p {a0:g}/{a1:.3g} bar")
    return [PaperCurve("exp_p0" + tag, "S/S(1.7 bar) against p0" + how, "p0 [bar]", c.p0_bar,
                       fit.ref_p0, c.progress_p0, c.status_p0),
            PaperCurve("exp_psi" + tag, "S/max S against psi" + how, "psi [deg]", c.psi_deg,
                       fit.ref_psi, c.progress_psi, c.status_psi)]


@dataclass(frozen=True)
class PaperPoints:
    """Every published curve in one gravity convention, with the verdicts of the CoT+ points beyond
    2 %."""

    gravity: str
    curves: tuple[PaperCurve, ...]
    verdicts: dict[str, list[dict]]
    """CoT+ curve key -> :func:`point_verdicts`"""

    def numbers(self) -> dict:
        return {c.key: {**c.summary(),
                        **({"points_beyond_2pc": self.verdicts[c.key]} if c.key in self.verdicts
                           else {})} for c in self.curves}


def paper_points(gravity: str = "paper", psi_amplitude_bar: float | None = None) -> PaperPoints:
    """Our values at every published point of Figs. CoT and exp in ``gravity`` ("paper" or
    "physical").

    Fig. exp twice: with the paper's form (ref) of the pressure input (flat rest, amplitude 0.4 bar
    on the p0 curve, ``psi_amplitude_bar`` [bar] on the psi curve, None: the stored fit), and with
    the raised sine and the stored fitted rest angle.  Some tens of seconds.
    """
    cot = cot_curves(gravity)
    # the verdicts are for the paper's convention, in which its figures were computed
    verdicts = {c.key: point_verdicts(c, gravity) for c in cot} if gravity == "paper" else {}
    amp = PSI_CURVE_AMPLITUDE_BAR if psi_amplitude_bar is None else psi_amplitude_bar
    form = pressure_points(gravity, FLAT_REST_DEG, (PAPER_FORM_AMPLITUDE_BAR, amp))
    raised = pressure_points(gravity, FITTED_REST_DEG[gravity], None, "_raised")
    return PaperPoints(gravity, tuple(cot + form + raised), verdicts)


def markdown(points: dict[str, PaperPoints]) -> str:
    """The report section: per figure and convention the median and largest relative error at the
    published points, and each CoT+ point beyond 2 % with its conditioning and amplitude match."""
    out = ["\n## Every published point\n",
           "Each point the paper publishes (Figs. CoT and exp, `ocp_crawl/data/paper`) evaluated "
           "at its own abscissa, in both gravity conventions: relative error ours/paper - 1 (S/max "
           "S for Fig. exp).\n"]
    rows = []
    for g, pts in points.items():
        for c in pts.curves:
            w, at = c.worst
            unit = c.x_name.split()[-1].strip("[]")
            rows.append([g, c.label, str(c.x.size), _pc(c.median), _pc(w, "+"),
                         f"{num(at, '.4g')} {unit}", str(c.beyond(COT_TOL)), str(c.missing)])
    out.append(table(["convention", "curve", "points", "median abs. rel.", "worst rel.", "at",
                      "beyond 2 %", "missing"],
                     rows))
    for g, pts in points.items():
        for key, rows_v in pts.verdicts.items():
            if not rows_v:
                continue
            out.append(f"\nCoT+ points of `{key}` beyond 2 % ({g} convention; ill-conditioned: "
                       f"more than {ILL_CONDITIONED_PER_DEG:.0%} change per degree; matched: some "
                       f"amplitude within +-{MATCH_WINDOW_DEG:g} deg gives the published value):\n")
            out.append(table(["A [deg]", "paper", "ours", "rel", "change per deg", "verdict"],
                             [[f"{r['A_deg']:.2f}", f"{r['paper']:.4g}", num(r["ours"]),
                               _pc(r["rel"], "+"),
                               _pc(r["slope_per_deg"]), r["verdict"]] for r in rows_v]))
    out.append(FINDINGS)
    return "\n".join(out) + "\n"


#: what the published points tell about the paper's inputs (measured at every published point;
#: paper's convention)
FINDINGS = (
    "\n"
    "What the differences are (measured at every published point, paper's convention):\n"
    "\n"
    "- **Realistic stiffness, +0.9 % bias**: the published curve is reproduced with rms 0.09 % "
    "(the floor of\n"
    "  the k = 5 curve, 0.10 %) by k/(M g L) = 2.717 instead of Table I's 0.1677/(0.052 * 9.81 * "
    "0.12) = 2.740:\n"
    "  the paper's realistic curve was computed with a k/(M g L) 0.84 % smaller than its Table I "
    "(CoT+ grows\n"
    "  about in proportion to k here: +0.96 % per +1 % of k).  Not a modelling error; the software "
    "keeps Table I.\n"
    "- **Low stiffness (0.3 M g L): the paper's curve was computed with psi = 42 deg, not 45.** "
    "Its text states\n"
    "  no phase difference for Fig. CoT; its other two curves are at 45 deg (CoT+ changes 0.34 % "
    "per degree of\n"
    "  psi at k = 5). With psi = 42.0 deg and Table I otherwise (row `cot_low_psi42`), the 32 "
    "points after the\n"
    "  first are within 0.63 % (rms 0.21 %; the k = 5 curve at its stated inputs, measured the "
    "same way: 0.19\n"
    "  %; least squares: psi = 42.03 deg); the first (A = 11.59 deg, 40 %/deg) is -2.7 % and "
    "matched at A =\n"
    "  11.52 deg, within 0.2 deg. With psi = 45 the same points are +1.0 .. +6.0 % (ours higher: "
    "our robot\n"
    "  moves less, CoT+ near the friction threshold falls steeply as psi decreases). Least squares "
    "with k free:\n"
    "  k x 0.998, psi 42.15 deg, rms 0.15 %. Ruled out, single inputs at their best fit (rms / "
    "worst over the\n"
    "  same 32 points): amplitude offset +0.68 deg 1.53 / 3.2 %; amplitude scale x1.053 1.08 / 3.4 "
    "%; k 0.2954\n"
    "  2.1 / 8.0 %; mu 0.370 0.99 / 3.3 %; gamma 92.5 deg 1.19 / 4.0 %; beta 1.946 2.1 / 7.7 %; "
    "actuator gain\n"
    "  tau = s k (phi_ref - pi) (s 0.988) 2.3 / 7.9 %; unequal amplitudes A (1 -+ 0.02) 2.3 / 6.2 "
    "%; unequal\n"
    "  gamma or mu: no gain (2.45 %); the gravity term's strength x0.8 .. 1.4: 2.3 .. 2.6 %. Pairs "
    "without psi:\n"
    "  (k, mu) 0.42 / 1.0 %, (k, gamma) 0.47 / 1.1 %, (mu, gamma) 0.44 / 1.1 %. Numerics: MPCC "
    "time stepping\n"
    "  with 20 or 30 steps per cycle moves CoT+ by -0.3 .. -2.1 % irregularly in A (and k = 5 by "
    "up to -1.3 %);\n"
    "  a fixed-step scheme that detects the contact events one step late (N = 30 .. 120) moves it "
    "by 0 .. +3.5\n"
    "  % at both stiffnesses, the wrong sign (the same scheme without the lag converges to the "
    "event solver,\n"
    "  within 0.005 % at 2000 steps). Also tried, without gain: the first instead of the steady "
    "cycle, the start\n"
    "  phase, the W+ definition and unequal friction. The default stays psi = 45 deg: at it the "
    "low-stiffness\n"
    "  curve is not within 2 % (table above), an input of the paper's.\n"
    "- **Pressure robot**: the paper's \"nominal pressure p0\" of \"inputs of the form (ref)\" "
    "read literally\n"
    "  (p_i = p0 + A_p sin(2 pi t +- psi/2), flat rest, bending from the clamped-segment "
    "calibration) with\n"
    "  A_p = 0.4 bar (the p0 curve starts at 0.4 bar, where p_i reaches 0) reproduces the p0 curve "
    "with no\n"
    "  fitted parameter (RMS 0.024 over 0.4..3 bar, 0.0013 up to 1.7 bar; the physical sign\n"
    "  does not: 0.05 up to 1.7 bar).  The psi curve's operating point is not stated (at p0 = 1.7 "
    "bar the\n"
    "  amplitude fitted to it is 0.99 bar).  This input is the pressure study's default; the rows\n"
    "  `_raised` show the earlier assumption (raised sine from 0 to a peak p0, fitted rest "
    "angle).  Its RMS <= 0.03 is out of reach of this input family, for a\n"
    "  measured reason: near psi = 0 the model's S is a friction threshold.  Where the robot is "
    "stuck at\n"
    "  psi = 1 deg (every amplitude up to p0 at p0 = 1.7 bar) the published 0.33 there alone gives "
    "RMS >=\n"
    "  0.334/sqrt(49) = 0.048; where a larger input makes it move at 1 deg (p0 = A_p >= 2.2 bar) "
    "it reaches\n"
    "  its maximum by psi = 8 deg instead of the published 12 deg (best of a scan of p0 = 0.4..3 "
    "bar,\n"
    "  A_p <= p0: RMS 0.032 at p0 = A_p = 2.2 bar, best psi 8.2 deg).  The published S(180 deg) = "
    "0.08 is not\n"
    "  reproduced either: the asymmetry of the Table I maps gives S(180 deg)/max S < 0.001 for "
    "every input tried.\n"
)


def _pc(x: float, sign: str = "") -> str:
    """A fraction as a percentage with two decimals ("n/a" if not finite)."""
    return "n/a" if not math.isfinite(x) else format(x, sign + ".2%")
