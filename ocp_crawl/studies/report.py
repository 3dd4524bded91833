"""The text of ``report.md`` (each figure with the numbers behind it, the paper's values where it
publishes them, every statement in both conventions) and the numbers of ``numbers.json``."""
from __future__ import annotations

import numpy as np

from ocp_crawl.version import __version__
from ocp_crawl.model.pressure import FITTED_REST_DEG
from ocp_crawl.studies.common import COT_K_LABELS, MM, REALISTIC_K_RATIO, SUCCESS
from ocp_crawl.studies.cot import AmplitudeStudy
from ocp_crawl.studies.pressure import P0_NORMALISE_BAR
from ocp_crawl.studies.statements import (PAPER_REALISTIC, PAPER_THRESHOLD, Statement,
                                          stiffness_runs_text)
from ocp_crawl.studies.suite import GRIDS, StudySet
from ocp_crawl.studies.text import counts_text, dec, fmt_mm, num, rel, table, threshold_text


def _fig(name: str, caption: str) -> str:
    return f"![{caption}]({name}.png)\n\n*{caption}* ([PDF]({name}.pdf))"


def report(sets: dict[str, StudySet], gravity: str, mode: str, statements: list[Statement],
           elapsed: float, jobs: int, extra: str = "") -> str:
    """The markdown of ``report.md``.

    ``sets``: the studies by convention ({gravity: StudySet}); ``gravity``: the convention of the
    figures; ``mode``: "quick" or "full"; ``elapsed``: wall time [s]; ``jobs``: worker processes;
    ``extra``: markdown sections placed after the studies, before the failed points and the timing
    (last).
    """
    s = sets[gravity]
    o = sets.get("physical" if gravity == "paper" else "paper")
    out = _intro(gravity, mode, elapsed, jobs) + _statements_section(sets, statements)
    out += (_gait_section(s) + _parametric_section(s, o) + _band_section(s, o)
            + _amplitude_section(s, o))
    out += _friction_section(s) + _stiffness_section(s, o) + _pressure_section(s) + [extra]
    out += _failures_section(s, sets)
    return "\n".join(out) + "\n"


def _intro(gravity: str, mode: str, elapsed: float, jobs: int) -> list[str]:
    """Title, conventions and the grids."""
    out: list[str] = []
    w = out.append
    w("# Reproduction of \"Understanding Inchworm Crawling for Soft-Robotics\"\n")
    w(f"`ocp-crawl reproduce` ({mode} run, ocp_crawl {__version__}, {elapsed:.0f} s with {jobs} "
      f"worker(s)). Figures in the **{gravity}** gravity convention "
      f"""({'the sign printed in eq. (intEq), which the paper computed its curves with'
            if gravity == 'paper' else 'the virtual-work sign'}); """
      "the statements table checks both conventions. Robot: Table I (M = 52 g, L = 120 mm, k = "
      f"0.1677 N m/rad = {REALISTIC_K_RATIO:.3f} M g L, mu = 0.389); reference gait gamma 90, A "
      "30, psi 45 deg, torque tau = k (phi_ref - pi).\n")
    w("**Sign convention.** S is the displacement per cycle along +x, from foot 1 to foot 2. With "
      "psi > 0 joint 1 leads and the robot moves towards foot 1, so S < 0; the figures plot the "
      "progress -S where they compare with the paper, whose figures show the magnitude of forward "
      "progress.\n")
    w("**Failed points are data.** A point whose run stops (a fold of the equilibrium branch, a "
      "foot lifting off, a joint touching the ground, no equilibrium at the start = `no_start`, "
      "...) is drawn as a marker whose shape names the status and is counted below; derived "
      "numbers use the successful points only.\n")
    w("## Grids\n")
    w(table(["grid", "quick", "full"],
            [[k, v, GRIDS["full"].rows()[k]] for k, v in GRIDS["quick"].rows().items()]))
    w(f"\nThis run: **{mode}**.\n")
    return out


