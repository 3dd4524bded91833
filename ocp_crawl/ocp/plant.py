"""The robot as the periodic-gait OCP sees it: the three-link robot or an n-link chain, in one
friction scenario (:class:`Plant`).

The transcription needs of a robot only its sizes (the m joints, M, g, L, the friction
coefficients), its stiffness and rest bend per joint (the envelope and the bandwidth act on the
reference angles phi_ref = pi + rest + tau/k), the parameter vector and the step equations of its
model, and its event-driven torque simulation (the guess and the replay judge).  The three-link
robot and the chain give the same numbers where they describe the same robot (the chain of
:meth:`~ocp_crawl.model.chain.Chain.from_robot`): a chain's step variables are laid out as the
three-link robot's for m = 2 (:class:`~ocp_crawl.model.step_equations.StepRows`).
"""
from __future__ import annotations

import math
from functools import cached_property
from typing import Union

import casadi as cs
import numpy as np

from ocp_crawl.model.chain import Chain
from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.model.statics import GravityConvention, Model, Robot

#: a robot the OCP takes: the symmetric three-link robot or a planar chain of n links
AnyRobot = Union[Robot, Chain]


def joints_of(robot: AnyRobot) -> int:
    """The number m of actuated joints of ``robot`` (2 for the three-link robot)."""
    return robot.n_joints if isinstance(robot, Chain) else 2


def stiffness_of(robot: AnyRobot) -> np.ndarray:
    """The joint stiffnesses (m,) [N m/rad]."""
    if isinstance(robot, Chain):
        return np.asarray(robot.stiffness, float)
    return np.full(2, robot.k)


def rest_of(robot: AnyRobot) -> np.ndarray:
    """The springs' rest bends from straight (m,) [rad] (0 for the three-link robot)."""
    if isinstance(robot, Chain):
        return np.asarray(robot.rest, float)
    return np.zeros(2)


def with_friction(robot: AnyRobot, mu1: float, mu2: float) -> AnyRobot:
    """``robot`` with the friction coefficients (mu1, mu2) [-]."""
    if isinstance(robot, Chain):
        return robot.replace(mu=(mu1, mu2))
    return robot.replace(mu1=mu1, mu2=mu2)


def envelope_centres(settings, robot: AnyRobot) -> np.ndarray:
    """The envelope's centre of each joint (m,) [rad]: ``settings.gamma_joints_deg`` (a chain's,
    one per joint), else gamma_deg for every joint."""
    m = joints_of(robot)
    g = settings.gamma_joints_deg
    if g is None:
        return np.full(m, math.radians(settings.gamma_deg))
    if not isinstance(robot, Chain):
        raise ValueError("OCPSettings.gamma_joints_deg is a chain's: the three-link robot's "
                         "envelope is centred on gamma_deg")
    if len(g) != m:
        raise ValueError(f"OCPSettings.gamma_joints_deg has {len(g)} angles for a robot of {m} "
                         "joints")
    return np.radians(np.asarray(g, float))


def envelope_offsets(settings, robot: AnyRobot) -> tuple[np.ndarray, np.ndarray]:
    """The range of tau/k of each joint (m,), (m,) [rad] that keeps its reference angle
    phi_ref = pi + rest + tau/k inside the envelope centre +- A_max (``settings``: an
    :class:`~ocp_crawl.ocp.settings.OCPSettings`)."""
    a = math.radians(settings.A_max_deg)
    g, rest = envelope_centres(settings, robot), rest_of(robot)
    return g - a - math.pi - rest, g + a - math.pi - rest


def joint_torque_bounds(settings, robot: AnyRobot) -> tuple[np.ndarray, np.ndarray]:
    """The torque range of each joint (m,), (m,) [N m]: its stiffness times
    :func:`envelope_offsets`."""
    k = stiffness_of(robot)
    lo, hi = envelope_offsets(settings, robot)
    return k * lo, k * hi


