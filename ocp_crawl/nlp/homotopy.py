"""The one relaxation homotopy of the package, shared by the MPCC step and the gait OCP.

A complementarity problem 0 <= s _|_ c >= 0 is relaxed by a parameter sigma (Scholtes: s c <= sigma;
the step solver also knows an l1 penalty and Fischer-Burmeister smoothing) and solved by IPOPT along
a decreasing :func:`schedule` of sigma: the first stage from a guess (the cold solver, or the warm
one when the guess carries multipliers), each later stage warm-started from the previous stage's
primal-dual point.  Every stage but the last may have its own solvers (a looser tolerance: such a
stage only leads to the next; per sigma with ``loose_at``; the last stage too with ``loose_last``,
when a polish follows).  A :meth:`Homotopy.polish` then solves the tightened NLP (each pair fixed to
its identified branch) from the homotopy's point, trying candidate tightenings in turn.  Every IPOPT
call is one :class:`Stage` record.

The engine knows nothing of the problem: the caller gives the IPOPT solvers (cold and warm, and
optionally those of the intermediate stages) and a function that makes
one call, ``call(solver, start, data) -> Solve``, where ``data`` holds the NLP's parameters and
bounds of the stage (``p``, ``lbx``, ``ubx``, ``lbg``, ``ubg``) and the returned :class:`Solve`
carries the point, the status table's verdict and the caller's residuals.
"""
from __future__ import annotations

import contextlib
import contextvars
import math
import time
from dataclasses import dataclass, field
from typing import Callable, Iterable, Iterator, TypeVar, cast

import casadi as cs
import numpy as np

from ocp_crawl.nlp.ipopt import IpoptCall, LazySolver, Solvers, ipopt_status


_T = TypeVar("_T")

#: callbacks told of every IPOPT call of every homotopy (see :func:`observe`)
_OBSERVERS: contextvars.ContextVar[tuple] = contextvars.ContextVar("homotopy_observers", default=())


@contextlib.contextmanager
def observe(callback: Callable[["Stage"], None], alone: bool = False) -> Iterator[None]:
    """Call ``callback(stage)`` with the :class:`Stage` record of every IPOPT call made by a
    homotopy inside the ``with`` block (for progress displays: ``stage.kind``, ``stage.sigma``,
    ``stage.iterations``); with ``alone``, only it (not the callbacks of enclosing blocks: a forked
    process sends its records to the parent's)."""
    token = _OBSERVERS.set((callback,) if alone else _OBSERVERS.get() + (callback,))
    try:
        yield
    finally:
        _OBSERVERS.reset(token)


def observers() -> tuple:
    """The callbacks that :func:`observe` has registered here (innermost last)."""
    return _OBSERVERS.get()


def observed_elsewhere(fn: Callable[[], _T]) -> tuple[Callable[[Callable], _T],
                                                      Callable[[object], None]]:
    """(task, forward) for :func:`~ocp_crawl.workers.overlap`: the task runs ``fn()`` with the
    records of its homotopies' IPOPT calls sent (not observed there), and ``forward`` gives each
    record to this process's observers (those registered when this is called), so that a solve in
    a forked process still reaches the progress display."""
    here = observers()

    def task(send: Callable) -> _T:
        with observe(send, alone=True):
            return fn()

    def forward(stage: object) -> None:
        for callback in here:
            callback(stage)
    return task, forward


def schedule(sigma0: float, factor: float, sigma_min: float) -> tuple[float, ...]:
    """Relaxation parameters sigma0, sigma0 factor, ... while above sigma_min, then sigma_min (the
    last one).

    ``factor`` in (0, 1); all three dimensionless (the relaxation of the scaled complementarity)."""
    out = []
    s = sigma0
    while s > sigma_min * (1 + 1e-9):
        out.append(s)
        s *= factor
    out.append(sigma_min)
    return tuple(out)


@dataclass(frozen=True)
class Stage:
    """One IPOPT call of a homotopy: a relaxation stage or a polish."""

    sigma: float
    """relaxation parameter of the stage [-] (NaN for a polish)"""
    return_status: str
    """IPOPT's return status (see :data:`~ocp_crawl.nlp.ipopt.IPOPT_RETURN_STATUS`)"""
    accepted: bool
    """the table says the point is usable and it is finite"""
    iterations: int
    comp_residual: float
    """largest complementarity residual at the point [-] (the caller's measure)"""
    time: float
    """wall time of the call [s]"""
    kind: str = "homotopy"
    """'homotopy' (a relaxation stage) or 'polish' (the tightened NLP)"""
    attempt: int = 0
    """the caller's attempt number (the step solver's retries; 0 for the OCP)"""
    objective: float = math.nan
    """IPOPT's objective value at the point"""
    S: tuple = ()
    """body displacement per scenario [m] (the OCP; empty for the step solver)"""
    message: str = ""
    """the return status and its meaning from the table"""
    eval_time: float = math.nan
    """wall time [s] of the call spent in the NLP's function and derivative evaluations"""


