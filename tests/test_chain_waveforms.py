"""A chain's joints driven by pulses ([gait] waveform = "pulse") and by samples from a file
(waveform = "samples", a column per joint): the paper's robot written as a chain moves as the
three-link robot under the same pulses and under the same sample file (every interpolation, both
drives); torque samples are the reference angles that stand for them; the five-link file's gait as
pulses and as a table goes through every command that takes a chain; what a chain's waveform
cannot be is one line naming the key or the file."""
import csv
import json
import tomllib

import numpy as np
import pytest

from ocp_crawl.cli import main
from ocp_crawl.model.pulse import JointPulse, Pulse
from ocp_crawl.problem import ProblemError, load_problem, problem_from_dict, run_problem
from ocp_crawl.status import Status

from _bad_input_rows import CHAIN, PAPER
from test_chain_problems import PAPER_AS_CHAIN

#: relative agreement of S and W+ between the chain's and the three-link code
RTOL = 1e-9


def _write_table(path, phases, columns: dict) -> None:
    """A sample file of the package's CSV convention: 'phase [-]' and the given columns."""
    with open(path, "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(["phase [-]", *columns])
        for j, t in enumerate(phases):
            out.writerow([repr(float(t)), *(repr(float(v[j])) for v in columns.values())])


def _samples_text(text: str, file: str, interpolation: str) -> str:
    """A problem file's text with its [gait] section replaced by the file's samples."""
    head, _, rest = text.partition("[gait]")
    tail = rest[rest.index("\n["):] if "\n[" in rest else ""
    return (f'{head}[gait]\nwaveform = "samples"\nfile = "{file}"\n'
            f'interpolation = "{interpolation}"\n{tail}')


def _pulses(ramp: str, psi: float) -> list[str]:
    return ['gait.waveform="pulse"', "gait.rise=0.3", "gait.hold=0.1", f'gait.ramp="{ramp}"',
            f"gait.psi_deg={psi}"]


@pytest.mark.parametrize("ramp", ["linear", "cosine"])
@pytest.mark.parametrize("psi", [90.0, 30.0, -45.0])
def test_the_paper_robot_as_a_chain_under_pulses(ramp, psi):
    """Trapezoids (kinks) and half-cosine edges (rests), with holds of every joint whose ends tie
    the feet's friction limits: S, W+ and the steady cycle's events of the three-link robot."""
    three = run_problem(load_problem(PAPER, _pulses(ramp, psi)))
    chain = run_problem(problem_from_dict(tomllib.loads(PAPER_AS_CHAIN),
                                          overrides=_pulses(ramp, psi)))
    assert three.success and chain.success, (three.message, chain.message)
    assert abs(chain.S - three.S) <= RTOL * abs(three.S)
    assert abs(chain.W_plus - three.W_plus) <= RTOL * three.W_plus
    a, b = chain.steady_events(), three.steady_events()
    assert [(e.mode_before, e.mode_after) for e in a] == [(e.mode_before, e.mode_after) for e in b]
    np.testing.assert_allclose([e.t - chain.t0 for e in a], [e.t - three.t0 for e in b],
                               atol=1e-8)


@pytest.mark.parametrize("psi", [12.0, 45.0, 90.0])
def test_the_paper_robot_as_a_chain_under_pressure(psi):
    """The pressure actuator of the paper's robot (Table I's map, a segment per joint) on the
    paper's robot written as a chain: the three-link robot's S and W+ to 1e-9."""
    over = ['gait.waveform="pressure"', "gait.p0_bar=1.0", f"gait.psi_deg={psi}",
            'model.gravity="paper"']
    three = run_problem(load_problem(PAPER, over))
    chain = run_problem(problem_from_dict(tomllib.loads(PAPER_AS_CHAIN), overrides=over))
    assert three.success and chain.success, (three.message, chain.message)
    assert abs(chain.S - three.S) <= RTOL * abs(three.S)
    assert abs(chain.W_plus - three.W_plus) <= RTOL * three.W_plus


def test_mirror_symmetric_pulses_share_the_slip_which_a_chain_does_not_model():
    """psi = 0 on the symmetric robot: the feet's limits tie all the time and the three-link robot
    shares the slip between its feet (S = 0); the chain, whose slips are one foot's, says so by a
    status."""
    three = run_problem(load_problem(PAPER, _pulses("linear", 0.0)))
    chain = run_problem(problem_from_dict(tomllib.loads(PAPER_AS_CHAIN),
                                          overrides=_pulses("linear", 0.0)))
    assert three.success and abs(three.S) <= 1e-15
    assert chain.status in (Status.NO_CONSISTENT_MODE, Status.SET_VALUED), chain.message


def test_joint_pulses_of_two_joints_are_the_pulse():
    """JointPulse with the leads (psi/2, -psi/2): Pulse's values, rates and knots, bitwise."""
    t = np.linspace(-1.0, 2.0, 997)
    for ramp in ("linear", "cosine"):
        for psi in (0.3, -2.0):
            a = Pulse(1.5, 1.6, 0.4, 0.3, psi, 0.3, 0.1, ramp)
            b = JointPulse([1.5, 1.6], [0.4, 0.3], [psi / 2, -psi / 2], 0.3, 0.1, ramp)
            assert np.array_equal(a(t), b(t)) and np.array_equal(a.derivative(t), b.derivative(t))
            assert np.array_equal(a(0.37), b(0.37)) and np.array_equal(a.t_knots, b.t_knots)
    with pytest.raises(ValueError, match="JointPulse: 2 rise"):
        JointPulse([1.5, 1.6, 1.7], [0.1] * 3, [0.0] * 3, 0.4, 0.3)


def _paper_table(tmp_path):
    """The paper gait's reference angles at 16 uneven phases, in a file both robots read."""
    three = load_problem(PAPER)
    t = np.sort(np.r_[0.0, np.random.default_rng(5).uniform(0.0, 1.0, 15)])
    ref = np.degrees(three.gait(t))
    _write_table(tmp_path / "paper.csv", t, {"phi1_ref [deg]": ref[0], "phi2_ref [deg]": ref[1]})
    return tmp_path / "paper.csv"


@pytest.mark.parametrize("interpolation", ["linear", "pchip", "spline"])
@pytest.mark.parametrize("drive", ["torque", "angles"])
def test_the_paper_robot_as_a_chain_under_a_sample_file(tmp_path, interpolation, drive):
    """The same file through the three-link and the chain problem: S and W+ to 1e-9."""
    _paper_table(tmp_path)
    files = {"three": _samples_text(PAPER.read_text(), "paper.csv", interpolation),
             "chain": _samples_text(PAPER_AS_CHAIN, "paper.csv", interpolation)}
    runs = {}
    for name, text in files.items():
        (tmp_path / f"{name}.toml").write_text(text)
        runs[name] = run_problem(load_problem(tmp_path / f"{name}.toml",
                                              [f'gait.drive="{drive}"']))
    three, chain = runs["three"], runs["chain"]
    assert three.success and chain.success, (three.message, chain.message)
    assert abs(chain.S - three.S) <= RTOL * abs(three.S)
    assert abs(chain.W_plus - three.W_plus) <= RTOL * three.W_plus


def _five_link_tables(tmp_path, knots: int = 24) -> dict:
    """The five-link file's harmonic gait at ``knots`` equal phases, as reference angles and as
    the torques k_j (phi_ref_j - pi - rest_j), in files beside two problem files."""
    problem = load_problem(CHAIN)
    t = np.arange(knots) / knots
    ref, tau = np.degrees(problem.gait(t)), np.asarray(problem.torque(t))
    _write_table(tmp_path / "angles.csv", t, {f"phi{j + 1}_ref [deg]": ref[j] for j in range(4)})
    _write_table(tmp_path / "torques.csv", t, {f"tau{j + 1} [N m]": tau[j] for j in range(4)})
    out = {}
    for name in ("angles", "torques"):
        out[name] = tmp_path / f"five_{name}.toml"
        out[name].write_text(_samples_text(CHAIN.read_text(), f"{name}.csv", "linear"))
    return out


@pytest.mark.slow
def test_torque_samples_are_the_reference_angles_that_stand_for_them(tmp_path):
    """A chain's torque table and the reference angles of those torques: the same signal to
    round-off and the same gait (S to 1e-12), for every interpolation."""
    files = _five_link_tables(tmp_path)
    for interpolation in ("linear", "pchip", "spline"):
        over = [f'gait.interpolation="{interpolation}"']
        a, b = (load_problem(files[n], over) for n in ("angles", "torques"))
        t = np.linspace(0.0, 1.0, 101)
        np.testing.assert_allclose(b.torque(t), a.torque(t), rtol=0, atol=1e-14)
        ra, rb = run_problem(a), run_problem(b)
        assert ra.success and rb.success
        assert abs(ra.S - rb.S) <= 1e-12 * abs(ra.S)
    spline = run_problem(load_problem(files["angles"], ['gait.interpolation="spline"']))
    assert abs(spline.S - run_problem(load_problem(CHAIN)).S) <= 1e-3 * abs(spline.S)


@pytest.mark.slow
def test_five_link_pulses_pass_the_crosscheck(capsys):
    """The five-link file's joints as trapezoid pulses: the chain's event-driven stepper against
    its switch-exact steps at N = 40 and 80."""
    argv = ["crosscheck", str(CHAIN), "--steps", "40", "80", "--json", "--set",
            'gait.waveform="pulse"', "--set", "gait.rise=0.25", "--set", "gait.hold=0.2"]
    assert main(argv) == 0
    check = json.loads(capsys.readouterr().out)
    assert check["passed"] is True, check["checks"]
    assert all(r["rel_diff_S"] <= 1e-9 for r in check["per_steps"])


@pytest.mark.slow
def test_a_five_link_table_through_every_command_that_takes_a_chain(tmp_path, capsys):
    """simulate (both solvers, both drives, --out), crosscheck PASS, a sweep whose point is the
    simulation, an animation: the table's kinks through every path."""
    files = _five_link_tables(tmp_path)
    file = str(files["angles"])
    results = {}
    for solver, drive in (("event", "torque"), ("mpcc", "torque"), ("event", "angles")):
        assert main(["simulate", file, "--json", "--set", f'simulation.solver="{solver}"',
                     "--set", f'gait.drive="{drive}"']) == 0
        results[solver, drive] = json.loads(capsys.readouterr().out)
        assert results[solver, drive]["success"]
    S = results["event", "torque"]["S"]
    assert abs(results["mpcc", "torque"]["S"] - S) <= 1e-9 * abs(S)
    assert main(["crosscheck", file, "--steps", "40", "80", "--json"]) == 0
    check = json.loads(capsys.readouterr().out)
    assert check["passed"] is True, check["checks"]
    assert main(["sweep", file, "--grid", "robot.stiffness[1]=0.2,0.3", "--out",
                 str(tmp_path / "sweep"), "--jobs", "1", "--no-progress"]) == 0
    capsys.readouterr()
    with open(tmp_path / "sweep" / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert float(rows[1]["S [m]"]) == pytest.approx(S, rel=1e-12)
    gif = tmp_path / "crawl.gif"
    assert main(["animate", file, "--out", str(gif), "--cycles", "1", "--frames-per-cycle",
                 "4"]) == 0
    assert gif.read_bytes()[:6] == b"GIF89a"


def test_what_a_chains_samples_cannot_be(tmp_path):
    """Inline samples (the three-link robot's two columns), a file without a column for every
    joint, torque samples under prescribed angles: one line naming the key or the file."""
    files = _five_link_tables(tmp_path)
    data = tomllib.loads(CHAIN.read_text())
    data["gait"] = {"waveform": "samples", "phase": [0.0, 0.5], "phi1_ref_deg": [90.0, 100.0],
                    "phi2_ref_deg": [90.0, 100.0]}
    with pytest.raises(ProblemError, match=r"\[gait\] phase = .* its samples come from a file"):
        problem_from_dict(data, source="x.toml")
    three = tmp_path / "three.csv"
    t = np.arange(8) / 8
    _write_table(three, t, {f"phi{j}_ref [deg]": 100.0 + 0 * t for j in (1, 2, 3)})
    with pytest.raises(ProblemError, match=r"three\.csv: needs 'phase \[-\]' and either 'tau1 "
                                           r"\[N m\]', .*'phi4_ref \[deg\]'"):
        load_problem(files["angles"], ['gait.file="three.csv"'])
    with pytest.raises(ProblemError, match=r'drive = "angles" .* torque samples \(tau1, tau2, '
                                           r'tau3, tau4\)'):
        load_problem(files["torques"], ['gait.drive="angles"'])
    with pytest.raises(ProblemError, match=r'waveform = "fourier" .* "harmonic", "pulse", '
                                           r'"samples"'):
        load_problem(CHAIN, ['gait.waveform="fourier"'])
    with pytest.raises(ProblemError, match=r'waveform = "pressure" \(from --set\) with a chain '
                                           r"of 5 links needs \[pressure\] segments"):
        load_problem(CHAIN, ['gait.waveform="pressure"', "gait.p0_bar=1.0"])
    with pytest.raises(ProblemError, match=r"rise = 0.4 \(from --set\) and hold = 0.3 are "
                                           r"invalid"):
        load_problem(CHAIN, ['gait.waveform="pulse"', "gait.rise=0.4", "gait.hold=0.3"])
