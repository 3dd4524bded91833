"""Non-harmonic inputs from problem files: ``[gait] waveform`` = fourier, samples (inline or a CSV
file), pulse.

Every kind is loaded from a file on disk and checked against something independent of its own code:
the harmonic gait (a Fourier series of first order is the same signal; samples of it converge to its
S; a cosine-edged pulse of rise 0.5 is the harmonic delayed by a quarter cycle), the
piecewise-linear interpolant of a trapezoid's corners, and the ``optimize`` replay, which
``simulate`` of the written ``optimal_gait.toml`` / ``--input torques.csv`` must reproduce to 1e-9.
"""
import json
import math
from pathlib import Path

import numpy as np
import pytest

from ocp_crawl.cli.app import main
from ocp_crawl.io.tables import read_table, write_table
from ocp_crawl.model.sampled import PeriodicLinear
from ocp_crawl.model.pulse import Pulse
from ocp_crawl.ocp.judge import REPLAY_INTERPOLATION, replay_signal
from ocp_crawl.problem import load_problem, paper_problem, run_problem
from ocp_crawl.problem.overrides import toml_text
from ocp_crawl.problem.run import PAPER_GAIT, ocp_settings
from ocp_crawl.problem.waveforms import INTERPOLANTS

REPO = Path(__file__).resolve().parent.parent
OCP = REPO / "problems" / "ocp_max_speed.toml"
GAMMA, A, PSI = 90.0, 30.0, 45.0  # the paper gait, deg


@pytest.fixture(scope="module")
def harmonic():
    """The paper's harmonic gait and its steady result (the reference of every comparison)."""
    problem = paper_problem()
    result = run_problem(problem)
    assert result.success, result.message
    return problem, result


