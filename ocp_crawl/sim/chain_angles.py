"""Prescribed-angle locomotion of an n-link chain (the paper's Section II-A for any n >= 3).

The algorithm of :mod:`ocp_crawl.sim.angles` with the kinematics of
:class:`~ocp_crawl.model.chain_model.ChainModel`.  The m = n - 1 joint angles phi(t) are imposed,
so the configuration, d(t) and the normal forces are known at every phase; where d' != 0 one foot
slips: the one with the smaller friction limit mu_i f_n,i (|mu1 f_n1 - mu2 f_n2| <= TIE M g: both
feet slip symmetrically), along sign(d'); f_t = sign(d') mu_s f_n,s and the holding torques follow
from the joint balance.  The switching instants (d' = 0: the slip reverses; mu1 f_n1 = mu2 f_n2:
the slipping foot changes) are located by Brent's method on the exact kinematics, by the functions
of :mod:`ocp_crawl.sim.angles` (event location, tie rule, foot bookkeeping, quadrature).  The
motion is periodic after one cycle (quasistatic: only the phase matters).
"""
from __future__ import annotations

from functools import lru_cache

import casadi as cs
import numpy as np

from ocp_crawl.model.chain_inputs import as_joint_signal
from ocp_crawl.model.chain_model import ChainModel, call_columns
from ocp_crawl.model.chain_statics import chain_geometry, chain_params, kin_names, n_params
from ocp_crawl.model.inputs import PeriodicSignal
from ocp_crawl.sim.angles import (PERIODIC_TOL, failure_result, first_failure, piece_sums,
                                  slip_anchors, slip_friction, switch_event,
                                  switching_instants)
from ocp_crawl.sim.assemble import (balance_metrics, default_phases, new_result, output_phases,
                                    sample_fields)
from ocp_crawl.sim.quadrature import positive_part_integral
from ocp_crawl.sim.result import CrawlResult, Mode
from ocp_crawl.status import Status


class ChainGait:
    """Vectorised kinematics and switching functions of a prescribed chain gait at phases t.

    Called with phases t [cycles] it returns the rows of
    :func:`~ocp_crawl.model.chain_statics.kin_names` (N,), ``phi`` and ``dphi`` (m, N) [rad,
    rad/cycle], ``ddot`` = d' [m/cycle], ``h`` = (mu1 f_n1 - mu2 f_n2)/(M g) [-] and ``theta``, the
    angle of the reference link ``n // 2 + 1`` [rad] (the body angle for three links).
    """

    def __init__(self, model: ChainModel, angles: PeriodicSignal):
        self.model, self.angles = model, angles
        self.mu = model.chain.mu
        self.Mg = model.Mg
        self.m = model.chain.n_joints
        self.names = kin_names(model.chain.n)

    def __call__(self, t) -> dict[str, np.ndarray]:
        t = np.atleast_1d(np.asarray(t, float))
        phi = np.asarray(self.angles(t), float).reshape(self.m, -1)
        dphi = np.asarray(self.angles.derivative(t), float).reshape(self.m, -1)
        k = call_columns(self.model.sym.kin, phi, self.model.p)
        out = {n: k[i] for i, n in enumerate(self.names)}
        out["phi"], out["dphi"] = phi, dphi
        out["ddot"] = sum(out[f"grad_d{j}"] * dphi[j - 1] for j in range(1, self.m + 1))
        out["h"] = (self.mu[0] * out["fn1"] - self.mu[1] * out["fn2"]) / self.Mg
        out["theta"] = out[f"alpha{self.model.chain.n // 2 + 1}"]
        return out

    def scalar(self, name: str):
        """The switching or guard function ``name`` as a function of one phase (a float)."""
        return lambda t: float(self(t)[name][0])


