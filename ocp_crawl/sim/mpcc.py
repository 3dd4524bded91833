"""One quasistatic step as a mathematical program with complementarity constraints (MPCC), solved by
IPOPT.

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
margins c_j lifted into variables.  The IPOPT NLP is built once per :class:`MPCCStep` with the
previous angles, the torque, the robot parameter vector p, the homotopy parameter and tie-break
weights as NLP parameters, and reused for every step.  Complementarity is handled by one of

* ``"scholtes"`` (default): relaxation s_j c_j <= sigma, sigma driven from sigma0 to sigma_min <
  1e-9; sigma enters only the constraint bounds, so the same solver serves every stage;
* ``"l1_penalty"``: exact l1 penalty of the complementarity (elastic mode): min sum_j s_j c_j /
  sigma subject to s, c >= 0 (each product is >= 0, so the sum is the l1 norm of the products), with
  the penalty 1/sigma raised along the same schedule until complementarity holds;
* ``"fischer_burmeister"``: smoothed Fischer-Burmeister equations s + c - sqrt(s^2 + c^2 + 2
  sigma) = 0, i.e. s c = sigma with s, c > 0, sigma driven to sigma_min.

A step is accepted only when IPOPT's return status is usable by
:data:`~ocp_crawl.nlp.ipopt.IPOPT_RETURN_STATUS` (the one table through which the step, the
time-stepping and the gait OCP read every solver outcome) and the complementarity and equation
residuals are below tolerance; failed attempts are retried (cold start, non-monotone sigma schedule,
then the fallback formulation :data:`FALLBACK_FORMULATION`), and a step that still fails returns a
status of the table with NaN solution fields.  The homotopy and the polish are those of
:mod:`ocp_crawl.nlp.homotopy` (shared with the gait OCP): after the homotopy a polish can solve the
tightened NLP (each pair fixed to its identified branch, s_j = 0 or c_j = 0, with the other kept
>= 0) with the same IPOPT solver; this removes the O(sigma/s) bias of the relaxation and resolves
pairs near their corner (a slip that starts or stops within the step).  The step's state and result
types are in :mod:`ocp_crawl.sim.step`.

Exact ties: when the friction limits of the two feet are equal (mirror-symmetric configurations)
any split of the slip between the feet solves the step.  The small regularising objective then
prefers the pair that slipped in the previous step (the warm start's mode) and otherwise splits the
slip equally (mode ``SLIP_BOTH_*``).  With ``"l1_penalty"`` the penalty dominates the objective and
the split at an exact tie follows IPOPT's path.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Literal

import casadi as cs
import numpy as np

from ocp_crawl.checks import real
from ocp_crawl.model.statics import NP, Model
from ocp_crawl.model.step_equations import NEQ, NPAIR, NW, step_equations
from ocp_crawl.nlp import ipopt as nlp_ipopt
from ocp_crawl.nlp.homotopy import Homotopy, Solve, Start, schedule
from ocp_crawl.nlp.ipopt import call_ipopt, check_ipopt_options, ipopt_solvers, ipopt_status
from ocp_crawl.sim.result import Mode
from ocp_crawl.sim.step import (SLIP_PAIR_MODES, StepResult, StepState, check_tau,
                                failed_step_result, finite_result, step_params, step_result_from_w)

Formulation = Literal["scholtes", "l1_penalty", "fischer_burmeister"]
FORMULATIONS = ("scholtes", "l1_penalty", "fischer_burmeister")
Polish = Literal["auto", "always", "never"]
POLISH = ("auto", "always", "never")

#: pairs left near their corner by the homotopy that the polish may try on the other branch
POLISH_FLIPS = 2


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
    (and after a failed cold start) with a non-monotone sigma schedule from a guess with small
    slips, and last with the fallback formulation (:data:`FALLBACK_FORMULATION`) from a cold
    start"""
    polish: Polish = "auto"
    """after the homotopy, solve the tightened NLP on the identified branches (exact
    complementarity): 'always', 'never', or 'auto' = only when the homotopy's complementarity
    residual exceeds comp_tol (saves one IPOPT call on most warm-started steps; the relaxation then
    leaves |min(s_j, c_j)| <= comp_tol, about 1e-10 rad in phi)"""
    ipopt: dict = field(default_factory=dict)
    """IPOPT options passed through (copied per instance); override
    :data:`~ocp_crawl.nlp.ipopt.STEP_IPOPT`"""
    verbose: bool = False
    """let IPOPT print its iterations"""

    def __post_init__(self) -> None:
        if self.formulation not in FORMULATIONS:
            raise ValueError(f"MPCCOptions.formulation must be one of {FORMULATIONS}, "
                             f"got {self.formulation!r}")
        for name in ("sigma0", "sigma0_warm", "sigma_min", "sigma_factor", "comp_tol", "eq_tol"):
            object.__setattr__(self, name,
                               real(f"MPCCOptions.{name}", getattr(self, name), positive=True))
        if not self.sigma_min < 1e-9:
            raise ValueError(f"MPCCOptions.sigma_min must be < 1e-9, got {self.sigma_min!r}")
        for name in ("sigma0", "sigma0_warm"):
            if getattr(self, name) < self.sigma_min:
                raise ValueError(f"MPCCOptions.{name} must be >= sigma_min = {self.sigma_min!r}, "
                                 f"got {getattr(self, name)!r}")
        if not self.sigma_factor < 1:
            raise ValueError("MPCCOptions.sigma_factor must be in (0, 1), "
                             f"got {self.sigma_factor!r}")
        object.__setattr__(self, "max_retries",
                           real("MPCCOptions.max_retries", self.max_retries, integer=True,
                                nonneg=True))
        if self.polish not in POLISH:
            raise ValueError(f"MPCCOptions.polish must be one of {POLISH}, got {self.polish!r}")
        if not isinstance(self.verbose, bool):
            raise TypeError(f"MPCCOptions.verbose must be a bool, got {self.verbose!r}")
        object.__setattr__(self, "ipopt", check_ipopt_options("MPCCOptions.ipopt", self.ipopt))

    def schedule(self, sigma0: float, factor: float | None = None) -> tuple[float, ...]:
        """Homotopy parameters from sigma0, divided by 1/``factor`` (default sigma_factor) down to
        sigma_min."""
        return schedule(sigma0, self.sigma_factor if factor is None else factor, self.sigma_min)



