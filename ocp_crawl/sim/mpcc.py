"""One quasistatic step as a mathematical program with complementarity constraints (MPCC), solved by IPOPT.

The step problem (incremental Coulomb friction, everything evaluated at the end of the step):
given the state after step k (phi_k, foot positions x1_k, x2_k) and the torque tau(t_{k+1}),
find phi_{k+1}, the tangential forces f_t1, f_t2 on the robot at the feet and, per foot, slip
increments s_i+, s_i- >= 0 (dx_i = s_i+ - s_i-) such that

* joint equilibrium F(phi_{k+1}, tau, f_t1) = 0 (the model's compiled residual, so the same gravity
  convention and physics as every other solver),
* horizontal balance f_t1 + f_t2 = 0,
* kinematic closure d(phi_{k+1}) - d(phi_k) = dx2 - dx1,
* Coulomb's law in incremental form, per foot i, with normal forces at phi_{k+1}:
  0 <= s_i+ _|_ mu_i f_n,i + f_t,i >= 0 and 0 <= s_i- _|_ mu_i f_n,i - f_t,i >= 0
  (a foot slipping towards +x needs the friction force f_t,i = -mu_i f_n,i, i.e. opposing motion).

The equations are those of :mod:`ocp_crawl.model.step_equations` (shared with the gait OCP), scaled
(forces by M g, lengths by L, torques by M g L) in the variables
w = (phi1, phi2, f_t1/Mg, f_t2/Mg, s1+/L, s1-/L, s2+/L, s2-/L, c1+, c1-, c2+, c2-) with the friction
margins c_j lifted into variables.  The IPOPT NLP is built once per :class:`MPCCStep` with the previous
angles, the torque, the robot parameter vector p, the homotopy parameter and tie-break weights as
NLP parameters, and reused for every step.  Complementarity is handled by one of

* ``"scholtes"`` (default): relaxation s_j c_j <= sigma, sigma driven from sigma0 to sigma_min < 1e-9;
  sigma enters only the constraint bounds, so the same solver serves every stage;
* ``"l1_penalty"``: exact l1 penalty of the complementarity (elastic mode): min sum_j s_j c_j / sigma
  subject to s, c >= 0 (each product is >= 0, so the sum is the l1 norm of the products), with the
  penalty 1/sigma raised along the same schedule until complementarity holds;
* ``"fischer_burmeister"``: smoothed Fischer-Burmeister equations s + c - sqrt(s^2 + c^2 + 2 sigma) = 0,
  i.e. s c = sigma with s, c > 0, sigma driven to sigma_min.

A step is accepted only when IPOPT's return status is usable by :data:`IPOPT_RETURN_STATUS` (the one table
through which the step, the time-stepping and the gait OCP read every solver outcome, see :func:`call_ipopt`)
and the complementarity and equation residuals are below tolerance; failed attempts are retried (cold
start, non-monotone sigma schedule, then the fallback formulation :data:`FALLBACK_FORMULATION`), and a step
that still fails returns a status of the table with NaN solution fields.  After the homotopy a polish can solve
the tightened NLP (each pair fixed to its identified branch, s_j = 0 or c_j = 0, with the other kept
>= 0) with the same IPOPT solver; this removes the O(sigma/s) bias of the relaxation and resolves
pairs near their corner (a slip that starts or stops within the step).

Exact ties: when the friction limits of the two feet are equal (mirror-symmetric configurations)
any split of the slip between the feet solves the step.  The small regularising objective then
prefers the pair that slipped in the previous step (the warm start's mode) and otherwise splits the
slip equally (mode ``SLIP_BOTH_*``).  With ``"l1_penalty"`` the penalty dominates the objective and
the split at an exact tie follows IPOPT's path.
"""
from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Literal, NamedTuple

import casadi as cs
import numpy as np

from ocp_crawl.model.statics import KIN, NP, Model, symbolic
from ocp_crawl.sim.result import Mode
from ocp_crawl.model.step_equations import NEQ, NPAIR, NW, step_equations

Formulation = Literal["scholtes", "l1_penalty", "fischer_burmeister"]
FORMULATIONS = ("scholtes", "l1_penalty", "fischer_burmeister")
Polish = Literal["auto", "always", "never"]
POLISH = ("auto", "always", "never")


class SolverOutcome(NamedTuple):
    """How the package reads one solver return status (a row of :data:`IPOPT_RETURN_STATUS`)."""

    status: str
    """the return status string (CasADi ``stats()['return_status']`` or one of this package's own)"""
    kind: str
    """our classification: 'success', 'acceptable', or a failure kind of :data:`FAILURE_KINDS`"""
    usable: bool
    """whether the point may be used (it still has to pass the caller's own residual checks)"""
    message: str
    """what it means, for a user"""
    source: str = "ipopt"
    """'ipopt' (IPOPT's ApplicationReturnStatus), 'casadi' (CasADi's own) or 'ocp_crawl' (this package's)"""

    def describe(self) -> str:
        """One line naming the status and its meaning, e.g. for failure messages."""
        return f"{self.status} ({self.message})"


#: failure kinds of :class:`SolverOutcome` (besides 'success' and 'acceptable'), in words
FAILURE_KINDS: dict[str, str] = {
    "infeasible": "no point satisfies the constraints (locally): the problem as posed has no solution there",
    "limit": "a resource limit (iterations, CPU or wall time) ended the solve before convergence",
    "no_progress": "the solver stalled or diverged (restoration failure, tiny or failed steps)",
    "invalid_number": "NaN or Inf in a function or derivative value (inputs or iterates out of range)",
    "setup": "the problem or the solver options are not valid for IPOPT",
    "residual": "the solver converged but the point fails this package's residual checks",
    "internal": "an error inside IPOPT or CasADi (exception, memory)",
    "no_solution": "the mode-enumeration oracle found no consistent contact mode",
    "unknown": "a status not in the table: treated as a failure",
}


def _o(status, kind, usable, message, source="ipopt"):
    return status, SolverOutcome(status, kind, usable, message, source)


