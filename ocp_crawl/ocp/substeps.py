"""Switch-exact sub-steps of the gait OCP: one friction scenario's variables and constraints, its
initial guess from an event-driven simulation and its solution in physical units.

Interval k (k = 1..N, from node k-1 at phase (k-1)/N to node k at phase k/N, node N = node 0) is
split into two sub-steps, ``a`` from node k-1 to an interior point at the torque
``tau_k-1 + theta_k (tau_k - tau_k-1)`` (``theta_k`` in [0, 1] a variable, the phase (k-1+theta_k)/N
on the linear-in-phase interpolant) and ``b`` from there to node k.  Each sub-step carries the full
incremental step equations and complementarity of :mod:`ocp_crawl.model.step_equations`.  Sub-step j
is column j of the (m+10, 2N) step variables (a of interval k is column 2k-2, b column 2k-1).  Cross
conditions (relaxed by the homotopy's sigma like the complementarity products, each scaled by N so
that it is of the size of a product s c):

* no sub-step has both feet slipping: ``N s1_j s2_j <= sigma`` with ``s_i = s_i+ + s_i-``;
* a foot starts slipping only at a sub-step boundary (slip onsets are switch-exact):
  ``N sum_q s_q,j c_q,j-1 <= sigma`` over the pairs q (s1+ with c1+, ...): a pair slips in sub-step
  j only if its margin is zero at the sub-step's start.  Without it a sub-step that sticks, then
  slips has the right end state (S is a function of the end states) but not the right path: a joint
  that turns one way while both feet stick and back once a foot slips does positive work that the
  midpoint rule of W+ nets out (min_cot at N = 100: W+ 0.32 % low, all of it in the one sub-step of
  an onset; with the rule 3e-7);
* the slipping foot changes at a sub-step boundary j (cyclically) only at the friction tie:
  ``N s1_j (s2+_j+1 c2+_j + s2-_j+1 c2-_j) <= sigma`` and the same with the feet exchanged: foot 2
  starts slipping in a direction only where its margin in that direction is already zero at the end
  of sub-step j.  A sub-step of zero length (theta = 0 or 1) has no slip of its own: sitting between
  two slips it would let the slipping foot change inside the next sub-step, away from the tie (an
  O(h) error per switch, which the optimiser exploits).  So the slip before boundary j is s_j plus
  the slips of its predecessors passed through short sub-steps with the weight max(0, 1 - l/SHORT)^2
  (l the sub-step's length as a fraction of its interval, SHORT = 0.1): s_j + w_j (s_j-1 + w_j-1
  s_j-2) (three sub-steps always span a whole interval).  The price: a slip of one foot, a stick
  shorter than SHORT h and a slip of the other without a tie is excluded.  A torque that stands
  still over a whole interval (allowed by the bandwidth) is not covered: it, too, makes a sub-step
  without slip.

A change of the slipping foot and a slip onset thus fall on sub-step boundaries (the interior point
moves to them), so the only remaining step errors are those of slip-to-stick and direction reversal
inside a sub-step, O(h^2) per event (at slip-to-stick d' falls to zero, so the angle rates do not
jump).  Both feet slipping at once (the event-driven simulator's slip-slip mode, possible only when
mu1 f_n1 = mu2 f_n2 identically, i.e. mirror-symmetric gaits) is excluded.

No held tie (:func:`tie_rows`, linear constraints): while one foot slips, the other must not sit at
its friction limit on the same side (c2- for s1+, c2+ for s1-, c1- for s2+, c1+ for s2-), neither
over the whole sub-step (``c_j-1 + c_j >= TIE_SLOPE s_j``) nor at its end or its start
(``c_j >= TIE_END s_j`` unless the other foot takes the slip over there, ``c_j-1 >= TIE_END s_j``
unless it hands the slip over there: a change of the slipping foot).  A held tie is the slip-slip
mode in disguise: in a mirror-symmetric posture under equal torques the two limits are equal all
along, the simulator slips both feet (half each, no net motion) while a transcription without the
rule slipped one foot only, from stick to the tie within one sub-step (min_cot at N = 100: a stroke
at the top of the envelope that moved the body 0.007 L a cycle, S 3.3 % off), or a touch of the
other foot's limit at a node after a change of the slipping foot (robust_speed: two consistent
successor modes in the replay).  A real change of the slipping foot passes: after it the margin of
the foot that stopped grows in proportion to the other's slip (both linearly from the switch); a
slip that stops near the tie slips little in its last sub-step.  The rules exclude margins that grow
by less than TIE_SLOPE M g per slip L, or end below TIE_END M g per slip L (about 0.3 % of the
friction limit for a sub-step's slip of 3e-3 L).
"""
from __future__ import annotations

