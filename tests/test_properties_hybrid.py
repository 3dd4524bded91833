"""Property-based tests of the event-driven stepper over random physical robots and gaits.

Every run either succeeds with all the invariants holding, or returns a documented failure status
with a message; never a NaN in a successful result, never an exception.

The example count is small by default (fast CI); set ``OCP_CRAWL_HYPOTHESIS_EXAMPLES`` for a large
run, e.g. ``OCP_CRAWL_HYPOTHESIS_EXAMPLES=1000 python -m pytest tests/test_properties_hybrid.py``.
"""
import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from ocp_crawl import (FourierSeries, Harmonic, Model, PeriodicPchip, ReferenceTorque, Robot,
                       simulate_torque)
from ocp_crawl.sim.result import Mode
from ocp_crawl.status import STATUS_MESSAGES, Status

EXAMPLES = int(os.environ.get("OCP_CRAWL_HYPOTHESIS_EXAMPLES", "25"))
SETTINGS = settings(max_examples=EXAMPLES, deadline=None,
                    derandomize="OCP_CRAWL_HYPOTHESIS_EXAMPLES" not in os.environ,
                    suppress_health_check=[HealthCheck.too_slow])


def log_uniform(lo, hi):
    return st.floats(math.log(lo), math.log(hi)).map(math.exp)


@st.composite
def robots(draw):
    """Physical robots: mass, length, body ratio, stiffness 0.05-100 M g L, friction 0.05-2 per
    foot."""
    robot = Robot(M=draw(log_uniform(0.005, 5.0)), L=draw(log_uniform(0.02, 1.0)),
                  beta=draw(log_uniform(0.3, 5.0)),
                  k=1.0, mu1=draw(log_uniform(0.05, 2.0)), mu2=draw(log_uniform(0.05, 2.0)),
                  g=draw(st.sampled_from([9.81, 1.62, 3.71])))
    return robot.with_stiffness_ratio(draw(log_uniform(0.05, 100.0)))


@st.composite
def references(draw):
    """Reference angles: the paper's harmonic (per-joint gamma), or a random periodic input built on
    it."""
    gamma = draw(st.floats(45.0, 135.0))
    base = Harmonic.from_degrees(gamma, draw(st.floats(0.0, 60.0)), draw(st.floats(-180.0, 180.0)),
                                 gamma2_deg=gamma + draw(st.floats(-15.0, 15.0)))
    kind = draw(st.sampled_from(["harmonic", "fourier", "pchip"]))
    if kind == "harmonic":
        return base
    n = draw(st.integers(2, 12))
    t = np.arange(4 * n + 8) / (4 * n + 8)
    ripple = np.array([[draw(st.floats(-0.15, 0.15)) for _ in range(n)] for _ in range(2)])
    phase = np.array([[draw(st.floats(0.0, 2 * math.pi)) for _ in range(n)] for _ in range(2)])
    values = base(t) + np.einsum("in,int->it", ripple,
                                 np.sin(2 * np.pi * np.arange(1, n + 1)[None, :, None]
                                        * t[None, None, :] + phase[..., None]))
    if kind == "fourier":
        return FourierSeries.fit(values, order=n)
    knots = np.arange(2 * n + 4) / (2 * n + 4)
    return PeriodicPchip(knots, base(knots) + np.array([[draw(st.floats(-0.1, 0.1)) for _ in knots]
                                                        for _ in range(2)]))