def simulate_chain_angles(chain_model: ChainModel, phi_of_t, t_eval=None,
                          n_scan: int = 512) -> CrawlResult:
    """Prescribed-angle gait of an n-link chain over one cycle (it is periodic after one cycle).

    Parameters
    ----------
    chain_model : ChainModel
        The chain and the gravity convention.
    phi_of_t : PeriodicSignal, callable or array_like
        1-periodic interior joint angles (phi_1 .. phi_m) [rad] (pi = straight) of the phase t
        [cycles]: a signal with m rows (:mod:`ocp_crawl.model.chain_inputs`; for three links
        also :class:`~ocp_crawl.model.inputs.Harmonic`), a callable ``f(t) -> (m,)`` or samples
        (m, K) of one cycle at t = j/K (periodic cubic spline).
    t_eval : array_like of float, optional
        Output phases in [0, 1] [cycles]; by default 201 equally spaced phases plus the switching
        instants.
    n_scan : int
        Phases scanned for sign changes of the switching functions before Brent's method (>= 8).

    Returns
    -------
    CrawlResult
        ``S`` [m] (along +x, from foot 1 to foot 2), ``W_plus`` [J] (sum over the joints of the
        integral of max(0, tau_j phi_j'); per joint ``W_plus_joint`` (m,)), CoT+ [-], the energy
        balance, the switching events and, on the output phases: ``phi``, ``tau`` (holding torques)
        (m, N), feet positions ``x1``, ``x2``, ``d`` [m], ``f_t``, ``f_n1``, ``f_n2`` [N], the mode
        codes ``mode`` (:class:`~ocp_crawl.sim.result.Mode`) and ``theta`` (reference link angle).
        ``extra``: ``links`` (n), ``foot`` (slipping foot per output phase: 0 none, 1, 2, 3 both),
        ``alpha`` (n, N) link angles [rad].

    A loss of contact (a foot lifting off, a joint reaching the ground, the feet meeting) is a
    failure status with its phase ``failure_t`` and the mode just before it.  Invalid input
    raises ValueError (TypeError for a wrong type), as :func:`ocp_crawl.sim.angles.simulate_angles`.
    """
    if not isinstance(chain_model, ChainModel):
        raise TypeError("simulate_chain_angles: chain_model must be a ChainModel, got "
                        f"{type(chain_model).__name__}")
    angles = as_joint_signal(phi_of_t, chain_model.chain.n_joints)
    if isinstance(n_scan, bool) or not isinstance(n_scan, (int, np.integer)) or n_scan < 8:
        raise ValueError(f"simulate_chain_angles: n_scan must be an integer >= 8, got {n_scan!r}")
    te = output_phases(t_eval)
    ts = np.linspace(0.0, 1.0, int(n_scan) + 1)
    gait = ChainGait(chain_model, angles)
    _check_angles(gait, ts)
    K = gait(ts)
    failure = first_failure(gait, ts, K, gait.Mg, gait.model.chain.L, gait.m)
    if failure is not None:
        return failure_result(chain_model, gait, *failure)
    switches = switching_instants(gait, ts, K)
    anchors, S = slip_anchors(gait, [0.0] + [e[0] for e in switches] + [1.0], float(K["d"][0]))
    events = [switch_event(gait, t_ev, name) for t_ev, name in switches]
    if te is None:
        te = default_phases([e[0] for e in switches])
    samples, extra = _samples(gait, gait(te), te, anchors)
    wplus, w_in, w_abs, diss = _cycle_integrals(gait, anchors,
                                                np.asarray(getattr(angles, "t_knots", ()), float))
    dV = float(chain_model.potential(angles(1.0)) - chain_model.potential(angles(0.0)))
    return new_result(chain_model, "angles", Status.SUCCESS,
                      f"prescribed-angle gait of {chain_model.chain.n} links: {len(switches)} "
                      "switching instants per cycle", cycles=1, events=events, **samples,
                      **balance_metrics(chain_model.chain, S, wplus, w_in, dV, diss, w_abs),
                      periodicity_residual=float(np.max(np.abs(angles(1.0) - angles(0.0)))),
                      extra=extra)


def _check_angles(gait: ChainGait, ts: np.ndarray) -> None:
    """ValueError unless the angles are finite with their derivative on the scan phases ``ts``,
    1-periodic and give a two-foot contact at t = 0 (d > 0, every joint above the ground, both
    normal forces > 0)."""
    angles, m = gait.angles, gait.m
    phi, dphi = np.asarray(angles(ts), float), np.asarray(angles.derivative(ts), float)
    if phi.shape != (m, ts.size) or dphi.shape != phi.shape:
        raise ValueError(f"simulate_chain_angles: angles(t) must have shape ({m}, N) for N "
                         f"phases, got {phi.shape}")
    bad = ~np.all(np.isfinite(phi), axis=0) | ~np.all(np.isfinite(dphi), axis=0)
    if bad.any():
        raise ValueError("simulate_chain_angles: angles or their derivative not finite at phase "
                         f"t = {ts[np.argmax(bad)]:.6g}")
    gap = float(np.max(np.abs(np.asarray(angles(1.0), float) - np.asarray(angles(0.0), float))))
    if not gap <= PERIODIC_TOL:
        raise ValueError("simulate_chain_angles: angles must be 1-periodic in the phase, got "
                         f"|phi(1) - phi(0)| = {gap:.3g} rad")
    check_start(gait)


def check_start(gait: ChainGait) -> None:
    """ValueError unless the angles at t = 0 give a two-foot contact: the feet apart (d > 0), every
    joint above the ground and both normal forces > 0."""
    m = gait.m
    k0 = gait(0.0)
    where = (f"prescribed configuration at t = 0, phi = "
             f"{np.degrees(k0['phi'][:, 0]).round(3).tolist()} deg")
    if not k0["d"][0] > 0:
        raise ValueError(f"{where}: feet crossed or coincident (d = {k0['d'][0]:.4g} m <= 0)")
    for j in range(1, m + 1):
        if not k0[f"zj{j}"][0] > 0:
            raise ValueError(f"{where}: joint {j} at or below the ground (height "
                             f"{k0[f'zj{j}'][0]:.4g} m)")
    for i in (1, 2):
        if not k0[f"fn{i}"][0] > 0:
            raise ValueError(f"{where}: foot {i} off the ground (f_n{i} = {k0[f'fn{i}'][0]:.4g} N "
                             "<= 0): the centre of mass must lie between the feet")