#: The one table of solver return statuses: every IPOPT ``ApplicationReturnStatus`` (as the strings CasADi
#: reports in ``stats()['return_status']``), CasADi's own, and this package's.  MPCC steps (:class:`MPCCStep`),
#: the MPCC time-stepping, the cross-check and the gait OCP read solver outcomes only through
#: :func:`ipopt_status`; a status missing from the table maps to the 'unknown' failure, never a KeyError.
IPOPT_RETURN_STATUS: dict[str, SolverOutcome] = dict([
    # IPOPT (IpReturnCodes_inc.h, enum ApplicationReturnStatus)
    _o("Solve_Succeeded", "success", True, "optimal point found to the requested tolerance"),
    _o("Solved_To_Acceptable_Level", "acceptable", True,
       "point found to IPOPT's acceptable (looser) tolerance, not the requested one"),
    _o("Feasible_Point_Found", "acceptable", True, "feasible point of a square problem found"),
    _o("Infeasible_Problem_Detected", "infeasible", False,
       "IPOPT converged to a point of local infeasibility: the constraints cannot be met there"),
    _o("Search_Direction_Becomes_Too_Small", "no_progress", False,
       "the search direction became too small: IPOPT stopped without confirming a solution"),
    _o("Diverging_Iterates", "no_progress", False, "the iterates diverge (problem unbounded or badly scaled?)"),
    _o("User_Requested_Stop", "limit", False, "stopped early by a user callback"),
    _o("Maximum_Iterations_Exceeded", "limit", False, "maximum number of IPOPT iterations (max_iter) exceeded"),
    _o("Maximum_CpuTime_Exceeded", "limit", False, "maximum CPU time (max_cpu_time) exceeded"),
    _o("Maximum_WallTime_Exceeded", "limit", False, "maximum wall-clock time (max_wall_time) exceeded"),
    _o("Restoration_Failed", "no_progress", False,
       "the feasibility restoration phase failed (no feasible point found from here)"),
    _o("Error_In_Step_Computation", "no_progress", False,
       "error in the step computation (singular or ill-conditioned KKT system)"),
    _o("Not_Enough_Degrees_Of_Freedom", "setup", False, "more equality constraints than free variables"),
    _o("Invalid_Problem_Definition", "setup", False,
       "invalid problem definition (e.g. a lower bound above an upper one)"),
    _o("Invalid_Option", "setup", False, "an IPOPT option is invalid or needs a library that is not available"),
    _o("Invalid_Number_Detected", "invalid_number", False,
       "NaN or Inf in a function or derivative value (inputs or iterates out of range)"),
    _o("Unrecoverable_Exception", "internal", False, "unrecoverable exception inside IPOPT"),
    _o("NonIpopt_Exception_Thrown", "internal", False, "exception thrown outside IPOPT (function evaluation?)"),
    _o("Insufficient_Memory", "internal", False, "IPOPT ran out of memory"),
    _o("Internal_Error", "internal", False, "internal IPOPT error"),
    # CasADi: its name for an IPOPT code it does not know, and an exception raised by the solver call
    _o("Unknown", "unknown", False, "CasADi reported IPOPT's return code as unknown", "casadi"),
    _o("Solver_Exception", "internal", False,
       "CasADi raised an exception from the solver call (evaluation error or invalid input)", "casadi"),
    # this package: IPOPT accepted the point but our own checks did not; the mode-enumeration oracle
    _o("Residual_Check_Failed", "residual", False,
       "IPOPT converged but the complementarity or equation residual exceeds the tolerance", "ocp_crawl"),
    _o("Enumeration_Succeeded", "success", True, "mode-enumeration oracle: consistent contact mode found",
       "ocp_crawl"),
    _o("No_Consistent_Mode", "no_solution", False, "mode-enumeration oracle: no consistent contact mode",
       "ocp_crawl"),
])

#: the kind of a status missing from :data:`IPOPT_RETURN_STATUS`
UNKNOWN_KIND = "unknown"


def ipopt_status(return_status) -> SolverOutcome:
    """The :class:`SolverOutcome` of a return status; a status not in the table is a failure of kind 'unknown'."""
    status = str(return_status)
    out = IPOPT_RETURN_STATUS.get(status)
    if out is None:
        return SolverOutcome(status, UNKNOWN_KIND, False,
                             f"unknown solver return status {status!r} (not in the table): treated as a failure",
                             "unknown")
    return out


@dataclass(frozen=True)
class IpoptCall:
    """Outcome of one solver call through :func:`call_ipopt` (the primal-dual point as NumPy arrays)."""

    outcome: SolverOutcome
    x: np.ndarray
    lam_x: np.ndarray
    lam_g: np.ndarray
    f: float
    iterations: int
    detail: str = ""
    """the exception text when CasADi raised (status Solver_Exception), else ''"""

    @property
    def status(self) -> str:
        return self.outcome.status

    @property
    def usable(self) -> bool:
        """the table says the point may be used, and it is finite"""
        return self.outcome.usable and bool(np.all(np.isfinite(self.x)))

    def describe(self) -> str:
        text = self.outcome.describe()
        if self.detail:
            text += f": {self.detail}"
        elif self.outcome.usable and not self.usable:
            text += ", but the point is not finite"
        return text


def call_ipopt(solver: cs.Function, nx: int, ng: int, **args) -> IpoptCall:
    """Call a CasADi IPOPT ``solver`` and read its outcome through :data:`IPOPT_RETURN_STATUS`.

    An exception raised by the call (CasADi evaluation errors, invalid inputs) is caught and reported as
    ``Solver_Exception`` with its first line; the point is then the initial guess ``x0`` (not usable).
    """
    try:
        sol = solver(**args)
    except RuntimeError as exc:
        detail = _casadi_reason(exc)
        x0 = np.asarray(args.get("x0", np.full(nx, np.nan)), float).ravel()
        return IpoptCall(ipopt_status("Solver_Exception"), x0, np.zeros(nx), np.zeros(ng), float("nan"), 0, detail)
    st = solver.stats()
    return IpoptCall(ipopt_status(st.get("return_status", "Unknown")), np.asarray(sol["x"], float).ravel(),
                     np.asarray(sol["lam_x"], float).ravel(), np.asarray(sol["lam_g"], float).ravel(),
                     float(sol["f"]), int(st.get("iter_count", 0)))


