"""The actual joint rates and foot sliding speeds: their peaks against a finite difference of an
independent dense sampling, the optional bound max_joint_rate_deg_s in the transcription and in the
replay judge, bad input."""
import math
from dataclasses import replace

import casadi as cs
import numpy as np
import pytest

from ocp_crawl import Robot
from ocp_crawl.model.sampled import PeriodicLinear
from ocp_crawl.model.statics import Model
from ocp_crawl.ocp import judge, optimize_gait
from ocp_crawl.ocp.baseline import value_from
from ocp_crawl.ocp.rates import JOINT_RATE_RTOL, replay_peaks, signal_peaks
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.substeps import SUBSTEP_RATE_SLACK, joint_rate_rows
from ocp_crawl.problem import ProblemError, load_problem
from ocp_crawl.sim.event import simulate_torque
from ocp_crawl.status import Status

ROBOT = Robot.paper()
MODEL = Model(ROBOT, gravity="physical")
N = 40
#: phases of the independent dense sampling (uniform: its differences are mean rates over 1/FINE of
#: a cycle)
FINE = 4000


def fd_peaks(signal, T: float) -> tuple[list, list]:
    """Peak joint rates [deg/s] and foot speeds [m/s] by finite differences of a uniform dense
    replay."""
    res = simulate_torque(MODEL, signal, t_eval=np.linspace(0.0, 1.0, FINE + 1))
    assert res.success, res.message
    rate = [math.degrees(np.max(np.abs(np.diff(res.phi[i])))) * FINE / T for i in range(2)]
    speed = [float(np.max(np.abs(np.diff(x)))) * FINE / T for x in (res.x1, res.x2)]
    return rate, speed


def linear_gait(lag: float = 0.8, amplitude_deg: float = 25.0):
    """A sine of the reference angles around 90 deg at N nodes, linear in phase between them (kinks
    at the nodes), joint 2 ``lag`` rad behind."""
    phase = np.arange(N) / N
    wave = np.vstack([np.sin(2 * np.pi * phase), np.sin(2 * np.pi * phase - lag)])
    ref = np.radians(amplitude_deg) * wave
    return PeriodicLinear(phase, ROBOT.k * (ref - np.pi / 2))


def agrees(peak: float, fd: float) -> bool:
    """The piecewise-polynomial peak against the finite difference: the differences are mean rates
    over 1/FINE of a cycle, so they lie below the peak, by at most the rate's change over that
    length."""
    return fd <= peak * (1 + 1e-7) and fd >= peak * (1 - 2e-3)


def test_peaks_against_a_dense_finite_difference():
    """Kinked input (nodes), slip switches and onsets: every peak agrees with the independent
    sampling."""
    signal, T = linear_gait(), 0.8
    res = simulate_torque(MODEL, signal)
    assert res.success, res.message
    peaks = replay_peaks(MODEL, signal, T, res, N)
    rate, speed = fd_peaks(signal, T)
    for i in range(2):
        assert agrees(peaks.joint_rate_deg_s[i], rate[i]), (peaks, rate)
        assert agrees(peaks.slip_speed_m_s[i], speed[i]), (peaks, speed)
    assert min(peaks.slip_speed_m_s) > 0  # both feet slip in this gait: not the stick's zero
    # the period converts phase to time: twice the period, half the rates
    slow = replay_peaks(MODEL, signal, 2 * T, res, N)
    assert slow.joint_rate_deg_s == pytest.approx(np.array(peaks.joint_rate_deg_s) / 2, rel=1e-12)


def test_smooth_input_peaks_and_failures_are_nan():
    """A harmonic input (no kinks: the pieces between the events alone) agrees too; a failed replay
    or a bad period gives NaN, never a number."""
    from ocp_crawl.model.inputs import Harmonic, ReferenceTorque

    signal = ReferenceTorque(Harmonic.from_degrees(90.0, 25.0, 40.0), ROBOT.k)
    peaks = signal_peaks(MODEL, signal, 0.6)
    rate, speed = fd_peaks(signal, 0.6)
    for i in range(2):
        assert agrees(peaks.joint_rate_deg_s[i], rate[i])
        assert agrees(peaks.slip_speed_m_s[i], speed[i])
    res = simulate_torque(MODEL, signal)
    assert all(math.isnan(v) for v in replay_peaks(MODEL, signal, 0.0, res).joint_rate_deg_s)
    failed = replace(res, success=False)
    assert all(math.isnan(v) for v in replay_peaks(MODEL, signal, 0.6, failed).slip_speed_m_s)


