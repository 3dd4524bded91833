"""Prescribed-angle gaits of n-link chains (ocp_crawl.sim.chain_angles) against the three-link
simulator (ocp_crawl.sim.angles), exact mirror and scaling relations, and an independent
brute-force integration written here in numpy.
"""
import math

import numpy as np
import pytest

from ocp_crawl.model.chain import Chain
from ocp_crawl.model.chain_inputs import JointCallable, JointFourier, JointSamples, as_joint_signal
from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.model.inputs import Harmonic
from ocp_crawl.model.statics import Model, Robot
from ocp_crawl.sim.angles import simulate_angles
from ocp_crawl.sim.chain_angles import simulate_chain_angles
from ocp_crawl.sim.result import Mode
from ocp_crawl.status import Status

GRAVITIES = ("physical", "paper")
#: relative tolerance of S and W+ against the three-link simulator
RTOL = 1e-9
#: output phases away from the cycle's ends and from the paper gait's events (0.25, 0.75)
T_OUT = (np.arange(120) + 0.37) / 120


def _three_link_cases() -> list[tuple[Robot, Harmonic]]:
    """The paper's robot and gait, and seeded robots and harmonic gaits near it (friction ratio
    within 15 %, so that the slipping foot changes in most of them)."""
    rng = np.random.default_rng(11)
    cases = [(Robot.paper(), Harmonic()), (Robot.paper(mu1=0.3, mu2=0.5), Harmonic())]
    for _ in range(8):
        mu = rng.uniform(0.2, 0.8)
        robot = Robot(M=rng.uniform(0.01, 2.0), L=rng.uniform(0.05, 1.0),
                      beta=rng.uniform(1.0, 4.0), k=rng.uniform(0.05, 10.0), mu1=mu,
                      mu2=mu * rng.uniform(0.85, 1.15), g=rng.uniform(1.0, 20.0))
        gait = Harmonic(*rng.uniform(1.1, 2.0, 2), *rng.uniform(0.2, 0.8, 2),
                        rng.uniform(0.3, 1.5) * rng.choice([-1, 1]))
        cases.append((robot, gait))
    return cases


CASES = _three_link_cases()
#: the outcome of each case (the same in both conventions): "moves" (|S| > 1e-3 L), "still" (one
#: foot slips all cycle long, S = 0) or the status of a loss of contact
OUTCOMES = ("moves", "still", "LIFT_OFF", "still", "still", "moves", "LIFT_OFF", "still", "moves",
            "moves")


def _away_from_events(res, t: np.ndarray) -> np.ndarray:
    """Mask of the phases t farther than 1e-9 cycles from every event of res."""
    ev = np.array([e.t for e in res.events])
    return np.all(np.abs(t[:, None] - ev[None, :]) > 1e-9, axis=1) if ev.size else \
        np.ones(t.size, bool)


def _rel(a, b, scale) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), scale), initial=0.0))


@pytest.fixture(scope="module", autouse=True)
def _built_functions():
    """Builds the CasADi functions and mapped evaluations that both simulators use once per
    process (about 2 s, a cost of the first call in a process, not of a simulation)."""
    for model in (Model(Robot.paper()), ChainModel(Chain.from_robot(Robot.paper()))):
        run = simulate_angles if isinstance(model, Model) else simulate_chain_angles
        run(model, Harmonic(), t_eval=T_OUT)


@pytest.mark.parametrize("gravity", GRAVITIES)
@pytest.mark.parametrize("case", range(len(CASES)))
def test_three_links_equal_simulate_angles(case, gravity):
    """n = 3: status, failure phase, S, W+ (per joint), events and every sampled trajectory equal
    those of simulate_angles on the paper gait and seeded robots and gaits."""
    robot, gait = CASES[case]
    L, Mg = robot.L, robot.M * robot.g
    ref = simulate_angles(Model(robot, gravity), gait, t_eval=T_OUT)
    got = simulate_chain_angles(ChainModel(Chain.from_robot(robot), gravity), gait, t_eval=T_OUT)
    assert got.status == ref.status and got.drive == "angles"
    outcome = ref.status.name if not ref.success else \
        "moves" if abs(ref.S) > 1e-3 * L else "still"
    assert outcome == OUTCOMES[case]
    # (coincident events, as the paper gait's reversal and switch, may come in either order)
    assert sorted(e.kind for e in got.events) == sorted(e.kind for e in ref.events)
    assert np.max(np.abs(np.sort([e.t for e in got.events])
                         - np.sort([e.t for e in ref.events])), initial=0.0) <= 1e-9
    if not ref.success:
        assert abs(got.failure_t - ref.failure_t) <= 1e-9
        assert got.failure_mode == ref.failure_mode
        return
    assert _rel(got.S, ref.S, 1e-6 * L) <= RTOL  # (|S| < 1e-6 L: no motion, S at round-off)
    assert _rel(got.W_plus, ref.W_plus, 1e-12 * robot.MgL) <= RTOL
    assert _rel(got.W_plus_joint, ref.W_plus_joint, 1e-12 * robot.MgL) <= RTOL
    assert got.CoT_plus == ref.CoT_plus or _rel(got.CoT_plus, ref.CoT_plus, 1e-12) <= RTOL
    ok = _away_from_events(ref, T_OUT)
    for name, s in (("phi", 1.0), ("theta", 1.0), ("d", L), ("x1", L), ("x2", L), ("f_t", Mg),
                    ("f_n1", Mg), ("f_n2", Mg), ("tau", robot.MgL)):
        a, b = getattr(got, name), getattr(ref, name)
        assert _rel(a[..., ok], b[..., ok], s) <= 1e-12, name
    assert np.array_equal(got.mode[ok], ref.mode[ok])