#: types of IPOPT option values
_IPOPT_VALUE_TYPES = (str, int, float, np.integer, np.floating)


def check_ipopt_options(owner: str, options) -> dict:
    """A copy of a dict of IPOPT options with string keys and finite number or string values (ValueError/TypeError
    naming ``owner`` and the key otherwise); IPOPT itself checks names and ranges when the solver is built."""
    if not isinstance(options, dict):
        raise TypeError(f"{owner} must be a dict of IPOPT options, got {type(options).__name__}")
    out = {}
    for key, value in options.items():
        if not isinstance(key, str) or not key:
            raise TypeError(f"{owner}: IPOPT option names must be strings, got {key!r}")
        if isinstance(value, bool) or not isinstance(value, _IPOPT_VALUE_TYPES):
            raise TypeError(f"{owner}[{key!r}] must be a number or a string, got {value!r} ({type(value).__name__})")
        if isinstance(value, (float, np.floating)) and not math.isfinite(value):
            raise ValueError(f"{owner}[{key!r}] must be finite, got {value!r}")
        out[key] = value.item() if isinstance(value, (np.integer, np.floating)) else value
    return out


def _casadi_reason(exc: BaseException) -> str:
    """The informative line of a CasADi exception: its text without source locations and the generic
    "Error in Function::call ..." / "Error calling ..." wrappers."""
    lines = [re.sub(r"^\S*\.(?:cpp|hpp|h):\d+:\s*", "", s.strip()) for s in str(exc).splitlines()]
    lines = [s for s in lines if s and not s.startswith(("Error in Function::", "Error calling "))]
    if not lines:
        return (str(exc).strip().splitlines() or [type(exc).__name__])[-1]
    return f"{lines[0]} {lines[1]}" if lines[0].endswith(":") and len(lines) > 1 else lines[0]


def build_ipopt(name: str, nlp: dict, options: dict, owner: str, user_options: dict) -> cs.Function:
    """The CasADi IPOPT solver of ``nlp`` with ``options`` (the package's only nlpsol call).

    IPOPT's rejection of an option (unknown name, wrong type, out of range) becomes one ValueError naming
    ``owner`` and the user's options instead of a CasADi traceback."""
    try:
        return cs.nlpsol(name, "ipopt", nlp, options)
    except RuntimeError as exc:
        raise ValueError(f"{owner} = {user_options!r}: IPOPT rejected the options: {_casadi_reason(exc)}") from None


#: IPOPT options of the step solver; :attr:`MPCCOptions.ipopt` overrides them key by key.
DEFAULT_IPOPT: dict = {
    "tol": 1e-12,
    "acceptable_tol": 1e-9,
    "constr_viol_tol": 1e-12,
    "max_iter": 150,
    "mu_strategy": "monotone",
}

#: options of the warm-started solver: start close to the central path of the previous solution
WARM_IPOPT: dict = {
    "warm_start_init_point": "yes",
    "mu_init": 1e-9,
    "warm_start_bound_push": 1e-12,
    "warm_start_bound_frac": 1e-12,
    "warm_start_slack_bound_push": 1e-12,
    "warm_start_slack_bound_frac": 1e-12,
    "warm_start_mult_bound_push": 1e-12,
}


def _real(name: str, value, *, positive: bool = True) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"MPCCOptions.{name} must be a real number, got {value!r} ({type(value).__name__})")
    value = float(value)
    if not math.isfinite(value) or (positive and value <= 0):
        raise ValueError(f"MPCCOptions.{name} must be a positive finite number, got {value!r}")
    return value


@dataclass(frozen=True)
class MPCCOptions:
    """Options of the MPCC step solver (all residuals and sigma are in the scaled variables)."""

    formulation: Formulation = "scholtes"
    """complementarity handling: 'scholtes' | 'l1_penalty' | 'fischer_burmeister'"""
    sigma0: float = 1e-2
    """first homotopy parameter of a cold start [-] (penalty formulation: first penalty 1/sigma0)"""
    sigma0_warm: float = 1e-12
    """first homotopy parameter when warm-started from a previous step's solution [-]: the previous
    steps have already followed the path, so one IPOPT call at the final sigma suffices (measured:
    about 6 iterations instead of about 19 for the stages 1e-8, 1e-10, 1e-12)"""
    sigma_min: float = 1e-12
    """last homotopy parameter [-]; must be < 1e-9"""
    sigma_factor: float = 1e-2
    """ratio of consecutive homotopy parameters, in (0, 1)"""
    comp_tol: float = 1e-8
    """largest accepted complementarity residual max_j |min(s_j/L, c_j/(M g))| [-]"""
    eq_tol: float = 1e-9
    """largest accepted residual of the scaled equations and bounds [-]"""
    max_retries: int = 3
    """a failed attempt is retried up to this many times: after a warm start from a cold start, then
    (and after a failed cold start) with a non-monotone sigma schedule from a guess with small slips,
    and last with the fallback formulation (:data:`FALLBACK_FORMULATION`) from a cold start"""
    polish: Polish = "auto"
    """after the homotopy, solve the tightened NLP on the identified branches (exact complementarity):
    'always', 'never', or 'auto' = only when the homotopy's complementarity residual exceeds comp_tol
    (saves one IPOPT call on most warm-started steps; the relaxation then leaves |min(s_j, c_j)| <= comp_tol,
    about 1e-10 rad in phi)"""
    ipopt: dict = field(default_factory=dict)
    """IPOPT options passed through (copied per instance); override :data:`DEFAULT_IPOPT`"""
    verbose: bool = False
    """let IPOPT print its iterations"""

    def __post_init__(self) -> None:
        if self.formulation not in FORMULATIONS:
            raise ValueError(f"MPCCOptions.formulation must be one of {FORMULATIONS}, got {self.formulation!r}")
        for name in ("sigma0", "sigma0_warm", "sigma_min", "sigma_factor", "comp_tol", "eq_tol"):
            object.__setattr__(self, name, _real(name, getattr(self, name)))
        if not self.sigma_min < 1e-9:
            raise ValueError(f"MPCCOptions.sigma_min must be < 1e-9, got {self.sigma_min!r}")
        for name in ("sigma0", "sigma0_warm"):
            if getattr(self, name) < self.sigma_min:
                raise ValueError(f"MPCCOptions.{name} must be >= sigma_min = {self.sigma_min!r}, "
                                 f"got {getattr(self, name)!r}")
        if not self.sigma_factor < 1:
            raise ValueError(f"MPCCOptions.sigma_factor must be in (0, 1), got {self.sigma_factor!r}")
        if isinstance(self.max_retries, bool) or not isinstance(self.max_retries, (int, np.integer)) \
                or self.max_retries < 0:
            raise ValueError(f"MPCCOptions.max_retries must be an integer >= 0, got {self.max_retries!r}")
        if self.polish not in POLISH:
            raise ValueError(f"MPCCOptions.polish must be one of {POLISH}, got {self.polish!r}")
        if not isinstance(self.verbose, bool):
            raise TypeError(f"MPCCOptions.verbose must be a bool, got {self.verbose!r}")
        object.__setattr__(self, "ipopt", check_ipopt_options("MPCCOptions.ipopt", self.ipopt))

    def schedule(self, sigma0: float, factor: float | None = None) -> tuple[float, ...]:
        """Homotopy parameters from sigma0, divided by 1/``factor`` down to sigma_min (the last one)."""
        factor = self.sigma_factor if factor is None else factor
        out = []
        s = sigma0
        while s > self.sigma_min * (1 + 1e-12):
            out.append(s)
            s *= factor
        out.append(self.sigma_min)
        return tuple(out)