def test_rows_numpy_and_casadi_agree():
    """The transcription's rows (CasADi) equal their numpy form, and they are >= 0 exactly when
    every interval's mean rate is within the bound and every sub-step's within it to
    SUBSTEP_RATE_SLACK."""
    rng = np.random.default_rng(3)
    n = 6
    theta = rng.uniform(0.1, 0.9, n)
    step = 0.3
    P, th = cs.SX.sym("P", 2, 2 * n + 1), cs.SX.sym("th", n)
    f = cs.Function("f", [P, th], [joint_rate_rows(P, th, step)])
    length = np.column_stack([theta, 1 - theta]).ravel()
    for scale in (0.05, 0.3, 1.0):  # all within, some rows beyond, most beyond
        phi = 1.5 + scale * np.cumsum(rng.uniform(-0.3, 0.3, (2, 2 * n + 1)), axis=1)
        rows = joint_rate_rows(phi, theta, step)
        assert rows.shape == (4, 3 * n)
        assert np.allclose(np.asarray(f(phi, theta)), rows, rtol=0, atol=1e-14)
        interval = np.abs(phi[:, 2::2] - phi[:, :-2:2])  # node k-1 to node k
        sub = np.abs(np.diff(phi, axis=1)) / length  # per sub-step, as a rate over a whole interval
        within = np.all(interval <= step) and np.all(sub <= (1 + SUBSTEP_RATE_SLACK) * step)
        assert bool(np.all(rows >= 0)) == within