@dataclass
class Solve:
    """One IPOPT call as the homotopy reads it: the primal-dual point, the table's verdict, the
    caller's residuals.  Mutable, so that a caller (or a test) may overrule the verdict."""

    x: np.ndarray
    lam_x: np.ndarray
    lam_g: np.ndarray
    status: str
    accepted: bool
    iterations: int
    detail: str = ""
    """CasADi's exception text when the call raised, else ''"""
    objective: float = math.nan
    comp: float = math.inf
    """complementarity residual [-]"""
    eq: float = math.inf
    """equation residual [-]"""
    S: tuple = ()
    s: np.ndarray | None = None
    """the complementarity pairs (s, c) at the point, when the caller measures them per pair"""
    c: np.ndarray | None = None
    eval_time: float = math.nan
    """wall time [s] IPOPT spent in function and derivative evaluations"""

    @classmethod
    def of(cls, call: IpoptCall, **measures) -> "Solve":
        """The solve of a :func:`~ocp_crawl.nlp.ipopt.call_ipopt` outcome with the caller's
        ``measures``."""
        return cls(call.x, call.lam_x, call.lam_g, call.status, call.usable, call.iterations,
                   call.detail, call.f, **measures, eval_time=call.eval_time)

    @property
    def text(self) -> str:
        """The status (with CasADi's exception text), for short failure reasons."""
        usable = ipopt_status(self.status).usable
        return self.status + (f": {self.detail}" if self.detail else "") + \
            (", but the point is not finite" if usable and not np.all(np.isfinite(self.x)) else "")

    def describe(self) -> str:
        """The status with its meaning from the table (and CasADi's exception text)."""
        out = ipopt_status(self.status)
        text = out.describe()
        if self.detail:
            return f"{text}: {self.detail}"
        return text + (", but the point is not finite" if out.usable
                       and not np.all(np.isfinite(self.x)) else "")

    def start(self) -> "Start":
        """This point with its multipliers: the warm start of the next stage."""
        return Start(self.x, self.lam_x, self.lam_g)


@dataclass(frozen=True)
class Start:
    """Where an IPOPT call starts: a primal point, with the multipliers of a previous solve (warm)
    or not."""

    x: np.ndarray
    lam_x: np.ndarray | None = None
    lam_g: np.ndarray | None = None

    @property
    def warm(self) -> bool:
        return self.lam_x is not None


@dataclass
class Run:
    """Outcome of :meth:`Homotopy.relax`: the last accepted solve, and the failed one if a stage
    failed."""

    last: Solve | None
    """the last accepted stage's solve (None if the first stage failed)"""
    failed: Solve | None = None
    """the solve of the stage that failed (None when every stage was accepted)"""
    stage: int = 0
    """index of the failed stage (or of the last stage run)"""
    stages: int = 0
    """number of stages of the schedule"""
    sigma: float = math.nan
    """sigma of the failed (or the last) stage"""
    loose_last: bool = False
    """the last stage of the schedule was solved by a loose solver (asked for, and one exists at its
    sigma)"""

    @property
    def ok(self) -> bool:
        return self.failed is None and self.last is not None


#: an IPOPT solver of a homotopy: a CasADi function, or a :class:`~ocp_crawl.nlp.ipopt.LazySolver`
#: (:class:`~ocp_crawl.nlp.ipopt.Solvers`) that builds one on first use
IpoptSolver = cs.Function | LazySolver
Call = Callable[[IpoptSolver, Start, dict], Solve]


