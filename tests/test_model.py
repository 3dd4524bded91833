"""Symbolic statics (virtual work, CasADi AD) against the paper's closed forms."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ocp_crawl import Model, Robot


def closed_forms(robot: Robot, phi, sign_paper: bool):
    """The paper's printed formulas, eqs. (theta), (d), (xc), (extEq), (delta), (intEq)."""
    b, l, m, g, M = robot.beta, robot.l, robot.m, robot.g, robot.M
    p1, p2 = phi
    th = math.atan((math.sin(p1) - math.sin(p2)) / (math.cos(p1) + math.cos(p2) - b))
    a, c = p1 - th, p2 + th
    d = l * (b * math.cos(th) - math.cos(a) - math.cos(c))
    xc = l / (2 * (2 + b)) * ((2 + b) * b * math.cos(th) - (3 + 2 * b) * math.cos(a) - math.cos(c))
    delta = (1 + b) / (2 * (2 + b)) * l * (math.cos(c) - math.cos(a))
    fn1, fn2 = (1 - xc / d) * M * g, xc / d * M * g
    grav = ((1 + b) * l**2 * m * g / (2 * d)
            * np.array([math.cos(a) * (b * math.cos(th) - 2 * math.cos(c)),
                        math.cos(c) * (b * math.cos(th) - 2 * math.cos(a))]))

    def residual(tau, ft):
        base = (np.asarray(tau) - robot.k * (np.asarray(phi) - math.pi)
                - l * np.array([math.sin(a), math.sin(c)]) * ft)
        # the paper prints +grav (eq. intEq); virtual work gives -grav (MODEL_NOTES erratum)
        return base + grav if sign_paper else base - grav

    return dict(theta=th, d=d, xc=xc, Delta=delta, fn1=fn1, fn2=fn2,
                grad_d=l * np.array([math.sin(a), math.sin(c)]), residual=residual)


robots = st.builds(
    Robot,
    M=st.floats(0.01, 2.0), L=st.floats(0.05, 1.0), beta=st.floats(2.0, 4.0),
    k=st.floats(0.01, 10.0),
    mu1=st.floats(0.05, 2.0), mu2=st.floats(0.05, 2.0), g=st.floats(1.0, 20.0),
)
angles = st.floats(math.radians(40), math.radians(150))


@settings(max_examples=150, deadline=None)
@given(robot=robots, p1=angles, p2=angles, t1=st.floats(-2, 2), t2=st.floats(-2, 2),
       ft=st.floats(-1, 1), gravity=st.sampled_from(["physical", "paper"]))
def test_symbolic_statics_equal_closed_forms(robot, p1, p2, t1, t2, ft, gravity):
    model = Model(robot, gravity=gravity)
    phi = np.array([p1, p2])
    kin = model.kinematics(phi)
    ref = closed_forms(robot, phi, sign_paper=gravity == "paper")
    L, Mg = robot.L, robot.M * robot.g
    for name in ("theta",):
        assert kin[name] == pytest.approx(ref[name], abs=1e-12)
    for name in ("d", "xc", "Delta"):
        assert kin[name] == pytest.approx(ref[name], abs=1e-12 * L)
    for name in ("fn1", "fn2"):
        assert kin[name] == pytest.approx(ref[name], abs=1e-12 * Mg)
    np.testing.assert_allclose([kin["grad_d1"], kin["grad_d2"]], ref["grad_d"], rtol=0,
                               atol=1e-12 * L)
    tau = np.array([t1, t2]) * robot.MgL
    res = model.equilibrium_residual(phi, tau, ft * Mg)
    np.testing.assert_allclose(res, ref["residual"](tau, ft * Mg), rtol=0,
                               atol=1e-12 * max(robot.MgL, robot.k))