# -------------------------------------------------------------------------------- five links
FIVE = Chain(lengths=(0.03, 0.05, 0.04, 0.045, 0.025), masses=(0.012, 0.025, 0.02, 0.018, 0.01),
             stiffness=(0.3, 0.5, 0.4, 0.6), mu=(0.38, 0.42), com=(0.4, 0.55, 0.5, 0.6, 0.45),
             rest=(0.1, -0.2, 0.0, 0.15), g=9.81)
#: a travelling bend along the five-link chain: every joint bent upwards (an arch)
FIVE_GAIT = JointFourier.harmonic([2.6, 2.67, 2.75, 2.72], [0.31, 0.28, 0.34, 0.22],
                                  [3.47, 3.73, 5.33, 0.91])


def _geometry(chain: Chain, phi: np.ndarray) -> dict:
    """Independent numpy kinematics of the chain at the joint angles phi (m, N): link 1 laid along
    +x, the chain rotated so that foot 2 is on the ground at +x; d, the normal forces from the
    moments about foot 1, the joint heights and the friction limits."""
    l, mass, com = (np.asarray(v, float)[:, None] for v in (chain.lengths, chain.masses,
                                                            chain.com))
    r = np.vstack([np.zeros(phi.shape[1]), np.cumsum(phi - math.pi, axis=0)])
    X, Z = np.sum(l * np.cos(r), axis=0), np.sum(l * np.sin(r), axis=0)
    alpha = r - np.arctan2(Z, X)
    dx, dz = l * np.cos(alpha), l * np.sin(alpha)
    x0 = np.vstack([np.zeros(phi.shape[1]), np.cumsum(dx, axis=0)[:-1]])
    M = float(np.sum(mass))
    xc = np.sum(mass * (x0 + com * dx), axis=0) / M
    d = np.hypot(X, Z)
    fn2 = xc / d * M * chain.g
    fn1 = M * chain.g - fn2
    return {"d": d, "fn1": fn1, "fn2": fn2, "zj": np.cumsum(dz, axis=0)[:-1],
            "lim1": chain.mu[0] * fn1, "lim2": chain.mu[1] * fn2}


