"""Calibrate the pressure-driven robot to the paper's experiments (``ocp-crawl fit``, step by step).

Data: the paper's measured S/max S against the nominal pressure p0 and the phase difference psi
(Fig. exp), as measurement files of the package's CSV convention with stated uncertainties
(examples/paper_pressure_p0.csv and paper_pressure_psi.csv; their comments say how they were
derived and which operating points are assumed).  Model: the Table I robot, paper gravity
convention, pressure actuator of ``ocp_crawl.model.pressure`` with the inputs of the paper's form
(ref), p_i = p0 + A_p sin(2 pi t +- psi/2), p0 the nominal (mean) pressure as the paper's text says,
and the flat rest shape (180 deg: the clamped-segment calibration measures the bending from flat).

1. The amplitude A_p of the psi curve's inputs (``pressure.amplitude_bar``), which the paper does
   not state.  The p0 file fixes its own A_p = 0.4 bar in a column: the normalised p0 curve does
   not determine it (fitted alone: 0.27 +- 2.2 bar), and it must stay <= 0.6 bar (p_i >= 0 at the
   smallest measured p0).
2. k and the four pressure-map constants a_i, b_i together, at the A_p of step 1, and the
   comparison with Table I.  Normalised data cannot fix the actuator, and the fit says so: it
   lists the directions the data do not determine (here the overall scale of the map, all four
   constants up together; k alone is fixed only loosely, through the sag under gravity).

Same as the command line (step 1):
    ocp-crawl fit problems/paper_gait_paper_gravity.toml examples/paper_pressure_p0.csv \\
        examples/paper_pressure_psi.csv --param pressure.amplitude_bar \\
        --bounds pressure.amplitude_bar=0.05:1.7 --out fit_amplitude

Run: ``python examples/08_fit_pressure_robot.py [OUT_DIR]``; writes ``OUT_DIR/amplitude/`` and
``OUT_DIR/k_and_map/`` (fitted_problem.toml, fit.json, residuals.csv, fit.png each); about 4 min of
CPU (step 2 on two worker processes).  With ``OCP_CRAWL_EXAMPLES_QUICK=1`` (the examples' test) both
fits stop after a few evaluations: the same outputs, not converged (the report says so).
"""
from pathlib import Path

from _common import output_dir, quick

from ocp_crawl.fit import fit_measurements, read_measurements, resolve_parameters
from ocp_crawl.fit.report import fit_report, write_fit
from ocp_crawl.model.statics import PAPER_PRESSURE_COEFFS, Robot
from ocp_crawl.problem import load_problem

HERE = Path(__file__).resolve().parent
PROBLEM = HERE.parent / "problems" / "paper_gait_paper_gravity.toml"
DATA = [HERE / "paper_pressure_p0.csv", HERE / "paper_pressure_psi.csv"]


def main(out: Path) -> None:
    nfev_amplitude, nfev_map = (2, 2) if quick() else (30, 150)
    problem = load_problem(PROBLEM)
    data = [read_measurements(p) for p in DATA]

    amp = fit_measurements(problem, data, resolve_parameters(problem, ["pressure.amplitude_bar"],
                                                             bounds=["pressure.amplitude_bar=0.05:1.7"]),
                           max_nfev=nfev_amplitude)
    print("== 1. amplitude A_p of the psi curve's inputs ==\n" + fit_report(amp))
    print("wrote", ", ".join(str(p) for p in write_fit(amp, out / "amplitude")), "\n")

    names = ["robot.k", "pressure.a1", "pressure.b1", "pressure.a2", "pressure.b2"]
    both = fit_measurements(problem, data, resolve_parameters(problem, names), max_nfev=nfev_map,
                            jobs=2, pressure={"amplitude_bar": float(amp.x[0])})
    print("== 2. k and the pressure map ==\n" + fit_report(both))
    print("wrote", ", ".join(str(p) for p in write_fit(both, out / "k_and_map")))
    table = {"robot.k": Robot.paper().k,
             **{f"pressure.{k}": v for k, v in PAPER_PRESSURE_COEFFS.items()}}
    print("\n== fitted constants against Table I ==")
    print(f"{'parameter':<14} {'Table I':>9} {'fitted':>9} {'sigma':>9} "
          f"{'(fit - Table I)/sigma':>22}")
    for p, x, s in zip(both.parameters, both.x, both.sigma):
        print(f"{p.name:<14} {table[p.name]:9.4f} {x:9.4f} {s:9.3g} "
              f"{(x - table[p.name]) / s:22.2f}")


if __name__ == "__main__":
    main(output_dir())
