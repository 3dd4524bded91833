"""Periodic-gait optimal control: optimal joint-torque profiles over one cycle.

Direct transcription over one cycle with N steps (quasistatic, hence time-scalable: only the
phase matters).  Node k sits at phase t_k = k/N; node 0 carries the free initial state and steps
k = 1..N are the incremental MPCC step equations of :mod:`ocp_crawl.model.step_equations` (the same
compiled model functions and the same complementarity formulation as the MPCC step solver), with
the torque of node k (node N uses the torque of node 0: the profile is periodic).  Periodicity of
the gait is imposed explicitly (angles and tangential force of node N equal those of node 0) and
reported as a residual.  The body displacement over the cycle is S = sum of the slips of foot 1.

Torques are free at every node (``parametrization = "free"``) or a Fourier series of chosen order
(``"fourier"``).  Bounds keep each reference angle phi_ref,i = pi + tau_i/k inside
[gamma - A_max, gamma + A_max], the envelope of the harmonic gaits of amplitude A_max; optional
rate limits bound |tau_k - tau_{k-1}| N; a small regularisation of the torque changes avoids
chattering.

Objectives: ``max_speed`` (maximise direction * S), ``min_cot`` (minimise CoT+ = W+/(M g S) with
the positive work written with slack variables, subject to direction * S >= S_min) and
``robust_speed`` (one torque profile shared by several friction scenarios, maximising the mean or
the worst direction * S).

Solution: initial guess from the best harmonic gait of the same envelope (psi sweep with the
event-driven stepper), Scholtes relaxation homotopy s_j c_j <= sigma with warm starts, every stage
checked against the IPOPT status table of :mod:`ocp_crawl.sim.mpcc`.  The optimal profile is then
replayed in the event-driven simulator (periodic shape-preserving cubic through the node torques).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Literal

import casadi as cs
import numpy as np

from ocp_crawl.sim.event import simulate_torque
from ocp_crawl.model.inputs import Harmonic, PeriodicPchip, ReferenceTorque
from ocp_crawl.model.statics import NP, Model, Robot
from ocp_crawl.sim.mpcc import IpoptCall, build_ipopt, call_ipopt, check_ipopt_options, ipopt_status
from ocp_crawl.sim.result import CrawlResult, Mode, cost_of_transport
from ocp_crawl.model.step_equations import NPAIR, NW, step_equations

Objective = Literal["max_speed", "min_cot", "robust_speed"]
OBJECTIVES = ("max_speed", "min_cot", "robust_speed")
PARAMETRIZATIONS = ("free", "fourier")


class OCPStatus:
    """String statuses of an OCP solve."""

    SUCCESS = "success"
    INFEASIBLE = "infeasible"
    SOLVER_FAILURE = "solver_failure"
    NOT_COMPLEMENTARY = "not_complementary"
    NO_INITIAL_GUESS = "no_initial_guess"
    REPLAY_FAILED = "replay_failed"


#: default curvature limit in units of the peak curvature of the envelope's harmonic gait
CURVATURE_FACTOR = 4.0


def _num(name, v, *, positive=False, nonneg=False, integer=False):
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise TypeError(f"OCPSettings.{name} must be a number, got {v!r}")
    if integer and int(v) != v:
        raise ValueError(f"OCPSettings.{name} must be an integer, got {v!r}")
    v = int(v) if integer else float(v)
    if not math.isfinite(v) or (positive and v <= 0) or (nonneg and v < 0):
        what = "> 0" if positive else ">= 0" if nonneg else "finite"
        raise ValueError(f"OCPSettings.{name} must be {what}, got {v!r}")
    return v


@dataclass(frozen=True)
class OCPSettings:
    """Settings of the periodic-gait optimal control problem."""

    objective: Objective = "max_speed"
    nodes: int = 100
    """steps per cycle N"""
    direction: int = -1
    """sign of S to pursue: -1 towards foot 1 (the direction of psi > 0 gaits), +1 towards foot 2"""
    gamma_deg: float = 90.0
    """centre of the reference-angle envelope [deg]"""
    A_max_deg: float = 30.0
    """half-width of the reference-angle envelope [deg]"""
    parametrization: str = "free"
    """'free' torque at every node (default, sparse), or 'fourier' series of order fourier_order
    (band-limited, but its dense coefficient columns make IPOPT iterations much slower)"""
    fourier_order: int = 4
    rate_limit: float | str | None = "harmonic"
    """largest |d tau/d t| [N m per cycle]; "harmonic" (default): the peak rate 2 pi k A_max of the
    envelope's harmonic gait, so that the optimum cannot gain by packing several strokes into one
    cycle (a higher actuation frequency); None: no limit"""
    curvature_limit: float | str | None = "harmonic"
    """largest |d^2 tau/d t^2| [N m per cycle^2]; "harmonic" (default): CURVATURE_FACTOR times the
    peak (2 pi)^2 k A_max of the envelope's harmonic gait.  Without a limit free profiles chatter:
    micro-strokes every few steps, each carrying an O(1/N) transition error of the transcription
    that the optimiser exploits and that does not vanish as N grows (the strokes multiply).  With
    the factor 1 the full-amplitude sine is about the only admissible stroke, hence 4 (room for a
    second harmonic at full amplitude).  None: no limit"""
    tie_margin: float = 0.0005
    """a foot may slip only while its friction limit is below the other foot's by tie_margin M g:
    at a tie the incremental Coulomb law leaves free which foot slips, which an optimiser would
    exploit and the continuous system does not allow (it slips both feet symmetrically)"""
    regularization: float = 1e-5
    """weight of N * sum_k |tau_k - tau_{k-1}|^2/(M g L)^2 in the objective"""
    S_min: float = 0.0
    """min_cot: smallest direction * S [m]"""
    mu_ratios: tuple = (0.9, 1.0, 1.1)
    """robust_speed: friction scenarios mu1/mu2 (mu1 = mu sqrt(r), mu2 = mu / sqrt(r))"""
    robust: str = "mean"
    """robust_speed: maximise the 'mean' or the 'worst' direction * S over the scenarios"""
    sigma0: tuple = (1e-2, 1e-6)
    """first relaxation parameters of the homotopies run from the harmonic initial guess (the
    problem is nonconvex and the relaxation path decides the local optimum: a loose start explores,
    a tight start stays near the guess); the best accepted result is kept"""
    sigma_min: float = 1e-10
    sigma_factor: float = 0.1
    comp_tol: float = 1e-6
    """largest accepted complementarity residual max_j |min(s_j/L, c_j/(M g))|"""
    periodic_tol: float = 1e-8
    harmonic_psi: int = 36
    """psi values of the harmonic sweep (initial guess and comparison), over (-180, 180] deg"""
    harmonic_A: int = 4
    """amplitudes of the harmonic sweep, up to A_max"""
    ipopt: dict = field(default_factory=dict)
    verbose: bool = False

    def __post_init__(self) -> None:
        if self.objective not in OBJECTIVES:
            raise ValueError(f"OCPSettings.objective must be one of {OBJECTIVES}, got {self.objective!r}")
        if self.parametrization not in PARAMETRIZATIONS:
            raise ValueError(f"OCPSettings.parametrization must be one of {PARAMETRIZATIONS}, got {self.parametrization!r}")
        if self.direction not in (-1, 1):
            raise ValueError(f"OCPSettings.direction must be -1 or +1, got {self.direction!r}")
        if self.robust not in ("mean", "worst"):
            raise ValueError(f"OCPSettings.robust must be 'mean' or 'worst', got {self.robust!r}")
        object.__setattr__(self, "nodes", _num("nodes", self.nodes, positive=True, integer=True))
        if self.nodes < 8:
            raise ValueError(f"OCPSettings.nodes must be >= 8, got {self.nodes}")
        object.__setattr__(self, "fourier_order", _num("fourier_order", self.fourier_order, positive=True, integer=True))
        s0 = (self.sigma0,) if isinstance(self.sigma0, (int, float)) else tuple(self.sigma0)
        if not s0 or any(isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v < 1 for v in s0):
            raise ValueError(f"OCPSettings.sigma0 must be numbers in (0, 1), got {self.sigma0!r}")
        object.__setattr__(self, "sigma0", tuple(float(v) for v in s0))
        for name in ("gamma_deg", "A_max_deg", "regularization", "S_min", "sigma_min", "sigma_factor",
                     "comp_tol", "periodic_tol"):
            object.__setattr__(self, name, _num(name, getattr(self, name), nonneg=name in ("regularization", "S_min"),
                                                positive=name not in ("regularization", "S_min")))
        if not 0 < self.A_max_deg < 90:
            raise ValueError(f"OCPSettings.A_max_deg must be in (0, 90), got {self.A_max_deg}")
        if not (0 < self.gamma_deg - self.A_max_deg and self.gamma_deg + self.A_max_deg < 180):
            raise ValueError("OCPSettings: the envelope gamma +- A_max must lie in (0, 180) deg")
        if self.rate_limit is not None and self.rate_limit != "harmonic":
            object.__setattr__(self, "rate_limit", _num("rate_limit", self.rate_limit, positive=True))
        object.__setattr__(self, "tie_margin", _num("tie_margin", self.tie_margin, nonneg=True))
        if self.curvature_limit is not None and self.curvature_limit != "harmonic":
            object.__setattr__(self, "curvature_limit", _num("curvature_limit", self.curvature_limit, positive=True))
        if not self.sigma_factor < 1 or not all(self.sigma_min < v for v in self.sigma0):
            raise ValueError("OCPSettings: need sigma_factor < 1 and sigma_min < sigma0")
        ratios = tuple(float(r) for r in self.mu_ratios)
        if not ratios or any(not (math.isfinite(r) and r > 0) for r in ratios):
            raise ValueError(f"OCPSettings.mu_ratios must be positive numbers, got {self.mu_ratios!r}")
        object.__setattr__(self, "mu_ratios", ratios)
        object.__setattr__(self, "ipopt", check_ipopt_options("OCPSettings.ipopt", self.ipopt))

    def scenarios(self, robot: Robot) -> list[Robot]:
        if self.objective != "robust_speed":
            return [robot]
        mu = math.sqrt(robot.mu1 * robot.mu2)
        return [robot.replace(mu1=mu * math.sqrt(r), mu2=mu / math.sqrt(r)) for r in self.mu_ratios]

    def rate_bound(self, robot: Robot) -> float | None:
        """Largest |d tau / d t| [N m per cycle] or None."""
        if self.rate_limit == "harmonic":
            return 2 * math.pi * robot.k * math.radians(self.A_max_deg)
        return self.rate_limit

    def curvature_bound(self, robot: Robot) -> float | None:
        """Largest |d^2 tau / d t^2| [N m per cycle^2] or None."""
        if self.curvature_limit == "harmonic":
            return CURVATURE_FACTOR * (2 * math.pi) ** 2 * robot.k * math.radians(self.A_max_deg)
        return self.curvature_limit

    def torque_bounds(self, robot: Robot) -> tuple[float, float]:
        """Torque range [N m] that keeps phi_ref = pi + tau/k inside the envelope."""
        g, a = math.radians(self.gamma_deg), math.radians(self.A_max_deg)
        return robot.k * (g - a - math.pi), robot.k * (g + a - math.pi)


@dataclass(frozen=True)
class HomotopyRecord:
    sigma: float
    """relaxation parameter of the stage (0 for the polish)"""
    return_status: str
    accepted: bool
    iterations: int
    comp_residual: float
    objective: float
    S: tuple
    time: float
    kind: str = "homotopy"
    """'homotopy' (a relaxation stage) or 'polish' (the tightened NLP, sigma = 0)"""
    message: str = ""
    """the return status and its meaning from :data:`~ocp_crawl.sim.mpcc.IPOPT_RETURN_STATUS`"""


@dataclass
class HarmonicChoice:
    """The best harmonic gait of the envelope for the objective, measured with the event-driven stepper."""

    psi_deg: float
    A_deg: float
    gamma_deg: float
    value: float
    """objective value (max_speed/robust_speed: direction * S [m]; min_cot: CoT+)"""
    S: list
    W_plus: list
    CoT_plus: list
    evaluated: int

    def to_dict(self) -> dict:
        """JSON-able (strict: a non-finite number, e.g. the infinite CoT+ of a gait short of S_min, is None)."""
        def num(x):
            return float(x) if math.isfinite(x) else None

        return {"psi_deg": self.psi_deg, "A_deg": self.A_deg, "gamma_deg": self.gamma_deg, "value": num(self.value),
                "S": [num(v) for v in self.S], "W_plus": [num(v) for v in self.W_plus],
                "CoT_plus": [num(v) for v in self.CoT_plus], "evaluated": self.evaluated}


@dataclass
class OCPResult:
    success: bool
    status: str
    message: str
    objective: str
    settings: OCPSettings
    phase: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tau: np.ndarray = field(default_factory=lambda: np.zeros((2, 0)))
    """optimal torques [N m] at the node phases (2, N)"""
    phi: list = field(default_factory=list)
    """per scenario: angles (2, N+1) [rad] at phases k/N, k = 0..N"""
    x1: list = field(default_factory=list)
    f_t: list = field(default_factory=list)
    modes: list = field(default_factory=list)
    S_ocp: list = field(default_factory=list)
    W_plus_ocp: list = field(default_factory=list)
    CoT_plus_ocp: list = field(default_factory=list)
    value_ocp: float = float("nan")
    complementarity_residual: float = float("nan")
    periodicity_residual: float = float("nan")
    equation_residual: float = float("nan")
    homotopy: list = field(default_factory=list)
    failed_stage: str | None = None
    solve_time_s: float = float("nan")
    harmonic: HarmonicChoice | None = None
    replay: list = field(default_factory=list)
    """per scenario: CrawlResult of the event-driven replay"""
    S_replay: list = field(default_factory=list)
    W_plus_replay: list = field(default_factory=list)
    CoT_plus_replay: list = field(default_factory=list)
    value_replay: float = float("nan")
    rel_diff_replay: float = float("nan")
    gain: float = float("nan")

    def summary(self) -> dict:
        def num(x):
            x = float(x)
            return x if math.isfinite(x) else None

        one = len(self.S_ocp) == 1
        return {
            "status": self.status, "success": bool(self.success), "message": self.message,
            "objective": self.objective, "nodes": self.settings.nodes,
            "parametrization": self.settings.parametrization,
            "S_ocp": (num(self.S_ocp[0]) if one else [num(s) for s in self.S_ocp]) if self.S_ocp else None,
            "S_replay": (num(self.S_replay[0]) if one else [num(s) for s in self.S_replay]) if self.S_replay else None,
            "W_plus_ocp": [num(w) for w in self.W_plus_ocp], "W_plus_replay": [num(w) for w in self.W_plus_replay],
            "CoT_plus_ocp": [num(c) for c in self.CoT_plus_ocp],
            "CoT_plus_replay": (num(self.CoT_plus_replay[0]) if one else [num(c) for c in self.CoT_plus_replay])
            if self.CoT_plus_replay else None,
            "objective_value_ocp": num(self.value_ocp), "objective_value_replay": num(self.value_replay),
            "rel_diff_replay": num(self.rel_diff_replay),
            "best_harmonic": self.harmonic.to_dict() if self.harmonic else None,
            "gain": num(self.gain), "solve_time_s": num(self.solve_time_s),
            "complementarity_residual": num(self.complementarity_residual),
            "periodicity_residual": num(self.periodicity_residual),
            "equation_residual": num(self.equation_residual),
            "failed_stage": self.failed_stage,
            "homotopy": [{k: (num(v) if isinstance(v, float) else [num(x) for x in v] if isinstance(v, tuple) else v)
                          for k, v in h.__dict__.items()} for h in self.homotopy],
        }


# --------------------------------------------------------------------------------------------
# objective values measured on simulations (harmonic sweep and replay use the same definition)
# --------------------------------------------------------------------------------------------
def objective_value(settings: OCPSettings, results: list[CrawlResult], enforce_s_min: bool = True) -> float:
    """Objective of a set of simulations (one per scenario); larger is better for speeds, smaller for CoT.

    Failed simulations give NaN.  min_cot of a gait that misses S_min gives +inf when
    ``enforce_s_min`` (harmonic selection); the replay reports the CoT+ itself and checks S_min apart.
    """
    if any(not r.success for r in results):
        return float("nan")
    return _value_from(settings, [r.S for r in results], [r.CoT_plus for r in results], enforce_s_min)


def _better(settings: OCPSettings, a: float, b: float) -> bool:
    """a strictly better than b (NaN never better)."""
    if not math.isfinite(a) and not (settings.objective == "min_cot" and a == math.inf):
        return False
    if not math.isfinite(b):
        return math.isfinite(a) or (b != b)
    return a < b if settings.objective == "min_cot" else a > b


def best_harmonic(robot: Robot, gravity: str, settings: OCPSettings) -> HarmonicChoice | None:
    """Best harmonic gait of the envelope (gamma fixed, psi and A <= A_max swept) for the objective."""
    models = [Model(r, gravity=gravity) for r in settings.scenarios(robot)]
    psis = np.linspace(-180.0, 180.0, settings.harmonic_psi + 1)[1:]
    amps = np.linspace(settings.A_max_deg / settings.harmonic_A, settings.A_max_deg, settings.harmonic_A)
    if settings.objective in ("max_speed", "robust_speed"):
        amps = amps[-1:]  # S grows with A (paper): the largest amplitude of the envelope
    best = None
    closest = None  # min_cot: the gait nearest to S_min when none reaches it (initial guess only)
    n = 0
    for A in amps:
        for psi in psis:
            gait = Harmonic.from_degrees(settings.gamma_deg, float(A), float(psi))
            try:
                res = [simulate_torque(m, ReferenceTorque(gait, m.robot.k)) for m in models]
            except ValueError:
                continue
            n += 1
            if any(not r.success for r in res):
                continue
            choice = HarmonicChoice(float(psi), float(A), settings.gamma_deg, objective_value(settings, res),
                                    [r.S for r in res], [r.W_plus for r in res], [r.CoT_plus for r in res], 0)
            if math.isfinite(choice.value) and (best is None or _better(settings, choice.value, best.value)):
                best = choice
            if closest is None or settings.direction * choice.S[0] > settings.direction * closest.S[0]:
                closest = choice
    best = best or (closest if settings.objective == "min_cot" else None)
    if best is not None:
        best.evaluated = n
    return best


# --------------------------------------------------------------------------------------------
# the NLP
# --------------------------------------------------------------------------------------------
DEFAULT_IPOPT = {"tol": 1e-10, "acceptable_tol": 1e-8, "max_iter": 2000, "mu_strategy": "adaptive",
                 "bound_relax_factor": 0.0, "nlp_scaling_method": "gradient-based"}
WARM_IPOPT = {"warm_start_init_point": "yes", "mu_init": 1e-6, "mu_strategy": "monotone",
              "warm_start_bound_push": 1e-9, "warm_start_bound_frac": 1e-9, "warm_start_slack_bound_push": 1e-9,
              "warm_start_slack_bound_frac": 1e-9, "warm_start_mult_bound_push": 1e-9}


def fourier_basis(N: int, K: int) -> np.ndarray:
    """(2K+1, N) values of 1, cos(2 pi n t), sin(2 pi n t), n = 1..K, at the node phases t = k/N."""
    t = np.arange(N) / N
    return np.vstack([np.ones(N)] + [f(2 * np.pi * n * t) for n in range(1, K + 1) for f in (np.cos, np.sin)])


class GaitOCP:
    """The periodic-gait NLP of one robot, gravity convention and settings, built once."""

    def __init__(self, robot: Robot, gravity: str = "physical", settings: OCPSettings | None = None):
        self.robot = robot
        self.gravity = gravity
        self.settings = settings or OCPSettings()
        self.scen = [Model(r, gravity=gravity) for r in self.settings.scenarios(robot)]
        self.kept_run: list[HomotopyRecord] = []
        """records of the homotopy whose result :meth:`solve` returned (empty if none succeeded)"""
        self._build()

    def _torque_nodes(self, z_tau, N):
        """Scaled torques at the N node phases as expressions of the torque variables."""
        s = self.settings
        if s.parametrization == "free":
            return cs.reshape(z_tau, 2, N)
        return cs.reshape(z_tau, 2, 2 * s.fourier_order + 1) @ cs.DM(fourier_basis(N, s.fourier_order))

    def _build(self) -> None:
        s = self.settings
        N = s.nodes
        r = self.robot
        MgL = r.M * r.g * r.L
        ntau = 2 * N if s.parametrization == "free" else 2 * (2 * s.fourier_order + 1)
        z_tau = cs.MX.sym("tau", ntau)
        T = self._torque_nodes(z_tau, N)  # (2, N) scaled

        # one step as a function, mapped over the N steps of each scenario
        phi_prev = cs.SX.sym("phi_prev", 2)
        w = cs.SX.sym("w", NW)
        th = cs.SX.sym("tau_hat", 2)
        p = cs.SX.sym("p", NP)
        g_eq, g_lift, sv, cv = step_equations(phi_prev, w, th, p)
        step = cs.Function("ocp_step", [phi_prev, w, th, p], [cs.vertcat(g_eq, g_lift), sv * cv])
        step_map = step.map(N)

        xs, lbx, ubx, g, lbg, ubg = [], [], [], [], [], []
        self._slices = {}

        def add_var(name, sym, lb, ub):
            start = sum(v.numel() for v in xs)
            xs.append(sym)
            lbx.append(np.broadcast_to(lb, (sym.numel(),)).astype(float))
            ubx.append(np.broadcast_to(ub, (sym.numel(),)).astype(float))
            self._slices[name] = slice(start, start + sym.numel())

        def add_con(name, expr, lb, ub):
            start = sum(e.numel() for e in g)
            g.append(expr)
            lbg.append(np.broadcast_to(lb, (expr.numel(),)).astype(float))
            ubg.append(np.broadcast_to(ub, (expr.numel(),)).astype(float))
            self._slices["g_" + name] = slice(start, start + expr.numel())

        tau_lo, tau_hi = (b / MgL for b in s.torque_bounds(r))
        if s.parametrization == "free":
            add_var("tau", z_tau, tau_lo, tau_hi)
        else:
            add_var("tau", z_tau, -np.inf, np.inf)
            add_con("tau_bounds", cs.vec(T), tau_lo, tau_hi)
        dT = T - cs.horzcat(T[:, -1], T[:, :-1])  # periodic differences tau_k - tau_{k-1}
        rate = s.rate_bound(r)
        if rate is not None:
            lim = rate / MgL / N
            add_con("rate", cs.vec(dT), -lim, lim)
        curv = s.curvature_bound(r)
        if curv is not None:
            lim = curv / MgL / N**2
            d2T = cs.horzcat(dT[:, 1:], dT[:, 0]) - dT  # periodic second differences
            add_con("curvature", cs.vec(d2T), -lim, lim)

        inf = np.inf
        S_list, W_list = [], []
        for j, model in enumerate(self.scen):
            phi0 = cs.MX.sym(f"phi0_{j}", 2)
            ft0 = cs.MX.sym(f"ft0_{j}")
            W = cs.MX.sym(f"w_{j}", NW, N)
            add_var(f"phi0_{j}", phi0, 0.0, math.pi)
            add_var(f"ft0_{j}", ft0, -inf, inf)
            lbw = np.r_[0.0, 0.0, -inf, -inf, np.zeros(2 * NPAIR)]
            ubw = np.r_[math.pi, math.pi, inf, inf, np.full(2 * NPAIR, inf)]
            add_var(f"w_{j}", cs.vec(W), np.tile(lbw, N), np.tile(ubw, N))
            PHI = cs.horzcat(phi0, W[0:2, :])  # (2, N+1)
            # step k (1..N) uses the torque of node k mod N
            Tstep = cs.horzcat(T[:, 1:], T[:, 0])
            eqs, comp = step_map(PHI[:, :-1], W, Tstep, cs.repmat(cs.DM(model.p), 1, N))
            add_con(f"eq_{j}", cs.vec(eqs), 0.0, 0.0)
            add_con(f"comp_{j}", cs.vec(comp), -inf, 0.0)  # upper bound sigma, set per stage
            add_con(f"periodic_{j}", cs.vertcat(W[0:2, -1] - phi0, W[2, -1] - ft0), 0.0, 0.0)
            if s.tie_margin > 0:
                # friction limits mu_i f_n,i/(M g) from the lifted margins: c_i+ + c_i- = 2 mu_i f_n,i/(M g)
                lim1 = 0.5 * (W[8, :] + W[9, :])
                lim2 = 0.5 * (W[10, :] + W[11, :])
                tie = cs.vertcat((W[4, :] + W[5, :]) * (lim2 - lim1 - s.tie_margin),
                                 (W[6, :] + W[7, :]) * (lim1 - lim2 - s.tie_margin))
                add_con(f"tie_{j}", cs.vec(tie), -inf, inf)  # lower bound -sigma, set per stage
            # S and W+ are lifted into scalar variables defined by linear constraints, so that a
            # nonlinear objective in them (W+/S) keeps the Hessian sparse
            S_var = cs.MX.sym(f"S_{j}")
            add_var(f"S_{j}", S_var, -inf, inf)
            add_con(f"S_def_{j}", S_var - cs.sum2(W[4, :] - W[5, :]), 0.0, 0.0)  # foot-1 displacement / L
            S_list.append(S_var)
            if s.objective == "min_cot":
                # positive work per actuator with slacks v >= tau_mid dphi, v >= 0 (scaled by M g L)
                V = cs.MX.sym(f"v_{j}", 2, N)
                add_var(f"v_{j}", cs.vec(V), 0.0, inf)
                Tprev = T
                tau_mid = 0.5 * (Tprev + Tstep)
                dphi = PHI[:, 1:] - PHI[:, :-1]
                add_con(f"wplus_{j}", cs.vec(V - tau_mid * dphi), 0.0, inf)
                W_var = cs.MX.sym(f"Wp_{j}")
                add_var(f"Wp_{j}", W_var, 0.0, inf)
                add_con(f"W_def_{j}", W_var - cs.sum1(cs.sum2(V)), 0.0, 0.0)
                W_list.append(W_var)
        d = s.direction
        reg = s.regularization * N * cs.sumsqr(dT)
        if s.objective == "max_speed":
            f = -d * S_list[0] + reg
        elif s.objective == "robust_speed":
            if s.robust == "mean":
                f = -d * sum(S_list) / len(S_list) + reg
            else:
                zeta = cs.MX.sym("zeta")
                add_var("zeta", zeta, -inf, inf)
                add_con("worst", cs.vertcat(*[d * Sj - zeta for Sj in S_list]), 0.0, inf)
                f = -zeta + reg
        else:
            add_con("S_min", d * S_list[0], s.S_min / r.L, inf)
            # CoT+ = W+ / (M g |S|) = (W_hat M g L) / (M g S_hat L) = W_hat / S_hat
            f = W_list[0] / (d * S_list[0]) + reg
        self._S = cs.Function("S", [cs.vertcat(*[cs.vec(x) for x in xs])], [cs.vertcat(*S_list)])
        X = cs.vertcat(*[cs.vec(x) for x in xs])
        G = cs.vertcat(*g)
        self.nx, self.ng = X.numel(), G.numel()
        self._lbx, self._ubx = np.concatenate(lbx), np.concatenate(ubx)
        self._lbg, self._ubg = np.concatenate(lbg), np.concatenate(ubg)
        self._T = cs.Function("T", [X], [T * MgL])
        self._g = cs.Function("g", [X], [G])
        self._f = cs.Function("f", [X], [f])
        ipopt = dict(DEFAULT_IPOPT)
        ipopt.update({"print_level": 5 if s.verbose else 0, "sb": "yes"})
        ipopt.update(s.ipopt)
        nlp = {"x": X, "f": f, "g": G}
        self.solver = build_ipopt("gait_ocp", nlp, {"print_time": bool(s.verbose), "error_on_fail": False,
                                                    "ipopt": ipopt}, "OCPSettings.ipopt", s.ipopt)
        # later homotopy stages start from the previous stage's primal-dual point: a small initial
        # barrier parameter and bound push keep IPOPT from walking back into the interior
        self.solver_warm = build_ipopt("gait_ocp_warm", nlp, {"print_time": bool(s.verbose), "error_on_fail": False,
                                                              "ipopt": dict(WARM_IPOPT, **ipopt)},
                                       "OCPSettings.ipopt", s.ipopt)

    # ------------------------------------------------------------------ initial guess from a simulation
    def initial_guess(self, torque_signal) -> np.ndarray:
        """Variables sampled from event-driven simulations (one per scenario) of a torque input
        (a gait that simulates successfully, e.g. the best harmonic of :func:`best_harmonic`)."""
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
            W[8:12] = np.vstack([rb.mu1 * fn1 + ft[1:], rb.mu1 * fn1 - ft[1:], rb.mu2 * fn2 - ft[1:], rb.mu2 * fn2 + ft[1:]])
            W[8:12] = np.maximum(W[8:12], 0.0)
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
                    modes.append(int((Mode.SLIP1_POS, Mode.SLIP1_NEG, Mode.SLIP2_POS, Mode.SLIP2_NEG)[i]))
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

    def solve(self, x0: np.ndarray) -> tuple[np.ndarray | None, list[HomotopyRecord], str | None, str]:
        """Homotopies from x0, one per sigma0; returns the best accepted (x, history, failed stage, status).

        ``status`` is the return status (see :data:`~ocp_crawl.sim.mpcc.IPOPT_RETURN_STATUS`) of the solve that
        decided: the last accepted stage or polish of the kept homotopy, else the failed stage of the last
        homotopy, whose ``failed`` then names the stage (``x`` is that homotopy's last accepted iterate or None).
        """
        best = None
        runs = []
        f0 = float(self._f(x0))  # objective of the (nearly feasible) initial guess
        for sigma0 in self.settings.sigma0:
            x, hist, failed, status = self._homotopy(x0, sigma0)
            runs.append((x, hist, failed, status))
            if x is not None and failed is None:
                f = float(self._f(x))
                if best is None or f < best[0]:
                    best = (f, x, hist, failed, status)
            if best is not None and best[0] < f0:
                break  # improved on the initial guess: the next (tighter) start is not needed
        history = [h for r in runs for h in r[1]]
        self.kept_run = best[2] if best is not None else []
        if best is not None:
            return best[1], history, None, best[4]
        x, _, failed, status = runs[-1]
        if len(runs) > 1:
            failed = "; ".join(f"start sigma0 = {sigma0:.0e}: {r[2]} ({r[3]})"
                               for sigma0, r in zip(self.settings.sigma0, runs))
        return x, history, failed, status

    def _stage(self, solver, sigma: float, kind: str, **args) -> tuple[IpoptCall, HomotopyRecord]:
        """One IPOPT call, read through the status table, and its record."""
        t0 = time.perf_counter()
        call = call_ipopt(solver, self.nx, self.ng, **args)
        un = self.unpack(call.x)
        comp = max(sc["comp"] for sc in un["scen"])
        rec = HomotopyRecord(sigma, call.status, call.usable, call.iterations, comp, call.f,
                             tuple(sc["S"] for sc in un["scen"]), time.perf_counter() - t0, kind=kind,
                             message=call.describe())
        return call, rec

    def _homotopy(self, x0: np.ndarray, sigma0: float):
        """One relaxation homotopy from x0, then the polish: (x or None, records, failed stage or None, status)."""
        s = self.settings
        sig = sigma0
        sched = []
        while sig > s.sigma_min * (1 + 1e-9):
            sched.append(sig)
            sig *= s.sigma_factor
        sched.append(s.sigma_min)
        x, lam_x, lam_g = x0, None, None
        best = None
        hist = []
        comp_idx = [self._slices[f"g_comp_{j}"] for j in range(len(self.scen))]
        tie_idx = [self._slices[k] for k in self._slices if k.startswith("g_tie_")]
        for k, sigma in enumerate(sched):
            ubg = self._ubg.copy()
            lbg = self._lbg.copy()
            for sl in comp_idx:
                ubg[sl] = sigma
            for sl in tie_idx:
                lbg[sl] = -sigma
            args = dict(x0=x, lbx=self._lbx, ubx=self._ubx, lbg=lbg, ubg=ubg)
            solver = self.solver
            if lam_x is not None:
                args.update(lam_x0=lam_x, lam_g0=lam_g)
                solver = self.solver_warm
            call, rec = self._stage(solver, sigma, "homotopy", **args)
            hist.append(rec)
            if not call.usable:
                return best, hist, f"homotopy stage {k + 1}/{len(sched)} (sigma = {sigma:.1e})", call.status
            x, lam_x, lam_g = call.x, call.lam_x, call.lam_g
            best = call.x
        decided = hist[-1].return_status
        # polish: each pair on its identified branch (s_j = 0 or c_j = 0 as bounds), which removes
        # the O(sqrt(sigma)) residual of biactive pairs; kept only if IPOPT accepts it
        lbx, ubx = self._lbx.copy(), self._ubx.copy()
        N = s.nodes
        for j in range(len(self.scen)):
            sl = self._slices[f"w_{j}"]
            W = x[sl].reshape(NW, N, order="F")
            fix = np.zeros((NW, N), bool)
            fix[4:8] = W[4:8] <= W[8:12]
            fix[8:12] = ~fix[4:8]
            ub = ubx[sl].reshape(NW, N, order="F").copy()
            ub[fix] = 0.0
            ubx[sl] = ub.ravel(order="F")
        ubg = self._ubg.copy()
        lbg = self._lbg.copy()
        for sl in tie_idx:
            lbg[sl] = -s.sigma_min
        call, rec = self._stage(self.solver_warm, 0.0, "polish", x0=np.minimum(x, ubx), lbx=lbx, ubx=ubx, lbg=lbg,
                                ubg=ubg, lam_x0=lam_x, lam_g0=lam_g)
        hist.append(rec)
        if call.usable and rec.comp_residual <= hist[-2].comp_residual:
            best = call.x
            decided = call.status
        return best, hist, None, decided


def replay_signal(phase: np.ndarray, tau: np.ndarray) -> PeriodicPchip:
    """Torque input of the event-driven replay: periodic shape-preserving cubic (PCHIP) through the node
    torques [N m]: it keeps the envelope (no overshoot, unlike a cubic spline) and has a continuous
    derivative (unlike linear interpolation, whose jumps of d tau/dt make d' jump at every node)."""
    return PeriodicPchip(phase, tau)


def optimize_gait(robot: Robot, gravity: str = "physical", settings: OCPSettings | None = None,
                  replay: bool = True) -> OCPResult:
    """Solve the periodic-gait OCP, replay the optimum in the event-driven simulator, compare with harmonics."""
    settings = settings or OCPSettings()
    t_start = time.perf_counter()
    res = OCPResult(success=False, status=OCPStatus.SOLVER_FAILURE, message="", objective=settings.objective,
                    settings=settings)
    harm = best_harmonic(robot, gravity, settings)
    res.harmonic = harm
    if harm is None:
        res.status = OCPStatus.NO_INITIAL_GUESS
        res.message = "no harmonic gait of the envelope simulates successfully: no initial guess"
        return res
    ocp = GaitOCP(robot, gravity, settings)
    gait = Harmonic.from_degrees(harm.gamma_deg, harm.A_deg, harm.psi_deg)
    guess_sig = ReferenceTorque(gait, robot.k)
    x0 = ocp.initial_guess(guess_sig)
    x, hist, failed, status = ocp.solve(x0)
    res.homotopy = hist
    res.solve_time_s = time.perf_counter() - t_start
    outcome = ipopt_status(status)
    if failed is not None:
        # every homotopy failed: the status table decides infeasible vs solver failure
        res.failed_stage = failed
        res.status = OCPStatus.INFEASIBLE if outcome.kind == "infeasible" else OCPStatus.SOLVER_FAILURE
        res.message = (f"{'infeasible' if res.status == OCPStatus.INFEASIBLE else 'IPOPT failed'}: "
                       f"IPOPT {outcome.describe()} at {failed}")
    if x is None:
        return res
    un = ocp.unpack(x)
    N = settings.nodes
    res.phase = np.arange(N) / N
    res.tau = un["tau"]
    for sc, model in zip(un["scen"], ocp.scen):
        res.phi.append(sc["phi"])
        res.x1.append(sc["x1"])
        res.f_t.append(sc["f_t"])
        res.modes.append(sc["modes"])
        res.S_ocp.append(sc["S"])
        w = ocp.positive_work(res.tau, sc["phi"])
        res.W_plus_ocp.append(w)
        res.CoT_plus_ocp.append(cost_of_transport(w, model.robot, sc["S"]))
    res.complementarity_residual = max(sc["comp"] for sc in un["scen"])
    res.periodicity_residual = max(sc["periodic"] for sc in un["scen"])
    res.equation_residual = ocp.equation_residual(x)
    res.value_ocp = _value_from(settings, res.S_ocp, res.CoT_plus_ocp)
    if failed is not None:
        res.message += "; the last accepted iterate is reported (not an optimum)"
        return res
    numbers = [*res.S_ocp, *res.W_plus_ocp, res.complementarity_residual, res.periodicity_residual,
               res.equation_residual, *np.ravel(res.tau)]
    if not all(math.isfinite(v) for v in numbers):
        res.status = OCPStatus.SOLVER_FAILURE
        res.message = f"IPOPT returned {ipopt_status(status).describe()} but the solution has NaN or Inf values"
        return res
    if not res.complementarity_residual <= settings.comp_tol:
        res.status = OCPStatus.NOT_COMPLEMENTARY
        res.message = (f"complementarity residual {res.complementarity_residual:.2e} above {settings.comp_tol:.1e} "
                       "after the homotopy")
        return res
    res.success = True
    res.status = OCPStatus.SUCCESS
    res.message = f"optimal {settings.objective} profile found ({len(hist)} IPOPT calls, final IPOPT status " \
                  f"{status})"
    last = ocp.kept_run[-1] if ocp.kept_run else None
    if last is not None and last.kind == "polish" and not last.accepted:
        res.message += f"; polish not kept: IPOPT {last.message}"
    if replay:
        _replay(res, robot, gravity, settings, ocp)
    res.solve_time_s = time.perf_counter() - t_start
    return res


def _value_from(settings: OCPSettings, S: list, CoT: list, enforce_s_min: bool = False) -> float:
    """Objective value from S [m] and CoT+ per scenario (see :func:`objective_value`)."""
    dS = [settings.direction * v for v in S]
    if settings.objective == "max_speed":
        return dS[0]
    if settings.objective == "robust_speed":
        return float(np.mean(dS) if settings.robust == "mean" else np.min(dS))
    if dS[0] <= 0 or (enforce_s_min and dS[0] < settings.S_min):
        return float("inf")
    return CoT[0]


def _replay(res: OCPResult, robot: Robot, gravity: str, settings: OCPSettings, ocp: GaitOCP) -> None:
    sig = replay_signal(res.phase, res.tau)
    sims = [simulate_torque(m, sig) for m in ocp.scen]
    res.replay = sims
    if any(not r.success for r in sims):
        bad = next(r for r in sims if not r.success)
        res.success = False
        res.status = OCPStatus.REPLAY_FAILED
        res.message = f"the replay of the optimal profile failed: {bad.message}"
        return
    res.S_replay = [r.S for r in sims]
    res.W_plus_replay = [r.W_plus for r in sims]
    res.CoT_plus_replay = [r.CoT_plus for r in sims]
    res.value_replay = objective_value(settings, sims, enforce_s_min=False)
    res.rel_diff_replay = (abs(res.value_replay - res.value_ocp) / abs(res.value_replay) if res.value_replay != 0
                           else float("nan"))
    if res.harmonic is not None and math.isfinite(res.harmonic.value) and res.harmonic.value != 0:
        h = res.harmonic.value
        res.gain = (h - res.value_replay) / h if settings.objective == "min_cot" else (res.value_replay - h) / abs(h)
