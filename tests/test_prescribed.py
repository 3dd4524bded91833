"""Prescribed-angle locomotion (paper Section II-A)."""
import numpy as np
import pytest

from ocp_crawl import Harmonic, Mode, Model, Robot, Status
from ocp_crawl.sim.angles import KinematicGait, simulate_angles


@pytest.mark.parametrize("mu1,mu2", [(0.389, 0.389), (0.33, 0.45)])
def test_prescribed_gait_invariants(gravity, mu1, mu2):
    robot = Robot.paper(mu1=mu1, mu2=mu2)
    model = Model(robot, gravity=gravity)
    gait = Harmonic.from_degrees(90, 30, 45)
    res = simulate_angles(model, gait)
    assert res.success, res.message
    np.testing.assert_allclose(res.phi, gait(res.t), rtol=0, atol=1e-15)
    # one foot always slips: f_t on the friction limit of the slipping foot, the other inside its
    # cone
    Mg = robot.M * robot.g
    for j in range(res.t.size):
        m = Mode(int(res.mode[j]))
        lim1, lim2 = mu1 * res.f_n1[j], mu2 * res.f_n2[j]
        slip_lim, other = (lim1, lim2) if m.foot == 1 else (lim2, lim1)
        assert abs(res.f_t[j]) == pytest.approx(slip_lim, abs=1e-12 * Mg)
        assert abs(res.f_t[j]) <= other + 1e-12 * Mg
        F = model.equilibrium_residual(res.phi[:, j], res.tau[:, j], res.f_t[j])
        assert np.max(np.abs(F)) < 1e-12
    assert abs(res.energy["balance_residual"]) < 1e-6
    # positions: the sticking foot does not move
    d_x1 = np.diff(res.x1)
    d_x2 = np.diff(res.x2)
    assert np.all(np.minimum(np.abs(d_x1), np.abs(d_x2)) < 1e-15)
    assert res.S == pytest.approx(res.x1[-1] - res.x1[0], rel=1e-12)


def test_switching_instants_are_located(gravity):
    robot = Robot.paper(mu1=0.33, mu2=0.45)
    model = Model(robot, gravity=gravity)
    gait = Harmonic.from_degrees(90, 30, 45)
    res = simulate_angles(model, gait)
    kin = KinematicGait(model, gait)
    kinds = {e.kind for e in res.events}
    assert kinds == {"slip_reversal", "slip_switch"}
    for ev in res.events:
        name = "ddot" if ev.kind == "slip_reversal" else "h"
        g = kin(np.array([ev.t - 1e-10, ev.t, ev.t + 1e-10]))[name]
        assert abs(g[1]) < 1e-9 * (robot.L if name == "ddot" else 1.0)
        assert g[0] * g[2] < 0  # a sign change within 1e-10 in phase
        assert ev.mode_before != ev.mode_after


def test_ideal_switching_for_symmetric_gait():
    """Equal friction and symmetric angles: d' and Delta vanish together (paper, 'ideal
    switching')."""
    res = simulate_angles(Model(Robot.paper()), Harmonic.from_degrees(90, 30, 45))
    rev = sorted(e.t for e in res.events if e.kind == "slip_reversal")
    sw = sorted(e.t for e in res.events if e.kind == "slip_switch")
    np.testing.assert_allclose(rev, sw, atol=1e-10)


def test_prescribed_psi_symmetries():
    model = Model(Robot.paper())
    fwd = simulate_angles(model, Harmonic.from_degrees(90, 30, 45))
    bwd = simulate_angles(model, Harmonic.from_degrees(90, 30, -45))
    sym = simulate_angles(model, Harmonic.from_degrees(90, 30, 0))
    assert fwd.S < 0
    assert bwd.S == pytest.approx(-fwd.S, rel=1e-10)
    assert abs(sym.S) < 1e-12 * model.robot.L
    assert {Mode(int(m)).foot for m in sym.mode} == {3}


def test_prescribed_lift_off_is_reported():
    model = Model(Robot.paper())
    gait = Harmonic.from_degrees(60, 40, 45)
    res = simulate_angles(model, gait)
    assert res.status == Status.LIFT_OFF and not res.success
    assert "phase" in res.message
    i = int(res.events[-1].kind[-1])
    assert abs(model.kinematics(gait(res.failure_t))[f"fn{i}"]) < 1e-9


def test_prescribed_bad_start_is_rejected():
    with pytest.raises(ValueError, match="(foot .* off|joint .* below) the ground"):
        simulate_angles(Model(Robot.paper()), Harmonic.from_degrees(20, 5, 45, gamma2_deg=40))


def test_prescribed_feet_meeting_is_reported():
    """A short body (beta = 1): a mirror-symmetric gait brings the feet together at phi = 60 deg
    (d = l (beta - 2 cos phi)), with both joints above the ground."""
    model = Model(Robot.paper(beta=1.0))
    gait = Harmonic.from_degrees(70, 15, 0)
    res = simulate_angles(model, gait)
    assert res.status == Status.FEET_CROSSED and not res.success
    assert res.events[-1].kind == "feet_crossed"
    # d only touches zero on the continuous branch of theta, so the phase comes from a
    # minimisation, accurate to ~sqrt(eps) rather than the 1e-10 of sign changes
    assert res.failure_t == pytest.approx(0.5 + np.arcsin(2 / 3) / (2 * np.pi), abs=1e-7)
