"""Which lumped model explains the pressure robot's experiments: three fits side by side.

The paper's robot moves at psi = 0 and about 4x farther than its three-link model; the authors
blame uneven segments and ask for "a model which better captures the higher order elastic effects
but remains lumped".  Three models of the Table I robot (physical gravity, the paper's input form
p_i = p0 + A_p sin(2 pi t +- psi/2), Table I's maps) are fitted by ``ocp-crawl fit`` to both
measured curves at once, S_norm against p0 and against psi with psi = 0 included
(examples/paper_pressure_p0.csv, examples/paper_pressure_psi_all.csv):

1. symmetric three-link (problems/paper_gait.toml under pressure): the amplitude A_p and the rest
   angle of the segments;
2. asymmetric three-link (problems/pressure_robot_chain.toml): also the two joints' stiffnesses
   k1, k2, from the best of a Latin hypercube sample of their bounds (``starts``): at equal joints
   S at psi = 0 is exactly 0 for every small asymmetry, so a search from there cannot leave it;
3. five links, each segment an arc of two hinges (problems/pressure_robot_five_links.toml): A_p
   and the rest angle.

For each it reports the fitted values with uncertainties (for the asymmetric one also chi2 against
k1 / k2, the others as fitted), chi2, the RMS of S_norm on each curve, S(psi = 0) / S_max and the
best psi of the model's psi curve, and S [mm] at the best psi (the data are normalised: they fix
no scale, so the 4x distance is compared with the models' own S).

Run: ``python examples/11_lumped_models.py [OUT_DIR]``; writes ``OUT_DIR/<model>/`` (the fit's
files) and ``lumped_models.png``; about 16 min of CPU, 11 min on two worker processes.  With
``OCP_CRAWL_EXAMPLES_QUICK=1`` (the examples' test) the two three-link models each fit their
amplitude alone to three rows of the psi curve in one evaluation and draw their curves at two
points, without fit.png or the chi2 profile of k1 / k2: the same steps, not a fit.
"""
import math
from pathlib import Path

import numpy as np
from _common import output_dir, quick, save
from matplotlib.figure import Figure

from ocp_crawl.fit import fit_measurements, read_measurements, resolve_parameters
from ocp_crawl.fit.forward import evaluate_rows, model_values, row_tasks
from ocp_crawl.fit.report import fit_report, write_fit
from ocp_crawl.io.tables import write_table
from ocp_crawl.problem import load_problem, run_problem

HERE = Path(__file__).resolve().parent
PROBLEMS = HERE.parent / "problems"
DATA = [HERE / "paper_pressure_p0.csv", HERE / "paper_pressure_psi_all.csv"]
SHAPE = ["pressure.amplitude_bar", "pressure.phi_rest_deg"]
SHAPE_BOUNDS = ["pressure.amplitude_bar=0.05:1.5", "pressure.phi_rest_deg=165:185"]
#: name -> (problem file, --set, parameters, bounds, Latin hypercube starts)
MODELS = {
    "symmetric": ("paper_gait.toml", ["gait.waveform=pressure", "gait.p0_bar=1.7",
                                      "pressure.phi_rest_deg=177"], SHAPE, SHAPE_BOUNDS, 0),
    "asymmetric": ("pressure_robot_chain.toml", ["pressure.phi_rest_deg=177"],
                   ["robot.stiffness[0]", "robot.stiffness[1]", *SHAPE],
                   ["robot.stiffness[0]=0.08:0.35", "robot.stiffness[1]=0.08:0.35",
                    *SHAPE_BOUNDS], 16),
    "five links": ("pressure_robot_five_links.toml", ["pressure.phi_rest_deg=177"], SHAPE,
                   SHAPE_BOUNDS, 0),
}
PSI_DEG = np.arange(0.0, 181.0, 5.0)
P0_BAR = np.round(np.arange(0.6, 1.71, 0.1), 2)
#: the ratios k1 / k2 of the asymmetric model's chi2 profile
RATIOS = (1.0, 1.6, 1.8, 2.0, 2.2, 2.6, 3.0)
#: the pressure amplitude of the p0 curve's inputs (its file's A_p column)
P0_CURVE_AMPLITUDE_BAR = 0.4