@dataclass
class Homotopy:
    """A relaxation homotopy over one NLP: its cold and warm IPOPT solvers and how to call them.

    ``call(solver, start, data)`` makes one IPOPT call (``data``: the stage's ``p`` and bounds) and
    measures the point; ``records`` collects a :class:`Stage` per call (a caller may share one list
    across runs).  ``stage_cold``, ``stage_warm``: the solvers of the stages that only lead to the
    next one (every stage but the last of a schedule, or every stage with
    ``relax(loose_last=True)``), e.g. with a looser tolerance
    (:class:`~ocp_crawl.nlp.ipopt.Solvers`); None: the cold and warm ones; ``loose_at`` chooses them
    per sigma."""

    cold: IpoptSolver
    warm: IpoptSolver
    call: Call
    records: list = field(default_factory=list)
    stage_cold: IpoptSolver | None = None
    stage_warm: IpoptSolver | None = None
    loose_at: Callable[[float], tuple[IpoptSolver, IpoptSolver]] | None = None
    """``loose_at(sigma)``: the (cold, warm) solvers of a loose stage at sigma (e.g. a tolerance
    that scales with sigma); None: ``stage_cold``, ``stage_warm`` at every sigma"""

    @classmethod
    def of(cls, solvers: Solvers, call: Call, records: list | None = None,
           loose_at: Callable[[float], tuple[IpoptSolver, IpoptSolver]] | None = None
           ) -> "Homotopy":
        """The homotopy of a :class:`~ocp_crawl.nlp.ipopt.Solvers` (cold, warm, stage_cold,
        stage_warm)."""
        return cls(solvers.cold, solvers.warm, call, [] if records is None else records,
                   solvers.stage_cold, solvers.stage_warm, loose_at)

    def __post_init__(self) -> None:
        self.stage_cold = self.cold if self.stage_cold is None else self.stage_cold
        self.stage_warm = self.warm if self.stage_warm is None else self.stage_warm

    def _solver(self, warm: bool, last: bool, sigma: float) -> IpoptSolver:
        """The solver of a stage at sigma: warm-started or cold, the tight one (``last``) or a loose
        one."""
        if last:
            return self.warm if warm else self.cold
        cold, warm_solver = (self.stage_cold,
                             self.stage_warm) if self.loose_at is None else self.loose_at(sigma)
        # __post_init__ replaced a None stage solver by the tight one
        return cast(IpoptSolver, warm_solver if warm else cold)

    def _stage(self, solver, start: Start, data: dict, sigma: float, kind: str,
               attempt: int) -> Solve:
        t0 = time.perf_counter()
        sol = self.call(solver, start, data)
        self.records.append(Stage(sigma, sol.status, sol.accepted, sol.iterations, sol.comp,
                                  time.perf_counter() - t0, kind, attempt, sol.objective,
                                  tuple(sol.S), sol.describe(), sol.eval_time))
        for callback in _OBSERVERS.get():
            callback(self.records[-1])
        return sol

    @property
    def loose(self) -> bool:
        """Whether the intermediate stages have their own (looser) solvers."""
        return (self.loose_at is not None or self.stage_cold is not self.cold
                or self.stage_warm is not self.warm)

    def relax(self, sigmas: Iterable[float], start: Start, data: Callable[[float], dict],
              attempt: int = 0,
              done: Callable[[Solve], bool] | None = None, loose_last: bool = False) -> Run:
        """Solve along ``sigmas`` from ``start``: the cold solver first unless ``start`` is warm,
        then each stage warm-started from the previous one.  ``data(sigma)``: parameters and bounds
        of the stage; ``done(sol)``: True ends the homotopy early (e.g. an exact penalty already
        complementary).  Stops at the first stage the table (or the caller) does not accept.  Every
        stage but the last (every stage with ``loose_last``) uses the stage solvers (a looser
        tolerance), whose point must not end the homotopy: with stage solvers ``done`` never ends it
        early (it is asked only of a tight last stage); without them it is asked after every stage.
        ``loose_last`` acts only where the last stage's loose solver is not the tight one
        (``Run.loose_last`` says whether it did)."""
        sigmas = tuple(sigmas)
        loose_last = loose_last and bool(sigmas) and self._solver(True, False,
                                                                  sigmas[-1]) is not self.warm
        run = Run(None, stages=len(sigmas), loose_last=loose_last)
        loose = self.loose
        for k, sigma in enumerate(sigmas):
            last = k == len(sigmas) - 1
            sol = self._stage(self._solver(start.warm, last and not loose_last, sigma), start,
                              data(sigma), sigma, "homotopy", attempt)
            run.stage, run.sigma = k, sigma
            if not sol.accepted:
                run.failed = sol
                return run
            run.last, start = sol, sol.start()
            if done is not None and ((last and not loose_last) or not loose) and done(sol):
                break
        return run

    def tighten(self, sol: Solve, sigma: float, data: dict, attempt: int = 0) -> Solve:
        """The stage at ``sigma`` solved again with the tight warm solver from ``sol`` (a loose
        stage's point)."""
        return self._stage(self.warm, sol.start(), data, sigma, "homotopy", attempt)

    def polish(self, sol: Solve, candidates: Iterable[dict], accept: Callable[[Solve], bool],
               attempt: int = 0, kind: str = "polish") -> Solve | None:
        """Tightened NLPs from the homotopy's solve ``sol``, warm-started with its multipliers, one
        per candidate (``data`` with the starting point ``x0``, e.g. ``sol.x`` on the tightened
        bounds), in order; the first accepted solve that passes ``accept`` is returned, else None
        (keep the homotopy's point).  ``kind``: the records' kind (e.g. "endgame")."""
        for data in candidates:
            data = dict(data)
            start = Start(data.pop("x0"), sol.lam_x, sol.lam_g)
            pol = self._stage(self.warm, start, data, math.nan, kind, attempt)
            if pol.accepted and accept(pol):
                return pol
        return None