@dataclass(frozen=True)
class StepState:
    """State after step k: joint angles [rad], foot positions [m], and the tangential force [N]
    (the force only seeds initial guesses; it is not part of the step problem's data)."""

    phi: np.ndarray
    x1: float
    x2: float
    f_t: float = 0.0

    def __post_init__(self) -> None:
        phi = np.asarray(self.phi, dtype=float).reshape(-1)
        if phi.shape != (2,) or not np.all(np.isfinite(phi)):
            raise ValueError(f"StepState.phi must be 2 finite angles [rad], got {self.phi!r}")
        object.__setattr__(self, "phi", phi)
        for name in ("x1", "x2", "f_t"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v):
                raise ValueError(f"StepState.{name} must be a finite real number, got {v!r}")
            object.__setattr__(self, name, float(v))


@dataclass(frozen=True)
class HomotopyStage:
    """One IPOPT call of a step: homotopy parameter, status, iterations, residual, wall time [s]."""

    attempt: int
    sigma: float
    """sigma of the stage (NaN for the polish solve)"""
    return_status: str
    accepted: bool
    iterations: int
    comp_residual: float
    time: float
    kind: str = "homotopy"
    """'homotopy' or 'polish'"""


@dataclass(frozen=True)
class StepResult:
    """Outcome of one step.  Forces [N] act on the robot; slips [m]; ``mode`` from the slips/forces.

    ``status`` is the IPOPT return status of the decisive solve (for the mode-enumeration oracle a
    status of its own); ``comp_residual`` = max over the four pairs of |min(s_j/L, c_j/(M g))|.
    """

    success: bool
    status: str
    """IPOPT return status (see :data:`IPOPT_RETURN_STATUS`) or the oracle's own status"""
    message: str
    phi: np.ndarray
    """joint angles after the step [rad], shape (2,)"""
    f_t: float
    """tangential force on the robot at foot 1 along +x [N] (at foot 2 it is -f_t)"""
    f_n1: float
    """normal force at foot 1 after the step [N]"""
    f_n2: float
    """normal force at foot 2 after the step [N]"""
    s1p: float
    """slip of foot 1 towards +x [m] (>= 0)"""
    s1m: float
    """slip of foot 1 towards -x [m] (>= 0)"""
    s2p: float
    """slip of foot 2 towards +x [m] (>= 0)"""
    s2m: float
    """slip of foot 2 towards -x [m] (>= 0)"""
    dx1: float
    """displacement of foot 1 [m] = s1p - s1m"""
    dx2: float
    """displacement of foot 2 [m] = s2p - s2m"""
    x1: float
    """position of foot 1 after the step [m]"""
    x2: float
    """position of foot 2 after the step [m]"""
    d: float
    """d(phi) after the step [m]"""
    mode: Mode
    """contact mode from the slips and friction margins (:func:`mode_from_pairs`)"""
    comp_residual: float
    """max_j |min(s_j/L, c_j/(M g))| [-]"""
    eq_residual: float
    """largest scaled residual of the equilibrium, balance and closure equations and the bounds [-]"""
    iterations: int
    """IPOPT iterations (Newton iterations for the oracle), all attempts"""
    solve_time: float
    """wall time of the step [s]"""
    homotopy: tuple = ()
    """:class:`HomotopyStage` records of every IPOPT call, all attempts"""
    attempts: int = 1
    """attempts used (1 = no retry)"""
    w: np.ndarray | None = None
    """scaled primal solution (warm start of the next step)"""
    lam_x: np.ndarray | None = None
    """multipliers of the variable bounds (warm start)"""
    lam_g: np.ndarray | None = None
    """multipliers of the constraints (warm start)"""
    extra: dict = field(default_factory=dict)

    @property
    def slips(self) -> np.ndarray:
        return np.array([self.s1p, self.s1m, self.s2p, self.s2m])

    def next_state(self) -> StepState:
        """The state after this step (input of the next one)."""
        return StepState(self.phi, self.x1, self.x2, self.f_t)