def curve(fit, p0_bar, psi_deg, amplitude_bar=None) -> np.ndarray:
    """S [m] of the fitted model at each (p0, psi) of the arrays (NaN where it fails), at the fit's
    pressure amplitude or ``amplitude_bar``."""
    pressure = {f"pressure.{k}": v for k, v in fit.pressure.items() if math.isfinite(v)}
    if amplitude_bar is not None:
        pressure["pressure.amplitude_bar"] = amplitude_bar
    out = []
    for p0, psi in np.broadcast(p0_bar, psi_deg):
        problem = fit.problem.with_values({"gait.waveform": "pressure", "gait.p0_bar": float(p0),
                                           "gait.psi_deg": float(psi), **pressure})
        result = run_problem(problem)
        out.append(result.S if result.success else math.nan)
    return np.array(out)


def summary(fit, psi_deg, p0_bar) -> dict:
    """What the fitted model explains: RMS of S_norm per curve fitted, S(0)/S_max, best psi, S
    there."""
    # the p0 curve at its file's amplitude (its A_p column), the psi curve at the fitted one
    s_psi, s_p0 = curve(fit, 1.7, psi_deg), curve(fit, p0_bar, 45.0, P0_CURVE_AMPLITUDE_BAR)
    best = int(np.nanargmax(np.abs(s_psi)))
    rms = {"psi" if "psi" in Path(f.data.path).name else "p0":
           float(np.sqrt(np.mean((f.model - f.data.y) ** 2))) for f in fit.files}
    return {"psi": s_psi / s_psi[best], "p0": s_p0 / s_p0[-1],
            "rms_psi": rms.get("psi", math.nan), "rms_p0": rms.get("p0", math.nan),
            "S0": abs(s_psi[0] / s_psi[best]), "best_psi": float(psi_deg[best]),
            "S_best_mm": abs(s_psi[best]) * 1e3}


def stiffness_ratio(fit) -> tuple[float, float]:
    """k1 / k2 of the fitted joints and its standard uncertainty (from the covariance of the two:
    the data may fix their ratio where they do not fix either)."""
    names = [p.name for p in fit.parameters]
    i, j = names.index("robot.stiffness[0]"), names.index("robot.stiffness[1]")
    k1, k2, cov = fit.x[i], fit.x[j], fit.covariance
    var = cov[i, i] / k1**2 + cov[j, j] / k2**2 - 2 * cov[i, j] / (k1 * k2)
    return k1 / k2, k1 / k2 * math.sqrt(max(var, 0.0))


def ratio_profile(fit, data, ratios) -> list[tuple[float, float]]:
    """chi2 of the fitted asymmetric model with k1 set to each ratio times the fitted k2 (the other
    parameters as fitted): what the data say of the ratio beyond the linearisation."""
    k2 = fit.values()["robot.stiffness[1]"]
    out = []
    for ratio in ratios:
        problem = fit.problem.with_values({"robot.stiffness[0]": ratio * k2})
        r = [(model_values(d, evaluate_rows(row_tasks(problem, d, {}, fit.pressure))) - d.y)
             / d.sigma for d in data]
        out.append((ratio, float(np.sum(np.concatenate(r) ** 2))))
    return out


def figure(results: dict, psi_deg, p0_bar, data) -> Figure:
    fig = Figure(figsize=(11, 4.4), layout="constrained")
    ax_psi, ax_p0 = fig.subplots(1, 2)
    p0_data, psi_data = data
    ax_psi.errorbar(np.degrees(psi_data.table["psi"]), psi_data.y, psi_data.sigma, fmt="ko",
                    capsize=3, label="experiment (Fig. exp)")
    ax_p0.errorbar(p0_data.table["p0"] / 1e5, p0_data.y, p0_data.sigma, fmt="ko", capsize=3,
                   label="experiment (Fig. exp)")
    for (name, (fit, s)), style in zip(results.items(), ("-", "--", ":")):
        label = f"{name}: RMS {s['rms_psi']:.3f} (psi), {s['rms_p0']:.3f} (p0)"
        ax_psi.plot(psi_deg, s["psi"], style, lw=2, label=label)
        ax_p0.plot(p0_bar, s["p0"], style, lw=2, label=label)
    ax_psi.set(xlabel="phase difference psi [deg]", ylabel="S / S_max [-]",
               title="S against psi at p0 = 1.7 bar")
    ax_p0.set(xlabel="nominal pressure p0 [bar]", ylabel="S / S(1.7 bar) [-]",
              title="S against p0 at psi = 45 deg")
    for ax in (ax_psi, ax_p0):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    best = min(results, key=lambda n: results[n][1]["rms_psi"])
    s = results[best][1]
    fig.suptitle("Lumped models of the pressure robot fitted to both measured curves (physical "
                 f"gravity, Table I's maps)\nbest on psi: {best}, RMS {s['rms_psi']:.3f}, "
                 f"S(0)/S_max {s['S0']:.2f} (measured 0.94), best psi {s['best_psi']:.0f} deg "
                 "(measured 10)")
    return fig


