"""IPOPT plumbing of the package: the one table of solver outcomes, the one place that builds and
calls a CasADi IPOPT solver, and the IPOPT option sets of every NLP (the MPCC step and the gait
OCP).

Floor ``nlp`` (above ``model``, below ``sim``): imports only :mod:`ocp_crawl.status` and
:mod:`ocp_crawl.nlp.process` (the process's heap and BLAS threads around a solve).  Every solver
outcome is read through :data:`IPOPT_RETURN_STATUS` (:func:`ipopt_status`); :func:`result_status`
turns an outcome into the package's one :class:`~ocp_crawl.status.Status`.  The option sets below
are the defaults of each use; a user's options (``MPCCOptions.ipopt``, ``OCPSettings.ipopt``) are a
dict copied per instance by :func:`check_ipopt_options` and override them key by key
(:func:`ipopt_solvers`).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Callable, NamedTuple

import casadi as cs
import numpy as np

from ocp_crawl.nlp.process import heap_allocations, single_threaded_blas
from ocp_crawl.status import Status


class SolverOutcome(NamedTuple):
    """How the package reads one solver return status (a row of :data:`IPOPT_RETURN_STATUS`)."""

    status: str
    """the return status string (CasADi ``stats()['return_status']`` or one of this package's
    own)"""
    kind: str
    """our classification: 'success', 'acceptable', or a failure kind of :data:`FAILURE_KINDS`"""
    usable: bool
    """whether the point may be used (it still has to pass the caller's own residual checks)"""
    message: str
    """what it means, for a user"""
    source: str = "ipopt"
    """'ipopt' (IPOPT's ApplicationReturnStatus), 'casadi' (CasADi's own) or 'ocp_crawl' (this
    package's)"""

    def describe(self) -> str:
        """One line naming the status and its meaning, e.g. for failure messages."""
        return f"{self.status} ({self.message})"


#: failure kinds of :class:`SolverOutcome` (besides 'success' and 'acceptable'), in words
FAILURE_KINDS: dict[str, str] = {
    "infeasible": "no point satisfies the constraints (locally): the problem as posed has no "
                  "solution there",
    "limit": "a resource limit (iterations, CPU or wall time) ended the solve before convergence",
    "no_progress": "the solver stalled or diverged (restoration failure, tiny or failed steps)",
    "invalid_number": "NaN or Inf in a function or derivative value (inputs or iterates out of "
                      "range)",
    "setup": "the problem or the solver options are not valid for IPOPT",
    "residual": "the solver converged but the point fails this package's residual checks",
    "internal": "an error inside IPOPT or CasADi (exception, memory)",
    "no_solution": "the mode-enumeration oracle found no consistent contact mode",
    "unknown": "a status not in the table: treated as a failure",
}


def _o(status, kind, usable, message, source="ipopt"):
    return status, SolverOutcome(status, kind, usable, message, source)


#: The one table of solver return statuses: every IPOPT ``ApplicationReturnStatus`` (as the strings
#: CasADi reports in ``stats()['return_status']``), CasADi's own, and this package's.  The MPCC
#: steps, the MPCC time-stepping, the cross-check and the gait OCP read solver outcomes only through
#: :func:`ipopt_status`; a status missing from the table maps to the 'unknown' failure, never a
#: KeyError.
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
    _o("Diverging_Iterates", "no_progress", False,
       "the iterates diverge (problem unbounded or badly scaled?)"),
    _o("User_Requested_Stop", "limit", False, "stopped early by a user callback"),
    _o("Maximum_Iterations_Exceeded", "limit", False,
       "maximum number of IPOPT iterations (max_iter) exceeded"),
    _o("Maximum_CpuTime_Exceeded", "limit", False, "maximum CPU time (max_cpu_time) exceeded"),
    _o("Maximum_WallTime_Exceeded", "limit", False,
       "maximum wall-clock time (max_wall_time) exceeded"),
    _o("Restoration_Failed", "no_progress", False,
       "the feasibility restoration phase failed (no feasible point found from here)"),
    _o("Error_In_Step_Computation", "no_progress", False,
       "error in the step computation (singular or ill-conditioned KKT system)"),
    _o("Not_Enough_Degrees_Of_Freedom", "setup", False,
       "more equality constraints than free variables"),
    _o("Invalid_Problem_Definition", "setup", False,
       "invalid problem definition (e.g. a lower bound above an upper one)"),
    _o("Invalid_Option", "setup", False,
       "an IPOPT option is invalid or needs a library that is not available"),
    _o("Invalid_Number_Detected", "invalid_number", False,
       "NaN or Inf in a function or derivative value (inputs or iterates out of range)"),
    _o("Unrecoverable_Exception", "internal", False, "unrecoverable exception inside IPOPT"),
    _o("NonIpopt_Exception_Thrown", "internal", False,
       "exception thrown outside IPOPT (function evaluation?)"),
    _o("Insufficient_Memory", "internal", False, "IPOPT ran out of memory"),
    _o("Internal_Error", "internal", False, "internal IPOPT error"),
    # CasADi: its name for an IPOPT code it does not know, and an exception from the solver call
    _o("Unknown", "unknown", False, "CasADi reported IPOPT's return code as unknown", "casadi"),
    _o("Solver_Exception", "internal", False,
       "CasADi raised an exception from the solver call (evaluation error or invalid input)",
       "casadi"),
    # this package: IPOPT accepted the point but our own checks did not; the mode-enumeration oracle
    _o("Residual_Check_Failed", "residual", False,
       "IPOPT converged but the complementarity or equation residual exceeds the tolerance",
       "ocp_crawl"),
    _o("Enumeration_Succeeded", "success", True,
       "mode-enumeration oracle: consistent contact mode found", "ocp_crawl"),
    _o("No_Consistent_Mode", "no_solution", False,
       "mode-enumeration oracle: no consistent contact mode", "ocp_crawl"),
])

