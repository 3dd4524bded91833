"""Direct transcription of the periodic-gait OCP: the NLP's variables, constraints and objective,
the bounds of its relaxation and of its identified branches, its initial guess from simulations and
the residuals of a solution (its solve: :class:`~ocp_crawl.ocp.solver.GaitSolver`).

Time is explicit.  The period T [s] of the gait is a variable, scaled as ``T_hat = T / period_ref``
(:meth:`~ocp_crawl.ocp.settings.OCPSettings.period_ref`).  Node k sits at phase k/N (k = 0..N-1) and
carries the torques tau_k; between nodes the torque is linear in phase (the replay's own
interpolant).  The actuator bandwidth reads ``|tau_i,k - tau_i,k-1| <= k R T / N`` (R =
max_rate_deg_s), the optional smoothness bound ``|tau_i,k+1 - 2 tau_i,k + tau_i,k-1| <= k a
(T/N)^2``, the envelope ``phi_ref = pi + rest + tau/k`` within gamma +- A_max (each joint with its
own k, rest bend and centre: :mod:`~ocp_crawl.ocp.plant`), the phase pin ``tau_1,k <= tau_1,0`` and
``T <= 2 period_ref`` (the resolution of the nodes: :data:`PERIOD_HAT_BOUNDS`).  Each interval is
two switch-exact sub-steps (:mod:`ocp_crawl.ocp.substeps`, with the optional bound
max_joint_rate_deg_s on the mean joint rates); periodicity (angles and tangential force) is a
constraint and the body displacement over the cycle is S = sum of the slips of foot 1.

Objectives (to minimise; v = direction S / T the mean speed): max_speed ``-v``; min_cot
``CoT+ = W+/(M g |S|)`` with ``v >= speed_min``; every objective with the bounds of ``constraints``
on cycle quantities (:mod:`ocp_crawl.ocp.quantities`).  Over a set of friction scenarios (one
profile and one T; robust_speed is max_speed over a set) ``-mean_j v_j`` or ``-min_j v_j``,
``mean_j CoT+_j`` or ``max_j CoT+_j`` with ``v_j >= speed_min`` in each.  Each adds
``regularization * (N sum |dtau|^2/(M g L)^2) / T_hat^2`` (the mean squared torque rate, a
tie-breaker) and ``regularization * sum (theta - 1/2)^2 / N`` (interior points without an event are
otherwise free); both are invariant under repeating the profile k times with T multiplied by k, as
the objectives are.  Scholtes' relaxation (s c <= sigma and the cross conditions <= sigma,
:meth:`GaitOCP.relaxed_ubg`) is driven to sigma_min by the solver, then polished on the identified
branches (:meth:`GaitOCP.branch_ubx`).
"""
from __future__ import annotations

from typing import Any

import casadi as cs
import numpy as np

from ocp_crawl.model.chain import Chain
from ocp_crawl.model.statics import GravityConvention
from ocp_crawl.model.step_equations import StepRows
from ocp_crawl.nlp.codegen import compiled_kernel
from ocp_crawl.ocp.guess import simulated_guess
from ocp_crawl.ocp.layout import KINDS, Layout, fourier_basis, rows_of
from ocp_crawl.ocp.design import Design
from ocp_crawl.ocp.plant import (AnyRobot, Plant, envelope_offsets, joint_accel_bounds,
                                 joint_rate_bounds, joint_torque_bounds, joints_of, stiffness_of)
from ocp_crawl.ocp.quantities import Symbols, constraint_rows, needs_work, physical
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.substeps import (Scenario, cross_residual, modes_of, onset_residual,
                                    positive_work, substep_torques, switch_windows)

#: bounds of the scaled period variable T_hat = T / period_ref.  The upper bound is the
#: transcription's resolution: a node may move a reference angle by up to R T / N, so at T = 2
#: period_ref = 4 pi A_max / R a cycle holds about three full strokes of the envelope (down and up
#: at the bandwidth, 4 A_max / R each).  By time-scale invariance it excludes no gait, only packed
#: copies of one, whose coarse sub-steps the relaxed problem exploited (robust_speed, N = 50,
#: unbounded: T grew to 4.2 s and the relaxed speed to 1.7 times the true optimum in 6000
#: iterations)
PERIOD_HAT_BOUNDS = (1e-3, 2.0)
#: how the NLP evaluates the sub-step kernel (see :class:`GaitOCP`)
KERNELS = ("expanded", "compiled")