def _statements_section(sets: dict[str, StudySet], statements: list[Statement]) -> list[str]:
    """The statements table and what the physical convention changes."""
    out: list[str] = []
    w = out.append
    w("## The paper's statements in both conventions\n")
    conv = list(sets)
    rows = []
    for st in statements:
        rows.append([f"{st.claim} ({st.where})"]
                    + [("yes" if st.holds[c] else "**no**") + ": " + st.numbers[c]
                       for c in conv])
    w(table(["statement (where)"] + [f"{c} convention" for c in conv], rows))
    changed = [st for st in statements if st.changed]
    w("\n### Statements the physical convention changes\n")
    if not changed or "physical" not in sets:
        w("None on these grids.\n")
    for st in changed:
        w(f"- **{st.claim}** ({st.where}) holds with the paper's sign: {st.holds.get('paper')}, "
          f"with the physical sign: {st.holds.get('physical')}. Paper's sign: "
          f"{st.numbers.get('paper')}. Physical sign: {st.numbers.get('physical')}.")
    if "paper" in sets and "physical" in sets:
        sp, sq = sets["paper"].gait.torque[0].S, sets["physical"].gait.torque[0].S
        w(f"- Every number shifts a little: S of the reference gait is {fmt_mm(sp)} (paper's sign) "
          f"vs {fmt_mm(sq)} (physical), {sq / sp - 1:+.1%}.")
    w("")
    w(_fig("conventions",
           "Both conventions: progress against stiffness, and CoT+ against amplitude "
           "(paper's sign solid, physical dashed)"))
    w("")
    return out


def _gait_section(s: StudySet) -> list[str]:
    """Fig. simu_conf and simu_forces."""
    gc = s.gait
    out: list[str] = []
    w = out.append
    w("## Fig. simu_conf: configuration and contact positions over a cycle\n")
    w(_fig("simu_conf",
           "Joint angles, contact positions and snapshots: prescribed angles (solid), torque drive "
           "at realistic (dashed) and low (dotted) stiffness"))
    rows = []
    for name, r in (("prescribed angles", gc.prescribed), ("torque, k = 2.74 M g L", gc.torque[0]),
                    ("torque, k = 0.3 M g L", gc.torque[1])):
        rows.append([name, r.status_name,
                     fmt_mm(r.S) if r.success else f"at t = {r.failure_t:.4f} ({r.failure_mode})",
                     f"{gc.stick_fraction(r):.3f}" if r.success else "-", dec(MM * gc.d_max(r)),
                     dec(r.W_plus * MM) if r.success else "-",
                     dec(r.CoT_plus) if r.success else "-"])
    w(table(["run", "status", "S", "stick-stick fraction", "largest d [mm]", "W+ [mJ]", "CoT+"],
            rows))
    w("\n## Fig. simu_forces: tangential force and friction limits\n")
    w(_fig("simu_forces", "f_t (black) and +-mu_i f_ni (dashed), background by contact mode"))
    w(f"\nLargest jump of f_t across an event: prescribed {gc.force_jump(gc.prescribed):.4f} N, "
      f"hybrid (k = 2.74) {gc.force_jump(gc.torque[0]):.2e} N.\n")
    return out


def _parametric_section(s: StudySet, o: StudySet | None) -> list[str]:
    """Fig. parametric."""
    out: list[str] = []
    w = out.append
    m = s.parametric
    w("## Fig. parametric: S over the psi-gamma plane, A = 30 deg\n")
    w(_fig("parametric", "Progress -S [mm] over psi and gamma; hatched/marked: failed points"))
    gb, pb, sb = m.best
    w(f"\nLargest progress {fmt_mm(-sb)} at gamma {gb:g}, psi {pb:g} deg. Points: "
      f"{counts_text(m.counts)}.\n")
    w(table(["psi [deg]"] + [f"{p:g}" for p in m.psi_deg],
             [["best gamma [deg]"] + [f"{v:.1f}" if np.isfinite(v) else "-" for v in m.gamma_opt],
              ["-S at gamma 90 [mm]"] + [dec(MM * v) for v in
                                         -m.S[int(np.argmin(np.abs(m.gamma_deg - 90)))]]]))
    if o is not None:
        w(f"\n{o.gravity} convention: points {counts_text(o.parametric.counts)}; largest progress "
          f"{fmt_mm(-o.parametric.best[2])} at gamma {o.parametric.best[0]:g}, psi "
          f"{o.parametric.best[1]:g} deg.\n")
    return out