def triangle(settings: OCPSettings):
    """Triangle waves between the envelope's torque bounds at N nodes, tau2 a quarter cycle behind,
    at the shortest period of the bandwidth (the gait of tests/test_replay_judge.py)."""
    lo, hi = settings.torque_bounds(ROBOT)
    j = np.arange(N)
    tri = lambda i: lo + (hi - lo) * (1 - np.abs(((i % N) - N / 2) / (N / 2)))  # noqa: E731
    T = 4 * settings.A_max_deg / settings.max_rate_deg_s
    return np.vstack([tri(j + N // 2), tri(j + N // 4)]), T


@pytest.fixture(scope="module")
def claim():
    """The triangle gait, its replay and its peak joint rates by the dense finite difference."""
    tau, T = triangle(OCPSettings())
    signal = PeriodicLinear(np.arange(N) / N, tau)
    res = simulate_torque(MODEL, signal)
    assert res.success, res.message
    return tau, T, res, fd_peaks(signal, T)[0]


@pytest.mark.parametrize("factor,flagged", [(1 / 1.05, True), (1.0, False), (None, False)])
def test_judge_checks_the_bound_on_the_replayed_peak(claim, factor, flagged):
    """The judge flags a replay whose peak joint rate (found independently here, by the dense finite
    difference) exceeds the bound beyond JOINT_RATE_RTOL, and names the bound; at the peak itself it
    passes."""
    tau, T, res, rate = claim
    bound = None if factor is None else max(rate) * factor
    st = OCPSettings(direction=int(np.sign(res.S)), max_joint_rate_deg_s=bound)
    value = value_from(st, [res.S], [res.CoT_plus], T)
    v = judge.judge_replay([MODEL], st, tau, T, value, [res.S])
    assert (v.status == Status.REPLAY_MISMATCH) == flagged, v.message
    assert ("max_joint_rate_deg_s" in v.message) == flagged
    assert len(v.peaks) == 1 and agrees(max(v.peaks[0].joint_rate_deg_s), max(rate))
    if factor is None:
        assert math.isnan(v.joint_rate_ratio)
    else:
        assert v.joint_rate_ratio == pytest.approx(1 / factor, rel=2e-3)


BOUND = 180.0


@pytest.fixture(scope="module")
def bounded():
    """max_speed at N = 20 with the joint rates bounded by 180 deg/s (unbounded, the optimum's peak
    is about 194 deg/s at this N: ``test_the_bound_costs_speed``).  The harmonic family only: the
    other families' search (the gains' comparators, no start) is not checked here."""
    settings = OCPSettings(nodes=20, starts=1, harmonic_psi=12, harmonic_A=2,
                           max_joint_rate_deg_s=BOUND, baseline_samples=8, baseline_starts=1,
                           baseline_evaluations=40, baselines="harmonic")
    return optimize_gait(ROBOT, "physical", settings, jobs=1)


@pytest.mark.slow
def test_bound_holds_in_the_replay(bounded):
    res = bounded
    assert res.success, res.message
    N20 = res.settings.nodes
    # the transcription: each interval's mean rate is a mean of its sub-steps' (each within the
    # bound)
    node_rate = np.degrees(np.abs(np.diff(res.phi[0], axis=1))) * N20 / res.T_ocp
    assert np.max(node_rate) <= BOUND * (1 + 1e-7)
    # the replay, sampled independently of the judge: within the tolerance, and the bound is active
    # (the peak reaches it: without the bound the optimum moves faster)
    rate, speed = fd_peaks(PeriodicLinear(res.phase, res.tau), res.T_ocp)
    assert BOUND * (1 - JOINT_RATE_RTOL) <= max(rate) <= BOUND * (1 + JOINT_RATE_RTOL)
    for i in range(2):
        assert agrees(res.peak_joint_rate_deg_s[0][i], rate[i])
        assert agrees(res.peak_slip_speed_m_s[0][i], speed[i])
    summary = res.summary()
    assert summary["max_joint_rate_deg_s"] == BOUND
    assert summary["peak_joint_rate_deg_s"] == pytest.approx(res.peak_joint_rate_deg_s[0], rel=0)
    ratio = max(res.peak_joint_rate_deg_s[0]) / BOUND
    assert summary["joint_rate_ratio"] == pytest.approx(ratio, rel=1e-12)
    # the harmonic baseline's peaks, by its own replay
    base = res.harmonic.torque_signal(ROBOT.k)
    rate_h, _ = fd_peaks(base, res.harmonic.T)
    for i in range(2):
        assert agrees(res.harmonic_peak_joint_rate_deg_s[0][i], rate_h[i])


@pytest.mark.heavy
def test_the_bound_costs_speed(bounded):
    """Unbounded, the same problem's optimum moves its joints faster than the bound and is
    faster."""
    settings = replace(bounded.settings, max_joint_rate_deg_s=None)
    free = optimize_gait(ROBOT, "physical", settings, jobs=1)
    assert free.success, free.message
    assert max(free.peak_joint_rate_deg_s[0]) > BOUND * (1 + JOINT_RATE_RTOL)
    assert free.value_replay > bounded.value_replay


@pytest.mark.parametrize("value,error,match", [
    (0.0, ValueError, r"OCPSettings.max_joint_rate_deg_s must be in \[0.01, 10000\]"),
    (-10.0, ValueError, r"OCPSettings.max_joint_rate_deg_s must be in \[0.01, 10000\]"),
    (1e5, ValueError, r"OCPSettings.max_joint_rate_deg_s must be in \[0.01, 10000\]"),
    (math.inf, ValueError, "OCPSettings.max_joint_rate_deg_s must be finite"),
    ("fast", TypeError, "OCPSettings.max_joint_rate_deg_s must be a real number"),
])
def test_settings_reject_bad_bounds(value, error, match):
    with pytest.raises(error, match=match):
        OCPSettings(max_joint_rate_deg_s=value)


@pytest.mark.parametrize("text,match", [
    ("0", r"\[ocp\] max_joint_rate_deg_s = 0"),
    ("-5", r"\[ocp\] max_joint_rate_deg_s = -5"),
    ('"fast"', r"max_joint_rate_deg_s"),
])
def test_problem_file_rejects_bad_bounds(tmp_path, text, match):
    """A bad value in a problem file: one line naming the key."""
    from ocp_crawl.problem.shipped import shipped_problem

    src = shipped_problem("ocp_max_speed").read_text()
    path = tmp_path / "x.toml"
    path.write_text(src.replace("[ocp]\n", f"[ocp]\nmax_joint_rate_deg_s = {text}\n", 1))
    with pytest.raises(ProblemError, match=match) as info:
        load_problem(path)
    assert "\n" not in str(info.value)


def test_problem_file_passes_the_bound_on():
    from ocp_crawl.problem.run import ocp_settings
    from ocp_crawl.problem.shipped import shipped_problem

    problem = load_problem(shipped_problem("ocp_max_speed"))
    assert ocp_settings(problem).max_joint_rate_deg_s is None
    bounded = problem.with_values({"ocp.max_joint_rate_deg_s": 175.0})
    assert ocp_settings(bounded).max_joint_rate_deg_s == 175.0