def check_run(model: Model, torque) -> tuple[str, object]:
    """Run and check the invariants; returns (status name, result)."""
    res = simulate_torque(model, torque)
    robot = model.robot
    Mg, L = robot.M * robot.g, robot.L
    assert res.status in set(int(s) for s in Status), res.status
    if not res.success:
        assert res.message.startswith(STATUS_MESSAGES[Status(res.status)]), res.message
        assert len(res.message) > len(STATUS_MESSAGES[Status(res.status)]) + 5  # says where and why
        if res.status != Status.NO_START:
            assert res.failure_t is not None and math.isfinite(res.failure_t) and res.failure_mode
        assert np.isnan(res.S)  # no number is presented for a failed run
        return res.status_name, res
    # success: no NaN anywhere, and the invariants hold at every output sample
    for name, arr in res.arrays().items():
        assert np.all(np.isfinite(arr)), name
    assert math.isfinite(res.S) and math.isfinite(res.W_plus) and res.W_plus >= 0
    assert res.CoT_plus > 0 and not math.isnan(res.CoT_plus)
    assert res.extra["max_residual_scaled"] <= 1e-9
    phi, ft = res.phi, res.f_t
    F = np.array([model.equilibrium_residual(phi[:, j], res.tau[:, j],
                                             ft[j]) for j in range(0, res.t.size, 10)])
    assert np.max(np.abs(F)) <= 1e-8 * Mg * L
    assert np.all(res.f_n1 > 0) and np.all(res.f_n2 > 0)
    assert np.all(res.d > 0)
    lim1, lim2 = robot.mu1 * res.f_n1, robot.mu2 * res.f_n2
    tol = 1e-9 * Mg
    assert np.all(np.abs(ft) <= np.minimum(lim1, lim2) + tol)
    for code in set(res.mode.tolist()):
        sel = res.mode == code
        m = Mode(code)
        if m.foot in (1, 2):  # the slipping foot is at its friction limit, opposing the slip
            lim = lim1 if m.foot == 1 else lim2
            assert np.allclose(ft[sel], m.sigma * lim[sel], rtol=0, atol=tol)
    e = res.energy
    assert abs(e["balance_residual"]) <= 1e-6, e
    assert e["dissipation"] >= -1e-12 * Mg * L
    assert res.periodicity_residual <= 1e-8
    # periodic: the state at the end of the steady cycle equals the state at its start
    assert np.allclose(res.phi[:, 0], res.phi[:, -1], rtol=0, atol=1e-7)
    assert abs(res.d[0] - res.d[-1]) <= 1e-7 * L
    # both feet advance by S
    assert abs((res.x1[-1] - res.x1[0]) - (res.x2[-1] - res.x2[0])) <= 1e-7 * L
    for ev in res.steady_events():
        assert abs(ev.guard) <= 1e-8, ev
    return res.status_name, res


@SETTINGS
@given(robot=robots(), reference=references(), gravity=st.sampled_from(["physical", "paper"]))
def test_random_robots_and_gaits_succeed_or_fail_cleanly(robot, reference, gravity):
    status, _ = check_run(Model(robot, gravity=gravity), ReferenceTorque(reference, robot.k))
    event(f"status {status}")


@SETTINGS
@given(robot=robots(), psi=st.floats(5.0, 175.0), A=st.floats(5.0, 45.0))
def test_mirrored_gait_moves_the_other_way(robot, psi, A):
    """Equal friction, equal-gamma harmonic gait: S(-psi) = -S(psi) when both runs succeed."""
    robot = robot.replace(mu2=robot.mu1)
    model = Model(robot, gravity="physical")
    fwd = simulate_torque(model, ReferenceTorque(Harmonic.from_degrees(90.0, A, psi), robot.k))
    bwd = simulate_torque(model, ReferenceTorque(Harmonic.from_degrees(90.0, A, -psi), robot.k))
    if fwd.success and bwd.success:
        assert bwd.S == pytest.approx(-fwd.S, rel=1e-7, abs=1e-12 * robot.L)
        assert bwd.W_plus == pytest.approx(fwd.W_plus, rel=1e-7, abs=1e-12 * robot.MgL)
    else:  # the mirror image fails the same way
        assert fwd.status == bwd.status


def test_paper_robot_sample_covers_success_and_failures():
    """The generators reach both outcomes: a fixed sample of the paper's robot family."""
    statuses = set()
    for k_ratio, gamma, A in ((1.3, 90, 30), (0.2, 90, 60), (20.0, 70, 40), (0.06, 100, 20)):
        robot = Robot.paper().with_stiffness_ratio(k_ratio)
        name, _ = check_run(Model(robot),
                            ReferenceTorque(Harmonic.from_degrees(gamma, A, 45), robot.k))
        statuses.add(name)
    assert "success" in statuses and len(statuses) >= 2