def _band_section(s: StudySet, o: StudySet | None) -> list[str]:
    """Fig. d_mu."""
    out: list[str] = []
    w = out.append
    b = s.band
    w("## Fig. d_mu: friction sensitivity and S against psi, negative psi included\n")
    w(_fig("d_mu",
           "Progress against psi: mu1 = mu2 (solid), mu1/mu2 in [0.9, 1.1] (band), average "
           "(dashed)"))
    po, pv = b.psi_opt
    w(f"\nOptimal psi of the average: **{po:.1f} deg** (average progress {fmt_mm(pv)}); mirror at "
      f"{b.psi_opt_negative[0]:.1f} deg. max |S(psi) + S(-psi)| = {b.antisymmetry():.2e} m. "
      "mu1/mu2 = "
      + ", ".join(f"{r:.3f}" for r in b.ratios)
      + f" at sqrt(mu1 mu2) = 0.389. Points: {counts_text(b.counts)}.\n")
    lo, hi = b.band
    sel = b.psi_deg >= 0
    w(table(["psi [deg]", "-S, mu1 = mu2 [mm]", "-S band [mm]", "-S average [mm]"],
             [[f"{p:g}", dec(-MM * n), f"{dec(-MM * h)} .. {dec(-MM * l)}", dec(-MM * a)]
              for p, n, l, h, a in zip(b.psi_deg[sel], b.nominal[sel], lo[sel], hi[sel],
                                       b.average[sel])]))
    if o is not None:
        w(f"\n{o.gravity} convention: optimal psi of the average {o.band.psi_opt[0]:.1f} deg "
          f"({fmt_mm(o.band.psi_opt[1])}).\n")
    return out


def _amplitude_section(s: StudySet, o: StudySet | None) -> list[str]:
    """Fig. CoT, with the paper's values."""
    out: list[str] = []
    w = out.append
    a = s.amplitude
    w("## Fig. CoT and S against the amplitude\n")
    w(_fig("cot", "Progress and CoT+ against A for k = 5, 2.74, 0.3 M g L (gamma 90, psi 45 deg)"
                  + (", with the paper's values" if a.gravity == "paper" else "")))
    w(f"\nPoints: {counts_text(a.counts)}. Least CoT+: " + ", ".join(
        f"{COT_K_LABELS[i]} k {a.CoT_min[i]:.2f}"
        + (f" at A = {a.A_opt[i]:.1f} deg" if np.isfinite(a.A_opt[i]) else
           " (at the end of the grid)") for i in range(len(a.k_ratios))) + ".\n")
    for study in (a,) + ((o.amplitude,) if o is not None else ()):
        out += _cot_against_paper(study)
    comp = a.paper_comparison()
    rows = []
    for j, A in enumerate(a.A_deg):
        row = [f"{A:.2f}"]
        for i in range(len(a.k_ratios)):
            row.append(dec(-MM * a.S[i, j]) if np.isfinite(a.S[i, j]) else a.status[i, j])
            cell = f"{a.CoT_plus[i, j]:.2f}" if np.isfinite(a.CoT_plus[i, j]) else (
                "inf (no motion)" if a.status[i, j] == SUCCESS else a.status[i, j])
            if comp is not None and np.isfinite(comp["paper"][i, j]):
                cell += (f" (paper {comp['paper'][i, j]:.2f}, "
                         f"{num(comp['rel_diff'][i, j], '+.1%')})"
                         if np.isfinite(comp["rel_diff"][i, j])
                         else f" (paper {comp['paper'][i, j]:.2f})")
            row.append(cell)
        rows.append(row)
    w(table(["A [deg]"] + [h for i in range(len(a.k_ratios)) for h in
                            (f"-S {COT_K_LABELS[i]} k [mm]", f"CoT+ {COT_K_LABELS[i]} k")], rows))
    return out


