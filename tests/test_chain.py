"""The n-link chain (ocp_crawl.model.chain*) against the three-link model (model.statics).

Every reference number comes from the existing three-link code (``Model``, ``symbolic()``); the
chain's own numbers are compared with themselves only for properties that the three-link code
cannot state (reversal and scaling of chains of four and more links), and there the three-link
case is checked against the existing code too.
"""
import math

import numpy as np
import pytest

from ocp_crawl.model.chain import Chain
from ocp_crawl.model.chain_model import ChainModel, slip_mode, stick_mode
from ocp_crawl.model.statics import AUX, KIN_NAMES, Model, Robot, call_mapped, symbolic

#: relative tolerance of every comparison with the three-link code
RTOL = 1e-12
GRAVITIES = ("physical", "paper")
MODES = (("stick", None), ("slip", (1, 1)), ("slip", (1, -1)), ("slip", (2, 1)), ("slip", (2, -1)))


def _robots() -> list[Robot]:
    """The paper's robot and three seeded variants of every parameter."""
    rng = np.random.default_rng(7)
    out = [Robot.paper()]
    for _ in range(3):
        out.append(Robot(M=rng.uniform(0.01, 2.0), L=rng.uniform(0.05, 1.0),
                         beta=rng.uniform(1.0, 4.0), k=rng.uniform(0.05, 10.0),
                         mu1=rng.uniform(0.05, 2.0), mu2=rng.uniform(0.05, 2.0),
                         g=rng.uniform(1.0, 20.0)))
    return out


ROBOTS = _robots()
ROBOT_IDS = ["paper", "variant1", "variant2", "variant3"]