import math

import casadi as cs
import numpy as np

from ocp_crawl.model.statics import NP
from ocp_crawl.model.step_equations import (NPAIR, NW, StepRows, friction_margins, rows_of,
                                            step_equations)
from ocp_crawl.sim.result import Mode
from ocp_crawl.sim.step import SLIP_PAIR_MODES

#: the guess's interior points: fraction of the interval when no foot switch is simulated inside it
THETA_GUESS = 0.5
#: a sub-step shorter than this fraction of its interval passes its predecessor's slip on to the
#: switch condition (a sub-step of zero length, theta = 0 or 1, has no slip of its own and would
#: hide a change of the slipping foot)
SHORT = 0.1
#: a simulated switch closer than this to a node [interval fraction] keeps the interior point off
#: the node
THETA_EDGE = 1e-6


def step_function() -> cs.Function:
    """One step's (equations and lifting, complementarity products) of (phi_prev, w, tau_hat, p)
    of the three-link robot (a chain's: :meth:`~ocp_crawl.ocp.plant.Plant.step_function`)."""
    phi_prev = cs.SX.sym("phi_prev", 2)
    w = cs.SX.sym("w", NW)
    th = cs.SX.sym("tau_hat", 2)
    p = cs.SX.sym("p", NP)
    g_eq, g_lift, sv, cv = step_equations(phi_prev, w, th, p)
    return cs.Function("ocp_step", [phi_prev, w, th, p], [cs.vertcat(g_eq, g_lift), sv * cv])


def substep_torques(T, theta):
    """Scaled torques at the ends of the 2N sub-steps (m, 2N): interior point of interval k at
    ``T_k-1 + theta_k (T_k - T_k-1)``, then node k (node N = node 0).  ``T``: node torques (m, N)
    of the m joints; ``theta``: (N,) or (1, N) interval fractions (CasADi or numpy)."""
    m = T.shape[0]
    if isinstance(T, np.ndarray):
        Tn = np.roll(T, -1, axis=1)
        Ta = T + np.reshape(theta, (1, -1)) * (Tn - T)
        return np.stack([Ta, Tn], axis=2).reshape(m, -1)
    Tn = cs.horzcat(T[:, 1:], T[:, 0])
    Ta = T + cs.repmat(cs.reshape(theta, 1, -1), m, 1) * (Tn - T)
    return cs.reshape(cs.vertcat(Ta, Tn), m, -1)


def _roll(x, n: int):
    """Cyclic shift along the sub-steps: element j of the result is element j - n of ``x`` (numpy or
    CasADi)."""
    if isinstance(x, np.ndarray):
        return np.roll(x, n, axis=-1)
    n %= x.shape[1]
    return x if n == 0 else cs.horzcat(x[:, -n:], x[:, :-n])