def _friction_section(s: StudySet) -> list[str]:
    """The supplementary figure on higher friction."""
    out: list[str] = []
    w = out.append
    h = s.friction
    w("\n## Supplementary figure: higher friction\n")
    w(_fig("s_psi_mu", "Progress against psi for mu = 1, 2, 3, 4 x 0.389"))
    w(f"\nPoints: {counts_text(h.counts)}.\n")
    w(table(["mu", "largest -S [mm]", "progress non-increasing in psi", "stops from psi [deg]"],
             [[f"{f:g} x 0.389", dec(np.nanmax(-MM * h.S[i])), str(bool(h.monotone()[i])),
               f"{h.psi_stop[i]:.1f}" if np.isfinite(h.psi_stop[i]) else "moves up to 180"]
              for i, f in enumerate(h.factors)]))
    return out


def _stiffness_section(s: StudySet, o: StudySet | None) -> list[str]:
    """Stiffness and the friction threshold."""
    out: list[str] = []
    w = out.append
    st = s.stiffness
    w("\n## Stiffness and the friction threshold\n")
    w(_fig("stiffness",
           "Progress and CoT+ against k/(M g L); the dashed line is the friction threshold"))
    w(f"\nFriction threshold: **k = {threshold_text(st.threshold)}** (bisection bracket "
      f"{num(st.threshold_bracket[0], '.5f')} .. {num(st.threshold_bracket[1], '.5f')}); the robot "
      f"crawls at every k from {threshold_text(st.onset)} on. The paper says ~{PAPER_THRESHOLD} M "
      f"g L: relative difference {num(st.threshold / PAPER_THRESHOLD - 1, '+.1%')}. The realistic "
      f"stiffness of Table I is {REALISTIC_K_RATIO:.3f} M g L (the paper rounds it to "
      f"{PAPER_REALISTIC}: {REALISTIC_K_RATIO / PAPER_REALISTIC - 1:+.1%}).\n")
    w("Outcomes along k: " + stiffness_runs_text(st) + f". Points: {counts_text(st.counts)}.\n")
    if o is not None:
        w(f"{o.gravity} convention: threshold {threshold_text(o.stiffness.threshold)}, crawls at "
          f"every k from {threshold_text(o.stiffness.onset)} on; outcomes: "
          f"{stiffness_runs_text(o.stiffness)}.\n")
    w(table(["k/(M g L)", "status", "-S [mm]", "CoT+"],
             [[f"{k:.4g}", stt, dec(-MM * v), dec(c) if np.isfinite(c) else "-"]
              for k, stt, v, c in zip(st.k_ratios, st.status, st.S, st.CoT_plus)]))
    return out