#: the kind of a status missing from :data:`IPOPT_RETURN_STATUS`
UNKNOWN_KIND = "unknown"


def ipopt_status(return_status) -> SolverOutcome:
    """The :class:`SolverOutcome` of a return status; a status not in the table is a failure of kind
    'unknown'."""
    status = str(return_status)
    out = IPOPT_RETURN_STATUS.get(status)
    if out is None:
        return SolverOutcome(status, UNKNOWN_KIND, False,
                             f"unknown solver return status {status!r} (not in the table): treated "
                             "as a failure",
                             "unknown")
    return out


@dataclass(frozen=True)
class IpoptCall:
    """Outcome of one solver call through :func:`call_ipopt` (the primal-dual point as NumPy
    arrays)."""

    outcome: SolverOutcome
    x: np.ndarray
    lam_x: np.ndarray
    lam_g: np.ndarray
    f: float
    iterations: int
    detail: str = ""
    """the exception text when CasADi raised (status Solver_Exception), else ''"""
    eval_time: float = math.nan
    """wall time [s] IPOPT spent in the NLP's function and derivative evaluations (CasADi's
    t_wall_nlp_*)"""

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


def call_ipopt(solver, nx: int, ng: int, **args) -> IpoptCall:
    """Call a CasADi IPOPT ``solver`` (or a :class:`LazySolver`, built first) and read its outcome
    through :data:`IPOPT_RETURN_STATUS`.

    An exception raised by the call (CasADi evaluation errors, invalid inputs) is caught and
    reported as ``Solver_Exception`` with its first line; the point is then the initial guess ``x0``
    (not usable).
    """
    # a LazySolver is built here, outside the solve
    function = solver.function() if isinstance(solver, LazySolver) else solver
    try:
        with heap_allocations():
            sol = function(**args)
    except RuntimeError as exc:
        detail = _casadi_reason(exc)
        x0 = np.asarray(args.get("x0", np.full(nx, np.nan)), float).ravel()
        return IpoptCall(ipopt_status("Solver_Exception"), x0, np.zeros(nx), np.zeros(ng),
                         float("nan"), 0, detail)
    st = function.stats()
    return IpoptCall(ipopt_status(st.get("return_status", "Unknown")),
                     np.asarray(sol["x"], float).ravel(),
                     np.asarray(sol["lam_x"], float).ravel(),
                     np.asarray(sol["lam_g"], float).ravel(),
                     float(sol["f"]), int(st.get("iter_count", 0)),
                     eval_time=sum(v for k, v in st.items() if k.startswith("t_wall_nlp_")))