class GaitOCP:
    """The periodic-gait NLP of one robot, gravity convention and settings, built once."""

    def __init__(self, robot: AnyRobot, gravity: GravityConvention = "physical",
                 settings: OCPSettings | None = None, kernel: str = "expanded",
                 design: Design | None = None, rate_weights=None,
                 stability: float | None = None):
        """``robot``: the three-link :class:`~ocp_crawl.model.robot.Robot` or an n-link
        :class:`~ocp_crawl.model.chain.Chain` (m = n - 1 torque profiles).  ``kernel``: how the NLP
        evaluates the sub-steps' equations: "expanded" (default) the whole NLP as one SX graph (the
        kernel inlined at every sub-step; its Hessian 8x faster than the map of the compiled kernel
        at N = 100), or "compiled" the compiled step kernel
        (:func:`~ocp_crawl.nlp.codegen.compiled_kernel`) mapped over the sub-steps in an MX graph
        (``scripts/bench.py ocp_kernel`` compares the two).  ``design``: robot parameters the NLP
        chooses too (a chain's; :mod:`~ocp_crawl.ocp.design`), its block ``design`` of variables
        scaled by the robot's values (:meth:`design_values` reads them); the regularisation then
        weighs each joint's torque rate by k_j / k_j(design), the rate of its reference angle in
        the robot's torque units (a tie-breaker that does not favour soft joints).
        ``rate_weights``: those weights (m,) of a fixed robot [-] (None: 1; a chosen design's NLP
        as the co-design NLP states it, k_start / k_chosen).  ``stability``: a chain's
        stick-stick reduced stiffness at every sub-step end at least this times M g L [-] (None:
        no such rows; :attr:`~ocp_crawl.ocp.plant.Plant.stability_function`)."""
        if kernel not in KERNELS:
            raise ValueError(f"GaitOCP: kernel must be one of {KERNELS}, got {kernel!r}")
        self.design: Design | None = None
        """the robot parameters the NLP chooses too (:class:`~ocp_crawl.ocp.design.Design`), or
        None"""
        if design is not None:
            if not isinstance(robot, Chain):
                raise ValueError("GaitOCP: a design is a chain's (Chain.from_robot gives the "
                                 "three-link robot as one)")
            self.design = design.checked(robot)
        self._rate_weights = None if rate_weights is None else np.asarray(rate_weights, float)
        if stability is not None and not isinstance(robot, Chain):
            raise ValueError("GaitOCP: stability rows are a chain's (Chain.from_robot gives the "
                             "three-link robot as one)")
        self.stability = stability
        """the smallest stick-stick reduced stiffness over M g L at every sub-step end, or None"""
        self.kernel = kernel
        self.robot = robot
        self.gravity = gravity
        self.settings = settings or OCPSettings()
        self.n_joints = joints_of(robot)
        """the number of torque profiles (the robot's joints)"""
        self.scen = [Plant(r, gravity) for r in self.settings.scenarios(robot)]
        """each friction scenario's :class:`~ocp_crawl.ocp.plant.Plant`"""
        self._build()

    # ------------------------------------------------------------------ the NLP (built once)
    def _torque_nodes(self, z_tau, N):
        """Scaled torques at the N node phases as expressions of the torque variables."""
        s, m = self.settings, self.n_joints
        if s.parametrization == "free":
            return cs.reshape(z_tau, m, N)
        return cs.reshape(z_tau, m,
                          2 * s.fourier_order + 1) @ cs.DM(fourier_basis(N, s.fourier_order))

    def _torques(self, nlp: Layout, MgL: float, k=None):
        """Torque and period variables, envelope, bandwidth, optional smoothness bound and phase
        pin; returns the scaled node torques T (m, N), their periodic differences dT and the scaled
        period Th.  Per joint: its envelope and bandwidth through its stiffness (and rest bend), the
        same numbers on every node (column-major as ``cs.vec``); ``k``: the stiffnesses (m,) as
        expressions of a design's variables (None: the robot's, the envelope as bounds of the
        variables)."""
        s, N, r, m = self.settings, self.settings.nodes, self.robot, self.n_joints
        ntau = m * N if s.parametrization == "free" else m * (2 * s.fourier_order + 1)
        z_tau = nlp.sym("tau", ntau)
        T = self._torque_nodes(z_tau, N)  # (m, N) scaled
        if k is not None:  # the envelope as rows linear in tau and k
            nlp.var("tau", z_tau, -np.inf, np.inf)
            lo, hi = (cs.repmat(k * cs.DM(b) / MgL, N, 1) for b in envelope_offsets(s, r))
            nlp.con("tau_low", cs.vec(T) - lo, 0.0, np.inf)
            nlp.con("tau_high", hi - cs.vec(T), 0.0, np.inf)
        else:
            tau_lo, tau_hi = (np.tile(b / MgL, N) for b in joint_torque_bounds(s, r))
            free = s.parametrization == "free"
            nlp.var("tau", z_tau, *((tau_lo, tau_hi) if free else (-np.inf, np.inf)))
            if not free:
                nlp.con("tau_bounds", cs.vec(T), tau_lo, tau_hi)
        Th = nlp.sym("T_hat")
        nlp.var("T_hat", Th, *PERIOD_HAT_BOUNDS)
        Tref = s.period_ref()
        dT = T - cs.horzcat(T[:, -1], T[:, :-1])  # periodic differences tau_k - tau_{k-1}
        # |dT| <= c_rate T_hat
        c_rate = (np.tile(joint_rate_bounds(s, r) * Tref / (MgL * N), N) if k is None else
                  cs.repmat(k * (np.radians(s.max_rate_deg_s) * Tref / (MgL * N)), N, 1))
        nlp.con("rate_up", cs.vec(dT) - c_rate * Th, -np.inf, 0.0)
        nlp.con("rate_down", cs.vec(dT) + c_rate * Th, 0.0, np.inf)
        accel = joint_accel_bounds(s, r)
        if accel is not None and s.max_accel_deg_s2 is not None:
            c_acc = (np.tile(accel * Tref**2 / (MgL * N**2), N) if k is None else
                     cs.repmat(k * (np.radians(s.max_accel_deg_s2) * Tref**2 / (MgL * N**2)),
                               N, 1))  # |d2T| <= c_acc T_hat^2
            d2T = cs.vec(cs.horzcat(dT[:, 1:], dT[:, 0]) - dT)  # periodic second differences
            nlp.con("accel_up", d2T - c_acc * Th**2, -np.inf, 0.0)
            nlp.con("accel_down", d2T + c_acc * Th**2, 0.0, np.inf)
        # node 0 is where tau_1 is largest
        nlp.con("phase_pin", cs.vec(T[0, 1:] - T[0, 0]), -np.inf, 0.0)
        return T, dT, Th

    def _design(self, nlp: Layout) -> tuple:
        """The design's scaled variables z (1 at the robot) and its fixed total length; returns
        the stiffnesses as expressions of z and each scenario's parameter vector (None, None
        without a design)."""
        d, r = self.design, self.robot
        if d is None:
            return None, [None] * len(self.scen)
        assert isinstance(r, Chain)
        scale = d.initial(r)
        lo, hi = d.limits()
        z = nlp.sym("design", scale.size)
        nlp.var("design", z, lo / scale, hi / scale)
        total = d.total_row(r, z)
        if total is not None:
            nlp.con("design_total", total, 0.0, 0.0, ("equation",))
        return d.stiffness_expr(r, z), [d.parameters(r, plant.p, z) for plant in self.scen]

    def _symbols(self, scen: list[Scenario], T, Th) -> Symbols:
        s, r = self.settings, self.robot
        return Symbols(T, Th, [sc.S for sc in scen], [sc.W_plus for sc in scen], r.M * r.g * r.L,
                       r.L, s.period_ref(), s.direction)

    def _requirements(self, nlp: Layout, sym: Symbols) -> None:
        """The rows of every bound on a cycle quantity (:attr:`OCPSettings.requirements`: min_cot's
        speed requirement, the ``constraints``), as
        :func:`~ocp_crawl.ocp.quantities.constraint_rows` states them."""
        for i, c in enumerate(self.settings.requirements):
            for k, (expr, lb, ub) in enumerate(constraint_rows(c, sym)):
                nlp.con(f"require_{i}_{k}", expr, lb, ub, ("requirement",))

    def _objective(self, nlp: Layout, scen: list[Scenario], T, dT, Th, weights=None):
        """The objective (to minimise) with the regularisation (``weights``: of each joint's
        torque rate, (m,) or None), and its extra constraints (the requirements first)."""
        s, inf, N = self.settings, np.inf, self.settings.nodes
        d = s.direction
        theta = cs.vertcat(*[sc.theta for sc in scen])
        rates = dT if weights is None else dT * cs.repmat(weights, 1, N)
        reg = s.regularization * (N * cs.sumsqr(rates) / Th**2 + cs.sumsqr(theta - 0.5)
                                  / (N * len(scen)))
        S_list = [sc.S for sc in scen]
        sym = self._symbols(scen, T, Th)
        self._requirements(nlp, sym)
        user = s.user_objective
        if user is not None:  # the user's expression in physical units, over its typical size
            f = user.nlp(physical(sym)) / user.scale
            return (f if user.sense == "min" else -f) + reg
        if s.objective == "min_cot":
            # CoT+ = W+ / (M g |S|) = (W_hat M g L) / (M g S_hat L) = W_hat / S_hat
            cots = [sc.W_plus / (d * Sj) for sc, Sj in zip(scen, S_list)]
            if len(cots) == 1 or s.robust == "mean":
                return sum(cots) / len(cots) + reg
            zeta = nlp.sym("zeta")  # the worst CoT+: W_hat_j <= zeta S_hat_j
            nlp.var("zeta", zeta, 0.0, inf)
            nlp.con("worst",
                    cs.vertcat(*[zeta * d * Sj - sc.W_plus for sc, Sj in zip(scen, S_list)]),
                    0.0, inf)
            return zeta + reg
        if len(S_list) == 1 or s.robust == "mean":
            return -d * sum(S_list) / (len(S_list) * Th) + reg
        zeta = nlp.sym("zeta")  # the worst scaled speed
        nlp.var("zeta", zeta, -inf, inf)
        nlp.con("worst", cs.vertcat(*[d * Sj - zeta * Th for Sj in S_list]), 0.0, inf)
        return -zeta + reg

    def _build(self) -> None:
        s, r = self.settings, self.robot
        MgL = r.M * r.g * r.L
        nlp = Layout(cs.SX.sym if self.kernel == "expanded" else cs.MX.sym)
        k, p_design = self._design(nlp)
        T, dT, Th = self._torques(nlp, MgL, k)
        step = self.scen[0].step_function
        kernel = step if self.kernel == "expanded" else compiled_kernel(step)
        step_map = kernel.map(2 * s.nodes)
        work = (s.objective == "min_cot" or needs_work(s.requirements)
                or (s.user_objective is not None and s.user_objective.work))
        scen = [Scenario(nlp, j, model, T, Th, step_map, s.nodes, work,
                         s.joint_rate_step(), p=p, stability=self.stability)
                for j, (model, p) in enumerate(zip(self.scen, p_design))]
        weights = (cs.DM(stiffness_of(r)) / k if k is not None
                   else None if self._rate_weights is None else cs.DM(self._rate_weights))
        f = self._objective(nlp, scen, T, dT, Th, weights)
        if s.perturbation == "always":  # in neither f nor g: IPOPT finds the Hessian degenerate
            nlp.var("free", nlp.sym("free"), -np.inf, np.inf)
        X = cs.vertcat(*[cs.vec(x) for x in nlp.xs])
        G = cs.vertcat(*nlp.g)
        self._slices = nlp.slices
        self.rows = {kind: rows_of(nlp.slices, nlp.kinds, kind) for kind in KINDS}
        """each kind of constraint (:data:`~ocp_crawl.ocp.layout.KINDS`): its slices of g"""
        self.nx, self.ng = X.numel(), G.numel()
        self.lbx, self.ubx = np.concatenate(nlp.lbx), np.concatenate(nlp.ubx)
        self.lbg, self.ubg = np.concatenate(nlp.lbg), np.concatenate(nlp.ubg)
        """the bounds of the variables and of the constraints, as built (relaxation:
        :meth:`relaxed_ubg`)"""
        self.nlp = {"x": X, "f": f, "g": G}
        """the optimiser's NLP (``casadi.nlpsol``'s input)"""
        self._T = cs.Function("T", [X], [T * MgL])
        self._g = cs.Function("g", [X], [G])
        self._f = cs.Function("f", [X], [f])
        # the profile-fixed check (GaitSolver.solve(fix_profile=True)) minimises only the distance
        # of the interior points from those of the start: no incentive to leave the physical
        # solution through the relaxation
        theta = cs.vertcat(*[sc.theta for sc in scen])
        theta_ref = nlp.sym("theta_ref", theta.numel())
        # ... and without the optimiser's own rules (friction tolerance, held ties, slip onsets on
        # sub-step boundaries) and the requirements: a profile given to be simulated need not meet
        # them (S does not depend on where a slip starts inside a sub-step; the onset rule is for
        # the optimiser's W+)
        keep = np.ones(self.ng, bool)
        for sl in self.rows["rule"] + self.rows["requirement"]:
            keep[sl] = False
        self.fixed_rows = np.flatnonzero(keep)
        """the constraints of the profile-fixed NLP: every row but the rules and the requirements"""
        self.fixed_nlp = {"x": X, "p": theta_ref, "f": cs.sumsqr(theta - theta_ref) / theta.numel(),
                          "g": G[self.fixed_rows.tolist()]}
        """the profile-fixed NLP (parameters: the interior points' reference)"""

    @property
    def slices(self) -> dict[str, slice]:
        """Each named block of the NLP's variables and constraints: its slice of x or of g."""
        return self._slices

    def export(self, sigma: float | None = None) -> dict:
        """The NLP for a solver of one's own: ``nlp`` (``casadi.nlpsol``'s ``{"x", "f", "g"}``) and
        the bounds ``lbx``, ``ubx``, ``lbg``, ``ubg`` of the relaxation at ``sigma`` (None:
        ``settings.sigma_min``); the blocks are :attr:`slices`, :meth:`initial_guess` gives a start,
        :meth:`unpack` reads a solution."""
        ubg = self.relaxed_ubg(self.settings.sigma_min if sigma is None else sigma)
        return {"nlp": dict(self.nlp), "lbx": self.lbx.copy(), "ubx": self.ubx.copy(),
                "lbg": self.lbg.copy(), "ubg": ubg}

    def relaxed_ubg(self, sigma: float, cross_sigma: float | None = None) -> np.ndarray:
        """The constraints' upper bounds of the relaxation at sigma: s_j c_j <= sigma, the cross
        products <= sigma (``cross_sigma`` if given)."""
        ubg = self.ubg.copy()
        for sl in self.rows["complementarity"]:
            ubg[sl] = sigma
        for sl in self.rows["cross"]:
            ubg[sl] = sigma if cross_sigma is None else cross_sigma
        return ubg

    def branch_ubx(self, x: np.ndarray, ubx: np.ndarray, ties: bool = True, onset: bool = True
                   ) -> np.ndarray:
        """The variables' upper bounds ``ubx`` with each pair on the branch x identifies (s_j = 0
        where s_j <= c_j, else c_j = 0), which removes the O(sqrt(sigma)) residual of biactive
        pairs; with ``onset`` likewise each onset pair (s_j = 0 where s_j <= c_j-1, else c_j-1 = 0:
        the slip starts on the boundary; the optimiser's NLP, not the profile-fixed one); with
        ``ties``, where the slipping foot changes between consecutive sub-steps, the new foot's
        margin in its slip direction fixed to 0 at the boundary (the tie)."""
        N = self.settings.nodes
        ubx = ubx.copy()
        R = StepRows(self.n_joints)
        for j in range(len(self.scen)):
            sl = self._slices[f"w_{j}"]
            W = x[sl].reshape(R.nw, 2 * N, order="F")
            slip = W[R.slips] > W[R.margins]
            fix = np.zeros((R.nw, 2 * N), bool)
            fix[R.slips] = ~slip
            fix[R.margins] = slip
            if onset:  # the onset pairs (s_j, c_j-1), each on its identified branch too
                early = W[R.slips] > np.roll(W[R.margins], 1, axis=1)
                fix[R.slips] |= ~early
                fix[R.margins] |= np.roll(early, -1, axis=1)
            ident = np.zeros((R.nw, 2 * N))
            ident[R.slips] = slip
            _, _, before, after = switch_windows(ident, x[self._slices[f"theta_{j}"]])
            for d in range(2 if ties else 0):
                # foot 1 -> foot 2: c2d = 0 at the boundary
                fix[R.c1p + 2 + d] |= (before[0] > 0) & (after[2 + d] > 0)
                # foot 2 -> foot 1: c1d = 0 at the boundary
                fix[R.c1p + d] |= (before[1] > 0) & (after[d] > 0)
            ub = ubx[sl].reshape(R.nw, 2 * N, order="F").copy()
            ub[fix] = 0.0
            ubx[sl] = ub.ravel(order="F")
        return ubx

    def objective(self, x: np.ndarray) -> float:
        """The NLP's objective (scaled, to minimise, with the regularisation) at the variables x."""
        return float(self._f(x))

    # ------------------------------------------------------------------ initial guess from
    # simulations
    def initial_guess(self, torque_signal, period: float, switches: bool = True) -> np.ndarray:
        """Variables sampled from event-driven simulations (one per scenario) of a torque input
        ``torque_signal(t)`` [N m] at phases t [cycles] of period ``period`` [s]: see
        :func:`~ocp_crawl.ocp.guess.simulated_guess`; a design's variables at the robot's
        values."""
        x = simulated_guess(self, torque_signal, period, switches)
        if self.design is not None:
            x[self._slices["design"]] = 1.0
        return x

    def design_values(self, x: np.ndarray) -> np.ndarray:
        """The design's variables at x in SI units (:meth:`~ocp_crawl.ocp.design.Design.names`
        order); empty without a design."""
        if self.design is None:
            return np.zeros(0)
        assert isinstance(self.robot, Chain)
        return x[self._slices["design"]] * self.design.initial(self.robot)

    # ------------------------------------------------------------------ the solution in physical
    # units
    def unpack(self, x: np.ndarray, onset: bool = True) -> dict:
        """The solution x in physical units (``onset``: the onset pairs' residual in ``comp``, as
        the optimiser's NLP states them; False for a profile-fixed solution, whose NLP has no onset
        rule).

        Returns a dict: ``tau`` (m, N) node torques of the m joints [N m], ``T`` period [s], and per
        scenario (``scen``): ``theta`` (N,) interior fractions [-], ``phi`` (m, N+1) node angles
        [rad] (node N = node 0 after one cycle), ``phi_sub`` (m, 2N+1) the angles at node 0 and
        every sub-step end, ``tau_sub`` (m, 2N) [N m] the torques at the sub-step ends, ``f_t``
        (N+1,) [N], ``x1`` (N+1,) and ``x1_sub`` (2N+1,) foot-1 positions [m], ``S`` [m], ``v =
        direction S / T`` [m/s], ``W_plus`` [J] (midpoint rule per sub-step), the contact ``modes``
        per interval and ``modes_sub`` per sub-step, and the complementarity (``comp``, including
        the cross conditions) and periodicity (``periodic``) residuals [-].
        """
        s, r = self.settings, self.robot
        N, Mg, R = s.nodes, r.M * r.g, StepRows(self.n_joints)
        tau = np.asarray(self._T(x)).reshape(self.n_joints, N)
        period = float(x[self._slices["T_hat"]][0]) * s.period_ref()
        out: dict[str, Any] = {"tau": tau, "T": period, "scen": []}
        for j in range(len(self.scen)):
            W = x[self._slices[f"w_{j}"]].reshape(R.nw, 2 * N, order="F")
            theta = x[self._slices[f"theta_{j}"]].copy()
            phi_sub = np.c_[x[self._slices[f"phi0_{j}"]], W[R.phi]]
            ft_sub = np.r_[x[self._slices[f"ft0_{j}"]], W[R.ft1]] * Mg
            x1_sub = np.r_[0.0, np.cumsum(W[R.s1p] - W[R.s1p + 1])] * r.L
            tau_sub = substep_torques(tau, theta)
            comp = max(float(np.max(np.abs(np.minimum(W[R.slips], W[R.margins])))),
                       cross_residual(W, theta), onset_residual(W) if onset else 0.0)
            modes_sub = modes_of(W)
            S = float(x1_sub[-1])
            out["scen"].append({
                "theta": theta, "phi": phi_sub[:, ::2], "phi_sub": phi_sub, "tau_sub": tau_sub,
                "f_t": ft_sub[::2],
                "x1": x1_sub[::2], "x1_sub": x1_sub, "S": S, "v": s.direction * S / period,
                "W_plus": positive_work(tau_sub, phi_sub), "comp": comp, "modes_sub": modes_sub,
                "modes": [a if a != 0 else b for a, b in zip(modes_sub[::2], modes_sub[1::2])],
                "periodic": float(max(np.max(np.abs(phi_sub[:, -1] - phi_sub[:, 0])),
                                      abs(ft_sub[-1] - ft_sub[0]) / Mg))})
        return out

    def equation_residual(self, x: np.ndarray) -> float:
        """Largest violation of the equality constraints (equilibrium, balance, closure, lifting,
        periodicity, definitions of S and W+) at x, in the scaled units of the NLP."""
        g = np.asarray(self._g(x)).ravel()
        return max((float(np.max(np.abs(g[sl] - self.lbg[sl]))) for sl in self.rows["equation"]),
                   default=0.0)