def _pressure_section(s: StudySet) -> list[str]:
    """Fig. exp."""
    out: list[str] = []
    w = out.append
    p = s.pressure
    c = p.fit.curves
    e_p0, e_psi = p.experiment_rms()
    w("\n## Fig. exp: the pressure-driven robot\n")
    w(_fig("exp",
           "S/Smax against p0 and psi: this model (blue), the paper's simulation (gray dashed), "
           "experiments (black, red error bars)"))
    w(_pressure_assumptions(p))
    fitted = "fitted in this run" if p.fit.fitted else "stored fit"
    w((f"Rest angle: **{c.phi_rest_deg:.2f} deg** ({fitted}, {c.gravity} convention; stored fits: "
       + ", ".join(f"{k} {v:g}" for k, v in FITTED_REST_DEG.items()) + ")"
       if c.amplitude_p0_bar is None else
       f"Pressure amplitude of the psi curve: **{c.amplitude_psi_bar:.3f} bar** ({fitted}, "
       f"{c.gravity} convention)")
      + f". Fit error in S/Smax (model - paper's simulation): RMS {p.fit.rms_p0:.4f} on the p0 "
        "curve (largest "
      f"{p.fit.max_p0[0]:.4f} at p0 = {p.fit.max_p0[1]:g} bar), RMS {p.fit.rms_psi:.4f} on the psi "
      f"curve (largest {p.fit.max_psi[0]:.4f} at psi = {p.fit.max_psi[1]:g} deg); failed points "
      f"{p.fit.failures}. Against the experiments: RMS {e_p0:.3f} (p0), {e_psi:.3f} (psi). Best "
      f"psi {p.psi_opt[0]:.1f} deg (paper's simulation: 12.0 deg; experiment: 10 deg).\n")
    w("The two features of the paper's psi curve this waveform does not give: S/Smax = 0.33 "
      "already at psi = 1 deg and 0.08 at psi = 180 deg (here both ends are near 0: only the small "
      "difference between the two segments' maps breaks the mirror symmetry).\n")
    w(table(["p0 [bar]", "model S/Smax", "paper's simulation", "difference", "relative difference",
             "status"],
             [[f"{x:g}", f"{v + 0.0:.4f}", f"{r:.4f}", f"{v - r:+.4f}", rel(v, r),
               stt] for x, v, r, stt in
              zip(c.p0_bar, c.progress_p0, p.fit.ref_p0, c.status_p0)]))
    w("")
    w(table(["psi [deg]", "model S/Smax", "paper's simulation", "difference", "relative difference",
             "status"],
             [[f"{x:.2f}", f"{round(v, 4) + 0.0:.4f}", f"{r:.4f}", f"{v - r:+.4f}", rel(v, r),
               stt] for x, v, r, stt in
              zip(c.psi_deg, c.progress_psi, p.fit.ref_psi, c.status_psi)]))
    return out


def _pressure_assumptions(p) -> str:
    """The pressure input of the study: the paper's form (ref) or the raised sine with a fitted rest
    angle."""
    c = p.fit.curves
    where = (f"The p0 curve is computed at psi = {c.psi_for_p0_deg:g} deg and normalised at p0 = "
             f"{P0_NORMALISE_BAR:g} bar (as the paper's), the psi curve at p0 = "
             f"{c.p0_for_psi_bar:g} bar and normalised by its maximum.\n")
    flat = (" (raised sine with the flat rest shape on the same grids: RMS error "
            f"{num(p.flat.rms_p0)} on the p0 curve, {num(p.flat.rms_psi)} on the psi curve, "
            f"{p.flat.failures} failed points)" if p.flat is not None else "")
    if c.amplitude_p0_bar is not None:
        return ("\n**Input**: the paper's \"inputs of the form (ref)\" with \"nominal pressure "
                "p0\", read literally: p_i(t) = p0 + A_p sin(2 pi t +- psi/2); the calibrated "
                "bending a_i p^2 + b_i p (Table I, measured from the flat clamped beam) lowers the "
                "joint's reference angle from the flat shape, phi_ref,i = 180 deg - "
                f"bending_i(p_i), tau_i = k (phi_ref,i - pi). A_p = {c.amplitude_p0_bar:g} bar on "
                "the p0 curve (it starts at 0.4 bar, where p_i reaches 0; no fitted parameter); "
                "the psi curve's amplitude is not stated and is fitted" + flat + ". " + where)
    return ("\n**Assumptions** (the paper does not state the waveform): pressures are raised sines "
            "from 0 to the peak p0, p_i(t) = p0 (1 + sin(2 pi t +- psi/2))/2; the calibrated "
            "bending a_i p^2 + b_i p (Table I) lowers the joint's reference angle from a rest "
            "angle phi_rest, phi_ref,i = phi_rest - bending_i(p_i), with tau_i = k (phi_ref,i - "
            "pi). phi_rest is the one fitted parameter" + flat + ". " + where)