#: types of IPOPT option values
_IPOPT_VALUE_TYPES = (str, int, float, np.integer, np.floating)


def check_ipopt_options(owner: str, options, by_ipopt: bool = False) -> dict:
    """A copy of a dict of IPOPT options with string keys and finite number or string values
    (ValueError/TypeError naming ``owner`` and the key otherwise); IPOPT itself checks names and
    ranges when the solver is built, or at once with ``by_ipopt`` (on a one-variable NLP)."""
    if not isinstance(options, dict):
        raise TypeError(f"{owner} must be a dict of IPOPT options, got {type(options).__name__}")
    out = {}
    for key, value in options.items():
        if not isinstance(key, str) or not key:
            raise TypeError(f"{owner}: IPOPT option names must be strings, got {key!r}")
        if isinstance(value, bool) or not isinstance(value, _IPOPT_VALUE_TYPES):
            raise TypeError(f"{owner}[{key!r}] must be a number or a string, got {value!r} "
                            f"({type(value).__name__})")
        if isinstance(value, (float, np.floating)) and not math.isfinite(value):
            raise ValueError(f"{owner}[{key!r}] must be finite, got {value!r}")
        out[key] = value.item() if isinstance(value, (np.integer, np.floating)) else value
    if by_ipopt:  # without output_file: building a solver opens (truncates) it
        ipopt = {"print_level": 0, "sb": "yes",
                 **{k: v for k, v in out.items() if k != "output_file"}}
        build_ipopt("options_check", _option_check_nlp(), {"error_on_fail": False, "ipopt": ipopt},
                    owner, out)
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
    """The CasADi IPOPT solver of ``nlp`` with ``options`` (the package's only nlpsol call), its
    BLAS on one thread (:func:`~ocp_crawl.nlp.process.single_threaded_blas`).

    IPOPT's rejection of an option (unknown name, wrong type, out of range) becomes one ValueError
    naming ``owner`` and the user's options instead of a CasADi traceback."""
    try:
        solver = cs.nlpsol(name, "ipopt", nlp, options)
    except RuntimeError as exc:
        raise ValueError(f"{owner} = {user_options!r}: IPOPT rejected the options: "
                         f"{_casadi_reason(exc)}") from None
    single_threaded_blas()
    return solver


def result_status(outcome: SolverOutcome, usable: bool | None = None) -> Status:
    """The result :class:`~ocp_crawl.status.Status` of a solve that ended with ``outcome``.

    ``usable`` (default ``outcome.usable``): whether the solve's point was accepted.  An accepted
    point is ``SUCCESS``; a failure is ``INFEASIBLE`` for the kind 'infeasible' and
    ``SOLVER_FAILURE`` otherwise (the IPOPT status itself stays the solver-level detail, in the
    result's message)."""
    if outcome.usable if usable is None else usable:
        return Status.SUCCESS
    return Status.INFEASIBLE if outcome.kind == "infeasible" else Status.SOLVER_FAILURE


# --------------------------------------------------------------------------------------------
# IPOPT option sets, one per use (cold: a solve from a guess; warm: from the previous stage's point)
# --------------------------------------------------------------------------------------------
#: the MPCC step solver (:class:`~ocp_crawl.sim.mpcc.MPCCStep`); ``MPCCOptions.ipopt`` overrides
#: them key by key
STEP_IPOPT: dict = {
    "tol": 1e-12,
    "acceptable_tol": 1e-9,
    "constr_viol_tol": 1e-12,
    "max_iter": 150,
    "mu_strategy": "monotone",
}

#: the warm-started MPCC step solver: start close to the central path of the previous solution
STEP_WARM_IPOPT: dict = {
    "warm_start_init_point": "yes",
    "mu_init": 1e-9,
    "warm_start_bound_push": 1e-12,
    "warm_start_bound_frac": 1e-12,
    "warm_start_slack_bound_push": 1e-12,
    "warm_start_slack_bound_frac": 1e-12,
    "warm_start_mult_bound_push": 1e-12,
}