def rel(a, b, scale) -> float:
    """Largest |a - b| / max(|b|, scale) over the entries [-]."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), scale)))


def _phis(model: Model, rng, n: int) -> np.ndarray:
    """n joint-angle columns in [40, 150] deg, away from the degenerate shapes (feet closer than
    0.1 L, the body turned over): (2, n)."""
    phi = rng.uniform(math.radians(40), math.radians(150), size=(2, 4 * n))
    kin = model.kinematics(phi)
    ok = (kin["d"] > 0.1 * model.robot.L) & (np.abs(kin["theta"]) < 1.2)
    assert ok.sum() >= n
    return phi[:, ok][:, :n]


def _mode_vector(kind, arg, d0):
    return stick_mode(d0) if kind == "stick" else slip_mode(*arg)


def _existing_solve(model: Model, x0, tau, q):
    """The three-link model's unrolled Newton (``symbolic().newton``), repeated to convergence and
    once more (its last iterates at the rounding level)."""
    x = np.asarray(x0, float)
    done = False
    for _ in range(10):
        xo, aux = symbolic().newton(x, tau, np.zeros(2), q, model.p)
        x, aux = np.asarray(xo).ravel(), np.asarray(aux).ravel()
        if done:
            return x
        done = aux[AUX["res"]] <= 1e-13
    raise AssertionError("the three-link Newton did not converge")


# -------------------------------------------------------------------------------- the Chain
def test_from_robot_is_the_three_link_robot():
    for robot in ROBOTS:
        chain = Chain.from_robot(robot)
        l, m, b = robot.L / (2 + robot.beta), robot.M / (2 + robot.beta), robot.beta
        assert chain.n == 3 and chain.n_joints == 2
        assert chain.lengths == (l, b * l, l) and chain.masses == (m, b * m, m)
        assert chain.com == (0.5, 0.5, 0.5) and chain.rest == (0.0, 0.0)
        assert chain.stiffness == (robot.k, robot.k) and chain.mu == (robot.mu1, robot.mu2)
        assert chain.g == robot.g
        assert chain.M == pytest.approx(robot.M, rel=1e-15)
        assert chain.L == pytest.approx(robot.L, rel=1e-15)


@pytest.mark.parametrize("changes, field", [
    (dict(lengths=(1.0, 1.0)), "lengths"), (dict(lengths=(1.0, -1.0, 1.0)), r"lengths\[1\]"),
    (dict(lengths=(1.0, 1e-3, 1.0)), "lengths"), (dict(masses=(1.0, 1.0)), "masses"),
    (dict(masses=(0.0, 0.0, 0.0)), "total mass"), (dict(masses=(1.0, -1.0, 1.0)), r"masses\[1\]"),
    (dict(com=(0.5, 1.5, 0.5)), r"com\[1\]"), (dict(stiffness=(1.0,)), "stiffness"),
    (dict(stiffness=(1.0, 0.0)), r"stiffness\[1\]"), (dict(rest=(0.0, 4.0)), r"rest\[1\]"),
    (dict(mu=(0.3,)), "mu"), (dict(mu=(0.3, 0.0)), r"mu\[1\]"), (dict(g=math.nan), "g"),
])
def test_bad_values_name_their_field(changes, field):
    good = dict(lengths=(1.0, 2.0, 1.0), masses=(1.0, 2.0, 1.0), stiffness=(1.0, 1.0),
                mu=(0.3, 0.3))
    with pytest.raises(ValueError, match=field):
        Chain(**{**good, **changes})
    with pytest.raises(TypeError, match="lengths"):
        Chain(**{**good, "lengths": "abc"})
    with pytest.raises(TypeError, match="robot"):
        Chain.from_robot("paper")


def test_reversed_and_merged():
    chain = Chain(lengths=(0.1, 0.2, 0.15, 0.05), masses=(0.1, 0.3, 0.2, 0.05),
                  stiffness=(1.0, 2.0, 3.0), mu=(0.2, 0.6), com=(0.3, 0.5, 0.6, 0.9),
                  rest=(0.1, 0.0, -0.2), g=9.0)
    back = chain.reversed()
    assert back.lengths == (0.05, 0.15, 0.2, 0.1) and back.mu == (0.6, 0.2)
    assert back.com == pytest.approx((0.1, 0.4, 0.5, 0.7)) and back.rest == (-0.2, 0.0, 0.1)
    assert back.reversed().lengths == chain.lengths
    merged = chain.merged(1)
    assert merged.lengths == pytest.approx((0.1, 0.35, 0.05))
    assert merged.masses == pytest.approx((0.1, 0.5, 0.05))
    # centre of mass of links 2 and 3: (0.3 * 0.1 + 0.2 * (0.2 + 0.09)) / 0.5 from link 2's start
    assert merged.com[1] == pytest.approx((0.03 + 0.058) / 0.5 / 0.35)
    assert merged.stiffness == (1.0, 3.0) and merged.rest == (0.1, -0.2)
    with pytest.raises(ValueError, match="rest"):
        chain.merged(0)
    with pytest.raises(ValueError, match="3 links"):
        Chain.from_robot(Robot.paper()).merged(0)
    robot = Robot.paper()
    four = _split_body(robot, 1e3)
    for a, b in zip(four.merged(1).__dict__.values(), Chain.from_robot(robot).__dict__.values()):
        assert np.allclose(a, b, rtol=1e-14, atol=0)


# -------------------------------------------------------------------------------- n = 3
@pytest.mark.parametrize("gravity", GRAVITIES)
@pytest.mark.parametrize("robot", ROBOTS, ids=ROBOT_IDS)
def test_kinematics_and_balance_equal_three_link(robot, gravity):
    model, chain = Model(robot, gravity), ChainModel(Chain.from_robot(robot), gravity)
    rng = np.random.default_rng(1)
    phi = _phis(model, rng, 200)
    ref, got = model.kinematics(phi), chain.kinematics(phi)
    L, Mg, MgL = robot.L, robot.M * robot.g, robot.M * robot.g * robot.L
    scales = dict(theta=1.0, d=L, xc=L, Delta=L, fn1=Mg, fn2=Mg, grad_d1=L, grad_d2=L,
                  grad_Ug1=MgL, grad_Ug2=MgL, U_el=MgL, U_g=MgL, zj1=L, zj2=L)
    for name in KIN_NAMES:
        assert rel(got["alpha2" if name == "theta" else name], ref[name], scales[name]) <= RTOL
    assert rel(chain.potential(phi), model.potential(phi), MgL) <= RTOL
    ft = rng.uniform(-1, 1, 200) * Mg
    assert rel(chain.hold_torque(phi, ft), model.hold_torque(phi, ft), MgL) <= RTOL
    for i in range(10):
        tau = rng.uniform(-2, 2, 2) * MgL
        assert rel(chain.equilibrium_residual(phi[:, i], tau, ft[i]),
                   model.equilibrium_residual(phi[:, i], tau, ft[i]), MgL) <= RTOL


@pytest.mark.parametrize("gravity", GRAVITIES)
@pytest.mark.parametrize("robot", ROBOTS, ids=ROBOT_IDS)
def test_mode_equations_equal_three_link(robot, gravity):
    """G, J, det J, every output of ``evaluate`` and d'' in every mode, at random states."""
    model, chain = Model(robot, gravity), ChainModel(Chain.from_robot(robot), gravity)
    rng = np.random.default_rng(2)
    n = 24
    phi = _phis(model, rng, n)
    L, Mg, MgL = robot.L, robot.M * robot.g, robot.M * robot.g * robot.L
    x = np.vstack([phi, rng.uniform(-1, 1, (1, n))])
    tau, dtau = rng.uniform(-2, 2, (2, n)) * MgL, rng.uniform(-2, 2, (2, n)) * MgL
    d = model.kinematics(phi)["d"]
    scale = dict(theta=1, d=L, xc=L, Delta=L, fn1=Mg, fn2=Mg, ft=Mg, lim1=Mg, lim2=Mg, zj1=L,
                 zj2=L)
    for kind, arg in MODES:
        q = np.array([_mode_vector(kind, arg, d0 * rng.uniform(0.9, 1.1)) for d0 in d]).T
        ref = call_mapped(symbolic().evaluate, x, tau, dtau, q, model.p)
        got = chain.evaluate(x, tau, dtau, q)
        # rates in units of the batch's largest joint rate (they scale with J^-1: near a fold they
        # are large and so are their rounding errors); det J and |G| relative to their largest size
        w = np.max(np.abs(ref[[AUX["dphi1"], AUX["dphi2"]]]))
        scale.update(ddot=L * w, dphi1=w, dphi2=w, dft=Mg * w, dfn1=Mg * w, dfn2=Mg * w,
                     dzj1=L * w, dzj2=L * w)
        for name, i in AUX.items():
            s = scale.get(name, np.max(np.abs(ref[i])))
            assert rel(got["alpha2" if name == "theta" else name], ref[i], s) <= RTOL, (kind, name)
        for j in range(n):
            G0, J0 = (np.asarray(v) for v in symbolic().system(x[:, j], tau[:, j], q[:, j],
                                                                model.p))
            G1, J1 = chain.mode_system(x[:, j], tau[:, j], q[:, j])
            assert rel(G1, G0.ravel(), np.max(np.abs(G0))) <= RTOL
            assert rel(J1, J0, np.max(np.abs(J0))) <= RTOL
        # d'' = a + b . tau'': a [m/s^2] relative to L w^2, b [m/(N m)] to 1/(M g)
        for j in range(4):
            a0 = np.asarray(symbolic().ddot2(x[:, j], tau[:, j], dtau[:, j], q[:, j],
                                             model.p)).ravel()
            a1, b1 = chain.ddot2(x[:, j], tau[:, j], dtau[:, j], q[:, j])
            assert rel(a1, a0[0], L * w**2) <= RTOL
            assert rel(b1, a0[1:], 1 / Mg) <= RTOL


def _equilibrium(model: Model, phi, kind, arg):
    """(tau, x, q): torques [N m] that make ``phi`` an equilibrium of the mode (from the three-link
    code's holding torque), the state x and the mode vector."""
    kin = model.kinematics(phi)
    if kind == "stick":
        ft, q = 0.3 * kin["fn1"] * model.robot.mu1, stick_mode(kin["d"])
    else:
        foot, sigma = arg
        ft = sigma * (model.robot.mu1 * kin["fn1"] if foot == 1 else model.robot.mu2 * kin["fn2"])
        q = slip_mode(foot, sigma)
    Mg = model.robot.M * model.robot.g
    return model.hold_torque(phi, ft), np.r_[phi, ft / Mg], q


@pytest.mark.parametrize("gravity", GRAVITIES)
@pytest.mark.parametrize("robot", ROBOTS, ids=ROBOT_IDS)
def test_torque_driven_equilibria_equal_three_link(robot, gravity):
    """Newton from a perturbed start: the chain's solution is the three-link Newton's."""
    model, chain = Model(robot, gravity), ChainModel(Chain.from_robot(robot), gravity)
    rng = np.random.default_rng(3)
    phis = _phis(model, rng, 4)
    for kind, arg in MODES:
        for phi in phis.T:
            tau, x_star, q = _equilibrium(model, phi, kind, arg)
            x0 = x_star + np.r_[rng.uniform(-0.02, 0.02, 2), 0.0]
            ref = _existing_solve(model, x0, tau, q)
            sol = chain.solve(x0, tau, q, tol=0.0)  # to the rounding level (a step <= xtol)
            assert sol.converged
            assert rel(sol.x, ref, 1.0) <= RTOL
            f_ref = model.kinematics(ref[:2])
            for name in ("fn1", "fn2"):
                assert rel(sol.aux[name], f_ref[name], robot.M * robot.g) <= RTOL


@pytest.mark.parametrize("gravity", GRAVITIES)
@pytest.mark.parametrize("robot", ROBOTS, ids=ROBOT_IDS)
def test_prescribed_angles_equal_three_link(robot, gravity):
    """The slipping foot, f_t = sign(d') mu_s f_n,s and the holding torques of prescribed
    angles."""
    model, chain = Model(robot, gravity), ChainModel(Chain.from_robot(robot), gravity)
    rng = np.random.default_rng(4)
    phi = _phis(model, rng, 100)
    dphi = rng.uniform(-3, 3, phi.shape)
    kin = model.kinematics(phi)
    ddot = kin["grad_d1"] * dphi[0] + kin["grad_d2"] * dphi[1]
    lim1, lim2 = robot.mu1 * kin["fn1"], robot.mu2 * kin["fn2"]
    ft = np.sign(ddot) * np.minimum(lim1, lim2)
    got = chain.prescribed(phi, dphi)
    assert np.array_equal(got["foot"], np.where(lim1 <= lim2, 1, 2))
    assert rel(got["ddot"], ddot, robot.L) <= RTOL
    assert rel(got["ft"], ft, robot.M * robot.g) <= RTOL
    assert rel(got["tau"], model.hold_torque(phi, ft), robot.M * robot.g * robot.L) <= RTOL


# -------------------------------------------------------------------------------- reversal
def _random_chain(rng, n: int) -> Chain:
    """A chain of n links of random lengths, masses, centres of mass, stiffnesses, rest bends and
    friction coefficients."""
    return Chain(lengths=tuple(rng.uniform(0.02, 0.06, n)),
                 masses=tuple(rng.uniform(0.01, 0.03, n)),
                 stiffness=tuple(rng.uniform(0.2, 1.0, n - 1)), mu=tuple(rng.uniform(0.2, 0.8, 2)),
                 com=tuple(rng.uniform(0.2, 0.8, n)), rest=tuple(rng.uniform(-0.3, 0.3, n - 1)))


def _chain_phis(model: ChainModel, rng, count: int) -> np.ndarray:
    """Joint angles of a low arch: each bend within 35 deg of straight, d > 0.5 L."""
    n = model.chain.n
    phi = math.pi + rng.uniform(-0.6, 0.1, (n - 1, 4 * count))
    ok = model.kinematics(phi)["d"] > 0.5 * model.chain.L
    return phi[:, ok][:, :count]


@pytest.mark.parametrize("gravity", GRAVITIES)
def test_reversal_mirrors_the_three_link_robot(gravity):
    """The reversed paper robot with unequal friction is the three-link model of the robot with the
    feet exchanged; at the same physical configuration (phi reversed) the three-link model of the
    robot itself has the normal forces exchanged, the same f_t and the torques reversed."""
    robot = Robot.paper(mu1=0.3, mu2=0.5)
    model, swapped = Model(robot, gravity), Model(robot.replace(mu1=0.5, mu2=0.3), gravity)
    back = ChainModel(Chain.from_robot(robot).reversed(), gravity)
    rng = np.random.default_rng(5)
    phi = _phis(model, rng, 50)
    psi = phi[::-1]
    Mg, L = robot.M * robot.g, robot.L
    ref, got, orig = swapped.kinematics(psi), back.kinematics(psi), model.kinematics(phi)
    scales = dict(theta=1.0, d=L, xc=L, Delta=L, fn1=Mg, fn2=Mg, grad_d1=L, grad_d2=L,
                  grad_Ug1=Mg * L, grad_Ug2=Mg * L, U_el=Mg * L, U_g=Mg * L, zj1=L, zj2=L)
    for name in KIN_NAMES:
        assert rel(got["alpha2" if name == "theta" else name], ref[name], scales[name]) <= RTOL
    for mine, theirs in (("fn1", "fn2"), ("fn2", "fn1"), ("d", "d"), ("zj1", "zj2")):
        assert rel(got[mine], orig[theirs], scales[mine]) <= RTOL
    assert rel(got["lim1"], robot.mu2 * orig["fn2"], Mg) <= RTOL
    ft = rng.uniform(-1, 1, 50) * Mg
    assert rel(back.hold_torque(psi, ft), swapped.hold_torque(psi, ft), Mg * L) <= RTOL
    assert rel(back.hold_torque(psi, ft)[::-1], model.hold_torque(phi, ft), Mg * L) <= RTOL


@pytest.mark.parametrize("gravity", GRAVITIES)
@pytest.mark.parametrize("n", [3, 4, 5])
def test_reversal_mirrors_the_forces(n, gravity):
    """Reading the chain from the other end: phi reversed, the same d, f_t and potential, normal
    forces and friction limits exchanged, x_c -> d - x_c; slip of foot 1 is slip of foot 2.  f_t is
    the force at foot 1 along the axis towards foot 2, so both the foot and the axis change: the
    force on the chain at each physical foot, along the first chain's +x, is unchanged."""
    rng = np.random.default_rng(10 + n)
    model = ChainModel(Chain.from_robot(ROBOTS[1]) if n == 3 else _random_chain(rng, n), gravity)
    back = ChainModel(model.chain.reversed(), gravity)
    phi = _chain_phis(model, rng, 40)
    a, b = model.kinematics(phi), back.kinematics(phi[::-1])
    L, Mg = model.chain.L, model.Mg
    pairs = [("d", "d", L), ("fn1", "fn2", Mg), ("fn2", "fn1", Mg), ("lim1", "lim2", Mg),
             ("U_el", "U_el", Mg * L), ("U_g", "U_g", Mg * L)]
    pairs += [(f"zj{j}", f"zj{n - j}", L) for j in range(1, n)]
    for mine, theirs, s in pairs:
        assert rel(b[theirs], a[mine], s) <= 1e-13, (mine, theirs)
    assert rel(b["xc"], a["d"] - a["xc"], L) <= 1e-13
    for i in range(1, n + 1):
        # link i is link n + 1 - i, run the other way (+pi) and seen with x' = -x (alpha -> pi -
        # alpha): alpha' = -alpha
        turn = np.angle(np.exp(1j * (b[f"alpha{n + 1 - i}"] + a[f"alpha{i}"])))
        assert np.max(np.abs(turn)) <= 1e-13
    for kind, arg in MODES:
        phi0 = phi[:, 0]
        kin = model.kinematics(phi0)
        if kind == "stick":
            ft, q, q_back = 0.2 * min(kin["lim1"], kin["lim2"]), stick_mode(kin["d"]), None
        else:
            ft = arg[1] * kin[f"lim{arg[0]}"]
            q, q_back = slip_mode(*arg), slip_mode(3 - arg[0], arg[1])
        tau = model.hold_torque(phi0, ft)
        x0 = np.r_[phi0 + rng.uniform(-0.02, 0.02, n - 1), ft / Mg]
        sol = model.solve(x0, tau, q)
        sol_back = back.solve(np.r_[x0[:-1][::-1], x0[-1]], tau[::-1],
                              q if q_back is None else q_back)
        assert sol.converged and sol_back.converged
        assert rel(sol_back.x[:-1][::-1], sol.x[:-1], 1.0) <= 1e-12
        # world-frame force at foot 1 (+f_t along +x) is the reversed chain's foot 2 force -f_t'
        # along x' = -x: f_t' = f_t
        assert rel(sol_back.aux["ft"], sol.aux["ft"], Mg) <= 1e-12


# -------------------------------------------------------------------------------- stiff joint
def _split_body(robot: Robot, K: float) -> Chain:
    """The robot's body split in the middle by a straight joint of stiffness K [N m/rad]."""
    l, m, b = robot.l, robot.m, robot.beta
    return Chain(lengths=(l, b * l / 2, b * l / 2, l), masses=(m, b * m / 2, b * m / 2, m),
                 stiffness=(robot.k, K, robot.k), mu=(robot.mu1, robot.mu2), g=robot.g)


def _split_all(robot: Robot, K: float) -> Chain:
    """Every link of the robot split in the middle by a straight joint of stiffness K [N m/rad]:
    six links, the robot's joints are joints 2 and 4 (1-based)."""
    l, m, b = robot.l, robot.m, robot.beta
    halves = [(l / 2, m / 2)] * 2 + [(b * l / 2, b * m / 2)] * 2 + [(l / 2, m / 2)] * 2
    return Chain(lengths=[h[0] for h in halves], masses=[h[1] for h in halves],
                 stiffness=(K, robot.k, K, robot.k, K), mu=(robot.mu1, robot.mu2), g=robot.g)


#: split chains: builder, indices of the robot's two joints, indices of the stiff joints
SPLITS = {"body": (_split_body, (0, 2), (1,)), "all": (_split_all, (1, 3), (0, 2, 4))}


@pytest.mark.parametrize("split", sorted(SPLITS))
@pytest.mark.parametrize("gravity", GRAVITIES)
def test_stiff_straight_joints_approach_three_link(gravity, split):
    """A chain with stiff straight joints inserted (one in the middle of the body: four links; one
    in the middle of every link: six links) tends to the three-link model as the joint stiffness K
    grows, with an error K times smaller per decade of K: the difference is O(1/K)."""
    build, robot_joints, stiff_joints = SPLITS[split]
    robot = Robot.paper(mu1=0.35, mu2=0.45)
    model = Model(robot, gravity)
    MgL, Mg = robot.MgL, robot.M * robot.g
    rng = np.random.default_rng(6)
    for phi in _phis(model, rng, 2).T:
        for kind, arg in MODES:
            tau, x_star, q = _equilibrium(model, phi, kind, arg)
            x_star = _existing_solve(model, x_star, tau, q)
            ref = model.kinematics(x_star[:2])
            errs = []
            for K in (1e2 * MgL, 1e3 * MgL, 1e4 * MgL, 1e5 * MgL):
                chain = ChainModel(build(robot, K), gravity)
                x0, tau_n = np.full(chain.chain.n, math.pi), np.zeros(chain.chain.n_joints)
                x0[list(robot_joints)], x0[-1] = x_star[:2], x_star[2]
                tau_n[list(robot_joints)] = tau
                sol = chain.solve(x0, tau_n, q)
                assert sol.converged
                errs.append(max(np.max(np.abs(sol.x[list(robot_joints)] - x_star[:2])),
                                abs(sol.x[-1] - x_star[2]),
                                np.max(np.abs(sol.x[list(stiff_joints)] - math.pi)),
                                abs(sol.aux["fn1"] - ref["fn1"]) / Mg))
            errs = np.array(errs)
            assert errs[-1] < 1e-4
            # O(1/K): each decade of K divides the error by 10 (within 2 %)
            np.testing.assert_allclose(errs[:-1] / errs[1:], 10.0, rtol=0.02)


# -------------------------------------------------------------------------------- scaling
@pytest.mark.parametrize("gravity", GRAVITIES)
def test_scaling_invariance(gravity):
    """Lengths x a, masses x b, stiffness x a b: the same equilibrium angles, forces x b, torques
    and energies x a b; for n = 3 the scaled chain is the three-link model of the scaled robot."""
    a, b = 2.7, 0.31
    robot = ROBOTS[2]
    scaled_robot = robot.replace(M=robot.M * b, L=robot.L * a, k=robot.k * a * b)
    ref = Model(scaled_robot, gravity)
    chain3 = ChainModel(Chain.from_robot(robot).scaled(a, b), gravity)
    rng = np.random.default_rng(8)
    phi = _phis(ref, rng, 50)
    k_ref, k3 = ref.kinematics(phi), chain3.kinematics(phi)
    for name, s in (("d", scaled_robot.L), ("fn1", ref.robot.M * ref.robot.g), ("U_g", 1e-30)):
        assert rel(k3[name], k_ref[name], s) <= RTOL
    for n in (3, 4, 5):
        base = ChainModel(Chain.from_robot(robot) if n == 3 else _random_chain(rng, n), gravity)
        big = ChainModel(base.chain.scaled(a, b), gravity)
        phi = _chain_phis(base, rng, 3)
        for kind, arg in MODES:
            kin = base.kinematics(phi[:, 0])
            ft = (0.2 * min(kin["lim1"], kin["lim2"]) if kind == "stick"
                  else arg[1] * kin[f"lim{arg[0]}"])
            q = stick_mode(kin["d"]) if kind == "stick" else slip_mode(*arg)
            tau = base.hold_torque(phi[:, 0], ft)
            x0 = np.r_[phi[:, 0] + 0.01, ft / base.Mg]
            s0 = base.solve(x0, tau, q)
            s1 = big.solve(x0, tau * a * b, q * np.array([1, 1, 1, a]))
            assert s0.converged and s1.converged
            assert rel(s1.x, s0.x, 1.0) <= 1e-12
            for name in ("ft", "fn1", "fn2"):
                assert rel(s1.aux[name], b * s0.aux[name], b * base.Mg) <= 1e-12
            assert rel(big.potential(s1.x[:-1]), a * b * base.potential(s0.x[:-1]),
                       a * b * base.Mg * base.chain.L) <= 1e-12


# -------------------------------------------------------------------------------- stability
def _stability_states(model: Model, rng, count: int):
    """(x (3, N), q (4, N)): random configurations with tangential forces within +-0.6 M g in
    every mode of MODES, and the modes' vectors (d0 of stick-stick: the configuration's d)."""
    phi = _phis(model, rng, count)
    d = model.kinematics(phi)["d"]
    xs, qs = [], []
    for j in range(count):
        kind, arg = MODES[j % len(MODES)]
        xs.append(np.r_[phi[:, j], rng.uniform(-0.6, 0.6)])
        qs.append(_mode_vector(kind, arg, d[j]))
    return np.array(xs).T, np.array(qs).T


@pytest.mark.parametrize("gravity", GRAVITIES)
@pytest.mark.parametrize("robot", ROBOTS, ids=ROBOT_IDS)
def test_stability_equals_three_link(robot, gravity):
    """margin, kappa, tr K and det K of chain_stability equal those of model.stability at random
    states of every mode; the SI stiffnesses equal reduced_stiffness and slip_stiffness."""
    from ocp_crawl.model import chain_stability as cst
    from ocp_crawl.model import stability as st

    model, chain = Model(robot, gravity), ChainModel(Chain.from_robot(robot), gravity)
    rng = np.random.default_rng(20)
    X, Q = _stability_states(model, rng, 40)
    got = cst.chain_stability_numbers(chain, X, Q)
    for j in range(X.shape[1]):
        ref = st.stability(model, X[:, j], Q[:, j])
        # each number relative to the size of K/(M g L) (tr K) or its square (det K)
        size = abs(ref["trK"]) + abs(ref["kappa"])
        for name, s in (("margin", size), ("kappa", size), ("trK", size), ("detK", size**2)):
            assert rel(got[name][j], ref[name], s) <= RTOL, (j, name)
    assert rel(cst.chain_stability_margins(chain, X, Q), st.stability_margins(model, X, Q),
               np.max(np.abs(got["trK"]))) <= RTOL
    MgL = robot.MgL
    for j in range(5):
        phi, ft = X[:2, j], X[2, j] * robot.M * robot.g
        assert rel(cst.reduced_stiffness(chain, phi, ft), st.reduced_stiffness(model, phi, ft),
                   MgL) <= RTOL
        for sigma, w in ((1, 1), (-1, 0)):
            assert rel(cst.slip_stiffness(chain, phi, sigma, w),
                       st.slip_stiffness(model, phi, sigma, w), MgL) <= RTOL


@pytest.mark.parametrize("n", [4, 5, 7])
def test_compiled_margins_equal_the_minor_sums(n):
    """The steppers' margins (the compiled chain_margin_function: a projected Hessian's smallest
    eigenvalue, the Faddeev-LeVerrier coefficients and the Routh recursion) equal those of
    chain_stability_numbers (an orthonormal tangent basis, sums of principal minors and Hurwitz
    determinants by LAPACK) on random states of soft random chains, sign for sign, in every mode;
    to 1e-11 for n = 4 and 5.  (At n = 7 a slip margin is the quotient of Hurwitz minors that
    nearly cancel, e.g. -119.3 from r_5 = -3.7e-9: the two ways of rounding differ there in the
    sixth digit, so only the signs are compared.)"""
    import dataclasses

    from ocp_crawl.model.chain_stability import chain_stability_margins, chain_stability_numbers

    rng = np.random.default_rng(23 + n)
    chain = _random_chain(rng, n)
    # (joints 50 times softer than _random_chain's: gravity makes many of the states unstable)
    soft = tuple(0.02 * np.array(chain.stiffness))
    model = ChainModel(dataclasses.replace(chain, stiffness=soft))
    phi = rng.uniform(1.0, 3.0, (n - 1, 60))
    X = np.vstack([phi, rng.uniform(-3.0, 3.0, (1, 60))])
    d = model.kinematics(phi)["d"]
    for kind, arg in MODES:
        Q = np.array([stick_mode(dj) if kind == "stick" else slip_mode(*arg) for dj in d]).T
        ref = chain_stability_numbers(model, X, Q)
        got = chain_stability_margins(model, X, Q)
        stable = ref["margin"] > 0
        assert np.array_equal(got > 0, stable), kind
        assert 0 < np.mean(stable) < 0.9, kind   # (stable and unstable states both tested)
        if n < 7:
            assert rel(got, ref["margin"], np.max(np.abs(ref["trK"]))) <= 1e-11, kind


def test_routh_margin_is_the_eigenvalue_criterion():
    """routh_margin > 0 exactly when every eigenvalue has a positive real part (random matrices of
    2 to 6 rows, half of them shifted to be stable); for 2 x 2 it is min(tr, det/|tr|)."""
    from ocp_crawl.model.chain_stability import routh_margin

    rng = np.random.default_rng(21)
    for m in range(2, 7):
        K = rng.normal(size=(400, m, m)) + rng.uniform(0, 3, (400, 1, 1)) * np.eye(m)
        margin = routh_margin(K)
        stable = np.min(np.linalg.eigvals(K).real, axis=1) > 0
        assert 0.2 < stable.mean() < 0.95
        assert np.array_equal(margin > 0, stable), m
        if m == 2:
            tr, det = np.trace(K, axis1=1, axis2=2), np.linalg.det(K)
            assert rel(margin, np.minimum(tr, det / np.abs(tr)), 1.0) <= 1e-12


def _jacobian_relations(model: ChainModel, x, q) -> tuple[float, float]:
    """(det J of the mode equations, the same from the stiffness): stick-stick
    (-1)^(m-1) |grad d|^2 det K_red / (L^2 (M g L)^(m-1)), slip (-1)^m det K / (M g L)^m."""
    from ocp_crawl.model.chain_stability import reduced_stiffness_matrix, slip_stiffness

    m, L, MgL = model.chain.n_joints, model.chain.L, model.chain.MgL
    phi = x[:m]
    det_j = np.linalg.det(model.mode_system(x, np.zeros(m), q)[1])
    if q[0] == 1:
        g = np.array([model.kinematics(phi)[f"grad_d{j}"] for j in range(1, m + 1)])
        red = reduced_stiffness_matrix(model, phi, x[m] * model.Mg)
        return det_j, (-1) ** (m - 1) * (g @ g) * np.linalg.det(red) / (L**2 * MgL ** (m - 1))
    return det_j, (-1) ** m * np.linalg.det(slip_stiffness(model, phi, q[1], q[2])) / MgL**m


@pytest.mark.parametrize("gravity", GRAVITIES)
@pytest.mark.parametrize("n", [4, 5])
def test_reduced_stiffness_is_the_curvature_on_the_manifold(n, gravity):
    """For n links: det J of the mode equations (CasADi's Jacobian) follows from K_red and K
    (module doc of chain_stability); at a stick-stick equilibrium the second derivative of
    Pi_tau along a curve on {d = d0} through it, by central differences, is v^T K_red v; the
    smallest eigenvalue is the minimum of these quadratic forms."""
    from ocp_crawl.model.chain_stability import reduced_stiffness, reduced_stiffness_matrix
    from ocp_crawl.model.chain_stability import tangent_basis

    rng = np.random.default_rng(30 + n)
    model = ChainModel(_random_chain(rng, n), gravity)
    m, Mg = n - 1, model.Mg
    for phi in _chain_phis(model, rng, 2).T:
        kin = model.kinematics(phi)
        for kind, arg in MODES:
            x = np.r_[phi, rng.uniform(-0.5, 0.5) if kind == "stick" else
                      arg[1] * kin[f"lim{arg[0]}"] / Mg]
            det_j, det_k = _jacobian_relations(model, x, _mode_vector(kind, arg, kin["d"]))
            assert abs(det_j - det_k) <= 1e-10 * abs(det_j), (kind, arg)
        ft = 0.3 * min(kin["lim1"], kin["lim2"])
        tau = model.hold_torque(phi, ft)
        grad = np.array([kin[f"grad_d{j}"] for j in range(1, n)])
        Z = tangent_basis(grad[None])[0]
        red = reduced_stiffness_matrix(model, phi, ft)
        for _ in range(3):
            v = Z @ rng.normal(size=m - 1)
            v /= np.linalg.norm(v)
            s = 2e-4

            def on_manifold(step):
                p = phi + step * v
                for _ in range(30):  # back onto d = d0 along grad d
                    k = model.kinematics(p)
                    g = np.array([k[f"grad_d{j}"] for j in range(1, n)])
                    p = p - (k["d"] - kin["d"]) / (g @ g) * g
                return model.potential(p) - tau @ p

            curv = (on_manifold(s) - 2 * on_manifold(0.0) + on_manifold(-s)) / s**2
            w = Z.T @ v
            assert abs(curv - w @ red @ w) <= 1e-4 * model.chain.MgL
            assert reduced_stiffness(model, phi, ft) <= w @ red @ w + 1e-12 * model.chain.MgL


@pytest.mark.parametrize("gravity", GRAVITIES)
def test_stiff_straight_joint_stability_approaches_three_link(gravity):
    """The body split by a straight joint of stiffness K (four links), held straight: the margin,
    kappa and the two finite eigenvalues of the slip stiffness tend to the three-link values as K
    grows, the difference O(1/K)."""
    from ocp_crawl.model import stability as st
    from ocp_crawl.model.chain_stability import chain_stability, slip_stiffness

    robot = Robot.paper(mu1=0.35, mu2=0.45)
    model = Model(robot, gravity)
    rng = np.random.default_rng(22)
    MgL = robot.MgL
    for phi in _phis(model, rng, 2).T:
        for kind, arg in MODES:
            _, x, q = _equilibrium(model, phi, kind, arg)
            ref = st.stability(model, x, q)
            eig3 = np.sort_complex(np.linalg.eigvals(st.slip_stiffness(model, phi, q[1], q[2])))
            errs = []
            for K in (1e2 * MgL, 1e3 * MgL, 1e4 * MgL):
                four = ChainModel(_split_body(robot, K), gravity)
                x4 = np.r_[x[0], math.pi, x[1:]]
                got = chain_stability(four, x4, q)
                eig4 = np.linalg.eigvals(slip_stiffness(four, x4[:3], q[1], q[2]))
                eig4 = np.sort_complex(eig4[np.argsort(np.abs(eig4))[:2]])
                errs.append(max(abs(got["margin"] - ref["margin"]),
                                abs(got["kappa"] - ref["kappa"]),
                                np.max(np.abs(eig4 - eig3)) / MgL))
            errs = np.array(errs)
            assert errs[-1] < 1e-3 * (abs(ref["trK"]) + 1)
            assert np.all(errs[1:] < 0.2 * errs[:-1]), (kind, arg, errs)