#: formulation of the last retry of a step, per primary formulation
FALLBACK_FORMULATION = {"scholtes": "l1_penalty", "fischer_burmeister": "l1_penalty",
                        "l1_penalty": "fischer_burmeister"}


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
        # equations only (no sign bounds): the residual of a point of :meth:`solve_in_mode`
        self._eq_only = cs.Function("mpcc_eq", [w, P], [cs.mmax(cs.fabs(cs.vertcat(g_eq, g_lift)))])

        self._solver_cold, self._solver_warm, *_ = ipopt_solvers(
            "mpcc_step", {"x": w, "p": P, "f": f, "g": g}, nlp_ipopt.STEP_IPOPT,
            nlp_ipopt.STEP_WARM_IPOPT, opt.ipopt, "MPCCOptions.ipopt", opt.verbose)
        inf = np.inf
        self._lbx = np.concatenate([np.full(4, -inf), np.zeros(2 * NPAIR)])
        self._ubx = np.full(NW, inf)
        self._lbg = np.zeros(self.ng)
        self._ubg = np.zeros(self.ng)
        if opt.formulation == "scholtes":
            self._lbg[NEQ + NPAIR:] = -inf

    # ------------------------------------------------------------------ primitives
    def _params(self, state: StepState, tau: np.ndarray, sigma: float,
                prefer: Mode = Mode.STICK) -> np.ndarray:
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

    def _call(self, solver, w0, lam_x, lam_g, P, lbx, ubx, lbg, ubg) -> Solve:
        """One IPOPT call from w0 (warm with the multipliers lam_x, lam_g unless None) and its
        residuals."""
        args = {"x0": w0, "p": P, "lbx": lbx, "ubx": ubx, "lbg": lbg, "ubg": ubg}
        if lam_x is not None:
            args["lam_x0"] = lam_x
            args["lam_g0"] = lam_g
        call = call_ipopt(solver, NW, self.ng, **args)
        self.ncalls += 1
        chk = np.asarray(self._check(call.x, P)).ravel()
        return Solve.of(call, eq=float(chk[0]), comp=float(chk[1]), s=call.x[4:8], c=chk[2:6])

    def _homotopy_of(self, stages: list) -> Homotopy:
        """The homotopy engine over this step's NLP, recording into ``stages``."""
        def call(solver, start: Start, data: dict) -> Solve:
            return self._call(solver, start.x, start.lam_x, start.lam_g, data["p"], data["lbx"],
                              data["ubx"], data["lbg"], data["ubg"])
        return Homotopy(self._solver_cold, self._solver_warm, call, stages)

    # ------------------------------------------------------------------ solve
    def initial_guess(self, state: StepState, tau: np.ndarray, slip: float = 0.0) -> np.ndarray:
        """Cold-start point: the previous configuration and force, slips ``slip`` (scaled), and the
        lifted margins evaluated there (clipped to >= 0)."""
        ft = state.f_t / self.Mg
        w = np.concatenate([state.phi, [ft, -ft], np.full(NPAIR, slip), np.zeros(NPAIR)])
        w[8:12] = np.maximum(np.asarray(self._margins(w, self._params(state, tau, 1.0))).ravel(),
                             0.0)
        return w

    def _fallback_step(self) -> "MPCCStep":
        """The step solver of the fallback formulation (built on first use): cold start and the
        non-monotone retry, no further fallback."""
        if self._fallback is None:
            opt = self.options
            self._fallback = MPCCStep(
                self.model,
                replace(opt, formulation=FALLBACK_FORMULATION[opt.formulation], max_retries=1))
        return self._fallback

    def _plans(self, state: StepState, tau: np.ndarray, warm_start: StepResult | None):
        """(label, start, sigma schedule) of the first attempt and the retries."""
        opt = self.options
        plans = []
        if warm_start is not None:
            if not isinstance(warm_start, StepResult):
                raise TypeError("warm_start must be a StepResult or None, "
                                f"got {type(warm_start).__name__}")
            # a warm start is used only if it is a complete finite primal-dual point of this NLP
            if warm_start.success and warm_start.w is not None and warm_start.w.shape == (NW,) \
                    and warm_start.lam_x is not None and warm_start.lam_x.shape == (NW,) \
                    and warm_start.lam_g is not None and warm_start.lam_g.shape == (self.ng,) \
                    and all(np.all(np.isfinite(a)) for a in (warm_start.w, warm_start.lam_x,
                                                             warm_start.lam_g)):
                plans.append(("warm start",
                              Start(warm_start.w.copy(), warm_start.lam_x, warm_start.lam_g),
                              opt.schedule(opt.sigma0_warm)))
        plans.append(("cold start", Start(self.initial_guess(state, tau)),
                      opt.schedule(opt.sigma0)))
        # non-monotone schedule: back up to a larger sigma, then decrease more slowly, from a point
        # with a small slip in every pair (pairs start away from their corner)
        up = min(1.0, 100.0 * opt.sigma0)
        sched = (opt.sigma0, up) + opt.schedule(up, math.sqrt(opt.sigma_factor))[1:]
        plans.append(("non-monotone sigma", Start(self.initial_guess(state, tau, slip=1e-3)),
                      sched))
        return plans[:1 + opt.max_retries]

    def solve(self, state: StepState, tau, warm_start: StepResult | None = None) -> StepResult:
        """Solve the step from ``state`` with the torque ``tau`` [N m] at t_{k+1}.

        ``warm_start``: a previous successful step's result whose primal and dual solution seed
        IPOPT (the homotopy then starts at ``sigma0_warm``) and whose slip is preferred at exact
        ties; failed attempts are retried from a cold start, then with a non-monotone sigma
        schedule, then with the fallback formulation (up to ``max_retries`` retries in all).  A
        failed step's status is that of the last failed attempt of the primary formulation
        (:data:`~ocp_crawl.nlp.ipopt.IPOPT_RETURN_STATUS`, or ``Residual_Check_Failed``); its
        solution fields are NaN.
        """
        if not isinstance(state, StepState):
            raise TypeError(f"state must be a StepState, got {type(state).__name__}")
        tau = check_tau(tau)
        t_start = time.perf_counter()
        stages: list = []
        reasons = []
        status = "Unknown"
        plans = self._plans(state, tau, warm_start)
        prefer = warm_start.mode if warm_start is not None and warm_start.success else Mode.STICK
        hom = self._homotopy_of(stages)
        for attempt, (label, start, sched) in enumerate(plans):
            res, reason, status = self._attempt(hom, attempt, label, state, tau, prefer, start,
                                                sched)
            if res is not None:
                return replace(res, solve_time=time.perf_counter() - t_start)
            reasons.append(f"{label}: {reason}")
        attempts = len(plans)
        if len(plans) < 1 + self.options.max_retries:
            res = self._solve_fallback(state, tau, stages, reasons, len(plans))
            if res.success:
                return replace(res, solve_time=time.perf_counter() - t_start)
            attempts += res.attempts
        return failed_step_result(
            self.model, state, tau, status=status,
            message=f"MPCC step failed with status {ipopt_status(status).describe()} after "
                    f"{attempts} attempt(s): " + "; ".join(reasons),
            iterations=sum(s.iterations for s in stages), solve_time=time.perf_counter() - t_start,
            homotopy=tuple(stages), attempts=attempts, extra={"reasons": reasons})

    def _attempt(self, hom: Homotopy, attempt: int, label: str, state: StepState, tau: np.ndarray,
                 prefer: Mode, start: Start, sched: tuple) -> tuple[StepResult | None, str, str]:
        """One attempt: the homotopy, the polish and the residual checks; (result or None, failure
        reason, status of the outcome)."""
        opt = self.options

        def data(sigma):
            lbx, ubx, lbg, ubg = self._bounds(sigma)
            return {"p": self._params(state, tau, sigma, prefer), "lbx": lbx, "ubx": ubx,
                    "lbg": lbg, "ubg": ubg}

        # exact penalty: once complementarity holds, a larger penalty changes nothing
        done = (lambda sol: sol.comp <= opt.comp_tol and sol.eq <= opt.eq_tol) \
            if opt.formulation == "l1_penalty" else None
        run = hom.relax(sched, start, data, attempt, done)
        if not run.ok:
            return None, f"IPOPT {run.failed.text} at sigma = {run.sigma:.3g}", run.failed.status
        sol = run.last
        if not sol.eq <= opt.eq_tol:
            return (None, f"equation residual {sol.eq:.3g} > eq_tol = {opt.eq_tol:g} "
                    f"(IPOPT {sol.status})", "Residual_Check_Failed")
        polished = False
        if opt.polish == "always" or (opt.polish == "auto" and not sol.comp <= opt.comp_tol):
            pol = hom.polish(sol, self._polish_candidates(state, tau, prefer, sol, run.sigma),
                             lambda p: p.eq <= opt.eq_tol and p.comp <= opt.comp_tol, attempt)
            if pol is not None:
                sol, polished = pol, True
        if not sol.comp <= opt.comp_tol:
            return None, (f"complementarity residual {sol.comp:.3g} > comp_tol = {opt.comp_tol:g} "
                          f"(IPOPT {sol.status})"), "Residual_Check_Failed"
        stages = hom.records
        ncalls = sum(s.attempt == attempt for s in stages)
        res = step_result_from_w(
            self.model, state, sol.x, tau, success=True, status=sol.status,
            message=f"step solved ({label}, {ncalls} IPOPT "
                    f"calls{', polished' if polished else ''})",
            iterations=sum(s.iterations for s in stages), solve_time=0.0,
            homotopy=tuple(stages), attempts=attempt + 1, w=sol.x, lam_x=sol.lam_x, lam_g=sol.lam_g,
            extra={"polished": polished})
        if not finite_result(res):
            return (None, f"the solution has non-finite values (IPOPT {sol.status})",
                    "Residual_Check_Failed")
        return res, "", sol.status

    def _solve_fallback(self, state: StepState, tau: np.ndarray, stages: list, reasons: list,
                        tried: int) -> StepResult:
        """The last retry: the fallback formulation, whose relaxation path differs (measured:
        Scholtes' homotopy can end in a local infeasibility at sigma ~ 1e-6 on soft robots, k ~ 0.1
        M g L, where the l1 penalty finds the step).  Its records join ``stages``; a failure's
        message joins ``reasons`` (the step keeps the primary formulation's status)."""
        fb = self._fallback_step()
        calls = fb.ncalls
        res = fb.solve(state, tau)
        self.ncalls += fb.ncalls - calls
        label = f"fallback {fb.options.formulation}"
        stages += [replace(h, attempt=h.attempt + tried) for h in res.homotopy]
        if not res.success:
            reasons.append(f"{label}: {res.message}")
            return res
        return replace(res,
                       message=(f"step solved ({label}, after {tried} failed attempt(s): "
                                + "; ".join(reasons) + ")"),
                       iterations=sum(s.iterations for s in stages),
                       homotopy=tuple(stages),
                       attempts=tried + res.attempts,
                       extra=dict(res.extra, fallback=fb.options.formulation))

    def _polish_candidates(self, state: StepState, tau: np.ndarray, prefer: Mode, sol: Solve,
                           sigma_last: float) -> list[dict]:
        """Tightened NLPs: each pair on its identified branch, the other side >= 0, its relaxation
        off.

        Branches (:meth:`_branches`): sticking pairs (s_j <= c_j) get s_j = 0, the slipping pair
        with the largest slip gets c_j = 0; any other slipping pair (the two feet at equal friction
        limits, where the split of the slip between them is free) keeps the relaxation of the last
        homotopy stage (``sigma_last``), so that the objective, not an over-determined system,
        decides the split.  Pairs the homotopy left near their corner (min(s_j, c_j) > comp_tol,
        possible up to sqrt(sigma)) may be on the wrong branch: if the tightened NLP fails, each of
        them is tried on the other branch (at most ``POLISH_FLIPS`` more IPOPT calls, only at such
        degenerate steps).
        """
        opt = self.options
        # a kept pair may need c_j = 0 exactly (equal limits), which smoothing (s_j c_j = sigma)
        # forbids; a tiny sigma keeps the switched-off rows' derivatives finite at s = c = 0
        P = self._params(state, tau,
                         1e-30 if opt.formulation == "fischer_burmeister" else sigma_last, prefer)
        natural = self._branches(sol)
        corner = sorted((j for j in range(NPAIR) if min(sol.s[j], sol.c[j]) > opt.comp_tol),
                        key=lambda j: -min(sol.s[j], sol.c[j]))
        candidates = [natural]
        for j in corner[:POLISH_FLIPS]:
            flipped = list(natural)
            flipped[j] = "slip" if natural[j] == "stick" else "stick"
            candidates.append(flipped)
        out = []
        for branches in candidates:
            _, _, lbg, ubg = self._bounds(sigma_last)
            lbg, ubg = lbg.copy(), ubg.copy()
            ubx = self._ubx.copy()
            w0 = sol.x.copy()
            for j, branch in enumerate(branches):
                if branch == "relaxed":
                    continue
                fixed = 8 + j if branch == "slip" else 4 + j
                ubx[fixed] = 0.0
                w0[fixed] = 0.0
                if self.ng > NEQ + NPAIR:
                    lbg[NEQ + NPAIR + j], ubg[NEQ + NPAIR + j] = -np.inf, np.inf
            out.append({"x0": w0, "p": P, "lbx": self._lbx, "ubx": ubx, "lbg": lbg, "ubg": ubg})
        return out

    def solve_in_mode(self, state: StepState, tau, slip_pair: int | None,
                      x0: np.ndarray | None = None) -> Solve:
        """The step with its contact mode imposed (one IPOPT call on this step's NLP, tightened
        bounds).

        ``slip_pair``: index j of the slipping pair (s1+, s1-, s2+, s2-), or None for stick-stick.
        The slipping pair's margin is fixed to zero and its slip is free in sign (a slip that
        reverses shows as s_j < 0); every other pair has s = 0 and a margin free in sign (a violated
        friction limit shows as c < 0).  The system is square (8 equations, 8 unknowns), so the
        point is the mode's equilibrium at the torque ``tau`` [N m]; the guards of the event search
        (:mod:`ocp_crawl.sim.step_split`) read s and c from the returned
        :class:`~ocp_crawl.nlp.homotopy.Solve` (``accepted`` and ``eq`` tell whether it is usable).
        """
        tau = check_tau(tau)
        P = self._params(state, tau, 1.0)
        lbx, ubx = self._lbx.copy(), self._ubx.copy()
        lbg, ubg = self._lbg.copy(), self._ubg.copy()
        lbg[NEQ + NPAIR:], ubg[NEQ + NPAIR:] = -np.inf, np.inf
        w0 = self.initial_guess(state, tau) if x0 is None else np.asarray(x0, float).copy()
        for j in range(NPAIR):
            if j == slip_pair:
                lbx[4 + j], lbx[8 + j], ubx[8 + j], w0[8 + j] = -np.inf, 0.0, 0.0, 0.0
            else:
                lbx[8 + j], ubx[4 + j], w0[4 + j] = -np.inf, 0.0, 0.0
        sol = self._call(self._solver_cold, w0, None, None, P, lbx, ubx, lbg, ubg)
        sol.eq = float(self._eq_only(sol.x, P))
        return sol

    @staticmethod
    def _branches(sol: Solve) -> list[str]:
        """Identified branch of each pair: 'stick' (s_j = 0), 'slip' (c_j = 0) or 'relaxed'."""
        slipping = [j for j in range(NPAIR) if sol.s[j] > sol.c[j]]
        lead = max(slipping, key=lambda j: sol.s[j]) if slipping else None
        return ["slip" if j == lead else "relaxed" if j in slipping
                else "stick" for j in range(NPAIR)]