#: the gait OCP (:class:`~ocp_crawl.ocp.transcription.GaitOCP`); ``OCPSettings.ipopt`` overrides
#: them key by key
OCP_IPOPT: dict = {
    "tol": 1e-10,
    "acceptable_tol": 1e-8,
    "max_iter": 2000,
    "mu_strategy": "adaptive",
    "bound_relax_factor": 0.0,
    "nlp_scaling_method": "gradient-based",
}

#: the warm-started OCP stages: a small bound push keeps IPOPT from walking back into the interior
#: (the barrier strategy is that of :data:`OCP_IPOPT`, adaptive, which sets mu from the point's
#: complementarity, unless ``OCPSettings.warm_barrier`` is "monotone"; mu_init acts only under a
#: monotone strategy, that one or the convergence run's warm solves)
OCP_WARM_IPOPT: dict = {
    "warm_start_init_point": "yes",
    "mu_init": 1e-6,
    "warm_start_bound_push": 1e-9,
    "warm_start_bound_frac": 1e-9,
    "warm_start_slack_bound_push": 1e-9,
    "warm_start_slack_bound_frac": 1e-9,
    "warm_start_mult_bound_push": 1e-9,
}


#: IPOPT's own default of ``tol``
IPOPT_DEFAULT_TOL = 1e-8

#: nlpsol options that take a derivative function, and the name of that function in a built solver
DERIVATIVES = {"hess_lag": "nlp_hess_l", "jac_g": "nlp_jac_g", "grad_f": "nlp_grad_f"}


class LazySolver:
    """An IPOPT solver of :func:`ipopt_solvers`, built on its first use: a call, or any attribute of
    the CasADi function (``stats()``, ``name()``, ...).  Used like the ``cs.Function`` it builds;
    the same object before and after (solvers are compared by identity).  Not picklable (it holds
    its builder): results never hold solvers."""

    def __init__(self, build: Callable[[], cs.Function]):
        self._build = build
        self._function: cs.Function | None = None

    @property
    def built(self) -> bool:
        """Whether the solver has been built."""
        return self._function is not None

    def function(self) -> cs.Function:
        """The CasADi solver (built now if not yet)."""
        if self._function is None:
            self._function = self._build()
        return self._function

    def __call__(self, *args, **kwargs):
        return self.function()(*args, **kwargs)

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)
        return getattr(self.function(), name)


class Solvers(NamedTuple):
    """The IPOPT solvers of one NLP (:func:`ipopt_solvers`): cold and warm-started, each also in a
    loose version for the intermediate stages of a homotopy (the same solver when no stage tolerance
    was asked for).  Each is a :class:`LazySolver`: built on first use."""

    cold: LazySolver
    warm: LazySolver
    stage_cold: LazySolver
    """the cold solver with the stage tolerance (the first stage of a homotopy that has later
    ones)"""
    stage_warm: LazySolver
    """the warm solver with the stage tolerance (an intermediate stage)"""
    loose: Callable[[float], tuple[LazySolver, LazySolver]] | None = None
    """``loose(tol)``: the (cold, warm) pair with IPOPT's ``tol`` = tol, made on first use and kept
    (the tight pair when tol is not looser than theirs)"""
    capped: Callable[[int], LazySolver] | None = None
    """``capped(max_iter)``: the tight warm solver with IPOPT's ``max_iter`` = max_iter (a solve
    that must pay off within a budget, else give way), made on first use and kept"""