def pass_weights(theta):
    """Weight (2N,) of each sub-step's predecessor in the switch condition: 1 for a sub-step of zero
    length, falling as max(0, 1 - l/SHORT)^2 to 0 at the length l = SHORT (fraction of the
    interval); ``theta`` (N,) (numpy or CasADi column)."""
    if isinstance(theta, np.ndarray):
        length = np.column_stack([theta, 1.0 - theta]).ravel()
        return np.maximum(0.0, 1.0 - length / SHORT) ** 2
    length = cs.reshape(cs.horzcat(theta, 1.0 - theta).T, 1, -1)
    return cs.fmax(0.0, 1.0 - length / SHORT) ** 2


def _foot_slips(W):
    """The slips (1, 2N) of foot 1 and of foot 2 (both directions) of sub-step variables W."""
    sp = rows_of(W).s1p
    return W[sp, :] + W[sp + 1, :], W[sp + 2, :] + W[sp + 3, :]


def switch_windows(W, theta):
    """The slips that the switch condition at boundary j reads: per foot, the slip of sub-step j
    plus its predecessors' passed through sub-steps of (nearly) zero length (``before``: s_j + w_j
    (s_j-1 + w_j-1 s_j-2)), and per pair the slip of sub-step j+1 (``after``, rows s1+, s1-, s2+,
    s2-).  Returns (s1, s2, before, after)."""
    s1, s2 = _foot_slips(W)
    w = pass_weights(theta)
    before = [s + w * (_roll(s, 1) + _roll(w, 1) * _roll(s, 2)) for s in (s1, s2)]
    sp = rows_of(W).s1p
    after = [_roll(W[sp + q, :], -1) for q in range(NPAIR)]
    return s1, s2, before, after


def cross_products(W, theta, N: int):
    """The cross conditions' products of the (m+10, 2N) sub-step variables and the interior
    fractions (N,) (CasADi or numpy): both feet slipping per sub-step, foot 1 -> foot 2 and foot 2
    -> foot 1 switches at boundary j (:func:`switch_windows`), each scaled by N (see the module
    docstring). Returns (3, 2N)."""
    s1, s2, before, after = switch_windows(W, theta)
    c = rows_of(W).c1p
    both = N * s1 * s2
    to2 = N * before[0] * (after[2] * W[c + 2, :] + after[3] * W[c + 3, :])
    to1 = N * before[1] * (after[0] * W[c, :] + after[1] * W[c + 1, :])
    if isinstance(W, np.ndarray):
        return np.vstack((both, to2, to1))
    return cs.vertcat(both, to2, to1)


def onset_products(W, N: int):
    """The slip onsets' products (1, 2N): N sum over the pairs q of s_q,j c_q,j-1 (a pair slips in
    sub-step j only if its margin is already zero at the sub-step's start; see the module
    docstring).  ``W``: (m+10, 2N) sub-step variables (CasADi or numpy)."""
    R = rows_of(W)
    return N * sum(W[R.s1p + q, :] * _roll(W[R.c1p + q, :], 1) for q in range(NPAIR))


def onset_residual(W: np.ndarray) -> float:
    """Largest violation of the onset condition as a min-residual: min(s_q,j, c_q,j-1) over pairs
    and sub-steps [-]."""
    R = rows_of(W)
    return float(max(np.max(np.abs(np.minimum(W[R.s1p + q, :],
                                              _roll(W[R.c1p + q, :], 1)))) for q in range(NPAIR)))


def cross_residual(W: np.ndarray, theta: np.ndarray) -> float:
    """Largest violation of the cross conditions as a min-residual (like the complementarity
    residual): min(s1_j, s2_j) and min(slip before boundary j of one foot,
    slip after it of the other in direction d, that foot's margin c_d at j) (both switch directions,
    d = +, -) [-]."""
    s1, s2, before, after = switch_windows(W, theta)
    c = rows_of(W).c1p
    res = [np.minimum(s1, s2)]
    for d in range(2):
        res.append(np.minimum(np.minimum(before[0], after[2 + d]), W[c + 2 + d]))
        res.append(np.minimum(np.minimum(before[1], after[d]), W[c + d]))
    return float(np.max(np.abs(np.vstack(res))))