def test_conventions_differ_only_in_gravity_sign(paper_robot):
    phi = np.radians([100.0, 75.0])
    tau = np.array([-0.1, -0.2])
    r_phys = Model(paper_robot, "physical").equilibrium_residual(phi, tau, 0.05)
    r_pap = Model(paper_robot, "paper").equilibrium_residual(phi, tau, 0.05)
    grav = closed_forms(paper_robot, phi, False)
    kin = Model(paper_robot).kinematics(phi)
    grad_ug = np.array([kin["grad_Ug1"], kin["grad_Ug2"]])
    assert np.max(np.abs(grad_ug)) > 1e-4  # the test is not vacuous
    np.testing.assert_allclose(r_pap - r_phys, 2 * grad_ug, rtol=1e-12, atol=1e-15)
    assert grav["d"] > 0


def test_pi_shape_is_a_maximum_of_the_centre_of_mass_height(paper_robot):
    """The physical sign: gravity pushes the joints away from the Pi shape (MODEL_NOTES erratum)."""
    model = Model(paper_robot)
    u = [model.kinematics(np.radians([a, a]))["U_g"] for a in (80.0, 90.0, 100.0)]
    assert u[1] > u[0] and u[1] > u[2]


def test_flat_and_pi_shapes(paper_robot):
    model = Model(paper_robot)
    flat = model.kinematics(np.array([math.pi, math.pi]))
    assert flat["d"] == pytest.approx(paper_robot.L, rel=1e-14)
    assert flat["theta"] == pytest.approx(0.0, abs=1e-15)
    pi_shape = model.kinematics(np.array([math.pi / 2, math.pi / 2]))
    assert pi_shape["d"] == pytest.approx(paper_robot.beta * paper_robot.l, rel=1e-14)
    assert pi_shape["fn1"] == pytest.approx(pi_shape["fn2"], rel=1e-14)


@pytest.mark.parametrize("field,value,match", [
    ("M", -1.0, "M must be >= 1e-12"), ("L", 0.0, "L must be >= 1e-12"),
    ("k", float("nan"), "k must be finite"),
    ("beta", -2.0, "beta must be >= 0.01"), ("mu1", -0.1, "mu1 must be >= 0.0001"),
    ("g", float("inf"), "g must be finite"),
])
def test_robot_rejects_non_physical_values(field, value, match):
    with pytest.raises(ValueError, match=match):
        Robot(**{field: value})


def test_robot_rejects_wrong_types():
    with pytest.raises(TypeError, match="k must be a real number"):
        Robot(k="stiff")
    with pytest.raises(TypeError, match="M must be a real number"):
        Robot(M=True)


def test_model_rejects_unknown_gravity(paper_robot):
    with pytest.raises(ValueError, match="gravity must be one of"):
        Model(paper_robot, gravity="upside-down")


def test_check_contact(paper_robot):
    model = Model(paper_robot)
    model.check_contact(np.radians([90.0, 90.0]))
    with pytest.raises(ValueError, match="foot 2 off the ground"):
        model.check_contact(np.radians([30.0, 50.0]))
    with pytest.raises(ValueError, match="joint 1 at or below the ground"):
        model.check_contact(np.radians([-5.0, 90.0]))


@pytest.mark.parametrize("field, value", [("mu1", 0.0), ("mu2", 1e5), ("beta", 1e-9), ("M", 1e300),
                                          ("L", 0.0), ("k", 10 ** 400), ("g", -9.81)])
def test_robot_refuses_what_a_problem_file_refuses(field, value, tmp_path):
    """The API's Robot and the [robot] keys of a file share their bounds: each value is refused by
    both."""
    from ocp_crawl.problem import ProblemError, problem_from_dict

    with pytest.raises(ValueError, match=field):
        Robot(**{field: value})
    robot = {"M": 0.052, "L": 0.12, "k": 0.1677, "mu1": 0.389, "mu2": 0.389, field: value}
    with pytest.raises(ProblemError, match=f"\\[robot\\] {field} = "):
        problem_from_dict({"robot": robot,
                           "gait": {"gamma_deg": 90.0, "A_deg": 30.0, "psi_deg": 45.0}})