def _quick_rows(out: Path, data) -> list:
    """Three rows of the psi curve (psi = 0, 10, 50 deg), for the examples' test."""
    psi, rows = data[1], [0, 2, 4]
    path = write_table(out / "psi_rows.csv", [
        ("psi", "deg", np.degrees(psi.table["psi"][rows])),
        ("p0", "bar", psi.table["p0"][rows] / 1e5),
        ("S_norm", "-", psi.y[rows]), ("sigma_S_norm", "-", psi.sigma[rows])])
    return [read_measurements(path)]


def main(out: Path) -> None:
    data = [read_measurements(p) for p in DATA]
    used, psi_deg, p0_bar, nfev = data, PSI_DEG, P0_BAR, 60
    if quick():
        used, psi_deg, p0_bar, nfev = _quick_rows(out, data), PSI_DEG[[0, 2]], P0_BAR[-2:], 1
    results = {}
    for name, (file, sets, names, bounds, starts) in MODELS.items():
        if quick() and name == "five links":   # (its rows cost 0.7 s each)
            continue
        problem = load_problem(PROBLEMS / file, sets)
        if quick():
            names, bounds, starts = names[-2:-1], bounds[-2:-1], min(starts, 1)
        params = resolve_parameters(problem, names, bounds=bounds)
        fit = fit_measurements(problem, used, params, max_nfev=nfev, jobs=1 if quick() else 2,
                               starts=starts)
        print(f"== {name} ==\n{fit_report(fit)}")
        if "robot.stiffness[1]" in names:
            print("k1 / k2 = {:.3g} +- {:.2g} (linearised)".format(*stiffness_ratio(fit)))
            for ratio, chi2 in ratio_profile(fit, used, RATIOS):
                print(f"  chi2 at k1 / k2 = {ratio:.1f}, the others as fitted: {chi2:.1f}")
        write_fit(fit, out / name.replace(" ", "_"), figure=not quick())
        results[name] = (fit, summary(fit, psi_deg, p0_bar))
    # the paper's simulated robot: Table I, A_p = 0.4 bar, flat rest shape (not fitted)
    paper = load_problem(PROBLEMS / "paper_gait.toml",
                         ["gait.waveform=pressure", "gait.p0_bar=1.7"])
    s_paper = max(abs(run_problem(paper.with_values({"gait.psi_deg": float(p)})).S)
                  for p in psi_deg) * 1e3
    print(f"\n{'model':<12} {'chi2':>7} {'RMS psi':>8} {'RMS p0':>7} {'S0/Smax':>8} "
          f"{'best psi':>9} {'S there [mm]':>13} {'/ paper':>8}")
    for name, (fit, s) in results.items():
        print(f"{name:<12} {fit.chi2:7.1f} {s['rms_psi']:8.3f} {s['rms_p0']:7.3f} "
              f"{s['S0']:8.2f} {s['best_psi']:9.0f} {s['S_best_mm']:13.2f} "
              f"{s['S_best_mm'] / s_paper:8.2f}")
    print(f"(/ paper: S at the best psi over that of Table I's robot at A_p = 0.4 bar and the flat "
          f"rest shape, {s_paper:.2f} mm; the measured robot moves about 4x that)")
    save(figure(results, psi_deg, p0_bar, data), out / "lumped_models.png")


if __name__ == "__main__":
    main(output_dir())