class Scenario:
    """The sub-step variables and constraints of one friction scenario, added to a Layout."""

    def __init__(self, nlp, j: int, model, T, Th, step_map, N: int, with_work: bool,
                 joint_rate: float | None = None, p=None,
                 stability: float | None = None):
        """Add scenario j: initial state, interior fractions, 2N sub-steps, periodicity, cross
        conditions, S and (``with_work``) W+ by the midpoint rule per sub-step.  ``model``: the
        scenario's :class:`~ocp_crawl.ocp.plant.Plant` (its parameter vector ``p``); ``T``: scaled
        node torques (m, N) of its m joints; ``Th``: the scaled period, which divides the relaxed
        products (a relaxation per unit time: the spurious slip that a relaxation sigma allows then
        cannot buy speed by shrinking the period); ``joint_rate`` (not None) bounds the joint rates
        (:func:`joint_rate_rows`, the angle change over a whole interval at T_hat = 1 [rad]);
        ``p``: the parameter vector as an expression (a design's; None: the Plant's numbers);
        ``stability`` (not None): every sub-step end's stick-stick reduced stiffness at least this
        times M g L (a chain's :attr:`~ocp_crawl.ocp.plant.Plant.stability_function`)."""
        inf = np.inf
        self.j, self.model, self.N = j, model, N
        m = T.shape[0]
        R = StepRows(m)
        phi0, ft0 = nlp.sym(f"phi0_{j}", m), nlp.sym(f"ft0_{j}")
        theta = nlp.sym(f"theta_{j}", N)
        W = nlp.sym(f"w_{j}", R.nw, 2 * N)
        nlp.var(f"phi0_{j}", phi0, 0.0, model.phi_max)
        nlp.var(f"ft0_{j}", ft0, -inf, inf)
        nlp.var(f"theta_{j}", theta, 0.0, 1.0)
        lbw = np.r_[np.zeros(m), -inf, -inf, np.zeros(2 * NPAIR)]
        ubw = np.r_[np.full(m, model.phi_max), inf, inf, np.full(2 * NPAIR, inf)]
        nlp.var(f"w_{j}", cs.vec(W), np.tile(lbw, 2 * N), np.tile(ubw, 2 * N))
        PHI = cs.horzcat(phi0, W[R.phi, :])  # (m, 2N+1)
        Tsub = substep_torques(T, theta)
        P = cs.repmat(cs.DM(model.p) if p is None else p, 1, 2 * N)
        eqs, comp = step_map(PHI[:, :-1], W, Tsub, P)
        nlp.con(f"eq_{j}", cs.vec(eqs), 0.0, 0.0, ("equation",))
        # the relaxed products' upper bound is sigma, set per homotopy stage
        nlp.con(f"comp_{j}", cs.vec(comp) / Th, -inf, 0.0, ("complementarity",))
        nlp.con(f"cross_{j}", cs.vec(cross_products(W, theta, N)) / Th, -inf, 0.0, ("cross",))
        nlp.con(f"onset_{j}", cs.vec(onset_products(W, N)) / Th, -inf, 0.0, ("cross", "rule"))
        nlp.con(f"periodic_{j}", cs.vertcat(W[R.phi, -1] - phi0, W[R.ft1, -1] - ft0), 0.0, 0.0,
                ("equation",))
        nlp.con(f"tie_{j}", cs.vec(tie_rows(W, theta)), 0.0, inf, ("rule",))
        if model.height_function is not None:   # a chain's joints above the ground
            heights = model.height_function.map(2 * N)(W[R.phi, :], P)
            nlp.con(f"height_{j}", cs.vec(heights), 0.0, inf)
        if stability is not None:   # no fold of the stick-stick equilibrium
            rows = model.stability_function.map(2 * N)(W[R.phi, :], W[R.ft1, :], P,
                                                       cs.DM.ones(1, 2 * N) * stability)
            nlp.con(f"stability_{j}", cs.vec(rows), 0.0, inf)
        if joint_rate is not None:
            rows = joint_rate_rows(PHI, theta, joint_rate * Th)
            nlp.con(f"joint_rate_{j}", cs.vec(rows), 0.0, inf, ("rule",))
        # S and W+ are lifted into running sums over the sub-steps (variables Sc_j, Wc_j, each
        # defined by a two-term recurrence): neither the nonlinear objective in them (W+/S, S/T) nor
        # their definitions make a dense row (a dense row costs one Jacobian direction per variable
        # it touches: 2.4x the evaluation time per IPOPT iteration at N = 100)
        # foot-1 displacement / L
        self.S = _running_sum(nlp, f"Sc_{j}", f"S_def_{j}", W[R.s1p, :] - W[R.s1p + 1, :])
        self.theta, self.W_plus = theta, None
        if with_work:
            # positive work per actuator and sub-step with slacks v >= tau_mid dphi, v >= 0 (scaled
            # by M g L)
            V = nlp.sym(f"v_{j}", m, 2 * N)
            nlp.var(f"v_{j}", cs.vec(V), 0.0, inf)
            tau_mid = 0.5 * (Tsub + cs.horzcat(Tsub[:, -1], Tsub[:, :-1]))
            nlp.con(f"wplus_{j}", cs.vec(V - tau_mid * (PHI[:, 1:] - PHI[:, :-1])), 0.0, inf)
            self.W_plus = _running_sum(nlp, f"Wc_{j}", f"W_def_{j}", cs.sum1(V))