def _brute_force(chain: Chain, gait, n_steps: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, x1, x2) [cycles, m, m] on a grid of n_steps steps: at each step the foot with the smaller
    friction limit takes the change of d (foot 1: x1 -= delta d, foot 2: x2 += delta d); a step in
    which the limits cross is split at the crossing of their linear interpolation."""
    t = np.linspace(0.0, 1.0, n_steps + 1)
    geo = _geometry(chain, np.asarray(gait(t), float))
    h = geo["lim1"] - geo["lim2"]
    dd = np.diff(geo["d"])
    cross = np.sign(h[:-1]) != np.sign(h[1:])
    s = np.where(cross, h[:-1] / np.where(cross, h[:-1] - h[1:], 1.0), 1.0)
    first_is_1 = h[:-1] < 0
    share1 = np.where(first_is_1, s, 1.0 - s)  # the part of the step slipped by foot 1
    x1 = np.concatenate([[0.0], -np.cumsum(share1 * dd)])
    x2 = np.concatenate([[geo["d"][0]], geo["d"][0] + np.cumsum((1.0 - share1) * dd)])
    return t, x1, x2


@pytest.mark.parametrize("gravity", GRAVITIES)
def test_five_links_against_brute_force(gravity):
    """A five-link chain with unequal lengths, masses, centres of mass, joints and friction: S and
    the feet positions over the cycle equal an independent fine-grid integration (20000 steps);
    the slipping foot is the one with the smaller friction limit; the energy balance closes; the
    torques hold the angles in equilibrium."""
    model = ChainModel(FIVE, gravity)
    t, x1, x2 = _brute_force(FIVE, FIVE_GAIT, 20_000)
    every = slice(0, None, 100)
    res = simulate_chain_angles(model, FIVE_GAIT, t_eval=t[every])
    assert res.success and res.extra["links"] == 5 and res.phi.shape == (4, t[every].size)
    assert abs(res.S) > 0.1 * FIVE.L
    assert _rel(res.S, x1[-1], 0.0) <= 1e-4
    assert np.max(np.abs(res.x1 - x1[every])) <= 1e-6 * FIVE.L
    assert np.max(np.abs(res.x2 - x2[every])) <= 1e-6 * FIVE.L
    assert abs(res.energy["balance_residual"]) <= 1e-10
    assert res.W_plus > 0 and res.W_plus_joint.shape == (4,)
    ok = _away_from_events(res, res.t)
    geo = _geometry(FIVE, res.phi)
    foot = res.extra["foot"]
    assert np.array_equal(foot[ok], np.where(geo["lim1"] <= geo["lim2"], 1, 2)[ok])
    lim = np.where(foot == 1, geo["lim1"], geo["lim2"])
    assert _rel(np.abs(res.f_t[ok]), lim[ok], model.Mg) <= 1e-12
    for j in np.nonzero(ok)[0][::20]:
        F = model.equilibrium_residual(res.phi[:, j], res.tau[:, j], res.f_t[j])
        assert np.max(np.abs(F)) <= 1e-12 * FIVE.MgL


def test_loss_of_contact_at_the_independent_phase():
    """A joint bent downwards far enough reaches the ground: the status, and the phase of the
    first zero of its height by the independent kinematics."""
    from scipy.optimize import brentq

    gait = JointFourier.harmonic([3.2, 2.67, 2.75, 2.72], [0.5, 0.28, 0.34, 0.22],
                                 [3.47, 3.73, 5.33, 0.91])
    res = simulate_chain_angles(ChainModel(FIVE), gait)
    assert res.status == Status.JOINT_ON_GROUND and not res.success and math.isnan(res.S)
    t = np.linspace(0, 1, 4001)
    z = _geometry(FIVE, gait(t))["zj"]
    j, k = np.argwhere(z <= 0)[np.argmin(np.argwhere(z <= 0)[:, 1])]
    t0 = brentq(lambda s: _geometry(FIVE, gait(np.array([s])))["zj"][j, 0], t[k - 1], t[k],
                xtol=1e-15)
    assert abs(res.failure_t - t0) <= 1e-10 and res.events[0].kind == f"joint_{j + 1}_on_ground"


# -------------------------------------------------------------------------------- mirrors
def _reversed_gait(gait):
    """The same angles with the joints numbered from the other end."""
    if isinstance(gait, Harmonic):
        return Harmonic(gait.gamma2, gait.gamma1, gait.A2, gait.A1, -gait.psi)
    return JointFourier(gait.a0[::-1], gait.a[::-1], gait.b[::-1])


MIRROR_CASES = {"three": (Chain.from_robot(Robot.paper(mu1=0.3, mu2=0.5)), None),
                "five": (FIVE, FIVE_GAIT)}


@pytest.mark.parametrize("gravity", GRAVITIES)
@pytest.mark.parametrize("which", sorted(MIRROR_CASES))
def test_reversed_chain_mirrors_the_gait(which, gravity):
    """The chain read from the other end (Chain.reversed) with the joint angles in reverse order is
    the same motion seen along x' = d(0) - x: S' = -S, x1'(t) = d(0) - x2(t), x2'(t) = d(0) -
    x1(t), the same d and f_t (the force at the physical foot, along the other axis), normal forces
    and slipping feet exchanged, torques and W+ per joint in reverse order, the same W+."""
    chain, gait = MIRROR_CASES[which]
    gait = Harmonic(math.radians(80), math.radians(95), 0.5, 0.6, 0.7) if gait is None else gait
    a = simulate_chain_angles(ChainModel(chain, gravity), gait, t_eval=T_OUT)
    b = simulate_chain_angles(ChainModel(chain.reversed(), gravity), _reversed_gait(gait),
                              t_eval=T_OUT)
    assert a.success and b.success and abs(a.S) > 0.01 * chain.L
    L, Mg = chain.L, chain.M * chain.g
    assert abs(b.S + a.S) <= 1e-12 * L
    assert _rel(b.W_plus_joint, a.W_plus_joint[::-1], 1e-12 * chain.MgL) <= 1e-12
    ok = _away_from_events(a, T_OUT)
    d0 = ChainModel(chain).kinematics(np.asarray(gait(0.0), float))["d"]
    for mine, theirs, s in (("x1", d0 - a.x2, L), ("x2", d0 - a.x1, L), ("d", a.d, L),
                            ("f_t", a.f_t, Mg), ("f_n1", a.f_n2, Mg), ("f_n2", a.f_n1, Mg),
                            ("tau", a.tau[::-1], chain.MgL)):
        assert _rel(getattr(b, mine)[..., ok], theirs[..., ok], s) <= 1e-12, mine
    foot_a, foot_b = a.extra["foot"][ok], b.extra["foot"][ok]
    assert np.array_equal(foot_b, np.where(foot_a == 1, 2, np.where(foot_a == 2, 1, foot_a)))
    assert np.array_equal([Mode(m).sigma for m in b.mode[ok]],
                          [Mode(m).sigma for m in a.mode[ok]])


@pytest.mark.parametrize("which", sorted(MIRROR_CASES))
def test_time_reversed_gait_goes_back(which):
    """phi(1 - t): the same configurations in reverse order, the same slipping foot at each,
    every change of d undone: S -> -S, x_i(t) -> x_i(1 - t) - S, f_t(t) -> -f_t(1 - t).  With the
    chain reversed too, S is unchanged."""
    chain, gait = MIRROR_CASES[which]
    gait = JointFourier.harmonic([math.radians(80), math.radians(95)], [0.5, 0.6], [0.35, -0.35]) \
        if gait is None else gait
    back = JointFourier(gait.a0, gait.a, -gait.b)
    model = ChainModel(chain)
    a = simulate_chain_angles(model, gait, t_eval=T_OUT)
    b = simulate_chain_angles(model, back, t_eval=1.0 - T_OUT[::-1])
    assert a.success and b.success and abs(a.S) > 0.01 * chain.L
    assert abs(a.S + b.S) <= 1e-12 * chain.L
    ok = _away_from_events(a, T_OUT)[::-1]
    for name, mirrored in (("x1", a.x1[::-1] - a.S), ("x2", a.x2[::-1] - a.S),
                           ("f_t", -a.f_t[::-1])):
        assert np.max(np.abs(getattr(b, name)[ok] - mirrored[ok])) <= 1e-12 * chain.L, name
    both = simulate_chain_angles(ChainModel(chain.reversed()), _reversed_gait(back),
                                 t_eval=T_OUT[:2])
    assert abs(both.S - a.S) <= 1e-12 * chain.L


# -------------------------------------------------------------------------------- stiff joint
@pytest.mark.parametrize("robot", [Robot.paper(), Robot.paper(mu1=0.35, mu2=0.45)],
                         ids=["paper", "unequal_mu"])
def test_straight_extra_joint_is_the_three_link_gait(robot):
    """The body split by a fourth joint whose angle is prescribed at pi: the geometry is the
    three-link robot's at every phase, so S and W+ equal those of simulate_angles (to rounding),
    whatever that joint's stiffness (prescribed angles: no limit K -> infinity needed)."""
    gait = Harmonic()
    ref = simulate_angles(Model(robot), gait, t_eval=T_OUT)
    l, m, b = robot.l, robot.m, robot.beta
    s1, s2 = math.sin(gait.psi / 2), math.cos(gait.psi / 2)
    four_gait = JointFourier([gait.gamma1, math.pi, gait.gamma2],
                             [[gait.A1 * s1], [0.0], [-gait.A2 * s1]],
                             [[gait.A1 * s2], [0.0], [gait.A2 * s2]])
    for K in (1e-3 * robot.MgL, 1e4 * robot.MgL):
        four = Chain(lengths=(l, b * l / 2, b * l / 2, l), masses=(m, b * m / 2, b * m / 2, m),
                     stiffness=(robot.k, K, robot.k), mu=(robot.mu1, robot.mu2), g=robot.g)
        got = simulate_chain_angles(ChainModel(four), four_gait, t_eval=T_OUT)
        assert got.success and ref.success
        assert _rel(got.S, ref.S, 0.0) <= 1e-12
        assert _rel(got.W_plus, ref.W_plus, 0.0) <= 1e-12
        assert _rel(got.W_plus_joint[[0, 2]], ref.W_plus_joint, 0.0) <= 1e-12
        assert got.W_plus_joint[1] == 0.0
        assert _rel(got.x1, ref.x1, robot.L) <= 1e-12 and _rel(got.x2, ref.x2, robot.L) <= 1e-12