def _samples(gait: ChainGait, Ko: dict, te: np.ndarray, anchors: list) -> tuple[dict, dict]:
    """The output array fields (:func:`~ocp_crawl.sim.assemble.sample_fields`) at the phases
    ``te`` with the kinematics ``Ko`` there, and the ``extra`` fields of the result."""
    n = len(te)
    modes, ft, x1o, x2o = np.empty(n, int), np.empty(n), np.empty(n), np.empty(n)
    for j, t in enumerate(te):
        _, _, m, xa1, xa2 = next((s for s in anchors if s[0] <= t <= s[1]), anchors[-1])
        modes[j] = int(m)
        k1 = {"fn1": Ko["fn1"][j], "fn2": Ko["fn2"][j]}
        ft[j] = slip_friction(gait.mu, k1, m)
        d = Ko["d"][j]
        if m.foot == 1:
            x1o[j], x2o[j] = xa2 - d, xa2
        elif m.foot == 2:
            x1o[j], x2o[j] = xa1, xa1 + d
        elif m.foot == 0:
            x1o[j], x2o[j] = xa1, xa2
        else:
            mid = 0.5 * (xa1 + xa2)
            x1o[j], x2o[j] = mid - 0.5 * d, mid + 0.5 * d
    chain_n = gait.model.chain.n
    tau = gait.model.hold_torque(Ko["phi"], ft)
    fields = sample_fields(te, Ko["phi"], Ko["theta"], Ko["d"], x1o, x2o, ft, Ko["fn1"], Ko["fn2"],
                           tau, modes)
    extra = {"links": chain_n, "foot": np.array([Mode(c).foot for c in modes], int),
             "alpha": np.array([Ko[f"alpha{i}"] for i in range(1, chain_n + 1)])}
    return fields, extra


@lru_cache(maxsize=None)
def _power_function(n: int) -> cs.Function:
    """CasADi function ``(phi[m], dphi[m], sw[2], p) -> tau * dphi`` (m) [W per cycle rate]: the
    power of each joint's holding torque ``tau = grad Pi + f_t grad d`` with ``f_t = sigma (w mu1
    f_n1 + (1 - w) mu2 f_n2)``, ``sw = (sigma, w)``; kinematics and torque in one call."""
    m = n - 1
    phi, dphi = cs.SX.sym("phi", m), cs.SX.sym("dphi", m)
    sw, p = cs.SX.sym("sw", 2), cs.SX.sym("p", n_params(n))
    geo = chain_geometry(phi, p, n)
    V = geo["U_el"] + chain_params(p, n).sgrav * geo["U_g"]
    ft = sw[0] * (sw[1] * geo["lim1"] + (1 - sw[1]) * geo["lim2"])
    tau = cs.gradient(V, phi) + ft * cs.gradient(geo["d"], phi)
    return cs.Function(f"chain{n}_power", [phi, dphi, sw, p], [tau * dphi],
                       ["phi", "dphi", "sw", "p"], ["power"])


class _Power:
    """Joint powers ``tau_j phi_j'`` (m, N) [J/cycle] in one mode at phases t, the last phases'
    values kept (the positive-part integral of every joint probes the same phases)."""

    def __init__(self, gait: ChainGait, mode: Mode):
        self.gait = gait
        self.sw = np.array([float(mode.sigma), 0.0 if mode.foot == 2 else 1.0])
        self.key, self.value = b"", np.zeros((gait.m, 0))

    def __call__(self, t) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, float))
        key = t.tobytes()
        if key != self.key:
            g = self.gait
            phi = np.asarray(g.angles(t), float).reshape(g.m, -1)
            dphi = np.asarray(g.angles.derivative(t), float).reshape(g.m, -1)
            self.value = call_columns(_power_function(g.model.chain.n), phi, dphi, self.sw,
                                     g.model.p)
            self.key = key
        return self.value


def _cycle_integrals(gait: ChainGait, anchors: list, knots: np.ndarray) -> tuple:
    """(W+ per joint (m,), input work, gross work, friction dissipation) [J] over the cycle, piece
    by piece: the stretches between switching instants split at the input's ``knots`` (as
    :func:`ocp_crawl.sim.angles._cycle_integrals`)."""
    wplus = np.zeros(gait.m)
    sums = np.zeros(3)
    pieces = []
    for a, b, m, _, _ in anchors:
        inner = knots[(knots > a) & (knots < b)]
        edges = np.concatenate([[a], inner, [b]])
        pieces += [(lo, hi, m) for lo, hi in zip(edges[:-1], edges[1:])]
    for a, b, m in pieces:
        power = _Power(gait, m)
        piece, h = piece_sums(gait.model, gait, gait.mu, a, b, m)
        sums += piece
        for i in range(gait.m):
            wplus[i] += positive_part_integral(a, b, lambda t, i=i: power(t)[i],
                                               lambda t, i=i: float(power(t)[i, 0]), h=h)
    w_in, w_abs, diss = (float(x) for x in sums)
    return wplus, w_in, w_abs, diss
