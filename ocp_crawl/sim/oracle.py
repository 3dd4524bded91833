"""Exact solution of one incremental step by enumerating the contact modes (reference for the MPCC
step).

The incremental problem of :mod:`ocp_crawl.sim.mpcc` has, generically, one of five contact modes at
the end of a step.  In each mode the unknowns z = (phi1, phi2, f_t/(M g)) solve three equations:
the joint balance F(phi, tau, f_t) = 0 (the model's compiled residual) and

===============  =========================================  =====================================
mode             equation                                   consistency (all other pairs, scaled)
===============  =========================================  =====================================
stick-stick      d(phi) = d(phi_k)                          every friction margin c_j >= 0
slip1+ / slip1-  mu1 f_n1 + f_t1 = 0 / mu1 f_n1 - f_t1 = 0  dx1 = d_k - d >= 0 / <= 0,
                                                            other c_j >= 0
slip2+ / slip2-  mu2 f_n2 + f_t2 = 0 / mu2 f_n2 - f_t2 = 0  dx2 = d - d_k >= 0 / <= 0,
                                                            other c_j >= 0
===============  =========================================  =====================================

with f_t1 = f_t, f_t2 = -f_t and normal forces at phi_{k+1}; a slipping foot's partner sticks.
Each mode is solved by a damped Newton method; the consistent solution is kept (normal forces > 0
too).  When several distinct consistent solutions exist (possible for a finite step of a nonlinear
problem) the one closest to phi_k is kept and the count is reported in ``extra``; coinciding ones (a
step ending exactly on a friction limit, or equal limits of the two feet) count once.  The
equations are written here from the model's compiled ``kin`` and ``residual`` in mode form,
independently of the MPCC's complementarity formulation.
"""
from __future__ import annotations

import time
from functools import lru_cache

import casadi as cs
import numpy as np

from ocp_crawl.model.statics import KIN, NP, Model, params, symbolic
from ocp_crawl.model.step_equations import NPAIR, friction_margins
from ocp_crawl.sim.result import Mode
from ocp_crawl.sim.step import (StepResult, StepState, check_tau, failed_step_result,
                                step_result_from_w)

#: modes enumerated, in the order of the selector vector; slip modes are indexed like the pairs
ENUM_MODES = (Mode.STICK, Mode.SLIP1_POS, Mode.SLIP1_NEG, Mode.SLIP2_POS, Mode.SLIP2_NEG)

NEWTON_TOL = 1e-14
"""Newton stops when the scaled residual max|G| is below this"""
CONSISTENCY_TOL = 1e-10
"""a scaled slip or friction margin >= -CONSISTENCY_TOL counts as nonnegative"""
DISTINCT_TOL = 1e-9
"""consistent solutions closer than this in phi [rad] are the same solution"""


@lru_cache(maxsize=1)
def mode_system() -> cs.Function:
    """(z[3], P[4+NP], sel[5]) -> (G[3], J[3x3], dd, c[4], fn[2]), all scaled; built once per
    process.

    P = (phi_k, tau/(M g L), p); sel is one-hot over :data:`ENUM_MODES`; dd = (d(phi) - d(phi_k))/L.
    """
    sym = symbolic()
    z = cs.SX.sym("z", 3)
    P = cs.SX.sym("P", 4 + NP)
    sel = cs.SX.sym("sel", len(ENUM_MODES))
    phi, ft = z[0:2], z[2]
    phi_k, tau_hat, p = P[0:2], P[2:4], P[4:4 + NP]
    prm = params(p)
    L, Mg = prm.L, prm.M * prm.g
    kin1 = sym.kin(phi, p)
    kin0 = sym.kin(phi_k, p)
    fn1, fn2 = kin1[KIN["fn1"]] / Mg, kin1[KIN["fn2"]] / Mg
    dd = (kin1[KIN["d"]] - kin0[KIN["d"]]) / L
    c = cs.vertcat(*friction_margins(prm.mu1, fn1, ft, prm.mu2, fn2, -ft))  # f_t2 = -f_t on foot 2
    mode_eq = sel[0] * dd + cs.dot(sel[1:], c)
    G = cs.vertcat(sym.residual(phi, tau_hat * Mg * L, ft * Mg, p) / (Mg * L), mode_eq)
    return cs.Function("step_mode_system", [z, P, sel],
                       [G, cs.jacobian(G, z), dd, c, cs.vertcat(fn1, fn2)],
                       ["z", "P", "sel"], ["G", "J", "dd", "c", "fn"])


def selector(mode: Mode) -> np.ndarray:
    sel = np.zeros(len(ENUM_MODES))
    sel[ENUM_MODES.index(mode)] = 1.0
    return sel


def damped_newton(f, z0: np.ndarray, P: np.ndarray, sel: np.ndarray,
            max_iter: int = 40) -> tuple[np.ndarray, bool, int]:
    """Damped Newton on G(z) = 0 (backtracking on max|G|)."""
    z = z0.copy()
    G, J = (np.asarray(a) for a in f(z, P, sel)[:2])
    G = G.ravel()
    r = float(np.max(np.abs(G)))
    for it in range(1, max_iter + 1):
        if r < NEWTON_TOL:
            return z, True, it - 1
        try:
            dz = np.linalg.solve(J, -G)
        except np.linalg.LinAlgError:
            return z, False, it
        if not np.all(np.isfinite(dz)):
            return z, False, it
        lam = 1.0
        while True:
            zn = z + lam * dz
            Gn, Jn = (np.asarray(a) for a in f(zn, P, sel)[:2])
            Gn = Gn.ravel()
            rn = float(np.max(np.abs(Gn))) if np.all(np.isfinite(Gn)) else np.inf
            if rn < r or rn < NEWTON_TOL or lam < 1e-4:
                break
            lam *= 0.5
        if not np.isfinite(rn):
            return z, False, it
        # a full step that no longer reduces the residual has hit round-off: stop if already tiny
        if rn >= r and r < 1e-11:
            return z, True, it
        z, G, J, r = zn, Gn, Jn, rn
    return z, r < 1e-11, max_iter