def _failures_section(s: StudySet, sets: dict[str, StudySet]) -> list[str]:
    """Failed points by study and the wall times."""
    out: list[str] = []
    w = out.append
    w("\n## Failed points by study\n")
    rows = []
    for conv_name, ss in sets.items():
        for name, counts in (("parametric", ss.parametric.counts), ("d_mu", ss.band.counts),
                             ("amplitude", ss.amplitude.counts),
                             ("higher friction", ss.friction.counts),
                             ("stiffness", ss.stiffness.counts)):
            fails = {k: v for k, v in counts.items() if k != SUCCESS}
            rows.append([conv_name, name, str(sum(counts.values())), str(sum(fails.values())),
                         counts_text(fails) or "-"])
    w(table(["convention", "study", "points", "failed", "by status"], rows))
    w("\n## Timing\n")
    w(table(["convention"] + list(s.elapsed), [[cn] + [f"{v:.1f} s" for v in ss.elapsed.values()]
                                                for cn, ss in sets.items()]))
    w("")
    return out


def _cot_against_paper(study: AmplitudeStudy) -> list[str]:
    """The relative difference of CoT+ to the paper's published values (nothing unless the paper's
    stiffnesses)."""
    comp = study.paper_comparison()
    if comp is None:
        return []
    rd = comp["rel_diff"]
    has = [np.isfinite(r).any() for r in rd]
    rows = [[f"{COT_K_LABELS[i]} ({study.k_ratios[i]:.2f} M g L)",
             str(int(np.isfinite(rd[i]).sum())), f"{_median_abs(rd[i]):.2%}" if has[i] else "-",
             f"{np.nanmax(np.abs(rd[i])):.2%}" if has[i] else "-",
             f"{study.A_deg[int(np.nanargmax(np.abs(rd[i])))]:.1f}" if has[i]
             else "-"] for i in range(3)]
    return [f"\nCoT+ against the paper's published values ({study.gravity} convention): relative "
            "difference ours/paper - 1 (median |.| and largest |.| over the amplitudes where both "
            "exist):\n",
            table(["stiffness", "points", "median |rel. diff.|", "largest |rel. diff.|",
                   "at A [deg]"], rows), ""]


def _median_abs(x: np.ndarray) -> float:
    """Median of |x| ignoring NaN (NaN if no value is finite)."""
    return float(np.nanmedian(np.abs(x))) if np.isfinite(x).any() else float("nan")


def numbers(sets: dict[str, StudySet], statements: list[Statement]) -> dict:
    """The numbers of ``numbers.json``: the statements and, per convention, the studies' key
    numbers.

    Non-finite numbers stay NaN here; :func:`~ocp_crawl.io.files.write_json` writes them as null.
    """
    out: dict = {"statements": {st.key: {"claim": st.claim, "holds": st.holds,
                                         "numbers": st.numbers}
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
                _median_abs(r) for r in comp["rel_diff"]])),
            "friction_psi_stop_deg": dict(zip((f"{f:g}" for f in s.friction.factors),
                                              s.friction.psi_stop.tolist())),
            "threshold_k_over_MgL": s.stiffness.threshold,
            "stiffness_outcomes": [list(r) for r in s.stiffness.ranges()],
            "pressure": {"phi_rest_deg": s.pressure.fit.phi_rest_deg,
                         "fitted": s.pressure.fit.fitted,
                         "rms_p0": s.pressure.fit.rms_p0, "rms_psi": s.pressure.fit.rms_psi,
                         "psi_opt_deg": s.pressure.psi_opt[0]},
            "elapsed_s": s.elapsed,
        }
    return out
