"""Bad input of ``ocp-crawl fit`` and of the fit library: exit 2 and one stderr line naming the
option or the file and row, before any simulation; the library raises ProblemError / TableError with
the same message.

Every CLI case runs with the least-squares search and the simulations replaced by a function that
fails the test (:func:`no_fit`): bad input must be rejected before them (a rejection after them
would be exit 1).
"""
from pathlib import Path

import pytest

import ocp_crawl.fit.forward
import ocp_crawl.fit.solve
from ocp_crawl.cli.app import main
from ocp_crawl.fit import fit_measurements, read_measurements, resolve_parameters
from ocp_crawl.fit.params import fixed_pressure
from ocp_crawl.io.tables import TableError
from ocp_crawl.problem import ProblemError, load_problem

REPO = Path(__file__).resolve().parent.parent
PAPER = REPO / "problems" / "paper_gait.toml"
PAPER_GRAVITY = REPO / "problems" / "paper_gait_paper_gravity.toml"
PSI_DATA = REPO / "ocp_crawl" / "data" / "examples" / "paper_pressure_psi.csv"
GAIT_ROWS = ("{col} [deg],S [mm],sigma_S "
             "[mm]\n{first},-27.7,0.2\n{bad},-41.1,0.2\n{last},-56.0,0.2\n")


def _computed(*args, **kwargs):
    raise AssertionError("a simulation or the search started before the bad input was rejected")


@pytest.fixture
def no_fit(monkeypatch):
    """The search and every simulation of a row fail the test if called."""
    monkeypatch.setattr(ocp_crawl.fit.solve, "least_squares", _computed)
    monkeypatch.setattr(ocp_crawl.fit.forward, "run_problem", _computed)
    monkeypatch.setattr(ocp_crawl.fit.forward, "simulate", _computed)


def _fit_cli(capsys, tmp_path, problem, data, *options) -> str:
    """Run ``ocp-crawl fit``; assert exit 2, nothing on stdout, one ``ocp-crawl: error:`` line;
    return it."""
    code = main(["fit", str(problem), *map(str, data), *options, "--no-figure", "--out",
                 str(tmp_path / "out")])
    out, err = capsys.readouterr()
    assert code == 2, err
    assert out == "" and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert err.startswith("ocp-crawl: error: "), err
    assert "np.float64" not in err and "np.int64" not in err, err
    return err.strip()


def _gait_file(tmp_path, col, bad, first=None, last=None):
    first, last = first or {"psi": 30, "A": 15, "gamma": 90}[col], last or {"psi": 60, "A": 30,
                                                                            "gamma": 80}[col]
    path = tmp_path / "d.csv"
    path.write_text(GAIT_ROWS.format(col=col, first=first, bad=bad, last=last))
    return path


@pytest.mark.parametrize("col, bad, key, valid", [("psi", "900", "gait.psi_deg", "[-360, 360]"),
                                                  ("A", "-20", "gait.A_deg", ">= 0"),
                                                  ("gamma", "0", "gait.gamma_deg", "(0, 360)")])
def test_a_gait_row_outside_its_key_range_is_bad_input(tmp_path, capsys, no_fit, col, bad, key,
                                                       valid):
    path = _gait_file(tmp_path, col, bad)
    err = _fit_cli(capsys, tmp_path, PAPER, [path], "--param", "robot.k")
    assert f"d.csv:3: {col} = {bad} deg is invalid" in err and key in err and valid in err, err
    with pytest.raises(TableError, match=f"d.csv:3: {col} = {bad} deg is invalid.*{key}"):
        read_measurements(path)


def test_a_gait_row_the_problem_rejects_is_bad_input_before_simulating(tmp_path, capsys, no_fit):
    """gamma = 30 deg is in the key's range, but with psi = 45 deg foot 1 starts off the ground: the
    problem's own validation (Problem.with_values) rejects the row, naming file, row and key, before
    any simulation."""
    path = _gait_file(tmp_path, "gamma", "30")
    err = _fit_cli(capsys, tmp_path, PAPER, [path], "--param", "robot.k")
    assert ("d.csv:3:" in err and "gamma = 30 deg" in err and "gamma_deg" in err
            and "off the ground" in err), err
    problem = load_problem(PAPER)
    with pytest.raises(TableError, match="d.csv:3: .*gamma_deg"):
        fit_measurements(problem, [read_measurements(path)],
                         resolve_parameters(problem, ["robot.k"]))