def solve_step_enumerate(model: Model, state: StepState, tau) -> StepResult:
    """Solve the incremental step exactly by enumerating the contact modes with Newton.

    Returns a :class:`~ocp_crawl.sim.step.StepResult` with status ``"Enumeration_Succeeded"`` or
    ``"No_Consistent_Mode"`` (both in :data:`~ocp_crawl.nlp.ipopt.IPOPT_RETURN_STATUS`; a failed
    result has NaN solution fields); ``extra['candidates']`` lists every mode tried,
    ``extra['lift_off']`` is True when no mode is consistent and a mode solution has a normal force
    <= 0.
    """
    if not isinstance(model, Model):
        raise TypeError(f"model must be a Model, got {type(model).__name__}")
    if not isinstance(state, StepState):
        raise TypeError(f"state must be a StepState, got {type(state).__name__}")
    tau = check_tau(tau)
    t_start = time.perf_counter()
    r = model.robot
    P = np.r_[state.phi, tau / (r.M * r.g * r.L), model.p]
    candidates = []
    iterations = 0
    for mode in ENUM_MODES:
        cand, its = _solve_mode(mode, state, P, (r.mu1, r.mu1, r.mu2, r.mu2), r.M * r.g)
        candidates.append(cand)
        iterations += its
    consistent = [c for c in candidates if c.get("consistent")]
    distinct = []
    for c in sorted(consistent, key=lambda c: _dphi(c["phi"], state.phi)):
        if not any(_dphi(c["phi"], d["phi"]) < DISTINCT_TOL for d in distinct):
            distinct.append(c)
    public = [{k: v for k, v in c.items() if k != "_w"} for c in candidates]
    extra = {"candidates": public, "n_consistent": len(consistent), "n_distinct": len(distinct),
             "lift_off": False}
    elapsed = time.perf_counter() - t_start
    if distinct:
        # among coinciding consistent solutions (a mode boundary) prefer the one with the most
        # margin
        chosen = max((c for c in consistent if _dphi(c["phi"], distinct[0]["phi"]) < DISTINCT_TOL),
                     key=lambda c: c["margin"])
        msg = f"consistent mode {chosen['mode']}"
        if len(distinct) > 1:
            msg += f" (closest to phi_k of {len(distinct)} distinct consistent solutions)"
        return step_result_from_w(model, state, chosen["_w"], tau=tau, success=True,
                                  status="Enumeration_Succeeded", message=msg,
                                  iterations=iterations, solve_time=elapsed, extra=extra)
    extra["lift_off"] = any(c.get("converged") and c["fn_min"] <= 0 for c in candidates)
    msg = "no consistent contact mode" + (" (a normal force would be <= 0: lift-off)"
                                          if extra["lift_off"] else "")
    return failed_step_result(model, state, tau, status="No_Consistent_Mode", message=msg,
                              iterations=iterations, solve_time=elapsed, extra=extra)


def _dphi(a, b) -> float:
    """Largest angle difference [rad] of two configurations."""
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))))


def _solve_mode(mode: Mode, state: StepState, P: np.ndarray, mus: tuple,
                Mg: float) -> tuple[dict, int]:
    """The candidate of one contact mode: Newton from phi_k (and, for a slip mode, from the slipping
    foot's friction limit at phi_k), then its consistency.  Returns (candidate dict, Newton
    iterations)."""
    f = mode_system()
    sel = selector(mode)
    guesses = [np.r_[state.phi, state.f_t / Mg]]
    j = ENUM_MODES.index(mode) - 1  # the slipping pair (-1: stick)
    if mode != Mode.STICK:
        fn = np.asarray(f(guesses[0], P, sel)[4]).ravel()
        sign = (-1.0, 1.0, 1.0, -1.0)[j]  # f_t/(Mg) on the friction limit of pair j
        guesses.append(np.r_[state.phi, sign * mus[j] * fn[0 if j < 2 else 1]])
    best, iterations = None, 0
    for z0 in guesses:
        z, ok, its = damped_newton(f, z0, P, sel)
        iterations += its
        if ok:
            best = z
            break
    if best is None:
        return {"mode": mode.label, "converged": False}, iterations
    _, _, dd, c, fn = (np.asarray(a).ravel() for a in f(best, P, sel))
    s = np.zeros(NPAIR)
    if mode != Mode.STICK:
        # closure d - d_k = dx2 - dx1 with the partner foot fixed
        dx = -float(dd[0]) if j < 2 else float(dd[0])
        s[j] = dx if j in (0, 2) else -dx
    margins = np.r_[c, s]
    if mode != Mode.STICK:
        margins[j] = np.inf  # c_j = 0 holds by construction
    consistent = bool(np.min(margins) >= -CONSISTENCY_TOL and np.min(fn) > 0)
    w = np.r_[best[:2], best[2], -best[2], np.maximum(s, 0.0)]
    return {"mode": mode.label, "converged": True, "consistent": consistent,
            "phi": best[:2].tolist(), "f_t": float(best[2]) * Mg,
            "margin": float(np.min(margins)), "fn_min": float(np.min(fn)) * Mg, "_w": w}, iterations