#: the stuck foot's margin on the slipping foot's side, summed over a slipping sub-step's two ends,
#: is at least this times the sub-step's slip [M g / L]: no sub-step slips one foot while the other
#: is held at its friction limit
TIE_SLOPE = 0.01
#: at the end and at the start of a sub-step in which one foot slips, the other foot's margin on the
#: same side (or its slip on that side just after, resp. just before: a change of the slipping foot)
#: is at least this times the sub-step's slip [M g / L]
TIE_END = 0.1
#: (slip pair, margin pair of the other foot on the same side, slip pair of the other foot into
#: that side) of :func:`tie_rows`, as indices into (s1+, s1-, s2+, s2-) and (c1+, c1-, c2+, c2-):
#: s1+ with c2- and s2-, s1- with c2+ and s2+, s2+ with c1- and s1-, s2- with c1+ and s1+
TIE_PAIRS = ((0, 3, 3), (1, 2, 2), (2, 1, 1), (3, 0, 0))


def tie_rows(W, theta):
    """Rows (12, 2N) that must be >= 0, for each triple (s, c, s') of :data:`TIE_PAIRS`:
    ``c_j-1 + c_j - TIE_SLOPE s_j`` (the stuck foot's margin at both ends of sub-step j, the start
    being the end of sub-step j-1 cyclically), then ``c_j + s'_j+1 + w_j+1 s'_j+2 - TIE_END s_j``
    (its margin at the end, or its slip on that side just after, through a sub-step of nearly zero
    length with the weight w of :func:`pass_weights`), then
    ``c_j-1 + s'_j-1 + w_j-1 s'_j-2 - TIE_END s_j`` (the same at the start: a slip does not start at
    the tie unless it comes from the other foot).  ``W``: (m+10, 2N) sub-step variables, ``theta``:
    (N,) interior fractions (CasADi or numpy)."""
    w = pass_weights(theta)
    R = rows_of(W)
    pairs = [(R.s1p + q, R.c1p + c, R.s1p + o) for q, c, o in TIE_PAIRS]
    rows = [_roll(W[c:c + 1, :], 1) + W[c:c + 1, :] - TIE_SLOPE
            * W[q:q + 1, :] for q, c, _ in pairs]
    # the end of sub-step j (the other foot's slip after it), then its start (before it)
    for shift in (-1, 1):
        rows += [_roll(W[c:c + 1, :], max(shift, 0)) + _roll(W[o:o + 1, :], shift)
                 + _roll(w, shift) * _roll(W[o:o + 1, :], 2 * shift) - TIE_END
                 * W[q:q + 1, :] for q, c, o in pairs]
    return np.vstack(rows) if isinstance(W, np.ndarray) else cs.vertcat(*rows)


