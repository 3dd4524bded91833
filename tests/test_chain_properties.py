"""Property test: the two simulators of n-link chains agree on random chains.

Random chains of 3 to 6 links with unequal lengths, masses, centres of mass, joint stiffnesses,
rest bends and foot frictions, driven by reference torques k_j (phi_ref,j - pi - rest_j) with a
harmonic reference per joint (legs bent down, the body near straight, a phase lag between
successive joints).  The event-driven chain simulator (:func:`~ocp_crawl.sim.simulate_chain_torque`)
and the chain's exact incremental steps split at the events
(:func:`~ocp_crawl.sim.simulate_chain_mpcc`, 50 steps per cycle) are independent solvers of the
same hybrid-quasistatic model: where both succeed, S must agree to 1e-9 relative, or to round-off
(1e-12 of the length) on a gait without net motion (switch-exact steps carry no discretisation
error in S; measured at most 1.2e-13 on eight random chains), a failure of either is a status
with a message, and a contact the event-driven simulator sees lost (a joint on the ground, a
foot lifting off, the feet crossing) ends the steps too, at the same phase when for the same
reason (the steps look between their ends for it).

The default suite checks the example below and a small fixed set; for a random run set
``OCP_CRAWL_HYPOTHESIS_EXAMPLES``, e.g.
``OCP_CRAWL_HYPOTHESIS_EXAMPLES=100 python -m pytest -q tests/test_chain_properties.py``.
"""
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, event, example, given, note, settings
from hypothesis import strategies as st

from ocp_crawl.model.chain import Chain
from ocp_crawl.model.chain_inputs import JointFourier
from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.sim.chain_mpcc import simulate_chain_mpcc
from ocp_crawl.sim.chain_torque import ChainReferenceTorque, simulate_chain_torque

#: the statuses of a lost contact
CONTACT = ("joint_on_ground", "lift_off", "feet_crossed")

EXAMPLES = int(os.environ.get("OCP_CRAWL_HYPOTHESIS_EXAMPLES", "3"))
SETTINGS = settings(max_examples=EXAMPLES, deadline=None, database=None,
                    derandomize="OCP_CRAWL_HYPOTHESIS_EXAMPLES" not in os.environ,
                    suppress_health_check=[HealthCheck.too_slow])
#: steps per cycle of the incremental simulator
STEPS = 50
#: largest relative difference of S between the two simulators
REL_S = 1e-9


def _chain(lengths, masses, com, ratios, rest, mu) -> Chain:
    """A chain whose joint stiffnesses are ``ratios`` times its M g L."""
    weight = 9.81 * float(np.sum(masses)) * float(np.sum(lengths))
    return Chain(lengths=tuple(lengths), masses=tuple(masses),
                 stiffness=tuple(float(r) * weight for r in ratios), mu=tuple(mu),
                 com=tuple(com), rest=tuple(rest))


@st.composite
def chains_and_gaits(draw):
    n = draw(st.integers(3, 6))
    m = n - 1
    floats = lambda lo, hi, size: draw(st.lists(st.floats(lo, hi), min_size=size,  # noqa: E731
                                                max_size=size))
    chain = _chain(floats(0.015, 0.035, n), floats(0.005, 0.015, n), floats(0.4, 0.6, n),
                   floats(1.0, 5.0, m), floats(-0.05, 0.05, m), floats(0.3, 0.5, 2))
    if m == 2:
        mean = np.full(m, draw(st.floats(80.0, 110.0)))
    else:   # the legs bent down, the body near straight
        mean = np.full(m, draw(st.floats(150.0, 175.0)))
        mean[0] = mean[-1] = draw(st.floats(95.0, 125.0))
    amplitude = np.asarray(floats(10.0, 30.0, m))
    lag = draw(st.floats(-90.0, 90.0))
    reference = JointFourier.harmonic(np.radians(mean), np.radians(amplitude),
                                      np.radians(lag) * np.arange(m))
    return chain, reference


#: a four-link chain whose slips end in stick-stick just before a step phase, inside a step whose
#: net slip is still positive: the step is split at the slip's end
PASSED_SLIP_END = (
    Chain(lengths=(0.031509756267871114, 0.018290145329482026, 0.02250293992993284,
                   0.021334763331139286),
          masses=(0.011913370352777411, 0.006785718781743719, 0.008962561622169865,
                  0.00505824595107981),
          stiffness=(0.06161417083407776, 0.08069301249940894, 0.04279027926802153),
          mu=(0.42663198920731155, 0.37608485397730645),
          com=(0.5450587876152477, 0.5307732022136789, 0.4862453497554812, 0.5734641011284398),
          rest=(0.013213511750016699, 0.03102743521062991, -0.015820527605988698)),
    JointFourier.harmonic([1.7608435980944581, 2.855214356658828, 1.7608435980944581],
                          [0.5222517968455301, 0.25943113807767604, 0.2641965860868644],
                          -1.3408629330557327 * np.arange(3)))


#: a five-link chain whose slip stops at 0.63363, inside the step [0.62, 0.64] (net slip still
#: negative), and whose joint 1 touches the ground at 0.63655 in the stick after it: the touch was
#: looked for in the slip's solution past its end (0.63657 at 25 and 50 steps)
SLIP_STOPPED_BEFORE_A_TOUCH = (
    Chain(lengths=(0.015, 0.02, 0.024689573074579883, 0.033203125, 0.02042326592857681),
          masses=(0.0078125, 0.01171875, 0.0078125, 0.0078125, 0.009765625),
          stiffness=(0.06242060780769592, 0.19974594498462694, 0.1498094587384702,
                     0.049936486246156736),
          mu=(0.5, 0.5), com=(0.5, 0.5, 0.5, 0.5, 0.5), rest=(0.0, 0.0, 0.0, 0.0)),
    JointFourier([1.6580627893946132, 2.6179938779914944, 2.6179938779914944, 1.6580627893946132],
                 [[0.0], [0.2218795758591703], [0.19254735068182713], [0.17071896203287812]],
                 [[0.17453292519943295], [0.4549205467520418], [0.15043447750965994],
                  [0.0362874355815836]]))


@pytest.mark.slow
@SETTINGS
@given(chains_and_gaits())
@example(PASSED_SLIP_END)
@example(SLIP_STOPPED_BEFORE_A_TOUCH)
def test_event_driven_and_incremental_chain_simulators_agree(case):
    chain, reference = case
    note(f"{chain}, {reference.describe()}")
    model = ChainModel(chain)
    torque = ChainReferenceTorque(reference, chain)
    ev = simulate_chain_torque(model, torque, t_eval=np.array([0.0, 1.0]))
    steps = simulate_chain_mpcc(model, torque, steps=STEPS)
    for res in (ev, steps):
        assert res.success or res.message, res.status_name
    event(f"n = {chain.n}: event-driven {ev.status_name}, steps {steps.status_name}")
    if ev.status_name in CONTACT:
        # (a lost contact inside a step is located there: no step end has to see it)
        note(f"failures at {ev.failure_t!r} and {steps.failure_t!r}")
        assert not steps.success
        if steps.status_name == ev.status_name:
            assert steps.failure_t == pytest.approx(ev.failure_t, abs=1e-8)
    if ev.success and steps.success:
        note(f"S {ev.S!r} and {steps.S!r}")
        # (plus round-off, for gaits without net motion)
        assert abs(steps.S - ev.S) <= REL_S * abs(ev.S) + 1e-12 * sum(chain.lengths)
