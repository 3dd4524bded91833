"""Direct transcription of the periodic-gait OCP: the NLP's variables, constraints and objective, its
initial guess from a simulation, the residuals of a solution, and its solve by the relaxation homotopy.

Node k sits at phase t_k = k/N; node 0 carries the free initial state and steps k = 1..N are the
incremental step equations of :mod:`ocp_crawl.model.step_equations` (the same compiled model functions
and complementarity formulation as the MPCC step solver), with the torque of node k (node N uses the
torque of node 0: the profile is periodic).  Periodicity (angles and tangential force of node N equal to
those of node 0) is a constraint.  The body displacement over the cycle is S = sum of the slips of foot 1.
Scholtes' relaxation s_j c_j <= sigma is driven to sigma_min by the homotopy engine of
:mod:`ocp_crawl.nlp.homotopy`, then polished on the identified branches.
"""
from __future__ import annotations

import math
from functools import lru_cache

import casadi as cs
import numpy as np

from ocp_crawl.model.statics import NP, Model, Robot
from ocp_crawl.model.step_equations import NPAIR, NW, friction_margins, step_equations
from ocp_crawl.model.compiled import compiled_function
from ocp_crawl.nlp import ipopt as nlp_ipopt
from ocp_crawl.nlp.codegen import KernelBuild, compiled_kernel, kernel_library
from ocp_crawl.nlp.homotopy import Homotopy, Solve, Stage, Start, schedule
from ocp_crawl.nlp.ipopt import call_ipopt, ipopt_solvers
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.sim.event import simulate_torque
from ocp_crawl.sim.result import Mode
from ocp_crawl.sim.step import SLIP_PAIR_MODES


def fourier_basis(N: int, K: int) -> np.ndarray:
    """(2K+1, N) values of 1, cos(2 pi n t), sin(2 pi n t), n = 1..K, at the node phases t = k/N."""
    t = np.arange(N) / N
    return np.vstack([np.ones(N)] + [f(2 * np.pi * n * t) for n in range(1, K + 1) for f in (np.cos, np.sin)])


@lru_cache(maxsize=1)
def step_function() -> cs.Function:
    """One step's (equations and lifting, complementarity products) of (phi_prev, w, tau_hat, p): the
    N-independent kernel of the transcription (compiled with its derivatives, :func:`step_kernel`)."""
    phi_prev = cs.SX.sym("phi_prev", 2)
    w = cs.SX.sym("w", NW)
    th = cs.SX.sym("tau_hat", 2)
    p = cs.SX.sym("p", NP)
    g_eq, g_lift, sv, cv = step_equations(phi_prev, w, th, p)
    return cs.Function("ocp_step", [phi_prev, w, th, p], [cs.vertcat(g_eq, g_lift), sv * cv])


@compiled_function
@lru_cache(maxsize=1)
def step_kernel() -> KernelBuild:
    """The compiled step kernel and its derivatives (:func:`ocp_crawl.nlp.codegen.kernel_library`; registered so
    that ``ocp-crawl warmup`` builds it)."""
    return kernel_library(step_function())


class Layout:
    """Variables and constraints of an NLP under construction, each block with its named slice."""

    def __init__(self) -> None:
        self.xs, self.lbx, self.ubx, self.g, self.lbg, self.ubg = [], [], [], [], [], []
        self.slices: dict[str, slice] = {}

    def var(self, name: str, sym, lb, ub) -> None:
        """Add the variables ``sym`` (bounds broadcast) as the block ``name``."""
        start = sum(v.numel() for v in self.xs)
        self.xs.append(sym)
        self.lbx.append(np.broadcast_to(lb, (sym.numel(),)).astype(float))
        self.ubx.append(np.broadcast_to(ub, (sym.numel(),)).astype(float))
        self.slices[name] = slice(start, start + sym.numel())

    def con(self, name: str, expr, lb, ub) -> None:
        """Add the constraints lb <= ``expr`` <= ub as the block ``"g_" + name``."""
        start = sum(e.numel() for e in self.g)
        self.g.append(expr)
        self.lbg.append(np.broadcast_to(lb, (expr.numel(),)).astype(float))
        self.ubg.append(np.broadcast_to(ub, (expr.numel(),)).astype(float))
        self.slices["g_" + name] = slice(start, start + expr.numel())