def test_a_pressure_row_phase_has_the_range_of_the_gait_phase(tmp_path, capsys, no_fit):
    lines = PSI_DATA.read_text().splitlines()
    row = next(i for i, line in enumerate(lines) if line.startswith("10.0,1.7"))
    lines[row] = lines[row].replace("10.0,1.7", "4500,1.7", 1)
    path = tmp_path / "p.csv"
    path.write_text("\n".join(lines) + "\n")
    err = _fit_cli(capsys, tmp_path, PAPER_GRAVITY, [path], "--param", "pressure.amplitude_bar")
    assert (f"p.csv:{row + 1}: psi = 4500 deg is invalid" in err and "gait.psi_deg" in err
            and "[-360, 360]" in err)
    with pytest.raises(TableError, match=f"p.csv:{row + 1}: psi = 4500 deg"):
        read_measurements(path)


def test_an_amplitude_above_a_row_nominal_pressure_is_bad_input(tmp_path, capsys, no_fit):
    """The default amplitude 0.4 bar with a row at p0 = 0.3 bar: a negative gauge pressure, named by
    file and row."""
    path = tmp_path / "p.csv"
    path.write_text("p0 [bar],psi [deg],S [mm],sigma_S "
                    "[mm]\n1.0,45,2,0.1\n0.3,45,1,0.1\n1.5,45,3,0.1\n")
    err = _fit_cli(capsys, tmp_path, PAPER_GRAVITY, [path], "--param", "robot.k")
    assert ("p.csv:3:" in err and "p0 = 0.3 bar" in err
            and "pressure.amplitude_bar = 0.4 bar" in err), err
    problem = load_problem(PAPER_GRAVITY)
    with pytest.raises(TableError, match="p.csv:3:.*amplitude"):
        fit_measurements(problem, [read_measurements(path)],
                         resolve_parameters(problem, ["robot.k"]))


def test_a_fixed_pressure_constant_outside_its_range_is_bad_input(tmp_path, capsys, no_fit):
    err = _fit_cli(capsys, tmp_path, PAPER_GRAVITY, [PSI_DATA], "--param", "robot.k", "--pressure",
                   "amplitude_bar=-1")
    assert "--pressure amplitude_bar=-1 is invalid" in err and ">= 0" in err, err
    with pytest.raises(ProblemError, match="--pressure amplitude_bar=-1 is invalid"):
        fixed_pressure(["amplitude_bar=-1"])
    assert fixed_pressure(["amplitude_bar=0", "a1=-0.5"]) == {"amplitude_bar": 0.0, "a1": -0.5}


@pytest.mark.parametrize("name, bounds, valid",
                         [("robot.k", "-1:1", "[1e-12, 1e12]"), ("robot.k", "0:1", "[1e-12, 1e12]"),
                          ("robot.mu", "0:1", "[1e-4, 1e4]"), ("gait.A_deg", "-10:40", ">= 0"),
                          ("pressure.amplitude_bar", "-1:1.7", ">= 0")])
def test_bounds_outside_the_valid_range_are_bad_input(tmp_path, capsys, no_fit, name, bounds,
                                                      valid):
    problem, data = ((PAPER_GRAVITY, PSI_DATA) if name.startswith("pressure")
                     else (PAPER, _gait_file(tmp_path, "psi", 45)))
    err = _fit_cli(capsys, tmp_path, problem, [data], "--param", name, "--bounds",
                   f"{name}={bounds}")
    low = bounds.split(":")[0]
    assert f"--bounds {name}={bounds}: the low end {low} is invalid" in err and valid in err, err
    with pytest.raises(ProblemError, match=f"--bounds {name}={bounds}: the low end"):
        resolve_parameters(load_problem(problem), [name], bounds=[f"{name}={bounds}"])


def test_a_start_outside_the_valid_range_is_bad_input(tmp_path, capsys, no_fit):
    err = _fit_cli(capsys, tmp_path, PAPER, [_gait_file(tmp_path, "A", 22)], "--param", "robot.k",
                   "--start", "robot.k=-1", "--bounds", "robot.k=1e-3:1")
    assert "--start robot.k=-1 is invalid" in err and "[1e-12, 1e12]" in err, err
    # each start in its range, but together the problem rejects them (foot 1 off the ground at phase
    # 0)
    err = _fit_cli(capsys, tmp_path, PAPER, [_gait_file(tmp_path, "A", 22)], "--param",
                   "gait.gamma_deg", "--start", "gait.gamma_deg=20")
    assert "--param gait.gamma_deg: the start values (gait.gamma_deg = 20) are invalid" in err, err