#: a scaled slip below this is no slip (round-off of the solvers); classifies modes at a corner s = c = 0
SLIP_EPS = 1e-12
SLIP_PAIR_MODES = (Mode.SLIP1_POS, Mode.SLIP1_NEG, Mode.SLIP2_POS, Mode.SLIP2_NEG)
#: both feet count as slipping (SLIP_BOTH_*) when the smaller foot slip is at least this part of the larger
BOTH_RATIO = 1e-3
#: pairs left near their corner by the homotopy that the polish may try on the other branch
POLISH_FLIPS = 2


@lru_cache(maxsize=1)
def step_outputs() -> cs.Function:
    """(z[8], P[4+NP]) -> out[10]: f_n1/Mg, f_n2/Mg, d [m], d_k [m], margins[4]/Mg, equation residual,
    complementarity residual, for a point z = (phi, f_t1/Mg, f_t2/Mg, s/L) of the step from phi_k
    with P = (phi_k, tau/(M g L), p).  Built once per process from the shared step equations."""
    z = cs.SX.sym("z", 8)
    P = cs.SX.sym("P", 4 + NP)
    phi_k, tau_hat, p = P[0:2], P[2:4], P[4:4 + NP]
    # with the lifted margins set to zero, the lifting residual is minus the margins
    g_eq, g_lift, s, _ = step_equations(phi_k, cs.vertcat(z, cs.SX.zeros(NPAIR)), tau_hat, p)
    c = -g_lift
    sym = symbolic()
    Mg = p[0] * p[6]
    kin1 = sym.kin(z[0:2], p)
    kin0 = sym.kin(phi_k, p)
    eq = cs.fmax(cs.mmax(cs.fabs(g_eq)), cs.fmax(cs.mmax(cs.fmax(-s, 0)), cs.mmax(cs.fmax(-c, 0))))
    comp = cs.mmax(cs.fabs(cs.fmin(s, c)))
    out = cs.vertcat(kin1[KIN["fn1"]] / Mg, kin1[KIN["fn2"]] / Mg, kin1[KIN["d"]], kin0[KIN["d"]], c, eq, comp)
    return cs.Function("step_outputs", [z, P], [out], ["z", "P"], ["out"])


def mode_from_pairs(s: np.ndarray, c: np.ndarray) -> tuple[Mode, int]:
    """Contact mode from the scaled pairs (s1+, s1-, s2+, s2-): pair j slips when s_j > max(c_j, SLIP_EPS).

    Returns (mode, number of slipping pairs).  Both feet slipping (possible only when the friction
    limits are equal, e.g. mirror-symmetric gaits) is ``SLIP_BOTH_*`` when the smaller foot slip is
    at least ``BOTH_RATIO`` of the larger and the two move the feet the same way in d; otherwise the
    pair with the largest slip gives the mode.
    """
    slipping = [j for j in range(NPAIR) if s[j] > c[j] and s[j] > SLIP_EPS]
    if not slipping:
        return Mode.STICK, 0
    j = max(slipping, key=lambda i: s[i])
    feet = {0 if i < 2 else 1: i for i in slipping}
    if len(feet) == 2:
        i1, i2 = feet[0], feet[1]
        # d' sign of each foot's slip: foot 1 moving -x (s1-) and foot 2 moving +x (s2+) open the feet
        sig1, sig2 = (-1 if i1 == 0 else 1), (1 if i2 == 2 else -1)
        if sig1 == sig2 and min(s[i1], s[i2]) >= BOTH_RATIO * max(s[i1], s[i2]):
            return (Mode.SLIP_BOTH_POS if sig1 > 0 else Mode.SLIP_BOTH_NEG), len(slipping)
    return SLIP_PAIR_MODES[j], len(slipping)


def step_params(model: Model, state: StepState, tau: np.ndarray) -> np.ndarray:
    """Parameter vector (phi_k, tau/(M g L), p) of the scaled step equations."""
    r = model.robot
    return np.concatenate([state.phi, tau / (r.M * r.g * r.L), model.p])


def step_result_from_w(model: Model, state: StepState, z: np.ndarray, tau: np.ndarray, **fields) -> StepResult:
    """Physical step result from a scaled solution z = (phi, f_t1/Mg, f_t2/Mg, s/L, ...) (MPCC and oracle)."""
    r = model.robot
    Mg, L = r.M * r.g, r.L
    z = np.asarray(z, float)
    out = np.asarray(step_outputs()(z[:8], step_params(model, state, tau))).ravel()
    s, c = z[4:8], out[4:8]
    mode, nslip = mode_from_pairs(s, c)
    sl = s * L
    dx1, dx2 = float(sl[0] - sl[1]), float(sl[2] - sl[3])
    extra = dict(fields.pop("extra", {}), slipping_pairs=nslip, margins=c.tolist())
    return StepResult(phi=z[:2].copy(), f_t=float(z[2] * Mg), f_n1=float(out[0] * Mg), f_n2=float(out[1] * Mg),
                      s1p=float(sl[0]), s1m=float(sl[1]), s2p=float(sl[2]), s2m=float(sl[3]),
                      dx1=dx1, dx2=dx2, x1=state.x1 + dx1, x2=state.x2 + dx2, d=float(out[2]), mode=mode,
                      comp_residual=float(out[9]), eq_residual=float(out[8]), extra=extra, **fields)


def _check_tau(tau) -> np.ndarray:
    tau = np.asarray(tau, dtype=float).reshape(-1)
    if tau.shape != (2,) or not np.all(np.isfinite(tau)):
        raise ValueError(f"tau must be 2 finite joint torques [N m], got {tau!r}")
    return tau


@dataclass
class _Solve:
    w: np.ndarray
    lam_x: np.ndarray
    lam_g: np.ndarray
    status: str
    accepted: bool
    iterations: int
    eq: float = math.inf
    comp: float = math.inf
    s: np.ndarray | None = None
    c: np.ndarray | None = None
    text: str = ""
    """the status (with CasADi's exception text), for messages"""


#: formulation of the last retry of a step, per primary formulation
FALLBACK_FORMULATION = {"scholtes": "l1_penalty", "fischer_burmeister": "l1_penalty",
                        "l1_penalty": "fischer_burmeister"}