# -------------------------------------------------------------------------------- scaling
def test_scaling():
    """S depends on the geometry and on which friction limit is smaller (ratios of forces): lengths
    x a gives S x a; masses x b, g x c, other stiffnesses or rest bends leave S unchanged.  The
    holding torques are K (phi - pi - rest) + sgrav grad U_g + f_t grad d, with U_g ~ masses g
    lengths, f_t ~ masses g, grad d ~ lengths: with the stiffnesses x a b c as well they scale by
    a b c, so W+ x a b c and CoT+ = W+/(M g |S|) is unchanged."""
    a, b, c = 2.3, 0.4, 1.7
    base = simulate_chain_angles(ChainModel(FIVE), FIVE_GAIT, t_eval=T_OUT[:2])
    scaled = FIVE.scaled(a, b).replace(g=FIVE.g * c,
                                       stiffness=tuple(a * b * c * k for k in FIVE.stiffness))
    got = simulate_chain_angles(ChainModel(scaled), FIVE_GAIT, t_eval=T_OUT[:2])
    assert _rel(got.S, a * base.S, 0.0) <= 1e-12
    assert _rel(got.W_plus, a * b * c * base.W_plus, 0.0) <= 1e-11
    assert _rel(got.CoT_plus, base.CoT_plus, 0.0) <= 1e-11
    other = FIVE.replace(masses=tuple(b * v for v in FIVE.masses), stiffness=(5.0, 0.1, 1.0, 2.0),
                         rest=(0.0, 0.3, -0.2, 0.1))
    moved = simulate_chain_angles(ChainModel(other), FIVE_GAIT, t_eval=T_OUT[:2])
    assert _rel(moved.S, base.S, 0.0) <= 1e-12
    assert abs(moved.W_plus / base.W_plus - b) > 0.1  # W+ has no such invariance