def test_default_bounds_end_in_the_valid_range():
    """x0 +- 45 deg would reach A = -15 deg: the default bound stops at the rule's edge, 0."""
    problem = load_problem(PAPER)
    (a,) = resolve_parameters(problem, ["gait.A_deg"])
    assert (a.low, a.x0, a.high) == (0.0, 30.0, 75.0)
    (k,) = resolve_parameters(problem, ["robot.k"])
    assert (k.low, k.high) == pytest.approx((problem.robot.k / 10, problem.robot.k * 10))
    (mu,) = resolve_parameters(problem, ["robot.mu"], start=["robot.mu=5e-4"])
    assert (mu.low, mu.high) == pytest.approx((1e-4, 5e-3), rel=1e-12)  # mu in [1e-4, 1e4]
    (psi,) = resolve_parameters(problem, ["gait.psi_deg"], start=["gait.psi_deg=340"])
    assert (psi.low, psi.high) == (295.0, 360.0)
    # gamma 20 deg stands with these
    flat = problem.with_values({"gait.psi_deg": 0.0, "gait.A_deg": 5.0})
    (g,) = resolve_parameters(flat, ["gait.gamma_deg"], start=["gait.gamma_deg=20"])
    assert 0 < g.low < 1e-9 and g.high == 65.0  # gamma in (0, 360): open at 0


def test_a_constant_fitted_and_fixed_is_bad_input(tmp_path, capsys, no_fit):
    err = _fit_cli(capsys, tmp_path, PAPER_GRAVITY, [PSI_DATA], "--param", "pressure.a1",
                   "--pressure", "a1=0.1")
    assert ("--pressure a1=0.1" in err and "--param pressure.a1" in err
            and "--start pressure.a1=0.1" in err), err
    problem = load_problem(PAPER_GRAVITY)
    with pytest.raises(ProblemError, match="either fitted or held fixed"):
        fit_measurements(problem, [read_measurements(PSI_DATA)],
                         resolve_parameters(problem, ["pressure.a1"]), pressure={"a1": 0.1})


@pytest.mark.parametrize("names", [("robot.mu", "robot.mu1"), ("robot.mu2", "robot.mu")])
def test_alternative_keys_cannot_be_fitted_together(tmp_path, capsys, no_fit, names):
    err = _fit_cli(capsys, tmp_path, PAPER, [_gait_file(tmp_path, "A", 22)],
                   *(a for n in names for a in ("--param", n)))
    assert "--param robot.mu and --param robot.mu" in err and "alternative keys" in err, err
    with pytest.raises(ProblemError, match="alternative keys of \\[robot\\]"):
        resolve_parameters(load_problem(PAPER), list(names))
    assert len(resolve_parameters(load_problem(PAPER), ["robot.mu1", "robot.mu2"])) == 2


def test_messages_show_plain_numbers_as_written(tmp_path, capsys, no_fit):
    bending = tmp_path / "b.csv"
    bending.write_text("p [bar],segment [-],phi [deg],sigma_phi "
                       "[deg]\n1,1,10,1\n1,3,10,1\n1.5,1,12,1\n")
    err = _fit_cli(capsys, tmp_path, PAPER, [bending], "--param", "pressure.a1")
    assert err.endswith("b.csv:3: segment = 3: must be 1 or 2"), err
    sigma = tmp_path / "s.csv"
    sigma.write_text("A [deg],S [mm],sigma_S [mm]\n15,-27.7,0.2\n22,-41.1,-0.2\n30,-56.0,0.2\n")
    err = _fit_cli(capsys, tmp_path, PAPER, [sigma], "--param", "robot.k")
    assert "s.csv:3: sigma_S = -0.2 mm: an uncertainty must be > 0" in err, err
    norm = tmp_path / "n.csv"
    norm.write_text("A [deg],S_norm [-],sigma_S_norm [-]\n15,-1,0.1\n22,-2,0.1\n30,-3,0.1\n")
    err = _fit_cli(capsys, tmp_path, PAPER, [norm], "--param", "robot.k")
    assert "n.csv:2: S_norm: the largest value, -1, must be > 0" in err, err