#: the joint-rate bound on each sub-step's mean rate is this much looser (relative) than on each
#: interval's (:func:`joint_rate_rows`)
SUBSTEP_RATE_SLACK = 0.005


def joint_rate_rows(PHI, theta, step):
    """Rows (2m, 3N) that must be >= 0: the optional bound on the actual joint rates of the m
    joints, first on each interval, ``step -+ dphi_i,k`` (dphi_i,k the change of joint angle i from
    node k-1 to node k), then on each sub-step, ``(1 + SUBSTEP_RATE_SLACK) step l_j -+ dphi_i,j``
    (l_j the sub-step's length as a fraction of its interval: theta_k, then 1 - theta_k).  ``step``:
    the largest change of a joint angle over an interval [rad], radians(max_joint_rate_deg_s) T / N
    (a CasADi expression of the period).

    The interval rows bound the mean rate where the rate is smooth (inside an interval without a
    contact event it changes by O(1/N)).  The sub-step rows bound it on each side of a slip onset or
    switch (on the interior point), where the rate jumps and an interval's mean would hide a peak
    (max_speed, N = 20 and 50, interval rows alone: the replay's peak 3 to 4 % above the bound).
    They are slightly looser so that they do not bind inside smooth intervals: as tight as the
    interval rows, they drove the free interior points to the nodes (theta about 1e-6: the long
    sub-step's mean is the interval's, the weakest bound) and the polish found no feasible point
    (max_speed, N = 50).  The replay's peak is thus within the bound to SUBSTEP_RATE_SLACK plus
    O(1/N) (the judge's tolerance, :data:`~ocp_crawl.ocp.rates.JOINT_RATE_RTOL`).  ``PHI``: the
    angles (m, 2N+1) of the m joints at node 0 and every sub-step end; ``theta``: (N,) interior
    fractions (CasADi or numpy)."""
    loose = (1 + SUBSTEP_RATE_SLACK) * step
    if isinstance(PHI, np.ndarray):
        length = np.column_stack([theta, 1.0 - theta]).ravel()[None, :]
        dnode, dsub = np.diff(PHI[:, ::2], axis=1), np.diff(PHI, axis=1)
        return np.hstack([np.vstack([step - dnode, step + dnode]),
                          np.vstack([loose * length - dsub, loose * length + dsub])])
    length = cs.repmat(cs.reshape(cs.horzcat(theta, 1.0 - theta).T, 1, -1), PHI.shape[0], 1)
    nodes = PHI[:, ::2]
    dnode, dsub = nodes[:, 1:] - nodes[:, :-1], PHI[:, 1:] - PHI[:, :-1]
    return cs.horzcat(cs.vertcat(step - dnode, step + dnode),
                      cs.vertcat(loose * length - dsub, loose * length + dsub))


def _running_sum(nlp, var: str, con: str, terms):
    """Add the running sums c_m = c_m-1 + terms_m (c_-1 = 0) of a (1, n) row of expressions as the
    variables ``var`` (n,), defined by the equality constraints ``con``; returns the total c_n-1 (a
    scalar expression)."""
    n = terms.numel()
    c = nlp.sym(var, n)
    nlp.var(var, c, -np.inf, np.inf)
    nlp.con(con, c - cs.vertcat(0.0, c[:-1]) - cs.vec(terms), 0.0, 0.0, ("equation",))
    return c[-1]