# -------------------------------------------------------------------------------- inputs
@pytest.fixture(scope="module")
def five_reference():
    """The five-link gait's result with the exact Fourier signal."""
    return simulate_chain_angles(ChainModel(FIVE), FIVE_GAIT, t_eval=T_OUT[:2])


def test_sampled_angles(five_reference):
    """Samples of one cycle (a periodic cubic spline through 64 samples: error O(K^-4)) give the S
    and W+ of the exact Fourier signal."""
    samples = FIVE_GAIT(np.arange(64) / 64)
    assert isinstance(as_joint_signal(samples, 4), JointSamples)
    res = simulate_chain_angles(ChainModel(FIVE), samples, t_eval=T_OUT[:2])
    assert _rel(res.S, five_reference.S, 0.0) <= 1e-6
    assert _rel(res.W_plus, five_reference.W_plus, 0.0) <= 1e-6


def test_callable_angles(five_reference):
    """A plain callable (derivative by central differences: only the torques' rates use it) gives
    the S and W+ of the exact Fourier signal."""
    assert isinstance(as_joint_signal(lambda t: FIVE_GAIT(t), 4), JointCallable)
    res = simulate_chain_angles(ChainModel(FIVE), lambda t: FIVE_GAIT(t), t_eval=T_OUT[:2])
    assert _rel(res.S, five_reference.S, 0.0) <= 1e-12
    assert _rel(res.W_plus, five_reference.W_plus, 0.0) <= 1e-9


def test_bad_angles_raise():
    """Wrong row count, a signal that is not periodic, a start below the ground, a three-link
    Model, a string and a too coarse scan raise errors that name what is wrong."""
    model = ChainModel(FIVE)
    with pytest.raises(ValueError, match="4 rows"):
        simulate_chain_angles(model, Harmonic())
    with pytest.raises(ValueError, match="1-periodic"):
        simulate_chain_angles(model, lambda t: FIVE_GAIT(t) + 0.01 * t)
    with pytest.raises(ValueError, match="joint 3 at or below the ground"):
        simulate_chain_angles(model, JointFourier([2.6, 2.67, 4.0, 2.72], np.zeros((4, 1)),
                                                  np.zeros((4, 1))))
    with pytest.raises(TypeError, match="ChainModel"):
        simulate_chain_angles(Model(Robot.paper()), Harmonic())
    with pytest.raises(TypeError, match="joint angles"):
        simulate_chain_angles(model, "gait")
    with pytest.raises(ValueError, match="n_scan"):
        simulate_chain_angles(model, FIVE_GAIT, n_scan=4)