class _Family:
    """The solvers of one NLP, built on first use; every solver after the first reuses the first
    one's derivative functions (generating them again costs as much as the first build: 9 s of the
    max_speed OCP at N = 400)."""

    def __init__(self, name: str, nlp: dict, base: dict, ipopt: tuple[dict, dict], owner: str,
                 user: dict):
        """``ipopt``: the whole IPOPT options of the cold and of the warm-started solvers."""
        self.name, self.nlp, self.base, self.owner, self.user = name, nlp, base, owner, user
        self.ipopt, self.ipopt_warm = ipopt
        self._source: cs.Function | None = None
        self._pairs: dict[float, tuple[LazySolver, LazySolver]] = {}
        self._capped: dict[int, LazySolver] = {}
        self.tight = (self.solver("_cold", self.ipopt), self.solver("_warm", self.ipopt_warm))

    def solver(self, suffix: str, ipopt: dict) -> LazySolver:
        """The solver named name + suffix with these IPOPT options, built on first use."""
        return LazySolver(lambda: self._build(self.name + suffix, ipopt))

    def _build(self, name: str, ipopt: dict) -> cs.Function:
        src = self._source
        shared = {} if src is None else {key: src.get_function(fun)
                                         for key, fun in DERIVATIVES.items()
                                         if src.has_function(fun)}
        solver = build_ipopt(name, self.nlp, dict(self.base, **shared, ipopt=ipopt), self.owner,
                             self.user)
        if src is None:
            self._source = solver
        return solver

    def capped(self, max_iter: int) -> LazySolver:
        """The tight warm solver with IPOPT's ``max_iter`` = max_iter."""
        # a user's smaller max_iter is kept
        max_iter = min(int(max_iter), int(self.ipopt_warm.get("max_iter", max_iter)))
        if max_iter not in self._capped:
            self._capped[max_iter] = self.solver(f"_warm_max{max_iter}",
                                                 dict(self.ipopt_warm, max_iter=max_iter))
        return self._capped[max_iter]

    def loose(self, tol: float, suffix: str | None = None) -> tuple[LazySolver, LazySolver]:
        """The (cold, warm) pair at IPOPT's ``tol`` = tol (the tight pair when tol is not looser
        than theirs)."""
        # a sigma from repeated products carries rounding noise: one pair per value
        tol = float(f"{float(tol):.6g}")
        if not tol > self.ipopt.get("tol", IPOPT_DEFAULT_TOL) * (1 + 1e-6):
            return self.tight
        if tol not in self._pairs:
            # CasADi names: no "-" or "."
            tag = f"_loose{len(self._pairs) + 1}" if suffix is None else suffix
            self._pairs[tol] = (self.solver(f"_stage_cold{tag}", dict(self.ipopt, tol=tol)),
                                self.solver(f"_stage_warm{tag}", dict(self.ipopt_warm, tol=tol)))
        return self._pairs[tol]


def _option_check_nlp() -> dict:
    """The NLP on which :func:`ipopt_solvers` checks the options at once (its real solvers are built
    on first use)."""
    x = cs.SX.sym("x")
    return {"x": x, "f": x**2, "g": x}


def ipopt_solvers(name: str, nlp: dict, defaults: dict, warm: dict, user: dict, owner: str,
                  verbose: bool = False, stage_tol: float | None = None,
                  warm_over: dict | None = None) -> Solvers:
    """The cold and the warm-started IPOPT solver of ``nlp`` (CasADi's ``{"x", "p", "f", "g"}``) and
    loose versions.

    Options: ``defaults`` (an option set of this module, read when called), quiet unless
    ``verbose``, then the ``user``'s options (named ``owner`` in errors); the warm solver adds
    ``warm`` under them and ``warm_over`` over the defaults (under the user's; e.g. another barrier
    strategy for the warm-started solves).  ``stage_tol`` (dimensionless, IPOPT's ``tol``): also
    build both solvers with this tolerance over every other option, for the stages of a homotopy
    that are only a path to the next one (None, or not looser than the solvers' own ``tol``: the
    loose solvers are the tight ones); ``Solvers.loose(tol)`` builds pairs at other tolerances on
    demand.  Every solver is built on its first use (:class:`LazySolver`; an NLP solved only warm
    never builds its cold solvers), the first one with the derivative functions, which the others
    reuse; the options are checked at once, on a one-variable NLP (ValueError naming ``owner``).
    Returns :class:`Solvers`."""
    quiet = {"print_level": 5 if verbose else 0, "sb": "yes"}
    ipopt, ipopt_warm = ({**defaults, **quiet, **user},
                         {**warm, **defaults, **(warm_over or {}), **quiet, **user})
    base = {"print_time": bool(verbose), "calc_lam_p": False, "error_on_fail": False}
    build_ipopt(f"{name}_options", _option_check_nlp(), dict(base, ipopt=ipopt_warm), owner, user)
    family = _Family(name, nlp, base, (ipopt, ipopt_warm), owner, user)
    stage = family.loose(stage_tol, suffix="") if stage_tol is not None else family.tight
    return Solvers(*family.tight, *stage, family.loose, family.capped)
