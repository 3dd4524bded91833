"""The event-driven stepper's cycle integrals (W+) on gaits with holds: segments where the joints
are at rest (their powers at round-off, ~1e-15 W) are integrated with a bounded number of mode
solves, and W+ agrees with an independent sum over a dense output of the same run."""
import numpy as np
import pytest

import ocp_crawl.model.statics as statics
from ocp_crawl import Model, PeriodicLinear, Robot, simulate
from ocp_crawl.model.inputs import Harmonic, ReferenceTorque

#: mode solves of one cycle's integrals: a few hundred on these gaits; a segment halved to the
#: quadrature's depth limit takes millions
MAX_SOLVES = 20_000


def counted_run(monkeypatch, model, signal, t_eval=None):
    """simulate(model, signal) and the number of points the batched mode solves took."""
    solved = []
    batch = statics.solve_many

    def counting(x0, *args):
        solved.append(x0.shape[1])
        return batch(x0, *args)

    monkeypatch.setattr(statics, "solve_many", counting)
    import ocp_crawl.sim.event_solve as event_solve
    if hasattr(event_solve, "solve_many"):
        monkeypatch.setattr(event_solve, "solve_many", counting)
    res = simulate(model, signal, t_eval=t_eval)
    monkeypatch.setattr(statics, "solve_many", batch)
    return res, sum(solved)


def dense_w_plus(res) -> np.ndarray:
    """W+ per joint [J] by the trapezoid sum of max(tau dphi, 0) over the run's samples (phases of
    its steady cycle; independent of the stepper's panels)."""
    phi, tau = res.phi, res.tau
    work = 0.5 * (tau[:, 1:] + tau[:, :-1]) * np.diff(phi, axis=1)
    return np.sum(np.maximum(work, 0.0), axis=1)


@pytest.mark.parametrize("case", ["symmetric-hold", "torque-plateaus"])
def test_holds_take_few_solves_and_w_plus_matches_a_dense_sum(monkeypatch, case):
    robot = Robot.paper()
    if case == "symmetric-hold":
        # psi = 0 at gamma 70 deg (physical gravity), mu1 just below mu2: the joints rest in
        # stick-stick between 0.75 and 0.797 of the cycle
        model = Model(robot.replace(mu1=robot.mu2 * (1 - 2e-4)), gravity="physical")
        signal = ReferenceTorque(Harmonic.from_degrees(70.0, 30.0, 0.0), robot.k)
    else:
        # a trapezoid-like torque table with plateaus (a soft actuator's pressure held)
        t = np.array([0.0, 0.2, 0.45, 0.55, 0.8])
        base = robot.k * (np.deg2rad(90.0) - np.pi)
        swing = robot.k * np.deg2rad(30.0)
        tau = np.array([base + swing * np.array([1.0, -1.0, -1.0, 1.0, 1.0]),
                        base + swing * np.array([1.0, 1.0, -1.0, -1.0, 1.0])])
        model, signal = Model(robot), PeriodicLinear(t, tau)
    res, solves = counted_run(monkeypatch, model, signal)
    assert res.success, res.message
    assert solves <= MAX_SOLVES, solves
    dense, _ = counted_run(monkeypatch, model, signal, t_eval=np.linspace(0.0, 1.0, 40_001))
    assert dense.success and dense.W_plus == res.W_plus
    np.testing.assert_allclose(dense_w_plus(dense), res.W_plus_joint, rtol=1e-5, atol=1e-12)
