"""The search's start: the best of a Latin hypercube sample of the bounds (``--starts``), where
the start values fail too, and the statuses where a file's normalising row does not move."""
import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from ocp_crawl.cli.app import main
from ocp_crawl.fit import fit_measurements, read_measurements, resolve_parameters
from ocp_crawl.fit.report import fit_dict, fit_report
from ocp_crawl.io.tables import write_table
from ocp_crawl.problem import load_problem
from ocp_crawl.status import Status
from test_fit import PAPER, TRUE, _s_vs_amplitude

REPO = Path(__file__).resolve().parent.parent
FITTED = REPO / "problems" / "pressure_robot_asymmetric_fit.toml"


def test_a_sampled_start_is_the_best_of_the_sample_and_the_fit_recovers_the_truth(tmp_path,
                                                                                 capsys):
    """--starts 12 from a far start: the search starts at the sample's best point (its chi2 that
    of a fresh evaluation there, at most the start's), inside the bounds, and recovers k and mu;
    the same fit twice starts at the same point; the report and the JSON say where it started."""
    problem = load_problem(PAPER)
    path, _ = _s_vs_amplitude(problem, tmp_path)
    params = resolve_parameters(problem, list(TRUE), start=["robot.k=0.6", "robot.mu=0.55"],
                                bounds=["robot.k=0.05:1.0", "robot.mu=0.2:0.6"])
    fits = [fit_measurements(problem, [read_measurements(path)], params, starts=12)
            for _ in range(2)]
    scan = fits[0].scan
    assert scan is not None and scan == fits[1].scan and scan.points == 12
    assert scan.chi2_best < scan.chi2_start and not scan.from_start
    assert all(p.low <= v <= p.high for p, v in zip(params, scan.best))
    again = fit_measurements(problem, [read_measurements(path)], [
        dataclasses.replace(p, x0=v) for p, v in zip(params, scan.best)], max_nfev=1)
    assert again.scan is None and again.chi2 <= scan.chi2_best * (1 + 1e-9)
    fit = fits[0]
    assert fit.success, fit.message
    for p, x, sigma in zip(fit.parameters, fit.x, fit.sigma):
        assert abs(x - TRUE[p.name]) < 3 * sigma, (p.name, x, sigma)
    assert "start      best of 12 Latin hypercube points" in fit_report(fit)
    assert main(["fit", str(PAPER), str(path), "--param", "robot.k", "--starts", "3", "--json",
                 "--no-figure", "--out", str(tmp_path / "cli")]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["scan"]["points"] == 3 and out["scan"]["chi2_best"] <= out["scan"]["chi2_start"]


def _psi_rows(tmp_path) -> Path:
    """S_norm at psi = 0 (the normalising row), 10 and 45 deg of the measured curve."""
    return write_table(tmp_path / "psi.csv", [
        ("psi", "deg", np.array([0.0, 10.0, 45.0])), ("p0", "bar", np.full(3, 1.7)),
        ("S_norm", "-", np.array([1.0, 0.97, 0.92])), ("sigma_S_norm", "-", np.full(3, 0.1))])


def test_a_normalising_row_that_does_not_move_is_a_status_naming_it(tmp_path):
    """The symmetric robot at psi = 0 does not move whatever its amplitude: the start and every
    sampled point fail, no_convergence naming the row, never a crash or NaN in the JSON."""
    problem = load_problem(PAPER, ["gait.waveform=pressure", "gait.p0_bar=1.7"])
    data = [read_measurements(_psi_rows(tmp_path))]
    params = resolve_parameters(problem, ["pressure.amplitude_bar"],
                                bounds=["pressure.amplitude_bar=0.1:0.8"])
    fit = fit_measurements(problem, data, params, starts=3)
    assert fit.status == Status.NO_CONVERGENCE
    assert "does not move at the normalising row" in fit.message and "psi.csv:2" in fit.message
    assert "every one of the 3 sampled points" in fit.message
    assert fit.scan is not None and fit.scan.best is None and fit.scan.failed == 3
    json.dumps(fit_dict(fit), allow_nan=False)


def test_the_sample_starts_the_search_where_the_start_values_fail(tmp_path):
    """Equal joints of the fitted asymmetric robot do not move at psi = 0, the normalising row:
    the search starts at the best sampled point that moves there (k2 well below k1)."""
    problem = load_problem(FITTED)
    data = [read_measurements(_psi_rows(tmp_path))]
    k1 = problem.robot.stiffness[0]
    params = resolve_parameters(problem, ["robot.stiffness[1]"],
                                start=[f"robot.stiffness[1]={k1}"],
                                bounds=[f"robot.stiffness[1]=0.1:{k1}"])
    fit = fit_measurements(problem, data, params, max_nfev=1, starts=4)
    scan = fit.scan
    assert scan is not None and scan.chi2_start is None and not scan.from_start
    assert scan.best is not None and scan.best[0] < k1 / 2 and np.isfinite(scan.chi2_best)
    assert fit.files[0].statuses == ("success",) * 3 and np.isfinite(fit.chi2)
    assert "at the start values: a row fails there" in fit_report(fit)


def test_starts_must_be_a_count():
    problem = load_problem(PAPER)
    for bad in (-1, 2.5, True):
        with pytest.raises(ValueError, match="starts must be an integer >= 0"):
            fit_measurements(problem, [], [], starts=bad)