def positive_work(tau_sub: np.ndarray, phi_sub: np.ndarray) -> float:
    """Discrete W+ of the transcription (the units of the inputs: [J] from [N m] and [rad]): the
    midpoint rule per sub-step, sum over actuators and sub-steps of max(0, tau_mid dphi).
    ``tau_sub``: torques at the sub-step ends (m, 2N) (the last one is node 0's); ``phi_sub``:
    angles (m, 2N+1) from node 0."""
    tau_mid = 0.5 * (tau_sub + np.roll(tau_sub, 1, axis=1))
    return float(np.sum(np.maximum(tau_mid * np.diff(phi_sub, axis=1), 0.0)))


def switch_fractions(res, N: int) -> np.ndarray:
    """Interior fractions of the guess: theta_k at the simulated change of the slipping foot inside
    interval k, else at another contact event there (slip onset, slip-to-stick: the sub-step
    boundary then makes it exact too), else THETA_GUESS.  ``res``: an event-driven CrawlResult;
    returns (N,)."""
    theta = np.full(N, THETA_GUESS)
    rank = np.full(N, 3)  # 0: a foot switch placed, 1: another event placed
    for ev in res.steady_events():
        if ev.kind.startswith("graze"):
            continue
        pos = (ev.t - res.t0) * N
        k = min(int(math.floor(pos)), N - 1)
        r = 0 if ev.kind == "slip_switch" else 1
        if 0 <= k < N and r < rank[k] and THETA_EDGE < pos - k < 1 - THETA_EDGE:
            theta[k], rank[k] = pos - k, r
    return theta


def guess_block(res, model, N: int) -> dict:
    """Scaled variables of one scenario sampled from an event-driven simulation ``res`` whose output
    phases are node 0 and the 2N sub-step ends: the state of node 0, the (m+10, 2N) sub-step
    variables and S.  ``model``: the scenario's model (its ``robot``: a Robot or a Chain)."""
    r = model.robot
    Mg, L = r.M * r.g, r.L
    phi, ft = res.phi, res.f_t / Mg
    R = StepRows(phi.shape[0])
    W = np.zeros((R.nw, 2 * N))
    W[R.phi] = phi[:, 1:]
    W[R.ft1], W[R.ft2] = ft[1:], -ft[1:]
    dx1, dx2 = np.diff(res.x1) / L, np.diff(res.x2) / L
    sp = R.s1p
    W[sp], W[sp + 1] = np.maximum(dx1, 0), np.maximum(-dx1, 0)
    W[sp + 2], W[sp + 3] = np.maximum(dx2, 0), np.maximum(-dx2, 0)
    fn1, fn2 = res.f_n1[1:] / Mg, res.f_n2[1:] / Mg
    # lifted margins at the simulated points (f_t2 = -f_t on foot 2), clipped to >= 0
    W[R.margins] = np.maximum(np.vstack(friction_margins(r.mu1, fn1, ft[1:], r.mu2, fn2,
                                                         -ft[1:])), 0.0)
    return {"phi0": phi[:, 0], "ft0": ft[0], "w": W, "S": float(np.sum(W[sp] - W[sp + 1]))}


def sample_phases(theta: np.ndarray) -> np.ndarray:
    """Phases [cycles] of node 0 and the 2N sub-step ends for the interior fractions ``theta``
    (N,)."""
    N = theta.size
    k = np.arange(N)
    return np.r_[0.0, np.column_stack([(k + theta) / N, (k + 1) / N]).ravel()]


def modes_of(W: np.ndarray) -> list[int]:
    """Contact mode of each sub-step (the pair that slips most, stick when none slips beyond its
    margin)."""
    R = rows_of(W)
    sv, cv = W[R.slips], W[R.margins]
    modes = []
    for k in range(W.shape[1]):
        sl = [i for i in range(NPAIR) if sv[i, k] > cv[i, k]]
        modes.append(int(Mode.STICK) if not sl
                     else int(SLIP_PAIR_MODES[max(sl, key=lambda q: sv[q, k])]))
    return modes