#: the numeric fields of a StepResult that a successful step must have finite
RESULT_FIELDS = ("f_t", "f_n1", "f_n2", "s1p", "s1m", "s2p", "s2m", "dx1", "dx2", "x1", "x2", "d", "comp_residual",
                 "eq_residual")


def _finite_result(res: StepResult) -> bool:
    return bool(np.all(np.isfinite(res.phi))) and all(math.isfinite(getattr(res, f)) for f in RESULT_FIELDS)


def failed_step_result(model: Model, state: StepState, tau: np.ndarray, **fields) -> StepResult:
    """A failed :class:`StepResult`: every solution field is NaN, so that nothing can pass for a solution."""
    nan = float("nan")
    return StepResult(success=False, phi=np.full(2, nan), f_t=nan, f_n1=nan, f_n2=nan, s1p=nan, s1m=nan,
                      s2p=nan, s2m=nan, dx1=nan, dx2=nan, x1=nan, x2=nan, d=nan, mode=Mode.STICK,
                      comp_residual=nan, eq_residual=nan, **fields)


class MPCCStep:
    """The step MPCC of one model: the NLP is built once here and reused by :meth:`solve`."""

    def __init__(self, model: Model, options: MPCCOptions | None = None):
        if not isinstance(model, Model):
            raise TypeError(f"model must be a Model, got {type(model).__name__}")
        options = MPCCOptions() if options is None else options
        if not isinstance(options, MPCCOptions):
            raise TypeError(f"options must be MPCCOptions, got {type(options).__name__}")
        self.model = model
        self.options = options
        r = model.robot
        self.Mg = r.M * r.g
        self.ncalls = 0
        """IPOPT calls made by this instance (including its fallback solver)"""
        self._fallback: MPCCStep | None = None
        self._build()

    # ------------------------------------------------------------------ NLP construction (once)
    def _build(self) -> None:
        opt = self.options
        w = cs.SX.sym("w", NW)
        P = cs.SX.sym("P", 4 + NP + 1 + NPAIR)
        sigma, weights = P[4 + NP], P[5 + NP:]
        # the friction margins are lifted into variables c_j (c_j = margin_j, c_j >= 0 as simple
        # bounds): the complementarity then couples two variables, which keeps the relaxed NLP far
        # better conditioned near the corner, and a warm start can sit strictly inside it
        g_eq, g_lift, s, c = step_equations(P[0:2], w, P[2:4], P[4:4 + NP])
        margins = c - g_lift
        # a small dissipation-like objective removes the non-uniqueness of the relaxed problems
        # (s+ and s- of one foot both positive) without moving the MPCC solution.  It also decides
        # exact ties (equal friction limits, where any split of the slip between the feet solves
        # the step): the linear weights favour the pair that slipped in the previous step, and
        # without a preference the quadratic term splits the slip equally (mirror-symmetric gaits)
        f_reg = 1e-3 * (cs.dot(weights, s) + cs.sumsqr(s))
        if opt.formulation == "scholtes":
            g_comp = s * c
            f = f_reg
        elif opt.formulation == "fischer_burmeister":
            g_comp = s + c - cs.sqrt(s**2 + c**2 + 2 * sigma)
            f = f_reg
        else:
            g_comp = cs.SX(0, 1)
            f = cs.dot(s, c) / sigma + f_reg
        g = cs.vertcat(g_eq, g_lift, g_comp)
        self.ng = g.shape[0]
        # residuals of a point in one call: equations (with lifting and bounds) and complementarity
        # measured on the margins computed from phi and f_t, not on the lifted copies
        eq = cs.fmax(cs.mmax(cs.fabs(cs.vertcat(g_eq, g_lift))), cs.mmax(cs.fmax(-w[4:12], 0)))
        comp = cs.mmax(cs.fabs(cs.fmin(s, margins)))
        self._check = cs.Function("mpcc_check", [w, P], [cs.vertcat(eq, comp, margins)])
        self._margins = cs.Function("mpcc_margins", [w, P], [margins])

        ipopt = dict(DEFAULT_IPOPT)
        ipopt.update({"print_level": 5 if opt.verbose else 0, "sb": "yes"})
        ipopt.update(opt.ipopt)
        base = {"print_time": bool(opt.verbose), "calc_lam_p": False, "error_on_fail": False, "ipopt": ipopt}
        warm = dict(base, ipopt=dict(WARM_IPOPT, **ipopt))
        nlp = {"x": w, "p": P, "f": f, "g": g}
        self._solver_cold = build_ipopt("mpcc_step_cold", nlp, base, "MPCCOptions.ipopt", opt.ipopt)
        self._solver_warm = build_ipopt("mpcc_step_warm", nlp, warm, "MPCCOptions.ipopt", opt.ipopt)
        inf = np.inf
        self._lbx = np.concatenate([np.full(4, -inf), np.zeros(2 * NPAIR)])
        self._ubx = np.full(NW, inf)
        self._lbg = np.zeros(self.ng)
        self._ubg = np.zeros(self.ng)
        if opt.formulation == "scholtes":
            self._lbg[NEQ + NPAIR:] = -inf

    # ------------------------------------------------------------------ primitives
    def _params(self, state: StepState, tau: np.ndarray, sigma: float, prefer: Mode = Mode.STICK) -> np.ndarray:
        weights = np.ones(NPAIR)
        if prefer in SLIP_PAIR_MODES:
            weights[SLIP_PAIR_MODES.index(prefer)] = 0.5
        return np.concatenate([step_params(self.model, state, tau), [sigma], weights])

    def _bounds(self, sigma: float):
        ubg = self._ubg
        if self.options.formulation == "scholtes":
            ubg = ubg.copy()
            ubg[NEQ + NPAIR:] = sigma
        return self._lbx, self._ubx, self._lbg, ubg

    def _call(self, solver, w0, lam_x, lam_g, P, lbx, ubx, lbg, ubg) -> _Solve:
        args = {"x0": w0, "p": P, "lbx": lbx, "ubx": ubx, "lbg": lbg, "ubg": ubg}
        if lam_x is not None:
            args["lam_x0"] = lam_x
            args["lam_g0"] = lam_g
        call = call_ipopt(solver, NW, self.ng, **args)
        self.ncalls += 1
        w = call.x
        chk = np.asarray(self._check(w, P)).ravel()
        text = call.status + (f": {call.detail}" if call.detail else "") + \
            (", but the point is not finite" if call.outcome.usable and not call.usable else "")
        return _Solve(w, call.lam_x, call.lam_g, call.status, call.usable, call.iterations, float(chk[0]),
                      float(chk[1]), w[4:8], chk[2:6], text)

    # ------------------------------------------------------------------ solve
    def initial_guess(self, state: StepState, tau: np.ndarray, slip: float = 0.0) -> np.ndarray:
        """Cold-start point: the previous configuration and force, slips ``slip`` (scaled), and the
        lifted margins evaluated there (clipped to >= 0)."""
        ft = state.f_t / self.Mg
        w = np.concatenate([state.phi, [ft, -ft], np.full(NPAIR, slip), np.zeros(NPAIR)])
        w[8:12] = np.maximum(np.asarray(self._margins(w, self._params(state, tau, 1.0))).ravel(), 0.0)
        return w

    def _fallback_step(self) -> "MPCCStep":
        """The step solver of the fallback formulation (built on first use): cold start and the
        non-monotone retry, no further fallback."""
        if self._fallback is None:
            opt = self.options
            self._fallback = MPCCStep(self.model, replace(opt, formulation=FALLBACK_FORMULATION[opt.formulation],
                                                          max_retries=1))
        return self._fallback

    def _plans(self, state: StepState, tau: np.ndarray, warm_start: StepResult | None):
        """(label, initial point, multipliers, sigma schedule) of the first attempt and the retries."""
        opt = self.options
        plans = []
        if warm_start is not None:
            if not isinstance(warm_start, StepResult):
                raise TypeError(f"warm_start must be a StepResult or None, got {type(warm_start).__name__}")
            # a warm start is used only if it is a complete finite primal-dual point of this NLP
            if warm_start.success and warm_start.w is not None and warm_start.w.shape == (NW,) \
                    and warm_start.lam_x is not None and warm_start.lam_x.shape == (NW,) \
                    and warm_start.lam_g is not None and warm_start.lam_g.shape == (self.ng,) \
                    and all(np.all(np.isfinite(a)) for a in (warm_start.w, warm_start.lam_x, warm_start.lam_g)):
                plans.append(("warm start", warm_start.w.copy(), warm_start.lam_x, warm_start.lam_g,
                              opt.schedule(opt.sigma0_warm)))
        plans.append(("cold start", self.initial_guess(state, tau), None, None, opt.schedule(opt.sigma0)))
        # non-monotone schedule: back up to a larger sigma, then decrease more slowly, from a point
        # with a small slip in every pair (pairs start away from their corner)
        up = min(1.0, 100.0 * opt.sigma0)
        sched = (opt.sigma0, up) + opt.schedule(up, math.sqrt(opt.sigma_factor))[1:]
        plans.append(("non-monotone sigma", self.initial_guess(state, tau, slip=1e-3), None, None, sched))
        return plans[:1 + opt.max_retries]

    def solve(self, state: StepState, tau, warm_start: StepResult | None = None) -> StepResult:
        """Solve the step from ``state`` with the torque ``tau`` [N m] at t_{k+1}.

        ``warm_start``: a previous successful step's result whose primal and dual solution seed IPOPT (the
        homotopy then starts at ``sigma0_warm``) and whose slip is preferred at exact ties; failed
        attempts are retried from a cold start, then with a non-monotone sigma schedule, then with the
        fallback formulation (up to ``max_retries`` retries in all).  A failed step's status is that of the
        last failed attempt of the primary formulation (:data:`IPOPT_RETURN_STATUS`, or
        ``Residual_Check_Failed``); its solution fields are NaN.
        """
        if not isinstance(state, StepState):
            raise TypeError(f"state must be a StepState, got {type(state).__name__}")
        tau = _check_tau(tau)
        opt = self.options
        t_start = time.perf_counter()
        stages: list[HomotopyStage] = []
        reasons = []
        status = "Unknown"
        plans = self._plans(state, tau, warm_start)
        prefer = warm_start.mode if warm_start is not None and warm_start.success else Mode.STICK
        for attempt, (label, w0, lam_x, lam_g, sched) in enumerate(plans):
            sol, reason, status = self._homotopy(attempt, state, tau, prefer, w0, lam_x, lam_g, sched, stages)
            if sol is None:
                reasons.append(f"{label}: {reason}")
                continue
            polished = False
            if opt.polish == "always" or (opt.polish == "auto" and not sol.comp <= opt.comp_tol):
                pol = self._polish(attempt, state, tau, prefer, sol, stages)
                if pol is not None:
                    sol, polished = pol, True
            if not sol.comp <= opt.comp_tol:
                status = "Residual_Check_Failed"
                reasons.append(f"{label}: complementarity residual {sol.comp:.3g} > comp_tol = {opt.comp_tol:g} "
                               f"(IPOPT {sol.status})")
                continue
            ncalls = sum(s.attempt == attempt for s in stages)
            res = step_result_from_w(
                self.model, state, sol.w, tau, success=True, status=sol.status,
                message=f"step solved ({label}, {ncalls} IPOPT calls{', polished' if polished else ''})",
                iterations=sum(s.iterations for s in stages), solve_time=time.perf_counter() - t_start,
                homotopy=tuple(stages), attempts=attempt + 1, w=sol.w, lam_x=sol.lam_x, lam_g=sol.lam_g,
                extra={"polished": polished})
            if not _finite_result(res):
                status = "Residual_Check_Failed"
                reasons.append(f"{label}: the solution has non-finite values (IPOPT {sol.status})")
                continue
            return res
        if len(plans) < 1 + opt.max_retries:
            # a retry is left: the fallback formulation, whose relaxation path differs (measured: Scholtes'
            # homotopy can end in a local infeasibility at sigma ~ 1e-6 on soft robots, k ~ 0.1 M g L, where the
            # l1 penalty finds the step); its failure keeps the primary formulation's status
            fb = self._fallback_step()
            calls = fb.ncalls
            res = fb.solve(state, tau)
            self.ncalls += fb.ncalls - calls
            label = f"fallback {fb.options.formulation}"
            stages += [replace(h, attempt=h.attempt + len(plans)) for h in res.homotopy]
            attempts = len(plans) + res.attempts
            if res.success:
                return replace(res, message=f"step solved ({label}, after {len(plans)} failed attempt(s): "
                                            + "; ".join(reasons) + ")",
                               iterations=sum(s.iterations for s in stages), homotopy=tuple(stages),
                               solve_time=time.perf_counter() - t_start, attempts=attempts,
                               extra=dict(res.extra, fallback=fb.options.formulation))
            reasons.append(f"{label}: {res.message}")
        else:
            attempts = len(plans)
        return failed_step_result(
            self.model, state, tau, status=status,
            message=f"MPCC step failed with status {ipopt_status(status).describe()} after {attempts} "
                    f"attempt(s): " + "; ".join(reasons),
            iterations=sum(s.iterations for s in stages), solve_time=time.perf_counter() - t_start,
            homotopy=tuple(stages), attempts=attempts, extra={"reasons": reasons})

    def _homotopy(self, attempt, state, tau, prefer, w0, lam_x, lam_g, sched, stages) \
            -> tuple[_Solve | None, str, str]:
        """One homotopy: (accepted solve or None, failure reason, status of the outcome)."""
        opt = self.options
        solver = self._solver_cold if lam_x is None else self._solver_warm
        sol = None
        for sigma in sched:
            t0 = time.perf_counter()
            sol = self._call(solver, w0, lam_x, lam_g, self._params(state, tau, sigma, prefer), *self._bounds(sigma))
            stages.append(HomotopyStage(attempt, sigma, sol.status, sol.accepted, sol.iterations, sol.comp,
                                        time.perf_counter() - t0))
            if not sol.accepted:
                return None, f"IPOPT {sol.text} at sigma = {sigma:.3g}", sol.status
            w0, lam_x, lam_g = sol.w, sol.lam_x, sol.lam_g
            solver = self._solver_warm
            if opt.formulation == "l1_penalty" and sol.comp <= opt.comp_tol and sol.eq <= opt.eq_tol:
                break  # exact penalty: complementarity already holds, a larger penalty changes nothing
        if not sol.eq <= opt.eq_tol:
            return (None, f"equation residual {sol.eq:.3g} > eq_tol = {opt.eq_tol:g} (IPOPT {sol.status})",
                    "Residual_Check_Failed")
        return sol, "", sol.status

    def _polish(self, attempt, state, tau, prefer, sol: _Solve, stages) -> _Solve | None:
        """Tightened NLP: each pair on its identified branch, the other side >= 0, its relaxation off.

        Branches (:meth:`_branches`): sticking pairs (s_j <= c_j) get s_j = 0, the slipping pair with
        the largest slip gets c_j = 0; any other slipping pair (the two feet at equal friction limits,
        where the split of the slip between them is free) keeps the relaxation of the last homotopy
        stage, so that the objective, not an over-determined system, decides the split.  Pairs the
        homotopy left near their corner (min(s_j, c_j) > comp_tol, possible up to sqrt(sigma)) may be
        on the wrong branch: if the tightened NLP fails, each of them is tried on the other branch
        (at most ``POLISH_FLIPS`` more IPOPT calls, only at such degenerate steps).  Returns None (keep
        the homotopy's point) if no tightened NLP succeeds with the residual checks.
        """
        opt = self.options
        sigma_last = stages[-1].sigma
        # a kept pair may need c_j = 0 exactly (equal limits), which smoothing (s_j c_j = sigma)
        # forbids; a tiny sigma keeps the switched-off rows' derivatives finite at s = c = 0
        sigma = 1e-30 if opt.formulation == "fischer_burmeister" else sigma_last
        natural = self._branches(sol)
        corner = sorted((j for j in range(NPAIR) if min(sol.s[j], sol.c[j]) > opt.comp_tol),
                        key=lambda j: -min(sol.s[j], sol.c[j]))
        candidates = [natural]
        for j in corner[:POLISH_FLIPS]:
            flipped = list(natural)
            flipped[j] = "slip" if natural[j] == "stick" else "stick"
            candidates.append(flipped)
        for branches in candidates:
            _, _, lbg, ubg = self._bounds(sigma_last)
            lbg, ubg = lbg.copy(), ubg.copy()
            ubx = self._ubx.copy()
            w0 = sol.w.copy()
            for j, branch in enumerate(branches):
                if branch == "relaxed":
                    continue
                fixed = 8 + j if branch == "slip" else 4 + j
                ubx[fixed] = 0.0
                w0[fixed] = 0.0
                if self.ng > NEQ + NPAIR:
                    lbg[NEQ + NPAIR + j], ubg[NEQ + NPAIR + j] = -np.inf, np.inf
            t0 = time.perf_counter()
            pol = self._call(self._solver_warm, w0, sol.lam_x, sol.lam_g, self._params(state, tau, sigma, prefer),
                             self._lbx, ubx, lbg, ubg)
            stages.append(HomotopyStage(attempt, float("nan"), pol.status, pol.accepted, pol.iterations, pol.comp,
                                        time.perf_counter() - t0, kind="polish"))
            if pol.accepted and pol.eq <= opt.eq_tol and pol.comp <= opt.comp_tol:
                return pol
        return None

    @staticmethod
    def _branches(sol: _Solve) -> list[str]:
        """Identified branch of each pair: 'stick' (s_j = 0), 'slip' (c_j = 0) or 'relaxed'."""
        slipping = [j for j in range(NPAIR) if sol.s[j] > sol.c[j]]
        lead = max(slipping, key=lambda j: sol.s[j]) if slipping else None
        return ["slip" if j == lead else "relaxed" if j in slipping else "stick" for j in range(NPAIR)]
