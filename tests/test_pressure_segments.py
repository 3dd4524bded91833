"""The pressure actuator on a chain of more than three links: the joints of a segment share its bend
(``[pressure] segments``).  A segment of two joints whose link between them vanishes is the
three-link robot's joint (its own simulator), the shares are those of the segment's bend, the two
steppers agree on a five-link robot, and bad keys are errors naming them."""
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from ocp_crawl.model.pressure import (BendingMap, PressureReference, PressureWaveform,
                                      SegmentJoints)
from ocp_crawl.problem import ProblemError, load_problem, problem_from_dict, run_problem
from ocp_crawl.sim.crosscheck import crosscheck

REPO = Path(__file__).resolve().parent.parent
PAPER = REPO / "problems" / "paper_gait.toml"
#: the paper's robot under pressure, a larger amplitude and a slightly bent rest shape (a gait
#: whose S does not hang on a tie of the feet's friction limits at psi = 90 deg)
PRESSURE = ["gait.waveform=pressure", "gait.p0_bar=1.7", "gait.psi_deg=90",
            "pressure.amplitude_bar=0.93", "pressure.phi_rest_deg=177"]


def _split_first_segment(eps: float) -> dict:
    """The paper's robot as four links: segment 1 bent at two joints eps apart (each of twice the
    joint stiffness, so that in series they are the segment's), a massless link between them."""
    return tomllib.loads(f"""
[robot]
lengths = [0.03, {eps!r}, {0.06 - eps!r}, 0.03]
masses = [0.013, 0.0, 0.026, 0.013]
stiffness = [0.3354, 0.3354, 0.1677]
mu = 0.389
[gait]
waveform = "pressure"
p0_bar = 1.7
[pressure]
segments = [1, 1, 2]
""")


def test_a_segment_of_two_joints_tends_to_the_three_link_joint():
    """W+ to O(eps) (halving eps halves the error) and S within 0.5 % at the shortest link the
    chain takes (its longest link at most 100 times its shortest)."""
    three = run_problem(load_problem(PAPER, PRESSURE))
    errors = []
    for eps in (2.4e-3, 1.2e-3, 6e-4):
        four = run_problem(problem_from_dict(_split_first_segment(eps), overrides=PRESSURE))
        assert three.success and four.success, four.message
        errors.append(abs(four.W_plus - three.W_plus) / three.W_plus)
    assert errors[-1] < 1e-4 and errors[0] / errors[-1] > 3.0, errors
    assert four.S == pytest.approx(three.S, rel=5e-3) and abs(three.S) > 1e-2


def test_the_joints_of_a_segment_share_its_bend():
    """Each joint bends by its segment's bend over the segment's joints; the rates are the
    derivative of the values (central differences)."""
    ref = PressureReference(PressureWaveform(1.2, 0.4, 0.5), math.radians(175.0), BendingMap())
    joints = SegmentJoints(ref, (0, 0, 0, 1, 1))
    t = np.linspace(0.0, 1.0, 37)
    bend, shared = ref(t) - math.pi, joints(t) - math.pi
    np.testing.assert_allclose(shared[:3], np.tile(bend[0] / 3, (3, 1)), rtol=1e-14)
    np.testing.assert_allclose(shared[3:], np.tile(bend[1] / 2, (2, 1)), rtol=1e-14)
    np.testing.assert_allclose(joints(0.3), joints(np.array([0.3]))[:, 0], rtol=1e-15)
    h = 1e-6
    np.testing.assert_allclose(joints.derivative(t), (joints(t + h) - joints(t - h)) / (2 * h),
                               rtol=1e-7, atol=1e-9)
    with pytest.raises(ValueError, match="both segments"):
        SegmentJoints(ref, (0, 0, 0))


def test_the_event_stepper_and_the_mpcc_steps_agree_on_five_links():
    """Each segment as two hinges (links 20/20/40/20/20 mm): crosscheck PASS."""
    five = tomllib.loads("""
[robot]
lengths = [0.020, 0.020, 0.040, 0.020, 0.020]
masses = [0.0087, 0.0087, 0.0173, 0.0087, 0.0087]
stiffness = [0.3354, 0.3354, 0.3354, 0.3354]
mu = 0.389
[gait]
waveform = "pressure"
p0_bar = 1.7
psi_deg = 45.0
[pressure]
segments = [1, 1, 2, 2]
""")
    problem = problem_from_dict(five)
    check = crosscheck(problem.model, problem.torque, steps=(50, 100))
    assert check.passed, {k: c.text() for k, c in check.checks.items() if not c.passed}
    assert all(r.rel_diff_S <= 1e-9 for r in check.rows) and abs(check.rows[0].S) > 1e-3


@pytest.mark.parametrize("segments, words", [
    (None, ["[gait] waveform", "needs [pressure] segments", "segments = [1, 1, 2, 2]"]),
    ("[1, 2, 2]", ["[pressure] segments = [1, 2, 2]", "each of its 4 joints"]),
    ("[1, 2, 1, 2]", ["segment 1's first"]),
    ("[1, 1, 1, 1]", ["each segment at least one"]),
    ("[1, 3, 2, 2]", ["[pressure] segments", "1 or 2"])])
def test_bad_segments_are_errors_naming_the_key(segments, words):
    text = (REPO / "problems" / "five_link_chain.toml").read_text()
    data = tomllib.loads(text)
    data["gait"] = {"waveform": "pressure", "p0_bar": 1.7, "psi_deg": 10.0}
    if segments is not None:
        data["pressure"] = {"segments": tomllib.loads(f"s = {segments}")["s"]}
    with pytest.raises(ProblemError) as err:
        problem_from_dict(data)
    for w in words:
        assert w in str(err.value), (w, str(err.value))


def test_segments_on_the_three_link_robot_are_an_error():
    with pytest.raises(ProblemError, match=r"\[pressure\] segments = \[1, 2\].* key of a chain"):
        load_problem(PAPER, [*PRESSURE, "pressure.segments=[1, 2]"])
