"""One incremental (time-stepping) step of an n-link chain with two Coulomb feet, and the
time-stepping simulation of a torque-driven chain gait built on it.

The step equations generalise :mod:`ocp_crawl.model.step_equations` to m = n - 1 joints.  Scaled
step variables (forces by M g, lengths by L, torques by M g L):

    w = (phi_1 .. phi_m, f_t1/Mg, f_t2/Mg, s1+/L, s1-/L, s2+/L, s2-/L, c1+, c1-, c2+, c2-)

with the joint balance F(phi, tau, f_t1) = 0 (m rows), the horizontal balance f_t1 + f_t2 = 0, the
closure (d(phi) - d(phi_k))/L = dx2 - dx1 with dx_j = s_j+ - s_j-, the lifted friction margins
c = (mu1 f_n1 + f_t1, mu1 f_n1 - f_t1, mu2 f_n2 + f_t2, mu2 f_n2 - f_t2)/(M g) at the end of the
step, and the complementarity pairs 0 <= s_j _|_ c_j >= 0 (the MPCC of the paper).

:class:`ChainStep` solves a step exactly by enumerating the five contact modes (stick-stick and a
slip of either foot either way, a slipping foot's partner sticking), as
:mod:`ocp_crawl.sim.oracle` does for three links: each mode's m + 1 equations in
z = (phi, f_t/(M g)) are solved by a damped Newton method from phi_k, and the consistent solution
(every slip and margin >= 0, normal forces > 0) closest to phi_k is kept.  The kept point is
checked against the MPCC equations of :func:`chain_step_nlp` (``eq_residual``,
``comp_residual``).  The simulation (:func:`simulate_chain_mpcc`) takes N such steps per cycle;
a step whose contact mode changes is split at the event located inside it
(:mod:`ocp_crawl.sim.chain_mpcc_split`), so that the foot positions and S carry no discretisation
error; without the splits each step is entirely in its end mode (an O(1/N) error in S).  The
switch-exact steps also end at the input's kinks (:func:`step_phases`), and a step stays in the
mode it starts in when that mode holds to its end (at a tie of the feet's limits at the step's
end, or a hold of the input, several modes close the step), as the event-driven stepper does.
A contact the steps find lost inside a step (at its end, or in a dip of its guard that the guard's
interpolant flags) ends the run where its guard first reaches zero
(:mod:`ocp_crawl.sim.chain_mpcc_checks`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import casadi as cs
import numpy as np

from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.model.chain_statics import chain_symbolic, kin_names, n_params
from ocp_crawl.model.step_equations import NPAIR, friction_margins
from ocp_crawl.sim.assemble import (balance_metrics, energy_gate, failure_message, new_result,
                                    output_phases, sample_fields, success_message)
from ocp_crawl.sim.chain_mpcc_checks import RunStop, check_end, dip_stop, mode_row
from ocp_crawl.sim.step_dips import CONTACT
from ocp_crawl.sim.chain_torque import ChainTorqueStepper, as_chain_torque
from ocp_crawl.sim.oracle import ENUM_MODES, damped_newton
from ocp_crawl.sim.result import Event, Mode, mode_change_kind
from ocp_crawl.sim.step import mode_from_pairs
from ocp_crawl.sim.timestepping_output import resample
from ocp_crawl.status import Status

#: a success's |energy balance residual| (relative to the gross work) is at most ENERGY_TOL_N2 / N^2
#: at N steps per cycle (the midpoint rule's order; the three-link MPCC's default)
ENERGY_TOL_N2 = 10.0

CONSISTENCY_TOL = 1e-10
"""a scaled slip or friction margin >= -CONSISTENCY_TOL counts as nonnegative [-]"""
DISTINCT_TOL = 1e-9
"""consistent solutions closer than this in phi [rad] are the same solution"""


def _kin_rows(n: int) -> dict[str, int]:
    return {k: i for i, k in enumerate(kin_names(n))}


def _scaled_kin(n: int, phi, p):
    """(d/L, f_n1/Mg, f_n2/Mg, mu1, mu2, M g, L) of the chain at phi (CasADi)."""
    sym, rows, m = chain_symbolic(n), _kin_rows(n), n - 1
    kin = sym.kin(phi, p)
    L = sum(p[i] for i in range(n))
    Mg = sum(p[i] for i in range(n, 2 * n)) * p[3 * n + 2 * m + 2]
    mu1, mu2 = p[3 * n + 2 * m], p[3 * n + 2 * m + 1]
    return kin[rows["d"]] / L, kin[rows["fn1"]] / Mg, kin[rows["fn2"]] / Mg, mu1, mu2, Mg, L


@lru_cache(maxsize=None)
def chain_step_nlp(n: int) -> cs.Function:
    """The MPCC step equations of the n-link chain (built once per n and process).

    Returns
    -------
    casadi.Function
        ``(w[m + 10], P[2 m + 5 n]) -> (g_eq[m + 2], g_lift[4], s[4], c[4])`` with
        P = (phi_k [rad], tau/(M g L) [-], p) and w as in the module docstring: the scaled joint
        balance, horizontal balance and closure residuals, the lifting residuals c - margins, and
        the complementarity pairs (slips / L, margins / (M g)).  A solution of the step is a w
        with g_eq = g_lift = 0, s >= 0, c >= 0 and s_j c_j = 0.
    """
    m = n - 1
    w, P = cs.SX.sym("w", m + 10), cs.SX.sym("P", 2 * m + n_params(n))
    phi_k, tau_hat, p = P[0:m], P[m:2 * m], P[2 * m:]
    phi, ft1, ft2, s, c = w[0:m], w[m], w[m + 1], w[m + 2:m + 6], w[m + 6:m + 10]
    d1, fn1, fn2, mu1, mu2, Mg, L = _scaled_kin(n, phi, p)
    d0 = _scaled_kin(n, phi_k, p)[0]
    F = chain_symbolic(n).residual(phi, tau_hat * Mg * L, ft1 * Mg, p) / (Mg * L)
    closure = (d1 - d0) - ((s[2] - s[3]) - (s[0] - s[1]))
    g_eq = cs.vertcat(F, ft1 + ft2, closure)
    margins = cs.vertcat(*friction_margins(mu1, fn1, ft1, mu2, fn2, ft2))
    return cs.Function(f"chain{n}_step_equations", [w, P], [g_eq, c - margins, s, c],
                       ["w", "P"], ["g_eq", "g_lift", "s", "c"])


@lru_cache(maxsize=None)
def chain_mode_system(n: int) -> cs.Function:
    """(z[n], P[2 m + 5 n], sel[5]) -> (G[n], J[n x n], dd, c[4], fn[2]) of the n-link chain.

    z = (phi [rad], f_t/(M g)); sel is one-hot over :data:`ENUM_MODES`;
    G = (joint balance / (M g L), mode equation), the mode equation dd = (d(phi) - d(phi_k))/L in
    stick-stick and the slipping pair's margin in a slip.
    """
    m = n - 1
    z, P, sel = cs.SX.sym("z", n), cs.SX.sym("P", 2 * m + n_params(n)), cs.SX.sym("sel", 5)
    phi, ft = z[0:m], z[m]
    phi_k, tau_hat, p = P[0:m], P[m:2 * m], P[2 * m:]
    d1, fn1, fn2, mu1, mu2, Mg, L = _scaled_kin(n, phi, p)
    dd = d1 - _scaled_kin(n, phi_k, p)[0]
    c = cs.vertcat(*friction_margins(mu1, fn1, ft, mu2, fn2, -ft))
    G = cs.vertcat(chain_symbolic(n).residual(phi, tau_hat * Mg * L, ft * Mg, p) / (Mg * L),
                   sel[0] * dd + cs.dot(sel[1:], c))
    return cs.Function(f"chain{n}_step_modes", [z, P, sel],
                       [G, cs.jacobian(G, z), dd, c, cs.vertcat(fn1, fn2)],
                       ["z", "P", "sel"], ["G", "J", "dd", "c", "fn"])


@dataclass(frozen=True)
class ChainStepResult:
    """One solved step of the chain.  Forces [N] act on the chain; slips and positions [m]."""

    success: bool
    message: str
    phi: np.ndarray
    """joint angles after the step [rad], shape (m,)"""
    f_t: float
    """tangential force on the chain at foot 1 along +x [N] (at foot 2 it is -f_t)"""
    f_n1: float
    """normal force at foot 1 after the step [N]"""
    f_n2: float
    """normal force at foot 2 after the step [N]"""
    slips: np.ndarray
    """(s1+, s1-, s2+, s2-) [m], each >= 0"""
    x1: float
    """position of foot 1 after the step [m]"""
    x2: float
    """position of foot 2 after the step [m]"""
    d: float
    """d(phi) after the step [m]"""
    mode: Mode
    """contact mode of the kept solution"""
    eq_residual: float
    """largest scaled residual of the MPCC equations (:func:`chain_step_nlp`) and bounds [-]"""
    comp_residual: float
    """max_j |min(s_j/L, c_j/(M g))| [-]"""
    extra: dict = field(default_factory=dict)


class ChainStep:
    """The exact incremental step of an n-link chain by mode enumeration.

    Parameters
    ----------
    model : ChainModel
        The chain and the gravity convention.
    """

    def __init__(self, model: ChainModel):
        if not isinstance(model, ChainModel):
            raise TypeError(f"model must be a ChainModel, got {type(model).__name__}")
        self.model = model
        self.n = model.chain.n
        self.m = self.n - 1
        self._f = chain_mode_system(self.n)
        self._eqs = chain_step_nlp(self.n)
        self.p = model.p
        self.Mg, self.L = model.Mg, model.chain.L
        mu1, mu2 = model.chain.mu
        self._mus = (mu1, mu1, mu2, mu2)

    def params(self, phi_k: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """The parameter vector P = (phi_k [rad], tau/(M g L), p) of the scaled step."""
        return np.concatenate([phi_k, np.asarray(tau, float) / (self.Mg * self.L), self.p])

    def solve(self, phi_k, x1: float, x2: float, tau, f_t: float = 0.0,
              prefer: Mode | None = None) -> ChainStepResult:
        """The step from the angles ``phi_k`` [rad] and feet ``x1``, ``x2`` [m] to the torques
        ``tau`` [N m] at the step's end; ``f_t`` [N] (the last force) seeds the Newton guesses.

        Of several consistent solutions the one closest to phi_k; with ``prefer``, the solution
        of that mode when it is consistent, named by it (a slip with zero slip over the step
        keeps its name), which the switch-exact steps ask for when the mode the step starts in
        holds to its end (:func:`~ocp_crawl.sim.chain_mpcc_split.advance`)."""
        phi_k = np.asarray(phi_k, float).reshape(self.m)
        tau = np.asarray(tau, float).reshape(self.m)
        P = self.params(phi_k, tau)
        cands = [self._candidate(k, phi_k, P, f_t / self.Mg) for k in range(len(ENUM_MODES))]
        ok = [c for c in cands if c is not None and c["consistent"]]
        if not ok:
            nan = float("nan")
            return ChainStepResult(False, "no consistent contact mode", np.full(self.m, nan), nan,
                                   nan, nan, np.full(4, nan), nan, nan, nan, Mode.STICK, nan,
                                   nan, {"candidates": cands})
        kept = [c for c in ok if c["mode"] is prefer]
        if kept:
            return self._result(kept[0], P, x1, x2, kept[0]["mode"])
        ok.sort(key=lambda c: float(np.max(np.abs(c["z"][:self.m] - phi_k))))
        near = [c for c in ok if np.max(np.abs(c["z"][:self.m] - ok[0]["z"][:self.m]))
                < DISTINCT_TOL]
        best = max(near, key=lambda c: c["margin"])
        return self._result(best, P, x1, x2)

    def mode_solution(self, mode: Mode, phi_k, tau, f_t: float = 0.0) -> dict | None:
        """The step from ``phi_k`` [rad] to the torques ``tau`` [N m] in one contact mode of
        :data:`ENUM_MODES`: a dict with ``z`` = (phi [rad], f_t/(M g)), the scaled slips ``slip``
        (signed) and margins ``c``, ``margin`` (the least of them, the slipping pair's margin
        left out) and ``consistent``; None when Newton fails."""
        phi_k = np.asarray(phi_k, float).reshape(self.m)
        return self._candidate(ENUM_MODES.index(mode), phi_k, self.params(phi_k, tau),
                               f_t / self.Mg)

    def _candidate(self, k: int, phi_k: np.ndarray, P: np.ndarray, ft0: float) -> dict | None:
        """Mode ``ENUM_MODES[k]``: Newton from phi_k (a slip also from its friction limit), then
        its slips, margins and consistency; None when Newton fails."""
        f, sel = self._f, np.eye(5)[k]
        guesses = [np.r_[phi_k, ft0]]
        j = k - 1
        if k:
            fn = np.asarray(f(guesses[0], P, sel)[4]).ravel()
            guesses.append(np.r_[phi_k, (-1.0, 1.0, 1.0, -1.0)[j] * self._mus[j]
                                 * fn[0 if j < 2 else 1]])
        for z0 in guesses:
            z, conv, _ = damped_newton(f, z0, P, sel)
            if conv:
                break
        else:
            return None
        _, _, dd, c, fn = (np.asarray(a).ravel() for a in f(z, P, sel))
        s = np.zeros(NPAIR)
        if k:
            dx = -float(dd[0]) if j < 2 else float(dd[0])
            s[j] = dx if j in (0, 2) else -dx
        margins = np.r_[c, s]
        if k:
            margins[j] = np.inf
        return {"mode": ENUM_MODES[k], "z": z, "s": np.maximum(s, 0.0), "c": c, "slip": s,
                "fn": fn * self.Mg, "margin": float(np.min(margins)),
                "consistent": bool(np.min(margins) >= -CONSISTENCY_TOL and np.min(fn) > 0)}

    def _result(self, cand: dict, P: np.ndarray, x1: float, x2: float,
                mode: Mode | None = None) -> ChainStepResult:
        """The physical result of a consistent candidate, checked on the MPCC equations; its mode
        ``mode``, or the one its complementarity pairs show."""
        m, z, s = self.m, cand["z"], cand["s"]
        _, _, dd, c, fn = (np.asarray(a).ravel() for a in self._f(z, P, np.eye(5)[0]))
        w = np.r_[z, -z[m], s, c]
        g_eq, g_lift, _, _ = (np.asarray(a).ravel() for a in self._eqs(w, P))
        eq = float(max(np.max(np.abs(g_eq)), np.max(np.abs(g_lift)),
                       np.max(np.maximum(-s, 0)), np.max(np.maximum(-c, 0))))
        comp = float(np.max(np.abs(np.minimum(s, c))))
        sl = s * self.L
        dx1, dx2 = sl[0] - sl[1], sl[2] - sl[3]
        d = float(x2 - x1 + dd[0] * self.L)
        return ChainStepResult(True, f"consistent mode {cand['mode'].label}", z[:m].copy(),
                               float(z[m] * self.Mg), float(fn[0] * self.Mg),
                               float(fn[1] * self.Mg), sl, float(x1 + dx1), float(x2 + dx2), d,
                               mode_from_pairs(s, c)[0] if mode is None else mode, eq, comp,
                               {"w": w})


def step_phases(torque, N: int, switch_exact: bool = True) -> np.ndarray:
    """The ends of one cycle's steps [cycles]: k / N, k = 0..N, and, for switch-exact steps, the
    input's kinks and the ends of its holds (:class:`~ocp_crawl.sim.chain_pieces.ChainPieces`), so
    that no step straddles a jump of the torques' rate or the end of a hold (a slip stopped there
    is an event there, located at the start of the step after it)."""
    grid = np.arange(N + 1) / N
    if not switch_exact:
        return grid
    from ocp_crawl.sim.chain_pieces import ChainPieces
    pieces = ChainPieces(torque)
    breaks = np.mod(np.concatenate([pieces.kinks, np.ravel(pieces.holds)]), 1.0)
    near = np.min(np.abs(breaks[:, None] - grid[None, :]), axis=1) if breaks.size else breaks
    return np.unique(np.concatenate([grid, breaks[near > 1e-12]]))


def _take_step(step: ChainStep, torque, rows: list, span: tuple, first: int, prev: tuple | None,
               located: set, switch_exact: bool) -> list:
    """The rows of the step ``span`` = (ta, tb) from rows[-1] (:func:`advance`; the phases of its
    events added to ``located``, rows[-1] dropped when the step redid the one before), checked
    (:func:`~ocp_crawl.sim.chain_mpcc_checks.check_end`); RunStop at a failure, or at a contact
    lost earlier in the cycle (its rows from ``first``)."""
    from ocp_crawl.sim.chain_mpcc_split import advance
    ta, tb = span
    before = rows[max(first - 1, 0):]
    try:
        new, res, dropped, found = advance(step, torque, rows[-1], ta, tb, switch_exact, prev)
        located.update(found)
        if dropped:
            rows.pop()
        before = rows[max(first - 1, 0):] + new[:-1]
        if not res.success:
            mode = res.extra.get("start_mode", rows[-1][8])
            end = mode_row(step, res, mode, tb)
            if end is not None:   # (the contact that mode's equilibrium has lost)
                check_end(step, torque, before, end, located, consistent=False)
            raise RunStop(res.extra.get("status", Status.NO_CONSISTENT_MODE), tb, rows[-1][8],
                          f"step at t = {tb:.6f}: {res.message}")
        check_end(step, torque, before, new[-1], located)
    except RunStop as stop:
        if stop.status not in CONTACT:   # (the step's own rows too: a lost contact came first)
            dip_stop(step, torque, before + ([new[-1]] if res.success else []), located)
        raise
    return new


def _run_cycles(step: ChainStep, torque, start, N: int, cycles_max: int,
                periodic_tol: float, switch_exact: bool) -> tuple[list, int, float, set]:
    """Steps of N per cycle from the released start until the state at a cycle's end repeats.

    Returns the rows (t, phi, x1, x2, f_t, f_n1, f_n2, d, mode) of every step, the cycles run,
    the last periodicity deviation [rad, -] and the phases of the events the steps located.
    """
    kin = step.model.kinematics(start.x[:-1])
    rows = [(0.0, start.x[:-1].copy(), 0.0, float(kin["d"]), 0.0, float(kin["fn1"]),
             float(kin["fn2"]), float(kin["d"]), Mode.STICK)]
    ends = [(rows[0][1], 0.0, Mode.STICK)]
    dev, located = float("nan"), set[float]()
    grid = step_phases(torque, N, switch_exact)
    for cycle in range(1, cycles_max + 1):
        first = len(rows) - 1
        for k in range(1, grid.size):
            ta, tb = cycle - 1 + grid[k - 1], cycle - 1 + grid[k]
            # the step that ended in rows[-1], when it stayed in one mode (its start rows[-2]):
            # an event it passed may be traced back into it
            prev = (rows[-2] if len(rows) >= 2 and rows[-2][8] == rows[-1][8] and k > 1
                    else None)
            rows.extend(_take_step(step, torque, rows, (ta, tb), first, prev, located,
                                   switch_exact))
        # (a contact guard may dip below zero and back inside a step, unseen at the steps' ends)
        dip_stop(step, torque, rows[max(first - 1, 0):], located)
        end = rows[-1]
        ends.append((end[1], end[4] / step.Mg, end[8]))
        (pa, fa, ma), (pb, fb, mb) = ends[-2], ends[-1]
        dev = max(float(np.max(np.abs(pa - pb))), abs(fa - fb))
        if cycle >= 2 and ma == mb and dev <= periodic_tol:
            return rows, cycle, dev, located
    raise RunStop(Status.NOT_PERIODIC, float(cycles_max), rows[-1][8],
                  f"not periodic after {cycles_max} cycles (last change {dev:.3g})")


def _events(rows: list, located: set) -> list[Event]:
    """The mode changes of the run's ``rows``: at the first row of the new mode, an event point
    where the step split located it (its phase in ``located``), else the end of the step the
    change happened in (the three-link time-stepping's "mode_change_between_steps")."""
    out = []
    for a, b in zip(rows, rows[1:]):
        if a[8] != b[8]:
            found = b[0] in located
            out.append(Event(b[0], mode_change_kind(a[8], b[8]), a[8].label, b[8].label,
                             0.0 if found else float("nan"),
                             "step_split" if found else "mode_change_between_steps"))
    return out


def _metrics(model: ChainModel, torque, rows: list, te) -> tuple[dict, dict]:
    """S, W+ (midpoint rule on the steps), CoT+ and the energy balance (trapezoidal friction) of
    the steps ``rows`` of one cycle, and the sample fields: on the step phases, or on the phases
    ``te`` of the cycle by linear interpolation between the steps."""
    t = np.array([r[0] for r in rows])
    phi = np.stack([r[1] for r in rows], axis=1)
    x1, x2, ft, fn1, fn2, d = (np.array([r[i] for r in rows]) for i in range(2, 8))
    tau_mid = np.asarray(torque(0.5 * (t[1:] + t[:-1])), float).reshape(phi.shape[0], -1)
    work = tau_mid * np.diff(phi, axis=1)
    f_mid = 0.5 * (ft[1:] + ft[:-1])
    diss = float(np.sum(-(f_mid * np.diff(x1) - f_mid * np.diff(x2))))
    dV = float(model.potential(phi[:, -1]) - model.potential(phi[:, 0]))
    metrics = balance_metrics(model.chain, float(x1[-1] - x1[0]),
                              np.maximum(work, 0.0).sum(axis=1), float(work.sum()), dV, diss,
                              float(np.abs(work).sum()))
    kin = model.kinematics(phi)
    mode = np.array([int(r[8]) for r in rows], int)
    cols = {"theta": kin[f"alpha{model.chain.n // 2 + 1}"], "d": d, "x1": x1, "x2": x2,
            "f_t": ft, "f_n1": fn1, "f_n2": fn2}
    if te is not None:
        t, phi, cols, mode = resample(t[0] + te, t, phi, cols, mode)
    tau = np.asarray(torque(t), float).reshape(phi.shape[0], -1)
    return metrics, sample_fields(t=t, phi=phi, tau=tau, mode=mode, **cols)


def simulate_chain_mpcc(chain_model: ChainModel, torques, *, steps: int = 200,
                        cycles_max: int = 12, periodic_tol: float = 1e-10,
                        switch_exact: bool = True, t_eval=None):
    """Time-stepping gait of an n-link chain: ``steps`` exact incremental steps per cycle.

    Parameters
    ----------
    chain_model : ChainModel
        The chain and the gravity convention.
    torques : PeriodicSignal, callable or array_like
        1-periodic joint torques tau(t) [N m] with m = n - 1 rows of the phase t [cycles], as
        for :func:`~ocp_crawl.sim.chain_torque.simulate_chain_torque`.
    steps : int
        Steps per cycle N; step k goes from t_{k-1} to t_k = k / N with the torques at t_k.
    cycles_max : int
        Most cycles run before the status ``not_periodic``.
    periodic_tol : float
        Largest change of phi [rad] and f_t/(M g) [-] at the cycle's end between the last two
        cycles of a periodic gait.
    switch_exact : bool
        Split a step whose contact mode changes at the event located inside it
        (:mod:`ocp_crawl.sim.chain_mpcc_split`); False: each step entirely in its end mode.
    t_eval : array_like of float, optional
        Output phases in [0, 1] of the steady cycle [cycles], by linear interpolation between the
        steps; default the step phases and the located events.

    Returns
    -------
    CrawlResult
        ``S`` [m] = x1(t0 + 1) - x1(t0), ``W_plus`` [J] by the midpoint rule
        sum_k sum_j max(0, tau_j(t_{k-1/2}) (phi_j,k - phi_j,k-1)) (per joint ``W_plus_joint``),
        CoT+, the energy balance (trapezoidal friction work) and the step samples of the last
        cycle (drive ``"torque"``); a failure is a status with ``failure_t``.
    """
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 2:
        raise ValueError(f"simulate_chain_mpcc: steps must be an integer >= 2, got {steps!r}")
    if isinstance(cycles_max, bool) or not isinstance(cycles_max, (int, np.integer)) \
            or cycles_max < 2:
        raise ValueError(f"simulate_chain_mpcc: cycles_max must be an integer >= 2, got "
                         f"{cycles_max!r}")
    step = ChainStep(chain_model)
    torque = as_chain_torque(torques, chain_model)
    te = output_phases(t_eval)
    try:
        start = ChainTorqueStepper(chain_model, torque, max_step=1.0 / 64, min_step=1e-11,
                                   event_xtol=1e-13, trial_step=1e-8, quad_h=1.0 / 32).start()
    except ValueError as exc:
        return new_result(chain_model, "torque", Status.NO_START,
                          failure_message(Status.NO_START, str(exc)), failure_t=0.0,
                          failure_mode="released start")
    N = int(steps)
    try:
        rows, cycles, dev, located = _run_cycles(step, torque, start, N, int(cycles_max),
                                                 periodic_tol, bool(switch_exact))
    except RunStop as stop:
        return new_result(chain_model, "torque", stop.status,
                          failure_message(stop.status, stop.detail), failure_t=stop.t,
                          failure_mode=stop.mode.label)
    t0 = float(cycles - 1)
    metrics, fields = _metrics(chain_model, torque,
                               [r for r in rows if t0 - 1e-12 <= r[0] <= t0 + 1 + 1e-12], te)
    extra = {"links": chain_model.chain.n, "steps_per_cycle": N, "periodicity_deviation": dev}
    res = new_result(chain_model, "torque", Status.SUCCESS,
                     success_message(cycles, t0, f" of {N} chain steps"), cycles=cycles, t0=t0,
                     events=_events(rows, located), nsteps=len(rows) - 1, periodicity_residual=dev,
                     extra=extra, **metrics, **fields)
    # (the midpoint rule's balance error is O(1/N^2): the three-link MPCC's default bound)
    return energy_gate(res, ENERGY_TOL_N2 / N**2, "ENERGY_TOL_N2 / N^2 of the chain's steps")