def test_an_empty_measurement_file_names_an_example_header(tmp_path, capsys, no_fit):
    empty = tmp_path / "e.csv"
    empty.write_text("# only a comment\n")
    err = _fit_cli(capsys, tmp_path, PAPER, [empty], "--param", "robot.k")
    assert "e.csv: no header row" in err and "e.g. )" not in err and "e.g. '" in err, err


STIFFNESS_ROWS = "phi [deg],sigma_phi [deg],tau [N m]\n{phi},{sigma},0.03\n20,{sigma2},0.06\n"


@pytest.mark.parametrize("sigma, sigma2, line", [("0.5", "1e-300", 3), ("1e-11", "0.5", 2)])
def test_an_uncertainty_too_small_to_weight_is_bad_input(tmp_path, capsys, no_fit, sigma, sigma2,
                                                         line):
    """sigma below 1e-12 x max(largest |phi|, 1 rad) = 5.73e-11 deg: the weighted residuals and
    their Jacobian would overflow (1e-300 deg once crashed the search with 'array must not contain
    infs or NaNs')."""
    path = tmp_path / "d.csv"
    path.write_text(STIFFNESS_ROWS.format(phi=10, sigma=sigma, sigma2=sigma2))
    err = _fit_cli(capsys, tmp_path, PAPER, [path], "--param", "robot.k")
    bad = sigma2 if line == 3 else sigma
    assert (f"d.csv:{line}: sigma_phi = {bad} deg is too small" in err
            and "1e-12 x max(the largest |phi|" in err), err
    assert "5.73e-11 deg" in err, err
    with pytest.raises(TableError, match=f"d.csv:{line}: sigma_phi = {bad} deg is too small"):
        read_measurements(path)
    # above the floor: accepted
    path.write_text(STIFFNESS_ROWS.format(phi=10, sigma="1e-10", sigma2="1e-10"))
    assert read_measurements(path).sigma.min() > 0


def test_the_uncertainty_floor_scales_with_the_data_and_holds_for_zero_data(tmp_path):
    """Relative to the largest |value| above 1 SI unit (S = 1e7 mm: floor 1e-5 mm); 1e-12 m when all
    S are 0."""
    big = tmp_path / "big.csv"
    big.write_text("A [deg],S [mm],sigma_S [mm]\n15,1e7,1e-4\n22,2e6,1e-6\n30,3e6,1e-4\n")
    with pytest.raises(TableError,
                       match=r"big.csv:3: sigma_S = 1e-06 mm is too small.* = 1e-05 mm"):
        read_measurements(big)
    zero = tmp_path / "zero.csv"
    zero.write_text("A [deg],S [mm],sigma_S [mm]\n15,0,0.1\n22,0,1e-300\n30,0,0.1\n")
    with pytest.raises(TableError,
                       match=r"zero.csv:3: sigma_S = 1e-300 mm is too small.* = 1e-09 mm"):
        read_measurements(zero)
    for example in (PSI_DATA, PSI_DATA.with_name("paper_pressure_p0.csv")):
        read_measurements(example)


@pytest.mark.parametrize("header, rows, param, message", [
    ("phi [deg],sigma_phi [deg],tau [N m]", "1e308,0.5,0.03\n20,0.5,0.06", "robot.k",
     "d.csv:2: phi = 1e+308 deg is out of range; every value of a measurement file must be at most "
     "1e12 rad"),
    ("p [bar],segment [-],phi [deg],sigma_phi [deg]", "1e308,1,10,1\n1,1,10,1\n1.5,1,12,1",
     "pressure.a1",
     "d.csv:2: p is out of range: its value overflows when converted to Pa; "
     "every value of a measurement file must be at most 1e12 Pa = 1e+07 bar"),
    ("phi [deg],sigma_phi [deg],tau [N m]", "10,0.5,0.03\n20,0.5,-2e12", "robot.k",
     "d.csv:3: tau = -2e+12 N m is out of range"),
])
def test_a_value_that_overflows_is_bad_input(tmp_path, capsys, no_fit, header, rows, param,
                                             message):
    """phi = 1e308 deg is finite in rad but overflows the residuals; p = 1e308 bar is not finite in
    Pa: both once gave 'success' with 'the search did not run'."""
    path = tmp_path / "d.csv"
    path.write_text(f"{header}\n{rows}\n")
    problem = PAPER_GRAVITY if param.startswith("pressure") else PAPER
    err = _fit_cli(capsys, tmp_path, problem, [path], "--param", param)
    assert message in err, err
    with pytest.raises(TableError, match=message.split(";")[0].replace("+", r"\+")):
        read_measurements(path)