class GaitOCP:
    """The periodic-gait NLP of one robot, gravity convention and settings, built once."""

    def __init__(self, robot: Robot, gravity: str = "physical", settings: OCPSettings | None = None):
        self.robot = robot
        self.gravity = gravity
        self.settings = settings or OCPSettings()
        self.scen = [Model(r, gravity=gravity) for r in self.settings.scenarios(robot)]
        self.kept_run: list[Stage] = []
        """records of the homotopy whose result :meth:`solve` returned (empty if none succeeded)"""
        self._build()

    # ------------------------------------------------------------------ the NLP (built once)
    def _torque_nodes(self, z_tau, N):
        """Scaled torques at the N node phases as expressions of the torque variables."""
        s = self.settings
        if s.parametrization == "free":
            return cs.reshape(z_tau, 2, N)
        return cs.reshape(z_tau, 2, 2 * s.fourier_order + 1) @ cs.DM(fourier_basis(N, s.fourier_order))

    def _torques(self, nlp: Layout, MgL: float):
        """Torque variables, envelope, rate and curvature limits; returns the scaled node torques T (2, N) and
        their periodic differences dT."""
        s, N, r = self.settings, self.settings.nodes, self.robot
        ntau = 2 * N if s.parametrization == "free" else 2 * (2 * s.fourier_order + 1)
        z_tau = cs.MX.sym("tau", ntau)
        T = self._torque_nodes(z_tau, N)  # (2, N) scaled
        tau_lo, tau_hi = (b / MgL for b in s.torque_bounds(r))
        if s.parametrization == "free":
            nlp.var("tau", z_tau, tau_lo, tau_hi)
        else:
            nlp.var("tau", z_tau, -np.inf, np.inf)
            nlp.con("tau_bounds", cs.vec(T), tau_lo, tau_hi)
        dT = T - cs.horzcat(T[:, -1], T[:, :-1])  # periodic differences tau_k - tau_{k-1}
        rate = s.rate_bound(r)
        if rate is not None:
            lim = rate / MgL / N
            nlp.con("rate", cs.vec(dT), -lim, lim)
        curv = s.curvature_bound(r)
        if curv is not None:
            lim = curv / MgL / N**2
            d2T = cs.horzcat(dT[:, 1:], dT[:, 0]) - dT  # periodic second differences
            nlp.con("curvature", cs.vec(d2T), -lim, lim)
        return T, dT

    def _scenario(self, nlp: Layout, j: int, model: Model, T, step_map):
        """Variables and constraints of scenario j: initial state, steps, periodicity, tie rule, S (and W+ for
        min_cot).  Returns the scaled S variable and the W+ variable (None unless min_cot)."""
        s, N, inf = self.settings, self.settings.nodes, np.inf
        phi0 = cs.MX.sym(f"phi0_{j}", 2)
        ft0 = cs.MX.sym(f"ft0_{j}")
        W = cs.MX.sym(f"w_{j}", NW, N)
        nlp.var(f"phi0_{j}", phi0, 0.0, math.pi)
        nlp.var(f"ft0_{j}", ft0, -inf, inf)
        lbw = np.r_[0.0, 0.0, -inf, -inf, np.zeros(2 * NPAIR)]
        ubw = np.r_[math.pi, math.pi, inf, inf, np.full(2 * NPAIR, inf)]
        nlp.var(f"w_{j}", cs.vec(W), np.tile(lbw, N), np.tile(ubw, N))
        PHI = cs.horzcat(phi0, W[0:2, :])  # (2, N+1)
        Tstep = cs.horzcat(T[:, 1:], T[:, 0])  # step k (1..N) uses the torque of node k mod N
        eqs, comp = step_map(PHI[:, :-1], W, Tstep, cs.repmat(cs.DM(model.p), 1, N))
        nlp.con(f"eq_{j}", cs.vec(eqs), 0.0, 0.0)
        nlp.con(f"comp_{j}", cs.vec(comp), -inf, 0.0)  # upper bound sigma, set per stage
        nlp.con(f"periodic_{j}", cs.vertcat(W[0:2, -1] - phi0, W[2, -1] - ft0), 0.0, 0.0)
        if s.tie_margin > 0:
            # friction limits mu_i f_n,i/(M g) from the lifted margins: c_i+ + c_i- = 2 mu_i f_n,i/(M g)
            lim1 = 0.5 * (W[8, :] + W[9, :])
            lim2 = 0.5 * (W[10, :] + W[11, :])
            tie = cs.vertcat((W[4, :] + W[5, :]) * (lim2 - lim1 - s.tie_margin),
                             (W[6, :] + W[7, :]) * (lim1 - lim2 - s.tie_margin))
            nlp.con(f"tie_{j}", cs.vec(tie), -inf, inf)  # lower bound -sigma, set per stage
        # S and W+ are lifted into scalar variables defined by linear constraints, so that a
        # nonlinear objective in them (W+/S) keeps the Hessian sparse
        S_var = cs.MX.sym(f"S_{j}")
        nlp.var(f"S_{j}", S_var, -inf, inf)
        nlp.con(f"S_def_{j}", S_var - cs.sum2(W[4, :] - W[5, :]), 0.0, 0.0)  # foot-1 displacement / L
        if s.objective != "min_cot":
            return S_var, None
        # positive work per actuator with slacks v >= tau_mid dphi, v >= 0 (scaled by M g L)
        V = cs.MX.sym(f"v_{j}", 2, N)
        nlp.var(f"v_{j}", cs.vec(V), 0.0, inf)
        tau_mid = 0.5 * (T + Tstep)
        nlp.con(f"wplus_{j}", cs.vec(V - tau_mid * (PHI[:, 1:] - PHI[:, :-1])), 0.0, inf)
        W_var = cs.MX.sym(f"Wp_{j}")
        nlp.var(f"Wp_{j}", W_var, 0.0, inf)
        nlp.con(f"W_def_{j}", W_var - cs.sum1(cs.sum2(V)), 0.0, 0.0)
        return S_var, W_var

    def _objective(self, nlp: Layout, S_list: list, W_list: list, dT):
        """The objective (to minimise) with the torque-change regularisation, and its extra constraints."""
        s, inf = self.settings, np.inf
        d = s.direction
        reg = s.regularization * s.nodes * cs.sumsqr(dT)
        if s.objective == "max_speed":
            return -d * S_list[0] + reg
        if s.objective == "robust_speed":
            if s.robust == "mean":
                return -d * sum(S_list) / len(S_list) + reg
            zeta = cs.MX.sym("zeta")
            nlp.var("zeta", zeta, -inf, inf)
            nlp.con("worst", cs.vertcat(*[d * Sj - zeta for Sj in S_list]), 0.0, inf)
            return -zeta + reg
        nlp.con("S_min", d * S_list[0], s.S_min / self.robot.L, inf)
        # CoT+ = W+ / (M g |S|) = (W_hat M g L) / (M g S_hat L) = W_hat / S_hat
        return W_list[0] / (d * S_list[0]) + reg

    def _build(self) -> None:
        s, r = self.settings, self.robot
        MgL = r.M * r.g * r.L
        nlp = Layout()
        T, dT = self._torques(nlp, MgL)
        step_map = compiled_kernel(step_function()).map(s.nodes)
        S_list, W_list = [], []
        for j, model in enumerate(self.scen):
            S_var, W_var = self._scenario(nlp, j, model, T, step_map)
            S_list.append(S_var)
            if W_var is not None:
                W_list.append(W_var)
        f = self._objective(nlp, S_list, W_list, dT)
        X = cs.vertcat(*[cs.vec(x) for x in nlp.xs])
        G = cs.vertcat(*nlp.g)
        self._slices = nlp.slices
        self.nx, self.ng = X.numel(), G.numel()
        self._lbx, self._ubx = np.concatenate(nlp.lbx), np.concatenate(nlp.ubx)
        self._lbg, self._ubg = np.concatenate(nlp.lbg), np.concatenate(nlp.ubg)
        self._T = cs.Function("T", [X], [T * MgL])
        self._g = cs.Function("g", [X], [G])
        self._f = cs.Function("f", [X], [f])
        self.solver, self.solver_warm = ipopt_solvers(
            "gait_ocp", {"x": X, "f": f, "g": G}, nlp_ipopt.OCP_IPOPT, nlp_ipopt.OCP_WARM_IPOPT, s.ipopt,
            "OCPSettings.ipopt", s.verbose)

    # ------------------------------------------------------------------ initial guess from a simulation
    def initial_guess(self, torque_signal) -> np.ndarray:
        """Variables sampled from event-driven simulations (one per scenario) of a torque input
        (a gait that simulates successfully, e.g. the best harmonic of
        :func:`~ocp_crawl.ocp.baseline.best_harmonic`): ``torque_signal(t)`` [N m] at phases t [cycles].
        Returns the NLP's variable vector (scaled)."""
        s = self.settings
        N = s.nodes
        r = self.robot
        MgL, Mg, L = r.M * r.g * r.L, r.M * r.g, r.L
        x = np.zeros(self.nx)
        t_nodes = np.arange(N) / N
        tau_nodes = torque_signal(t_nodes).reshape(2, N) / MgL
        if s.parametrization == "free":
            x[self._slices["tau"]] = tau_nodes.ravel(order="F")
        else:
            basis = fourier_basis(N, s.fourier_order)
            coef, *_ = np.linalg.lstsq(basis.T, tau_nodes.T, rcond=None)
            x[self._slices["tau"]] = coef.T.ravel(order="F")
        dS = []
        for j, model in enumerate(self.scen):
            te = np.arange(N + 1) / N
            res = simulate_torque(model, torque_signal, t_eval=te)
            dS.append(self.settings.direction * res.S)
            phi, ft, x1, x2 = res.phi, res.f_t / Mg, res.x1, res.x2
            rb = model.robot
            W = np.zeros((NW, N))
            W[0:2] = phi[:, 1:]
            W[2] = ft[1:]
            W[3] = -ft[1:]
            dx1, dx2 = np.diff(x1) / L, np.diff(x2) / L
            W[4], W[5] = np.maximum(dx1, 0), np.maximum(-dx1, 0)
            W[6], W[7] = np.maximum(dx2, 0), np.maximum(-dx2, 0)
            fn1, fn2 = res.f_n1[1:] / Mg, res.f_n2[1:] / Mg
            # lifted margins at the simulated points (f_t2 = -f_t on foot 2), clipped to >= 0
            W[8:12] = np.maximum(np.vstack(friction_margins(rb.mu1, fn1, ft[1:], rb.mu2, fn2, -ft[1:])), 0.0)
            x[self._slices[f"phi0_{j}"]] = phi[:, 0]
            x[self._slices[f"ft0_{j}"]] = ft[0]
            x[self._slices[f"w_{j}"]] = W.ravel(order="F")
            x[self._slices[f"S_{j}"]] = np.sum(W[4] - W[5])
            if f"v_{j}" in self._slices:
                tau = torque_signal(te).reshape(2, -1) / MgL
                tau_mid = 0.5 * (tau[:, :-1] + tau[:, 1:])
                V = np.maximum(tau_mid * np.diff(phi, axis=1), 0.0)
                x[self._slices[f"v_{j}"]] = V.ravel(order="F")
                x[self._slices[f"Wp_{j}"]] = V.sum()
        if "zeta" in self._slices:
            x[self._slices["zeta"]] = min(dS) / L
        return x

    # ------------------------------------------------------------------ residuals of a solution
    def unpack(self, x: np.ndarray) -> dict:
        """The solution x in physical units: ``tau`` (2, N) [N m] and per scenario (``scen``) the angles ``phi``
        (2, N+1) [rad], ``f_t`` [N], ``x1`` [m], ``S`` [m], the contact ``modes``, and the complementarity
        (``comp``) and periodicity (``periodic``) residuals [-]."""
        N = self.settings.nodes
        r = self.robot
        out = {"tau": np.asarray(self._T(x)).reshape(2, N), "scen": []}
        for j, model in enumerate(self.scen):
            W = x[self._slices[f"w_{j}"]].reshape(NW, N, order="F")
            phi = np.c_[x[self._slices[f"phi0_{j}"]], W[0:2]]
            ft = np.r_[x[self._slices[f"ft0_{j}"]], W[2]] * r.M * r.g
            sv, cv = W[4:8], W[8:12]
            x1 = np.r_[0.0, np.cumsum(sv[0] - sv[1])] * r.L
            comp = float(np.max(np.abs(np.minimum(sv, cv))))
            modes = []
            for k in range(N):
                sl = [i for i in range(4) if sv[i, k] > cv[i, k]]
                if not sl:
                    modes.append(int(Mode.STICK))
                else:
                    i = max(sl, key=lambda q: sv[q, k])
                    modes.append(int(SLIP_PAIR_MODES[i]))
            out["scen"].append({"phi": phi, "f_t": ft, "x1": x1, "S": float(x1[-1]), "comp": comp, "modes": modes,
                                "periodic": float(max(np.max(np.abs(phi[:, -1] - phi[:, 0])),
                                                      abs(ft[-1] - ft[0]) / (r.M * r.g)))})
        return out

    def equation_residual(self, x: np.ndarray) -> float:
        """Largest violation of the equality constraints (equilibrium, balance, closure, lifting,
        periodicity, definitions of S and W+) at x, in the scaled units of the NLP."""
        g = np.asarray(self._g(x)).ravel()
        worst = 0.0
        for name, sl in self._slices.items():
            if name.startswith(("g_eq_", "g_periodic_", "g_S_def_", "g_W_def_")):
                worst = max(worst, float(np.max(np.abs(g[sl] - self._lbg[sl]))))
        return worst

    def positive_work(self, tau_nodes: np.ndarray, phi: np.ndarray) -> float:
        """Discrete W+ [J] of the transcription: sum over actuators and steps of max(0, tau_mid dphi)."""
        tau_step = np.c_[tau_nodes[:, 1:], tau_nodes[:, 0]]
        tau_mid = 0.5 * (tau_nodes + tau_step)
        return float(np.sum(np.maximum(tau_mid * np.diff(phi, axis=1), 0.0)))

    # ------------------------------------------------------------------ solve: the relaxation homotopy
    def solve(self, x0: np.ndarray) -> tuple[np.ndarray | None, list[Stage], str | None, str]:
        """Homotopies from x0, one per sigma0; returns the best accepted (x, history, failed stage, status).

        ``status`` is the return status (see :data:`~ocp_crawl.nlp.ipopt.IPOPT_RETURN_STATUS`) of the solve that
        decided: the last accepted stage or polish of the kept homotopy, else the failed stage of the last
        homotopy, whose ``failed`` then names the stage (``x`` is that homotopy's last accepted iterate or None).
        """
        hom = Homotopy(self.solver, self.solver_warm, self._call)
        best = None
        runs = []
        f0 = float(self._f(x0))  # objective of the (nearly feasible) initial guess
        for sigma0 in self.settings.sigma0:
            n0 = len(hom.records)
            x, failed, status = self._homotopy(hom, x0, sigma0)
            runs.append((x, hom.records[n0:], failed, status))
            if x is not None and failed is None:
                f = float(self._f(x))
                if best is None or f < best[0]:
                    best = (f, x, hom.records[n0:], status)
            if best is not None and best[0] < f0:
                break  # improved on the initial guess: the next (tighter) start is not needed
        self.kept_run = best[2] if best is not None else []
        if best is not None:
            return best[1], hom.records, None, best[3]
        x, _, failed, status = runs[-1]
        if len(runs) > 1:
            failed = "; ".join(f"start sigma0 = {sigma0:.0e}: {r[2]} ({r[3]})"
                               for sigma0, r in zip(self.settings.sigma0, runs))
        return x, hom.records, failed, status

    def _call(self, solver, start: Start, data: dict) -> Solve:
        """One IPOPT call of the homotopy and the residuals of its point."""
        args = dict(data, x0=start.x)
        if start.warm:
            args.update(lam_x0=start.lam_x, lam_g0=start.lam_g)
        call = call_ipopt(solver, self.nx, self.ng, **args)
        scen = self.unpack(call.x)["scen"]
        return Solve.of(call, comp=max(sc["comp"] for sc in scen), S=tuple(sc["S"] for sc in scen))

    def _stage_data(self, sigma: float, tie_sigma: float | None = None) -> dict:
        """Bounds of a relaxation stage: s_j c_j <= sigma, tie products >= -sigma (``tie_sigma`` if given)."""
        ubg, lbg = self._ubg.copy(), self._lbg.copy()
        for j in range(len(self.scen)):
            ubg[self._slices[f"g_comp_{j}"]] = sigma
        for name, sl in self._slices.items():
            if name.startswith("g_tie_"):
                lbg[sl] = -(sigma if tie_sigma is None else tie_sigma)
        return {"lbx": self._lbx, "ubx": self._ubx, "lbg": lbg, "ubg": ubg}

    def _polish_data(self, x: np.ndarray) -> dict:
        """The tightened NLP from x: each pair on its identified branch (s_j = 0 where s_j <= c_j, else
        c_j = 0, as bounds), which removes the O(sqrt(sigma)) residual of biactive pairs."""
        N = self.settings.nodes
        data = self._stage_data(0.0, tie_sigma=self.settings.sigma_min)
        ubx = self._ubx.copy()
        for j in range(len(self.scen)):
            sl = self._slices[f"w_{j}"]
            W = x[sl].reshape(NW, N, order="F")
            fix = np.zeros((NW, N), bool)
            fix[4:8] = W[4:8] <= W[8:12]
            fix[8:12] = ~fix[4:8]
            ub = ubx[sl].reshape(NW, N, order="F").copy()
            ub[fix] = 0.0
            ubx[sl] = ub.ravel(order="F")
        return dict(data, ubx=ubx, x0=np.minimum(x, ubx))

    def _homotopy(self, hom: Homotopy, x0: np.ndarray, sigma0: float) -> tuple[np.ndarray | None, str | None, str]:
        """One relaxation homotopy from x0, then the polish (kept only if IPOPT accepts it and it does not
        raise the complementarity residual): (x or None, failed stage or None, status)."""
        s = self.settings
        run = hom.relax(schedule(sigma0, s.sigma_factor, s.sigma_min), Start(x0), self._stage_data)
        if not run.ok:
            x = run.last.x if run.last is not None else None
            return x, f"homotopy stage {run.stage + 1}/{run.stages} (sigma = {run.sigma:.1e})", run.failed.status
        sol = run.last
        pol = hom.polish(sol, [self._polish_data(sol.x)], lambda p: p.comp <= sol.comp)
        return (pol.x, None, pol.status) if pol is not None else (sol.x, None, sol.status)
