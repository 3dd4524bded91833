"""The friction tolerance (ocp.friction_tol): which foot slips must not depend on friction
coefficients known only to +-eps/2.  The slip-weighted margin of a simulation is checked against an
independent computation from the result arrays on a fine output grid (the slipping foot read from
``mode``, not from the displacements; rectangle rule instead of the trapezoid), and the rule against
the harmonic family and the replay judge."""
import math

import numpy as np
import pytest

from ocp_crawl import Robot
from ocp_crawl.model.inputs import Harmonic, ReferenceTorque
from ocp_crawl.model.sampled import PeriodicLinear
from ocp_crawl.model.statics import Model
from ocp_crawl.ocp import judge
from ocp_crawl.ocp.baseline import value_from
from ocp_crawl.ocp.family import WaveFamily, WaveParams
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.slip_margin import result_margins, slip_margins
from ocp_crawl.sim.event import simulate_torque
from ocp_crawl.sim.result import Mode
from ocp_crawl.status import Status

ROBOT = Robot.paper()
MODEL = Model(ROBOT, gravity="physical")


def harmonic(psi_deg: float, robot: Robot = ROBOT) -> ReferenceTorque:
    return ReferenceTorque(Harmonic.from_degrees(90.0, 30.0, psi_deg), robot.k)


def margin_from_modes(res, robot: Robot) -> float:
    """Independent: on output samples, the foot that slips after sample k is ``Mode(mode[k]).foot``;
    its slip is
    |x_foot,k+1 - x_foot,k|; the limits are taken at sample k (rectangle rule)."""
    l1, l2 = robot.mu1 * res.f_n1, robot.mu2 * res.f_n2
    num = den = 0.0
    for k in range(res.t.size - 1):
        foot = Mode(int(res.mode[k])).foot
        if foot == 0:
            continue
        for i, (x, own, other) in enumerate(((res.x1, l1, l2), (res.x2, l2, l1)), start=1):
            if foot in (i, 3):
                slip = abs(x[k + 1] - x[k])
                num += slip * (other[k] - own[k])
                den += slip * 0.5 * (own[k] + other[k])
    return num / den


@pytest.mark.parametrize("psi, robot",
                         [(45.0, ROBOT), (-30.0, ROBOT), (45.0, ROBOT.replace(mu1=0.35, mu2=0.43))])
def test_margin_of_a_simulation_matches_the_independent_computation(psi, robot):
    model = Model(robot, gravity="physical")
    res = simulate_torque(model, harmonic(psi, robot))
    fine = simulate_torque(model, harmonic(psi, robot), t_eval=np.linspace(0.0, 1.0, 20001))
    assert res.success and fine.success
    m, low = result_margins(res, robot)
    # unequal friction: a direct change of the slipping foot passes the tie (low = 0)
    assert -1e-12 < low < m
    assert m == pytest.approx(margin_from_modes(fine, robot), rel=2e-3)


def test_margin_is_zero_at_the_tie_and_infinite_without_slip():
    n = np.linspace(1.0, 2.0, 5)
    x = np.cumsum(np.r_[0.0, np.ones(4)])
    assert slip_margins(ROBOT, n, n, x, np.zeros(5)) == (0.0, 0.0)
    assert slip_margins(ROBOT, n, n, np.zeros(5), np.zeros(5)) == (math.inf, math.inf)
    # foot 2 slips with the lower limit: margin (lim1 - lim2) / mean = 2 (2 - 1) / 3
    m, low = slip_margins(ROBOT, np.full(5, 2.0), np.ones(5), np.zeros(5), x)
    assert m == pytest.approx(2 / 3) and low == pytest.approx(2 / 3)


def test_near_mirror_symmetric_harmonic_gait_is_rejected_and_psi_45_accepted():
    settings = OCPSettings(friction_tol=0.05)
    fam = WaveFamily(ROBOT, "physical", settings)
    tie = fam.evaluate(WaveParams(90.0, 90.0, 30.0, 30.0, 0.01))
    ok = fam.evaluate(WaveParams(90.0, 90.0, 30.0, 30.0, 45.0))
    assert not tie.success and "friction_tol" in tie.message and tie.margin[0] < 1e-3
    assert ok.success and ok.margin[0] > 0.05
    # without the tolerance the near-symmetric gait is a member (the faster one)
    free = WaveFamily(ROBOT, "physical", OCPSettings(friction_tol=0.0))
    assert free.evaluate(WaveParams(90.0, 90.0, 30.0, 30.0, 0.01)).success


@pytest.mark.parametrize("psi, status", [(0.01, Status.REPLAY_MISMATCH), (45.0, Status.SUCCESS)])
def test_judge_rejects_a_replay_that_holds_the_tie(psi, status):
    settings = OCPSettings(friction_tol=0.05)
    N = 100
    phase = np.arange(N) / N
    tau = np.asarray(harmonic(psi)(phase), float).reshape(2, N)
    T = 2.0 * settings.min_period(30.0, 30.0)  # well inside the bandwidth
    ref = simulate_torque(MODEL, PeriodicLinear(phase, tau))
    # an honest claim: only the margin can fail
    claim = value_from(settings, [ref.S], [ref.CoT_plus], T)
    verdict = judge.judge_replay([MODEL], settings, tau, T, claim)
    assert verdict.status == status, verdict.message
    if status == Status.REPLAY_MISMATCH:
        assert "friction_tol" in verdict.message and verdict.margin[0] < 0.05


def test_transcription_friction_rows_give_the_simulated_margin():
    """The OCP's constraint terms on sub-step variables sampled from a simulation (trapezoid limits,
    N = 200) give the slip-weighted margin of the simulation (trapezoid limits on its own steps) to
    O(1/N)."""
    from ocp_crawl.ocp.substeps import friction_rows, guess_block, sample_phases

    N, eps = 200, 0.05
    res = simulate_torque(MODEL, harmonic(45.0), t_eval=sample_phases(np.full(N, 0.5)))
    W = guess_block(res, MODEL, N)["w"]
    num = np.sum(friction_rows(W, 0.0))
    den = num - np.sum(friction_rows(W, 1.0))  # the terms are linear in eps
    m_ocp = num / den
    assert np.sum(friction_rows(W, eps)) == pytest.approx(num - eps * den, rel=1e-12)
    m_sim, _ = result_margins(simulate_torque(MODEL, harmonic(45.0)), ROBOT)
    # measured: 5.2e-4 at N = 50, 8.8e-5 at N = 200 (the simulation's own steps give its m to about
    # 1e-4)
    assert m_ocp == pytest.approx(m_sim, rel=1e-3)
    assert (np.sum(friction_rows(W, m_sim * 1.05)) < 0) and (np.sum(friction_rows(W, m_sim * 0.95))
                                                             > 0)