def write_problem(path: Path, gait: dict) -> Path:
    """The paper's robot with the given [gait] section, written as a TOML problem file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(toml_text({"robot": dict(PAPER_GAIT["robot"]), "gait": gait,
                               "model": {"gravity": "physical"}}))
    return path


def fourier_gait(order_padding: int = 0) -> dict:
    """eq. (ref) as a Fourier series: gamma + A sin(w +- psi/2) = gamma + A sin(+-psi/2) cos w + A
    cos(psi/2) sin w."""
    s, c = A * math.sin(math.radians(PSI / 2)), A * math.cos(math.radians(PSI / 2))
    pad = [0.0] * order_padding
    return {"waveform": "fourier", "gamma_deg": GAMMA, "cos1_deg": [s, *pad], "sin1_deg": [c, *pad],
            "cos2_deg": [-s], "sin2_deg": [c, *pad]}


def test_fourier_first_harmonic_is_the_harmonic_gait(tmp_path, harmonic):
    base, ref = harmonic
    problem = load_problem(write_problem(tmp_path / "f.toml", fourier_gait(order_padding=3)))
    t = np.linspace(0, 1, 1001)
    np.testing.assert_allclose(problem.gait(t), base.gait(t), rtol=0, atol=1e-14)
    np.testing.assert_allclose(problem.gait.derivative(t), base.gait.derivative(t), rtol=0,
                               atol=1e-13)
    result = run_problem(problem)
    assert result.success, result.message
    assert abs(result.S - ref.S) <= 1e-12 * abs(ref.S)
    assert ocp_settings(problem).gamma_deg == pytest.approx(GAMMA, abs=1e-12)


def _sample_table(path: Path, problem, n: int, torque: bool) -> Path:
    """n samples of the harmonic gait over one cycle: torques in mN m, or reference angles in
    deg."""
    t = np.arange(n) / n
    path.parent.mkdir(parents=True, exist_ok=True)
    if torque:
        tau = problem.torque(t) * 1e3
        return write_table(path,
                           [("phase", "-", t), ("tau1", "mN m", tau[0]), ("tau2", "mN m", tau[1])])
    phi = np.degrees(problem.gait(t))
    return write_table(path,
                       [("phase", "-", t), ("phi1_ref", "deg", phi[0]),
                        ("phi2_ref", "deg", phi[1])])


@pytest.mark.slow
@pytest.mark.parametrize("torque, interpolation", [(False, "spline"), (True, "pchip")])
def test_samples_file_converges_to_the_harmonic_gait(tmp_path, harmonic, torque, interpolation):
    """A file of samples of the harmonic gait gives its S to interpolation accuracy, shrinking with
    more samples (file relative to the problem file, read from another directory)."""
    base, ref = harmonic
    errors = []
    for n in (16, 32, 64, 128):
        _sample_table(tmp_path / "data" / f"s{n}.csv", base, n, torque)
        path = write_problem(tmp_path / "problems" / f"s{n}.toml",
                             {"waveform": "samples", "file": f"../data/s{n}.csv",
                              "interpolation": interpolation})
        problem = load_problem(path)
        assert (problem.input_torque is not None) == torque
        result = run_problem(problem)
        assert result.success, result.message
        errors.append(abs(result.S - ref.S) / abs(ref.S))
    assert all(b < a for a, b in zip(errors, errors[1:])), errors
    assert errors[-1] < 1e-6 and errors[0] / errors[-1] > 30, errors


def test_inline_samples_equal_the_same_samples_from_a_file(tmp_path, harmonic):
    base, _ = harmonic
    n = 48
    t = np.arange(n) / n
    phi = np.degrees(base.gait(t))
    # inline, with the closing sample at phase 1 repeating phase 0 (the periodic form of a measured
    # cycle)
    inline = load_problem(write_problem(tmp_path / "inline.toml", {
        "waveform": "samples", "phase": [*t, 1.0], "phi1_ref_deg": [*phi[0], phi[0, 0]],
        "phi2_ref_deg": [*phi[1], phi[1, 0]]}))
    _sample_table(tmp_path / "s.csv", base, n, torque=False)
    from_file = load_problem(write_problem(tmp_path / "file.toml",
                                           {"waveform": "samples", "file": "s.csv"}))
    tt = np.linspace(0, 1, 777)
    np.testing.assert_allclose(inline.gait(tt), from_file.gait(tt), rtol=0, atol=1e-13)
    a, b = run_problem(inline), run_problem(from_file)
    assert a.success and b.success
    assert abs(a.S - b.S) <= 1e-12 * abs(a.S)


def test_trapezoid_pulse_is_the_linear_interpolant_of_its_corners(tmp_path):
    """The trapezoid (closed form) against PeriodicLinear through its corners; shrinking the rise
    tends to the square wave."""
    gait = {"waveform": "pulse", "gamma1_deg": 95.0, "gamma2_deg": 85.0, "A1_deg": 20.0,
            "A2_deg": 25.0, "psi_deg": 72.0, "rise": 0.1, "hold": 0.3}
    problem = load_problem(write_problem(tmp_path / "p.toml", gait))
    assert isinstance(problem.gait, Pulse)
    t = np.linspace(0, 1, 2001)
    for j, (g, a, shift) in enumerate(((95.0, 20.0, 72.0 / 720), (85.0, 25.0, -72.0 / 720))):
        # the corners in the pulse's own phase s = t + shift: low, high, high, low (low until the
        # next period)
        s_corner, level = np.array([0.0, 0.1, 0.4, 0.5]), np.array([g - a, g + a, g + a, g - a])
        t_knots = np.mod(s_corner - shift, 1.0)
        order = np.argsort(t_knots)
        lin = PeriodicLinear(t_knots[order], np.radians([level[order], level[order]]))
        np.testing.assert_allclose(problem.gait(t)[j], lin(t)[0], rtol=0, atol=1e-12)
        # derivative: +-2A/rise on the edges, 0 elsewhere (away from the corners)
        inner = np.min(np.abs(np.mod(t[:, None] - t_knots[None, :] + 0.5, 1.0) - 0.5),
                       axis=1) > 1e-6
        np.testing.assert_allclose(problem.gait.derivative(t)[j][inner],
                                   lin.derivative(t)[0][inner], rtol=1e-9)
    square = load_problem(write_problem(tmp_path / "sq.toml",
                                        dict(gait, rise=1e-6, hold=0.5 - 1e-6)))
    s = np.mod(t + 72.0 / 720, 1.0)
    away = (np.abs(s - 0.5) > 1e-5) & (s > 1e-5) & (s < 1 - 1e-5)
    high = s < 0.5
    np.testing.assert_allclose(square.gait(t)[0][away],
                               np.radians(np.where(high, 115.0, 75.0))[away], atol=1e-12)


def test_trapezoid_pulse_simulates_as_the_linear_samples_of_its_corners(tmp_path):
    """The same trapezoid as a pulse (closed form) and as linear samples at its corners: the same
    S."""
    pulse = {"waveform": "pulse", "gamma_deg": GAMMA, "A_deg": A, "psi_deg": 90.0, "rise": 0.35,
             "hold": 0.1}
    problem = load_problem(write_problem(tmp_path / "p.toml", pulse))
    t = problem.gait.t_knots
    phi = np.degrees(problem.gait(t))
    samples = load_problem(write_problem(tmp_path / "s.toml", {
        "waveform": "samples", "interpolation": "linear", "phase": t.tolist(),
        "phi1_ref_deg": phi[0].tolist(), "phi2_ref_deg": phi[1].tolist()}))
    a, b = run_problem(problem), run_problem(samples)
    assert a.success and b.success, (a.message, b.message)
    assert abs(a.S - b.S) <= 1e-10 * abs(b.S), (a.S, b.S)


def test_pulse_edges_do_not_matter_when_one_joint_moves_at_a_time(tmp_path):
    """rise = hold = 1/4 and psi = 90 deg: the joints take turns, so both edge shapes drive the
    robot along the same path of reference angles; a quasistatic gait is rate independent, so S is
    the same."""
    gait = {"waveform": "pulse", "gamma_deg": GAMMA, "A_deg": A, "psi_deg": 90.0, "rise": 0.25,
            "hold": 0.25}
    S = []
    for ramp in ("linear", "cosine"):
        result = run_problem(load_problem(write_problem(tmp_path / f"{ramp}.toml",
                                                        dict(gait, ramp=ramp))))
        assert result.success, result.message
        S.append(result.S)
    assert abs(S[0] - S[1]) <= 1e-9 * abs(S[1]), S


def test_cosine_pulse_of_rise_half_is_the_harmonic_a_quarter_cycle_later(tmp_path, harmonic):
    """Cosine edges, rise 0.5, hold 0: p(s) = (1 - cos 2 pi s)/2, so phi = gamma - A cos(2 pi t +-
    psi/2), the harmonic delayed by 1/4 cycle; the steady gait, hence S, does not depend on where
    the cycle starts."""
    base, ref = harmonic
    problem = load_problem(write_problem(tmp_path / "c.toml", {
        "waveform": "pulse", "gamma_deg": GAMMA, "A_deg": A, "psi_deg": PSI, "rise": 0.5,
        "hold": 0.0, "ramp": "cosine"}))
    t = np.linspace(0, 1, 1001)
    np.testing.assert_allclose(problem.gait(t), base.gait(t - 0.25), rtol=0, atol=1e-13)
    np.testing.assert_allclose(problem.gait.derivative(t), base.gait.derivative(t - 0.25), rtol=0,
                               atol=1e-12)
    result = run_problem(problem)
    assert result.success, result.message
    assert abs(result.S - ref.S) <= 1e-8 * abs(ref.S), (result.S, ref.S)


def test_replay_interpolation_is_the_ocp_replays():
    t, tau = np.arange(5) / 5, np.random.default_rng(1).normal(size=(2, 5))
    assert INTERPOLANTS[REPLAY_INTERPOLATION][0] is type(replay_signal(t, tau)) is PeriodicLinear


def at_own_friction(values):
    """Of a per-scenario list of the max_speed file's optimum, the scenario at the robot's own
    friction (mu1/mu2 as the file gives it, the middle of its friction set), which its
    optimal_gait.toml simulates; a single value as it is."""
    if not isinstance(values, list):
        return values
    return values[list(ocp_settings(load_problem(OCP)).friction_ratios).index(1.0)]


def test_optimize_torques_replayed_by_simulate(cli_optimize_run, capsys):
    """optimize --out writes torques.csv (full precision) and optimal_gait.toml; simulating either
    gives the optimize replay's S to 1e-9 (also with --input, and with --set from the problem file's
    directory)."""
    code, stdout, _, out, nodes = cli_optimize_run
    summary = json.loads(stdout)
    assert code == 0 and summary["success"], summary["message"]
    arrays = np.load(out / "arrays.npz")
    table = read_table(out / "torques.csv",
                       {"phase": "dimensionless", "tau1": "torque", "tau2": "torque",
                        "period": "time"})
    assert np.array_equal(table["phase"], arrays["phase"]) and np.array_equal(table["phase"],
                                                                              np.arange(nodes)
                                                                              / nodes)
    assert np.all(table["period"] == summary["T_ocp"])
    assert np.array_equal(np.array([table["tau1"], table["tau2"]]), arrays["tau"])
    runs = {"toml": ["simulate", str(out / "optimal_gait.toml"), "--json"],
            "input": ["simulate", str(OCP), "--input", str(out / "torques.csv"), "--set",
                      'gait.interpolation="linear"', "--json"],
            "set": ["simulate", str(out / "optimal_gait.toml"), "--set",
                    "gait.file=\"torques.csv\"", "--json"]}
    S_replay = at_own_friction(summary["S_replay"])
    for name, argv in runs.items():
        assert main(argv) == 0, name
        S = json.loads(capsys.readouterr().out)["S"]
        assert abs(S - S_replay) <= 1e-9 * abs(S_replay), (name, S, S_replay)


def test_optimal_gait_toml_reports_the_speed_of_optimize(cli_optimize_run, capsys):
    """The optimum's files keep its period: simulate of optimal_gait.toml (and of the problem with
    --input torques.csv, whose period column is the period) reports the optimize replay's speed, to
    1e-9 in --json and to the printed precision in the text; S alone would not give it (the
    quasistatic S per cycle has no time)."""
    from ocp_crawl.cli.optimize_command import format_optimize

    code, stdout, _, out, _ = cli_optimize_run
    summary = json.loads(stdout)
    assert code == 0 and summary["success"], summary["message"]
    runs = {"toml": ["simulate", str(out / "optimal_gait.toml")],
            "input": ["simulate", str(OCP), "--input", str(out / "torques.csv"), "--set",
                      'gait.interpolation="linear"']}
    replay_speed = next(line for line in format_optimize(summary).splitlines()
                        if line.startswith("speed"))
    own = replay_speed.split("mu1/mu2 = 1: ")[-1]  # the scenario at the robot's own friction
    shown = own.split("replay ")[1].split(";")[0]
    assert shown.endswith(" mm/s")
    for name, argv in runs.items():
        assert main([*argv, "--json"]) == 0, name
        data = json.loads(capsys.readouterr().out)
        assert data["period"] == summary["T_ocp"], name
        assert data["speed"] == pytest.approx(at_own_friction(summary["v_replay"]), rel=1e-9), name
        assert main(argv) == 0, name
        text = capsys.readouterr().out
        assert (f"speed      {shown} (|S| / period, period {summary['T_ocp']:.6g} "
                "s)" in text), (name, text)


@pytest.mark.parametrize("form, rest, amplitude", [("paper", 180.0, 0.5), ("raised", None, None)])
def test_pressure_waveform_is_the_pressure_driven_robot(form, rest, amplitude):
    """[gait] waveform = "pressure" drives the robot of ocp_crawl.model.pressure: its torque is
    pressure_torque's at p0_bar, psi_deg and the [pressure] constants (absent rest angle: the
    form's, the fitted one of the gravity convention for the raised sine), and so is its S."""
    from ocp_crawl.model.pressure import FITTED_REST_DEG, BendingMap, pressure_torque
    from ocp_crawl.sim import simulate

    sets = ["model.gravity=paper", "gait.waveform=pressure", "gait.p0_bar=1.5", "gait.psi_deg=30",
            "pressure.a1=0.1",
            f"pressure.form={form}",
            *([f"pressure.amplitude_bar={amplitude}"] if amplitude else [])]
    problem = paper_problem(sets)
    assert problem.given_dict()["gait"] == {"drive": "torque", "waveform": "pressure",
                                            "psi_deg": 30.0, "p0_bar": 1.5}
    signal = pressure_torque(problem.robot, 1.5, 30.0, rest or FITTED_REST_DEG["paper"],
                             BendingMap(a1=0.1), amplitude)
    t = np.linspace(0, 1, 101)
    assert np.array_equal(problem.torque(t), signal(t))
    assert run_problem(problem).S == simulate(problem.model, signal, "event").S