def joint_rate_bounds(settings, robot: AnyRobot) -> np.ndarray:
    """The largest torque rate of each joint (m,) [N m/s]: its stiffness times the bandwidth
    max_rate_deg_s."""
    return stiffness_of(robot) * math.radians(settings.max_rate_deg_s)


def joint_accel_bounds(settings, robot: AnyRobot) -> np.ndarray | None:
    """The largest torque acceleration of each joint (m,) [N m/s^2], or None (no bound)."""
    if settings.max_accel_deg_s2 is None:
        return None
    return stiffness_of(robot) * math.radians(settings.max_accel_deg_s2)


class Plant:
    """One robot in one friction scenario, as the transcription, its guess and the judge use it.

    Parameters
    ----------
    robot : Robot or Chain
        The robot (SI units).
    gravity : str
        The gravity convention ("physical" or "paper").
    model : Model or ChainModel, optional
        The robot's statics, when built already (None: built here).
    """

    def __init__(self, robot: AnyRobot, gravity: GravityConvention = "physical",
                 model: Model | ChainModel | None = None):
        if not isinstance(robot, (Robot, Chain)):
            raise TypeError(f"Plant: robot must be a Robot or a Chain, got {type(robot).__name__}")
        self.robot = robot
        self.gravity = gravity
        self.chain = isinstance(robot, Chain)
        if model is None:
            model = (ChainModel(robot, gravity=gravity) if isinstance(robot, Chain)
                     else Model(robot, gravity=gravity))
        self.model: Model | ChainModel = model
        """the robot's statics (a :class:`Model` or a :class:`ChainModel`)"""

    @property
    def n_joints(self) -> int:
        """number of actuated joints m"""
        return joints_of(self.robot)

    @property
    def MgL(self) -> float:
        """the torque scale M g L [N m]"""
        r = self.robot
        return r.M * r.g * r.L

    @property
    def k(self) -> np.ndarray:
        """joint stiffnesses (m,) [N m/rad]"""
        return stiffness_of(self.robot)

    @property
    def p(self) -> np.ndarray:
        """the model's parameter vector (the step function's last input)"""
        return np.asarray(self.model.p, float)

    @cached_property
    def step_function(self) -> cs.Function:
        """One step's (equations and lifting, complementarity products) of
        (phi_prev [m], w [m + 10], tau_hat [m], p) (SX; the three-link robot's is
        :func:`~ocp_crawl.ocp.substeps.step_function`)."""
        if not self.chain:
            from ocp_crawl.ocp.substeps import step_function
            return step_function()
        from ocp_crawl.sim.chain_mpcc import chain_step_nlp
        assert isinstance(self.robot, Chain)
        n, m = self.robot.n, self.n_joints
        step = chain_step_nlp(n)
        phi_prev, w = cs.SX.sym("phi_prev", m), cs.SX.sym("w", m + 10)
        th, p = cs.SX.sym("tau_hat", m), cs.SX.sym("p", self.p.size)
        g_eq, g_lift, sv, cv = step(w, cs.vertcat(phi_prev, th, p))
        return cs.Function(f"ocp_chain{n}_step", [phi_prev, w, th, p],
                           [cs.vertcat(g_eq, g_lift), sv * cv])

    @property
    def phi_max(self) -> float:
        """The largest joint angle of the transcription [rad]: pi for the three-link robot (its
        joints above the line of its feet), 2 pi for a chain, whose joint heights are rows of their
        own (:attr:`height_function`)."""
        return 2.0 * math.pi if self.chain else math.pi

    @cached_property
    def height_function(self) -> cs.Function | None:
        """A chain's joint heights over L (m,) of (phi [m], p) (SX), which the transcription keeps
        >= 0 at every sub-step end; None for the three-link robot."""
        if not self.chain:
            return None
        from ocp_crawl.model.chain_statics import chain_symbolic, kin_names

        assert isinstance(self.robot, Chain)
        n, m = self.robot.n, self.n_joints
        rows = {k: i for i, k in enumerate(kin_names(n))}
        phi, p = cs.SX.sym("phi", m), cs.SX.sym("p", self.p.size)
        kin = chain_symbolic(n).kin(phi, p)
        L = sum(p[i] for i in range(n))
        z = cs.vertcat(*[kin[rows[f"zj{j}"]] for j in range(1, n)]) / L
        return cs.Function(f"ocp_chain{n}_heights", [phi, p], [z])

    @cached_property
    def stability_function(self) -> cs.Function:
        """A chain's stick-stick stability rows (m,) of (phi [m], f_t / (M g), p, kappa_min) (SX):
        the leading principal minors of ``A = P H P / (M g L) + (1 + kappa_min) u u^T -
        kappa_min I``, with ``H`` the symmetric part of hess Pi + f_t hess d, ``u`` the unit
        gradient of the feet distance d and ``P = I - u u^T``
        (:mod:`~ocp_crawl.model.chain_stability`).  A's eigenvalues are those of the reduced
        stiffness K_red over M g L less kappa_min, and 1 (along u): every row >= 0 (Sylvester's
        criterion, exact where the lower minors are > 0; a lower minor at exactly 0 is a
        degenerate boundary) holds the equilibrium at least kappa_min M g L stiff along the
        stick-stick manifold, away from a fold.  The rows hold at every sub-step end, slipping
        ones too: a foot that stops slipping there sticks into that equilibrium.  The three-link
        robot has none (a ValueError)."""
        if not self.chain:
            raise ValueError("Plant.stability_function: a chain's (Chain.from_robot gives the "
                             "three-link robot as one)")
        from ocp_crawl.model.chain_stability import chain_stiffness_function
        from ocp_crawl.model.chain_statics import chain_params

        assert isinstance(self.robot, Chain)
        n, m = self.robot.n, self.n_joints
        phi, ft, p = cs.SX.sym("phi", m), cs.SX.sym("ft_hat"), cs.SX.sym("p", self.p.size)
        kappa_min = cs.SX.sym("kappa_min")
        par = chain_params(p, n)
        Mg = sum(par.masses) * par.g
        MgL = Mg * sum(par.lengths)
        s = chain_stiffness_function(n)(phi, ft * Mg, cs.DM.zeros(4), p)
        grad = s[:m]
        H = cs.reshape(s[m:m + m * m], m, m)
        u = grad / cs.norm_2(grad)
        P = cs.SX.eye(m) - u @ u.T
        A = (P @ (0.5 * (H + H.T)) @ P / MgL + (1.0 + kappa_min) * (u @ u.T)
             - kappa_min * cs.SX.eye(m))
        minors = cs.vertcat(*[cs.det(A[:k, :k]) for k in range(1, m + 1)])
        return cs.Function(f"ocp_chain{n}_stability", [phi, ft, p, kappa_min], [minors])

    def simulate(self, torque, t_eval=None):
        """The event-driven torque simulation of ``torque`` (a 1-periodic signal of the phase with
        m rows [N m]) on the output phases ``t_eval`` [cycles] (None: the simulator's default):
        :func:`~ocp_crawl.sim.event.simulate_torque` or, for a chain,
        :func:`~ocp_crawl.sim.chain_torque.simulate_chain_torque`; a CrawlResult."""
        if self.chain:
            from ocp_crawl.sim.chain_torque import simulate_chain_torque
            return simulate_chain_torque(self.model, torque, t_eval=t_eval)
        from ocp_crawl.sim.event import simulate_torque
        return simulate_torque(self.model, torque, t_eval=t_eval)


def as_plant(model: Plant | Model | ChainModel) -> Plant:
    """``model`` as a :class:`Plant`: a Plant itself, or the Plant of a three-link :class:`Model`
    or of a :class:`ChainModel` (the model kept, not built again)."""
    if isinstance(model, Plant):
        return model
    if isinstance(model, ChainModel):
        return Plant(model.chain, model.gravity, model)
    if isinstance(model, Model):
        return Plant(model.robot, model.gravity, model)
    raise TypeError(f"as_plant: expected a Plant, Model or ChainModel, got {type(model).__name__}")