@pytest.mark.slow
def test_sweeps_of_waveform_problems(tmp_path, monkeypatch, harmonic):
    """robot.k of a samples problem (file relative to the problem file, run from elsewhere) and psi
    of a pulse."""
    from ocp_crawl.sweep import run_sweep

    base, _ = harmonic
    _sample_table(tmp_path / "p" / "s.csv", base, 40, torque=False)
    path = write_problem(tmp_path / "p" / "s.toml", {"waveform": "samples", "file": "s.csv"})
    monkeypatch.chdir(tmp_path)
    problem = load_problem(path)
    sweep = run_sweep(problem, {"robot.k": [0.12, 0.1677]})
    assert [r["status"] for r in sweep.rows] == ["success", "success"]
    direct = [run_problem(problem.with_values({"robot.k": k})).S for k in (0.12, 0.1677)]
    np.testing.assert_array_equal(sweep.array("S"), direct)
    assert direct[0] != direct[1]
    pulse = load_problem(write_problem(tmp_path / "pulse.toml", {
        "waveform": "pulse", "gamma_deg": GAMMA, "A_deg": A, "psi_deg": PSI, "rise": 0.5,
        "hold": 0.0, "ramp": "cosine"}))
    rows = run_sweep(pulse, {"gait.psi_deg": [30.0, 60.0]}).rows
    assert [r["status"] for r in rows] == ["success", "success"] and rows[0]["S"] != rows[1]["S"]


def test_setting_the_waveform_drops_the_other_waveforms_keys(harmonic):
    base, _ = harmonic
    n = 24
    t = np.arange(n) / n
    phi = np.degrees(base.gait(t))
    samples = base.with_values({"gait.waveform": "samples", "gait.phase": t.tolist(),
                                "gait.phi1_ref_deg": phi[0].tolist(),
                                "gait.phi2_ref_deg": phi[1].tolist()})
    assert set(samples.sections["gait"]) == {"drive", "waveform", "phase", "phi1_ref_deg",
                                             "phi2_ref_deg", "interpolation"}
    back = samples.with_values({"gait.waveform": "harmonic", "gait.gamma_deg": GAMMA,
                                "gait.A_deg": A, "gait.psi_deg": PSI})
    assert back.gait == base.gait
