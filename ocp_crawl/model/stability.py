"""Stability of the quasistatic equilibria of each contact mode.

An equilibrium of the mode equations ``G(x, tau, q, p) = 0`` of :mod:`ocp_crawl.model.statics`
is a result only if the robot would stay near it when slightly disturbed.  With the torque held
fixed, the joint balance of :mod:`~ocp_crawl.model.statics` is ``F = -grad Pi_tau - f_t grad d = 0``
with ``Pi_tau = U_el + sgrav U_g - tau . phi``; the torque term is linear in ``phi`` and drops out
of every second derivative, so below ``Pi = U_el + sgrav U_g`` [J].

Stick-stick (``e_ss = 1``; both feet fixed, ``d(phi) = d0``, ``f_t`` the Lagrange multiplier)
    The equilibrium is a constrained stationary point of ``Pi_tau`` with Lagrangian
    ``Pi_tau + f_t (d - d0)`` (its stationarity is ``F = 0``).  It is stable iff it is a strict
    minimum on the constraint curve, i.e. iff the *reduced stiffness*

        kappa = v^T (hess Pi + f_t hess d) v        [N m / rad^2, written N m/rad]

    is positive, with ``v = (-d_phi2, d_phi1)/|grad d|`` the unit tangent of ``d = const``.  kappa
    is the second derivative of ``Pi_tau`` along the curve ``d = d0`` parametrised by arc length in
    ``phi`` (the multiplier term accounts for the curvature of the constraint).

Slip (``e_ss = 0``; one foot at its friction limit,
    ``f_t(phi) = sigma (w mu1 fn1 + (1-w) mu2 fn2)``) Friction is not conservative and ``f_t``
    depends on ``phi`` through the normal forces, so there is no potential to minimise.  The
    criterion used is the linear stability of the overdamped (gradient-like) dynamics of the mode
    with the torque held fixed,

        phi' = -(grad Pi_tau + f_t(phi) grad d),   linearised:  dphi' = -K dphi,
        K = d/dphi [grad Pi + f_t(phi) grad d]     (2x2, not symmetric)  [N m/rad],

    which is stable iff both eigenvalues of K have positive real parts, i.e. iff
    ``trace K > 0`` and ``det K > 0``.  **Assumption:** an identity damping (mobility) metric in the
    joint angles, i.e. equal viscous damping of the two joints and none coupled; the slipping foot
    is assumed to keep slipping in the mode's direction ``sigma`` during the perturbation (a
    perturbation that moves it against ``sigma`` makes it stick, where kappa decides).  The
    sign of ``det K`` does not depend on the metric (any positive-definite damping gives the
    same determinant sign), the sign of ``trace K`` can (complex eigenvalues of K).
    A perturbed *quasistatic* run cannot test this: Newton converges to the same root whatever
    its stability; only a dynamic run can (see the tests).

Relation to the mode Jacobian ``J = dG/dx`` of :mod:`~ocp_crawl.model.statics` (its determinant is
already computed along every branch as ``aux["det"]``):

* stick-stick: ``det J = -kappa |grad d|^2 / (M g L^3)``, so kappa changes sign exactly where the
  mode's equations become singular (a fold);
* slip: ``det J = det K / (M g L)^2``; ``trace K`` can change sign (with ``det K > 0``) without
  ``det J`` vanishing: a sign change of ``det J`` alone does not detect it.

Units of :func:`stability_margin` (nondimensional, scaled by ``M g L``):
``kappa/(M g L)`` in stick-stick; ``min(tr K, det K/|tr K|)/(M g L)`` in slip modes
(``det K/|tr K|`` is a stiffness: for real positive eigenvalues it lies between half the smaller one
and the smaller one).  Margin > 0 <=> stable.
"""
from __future__ import annotations

from functools import lru_cache

import casadi as cs
import numpy as np

from ocp_crawl.model.compiled import compiled_function
from ocp_crawl.model.statics import NP, NQ, _geometry, call_mapped, params, symbolic

#: names of the outputs of :func:`stability_function`
STABILITY_NAMES = ("margin", "kappa", "trK", "detK")


@lru_cache(maxsize=1)
def stability_function() -> cs.Function:
    """CasADi function ``(x[3], q[4], p[NP]) -> s[4]`` (built once per process).

    ``x = (phi1, phi2, f_t/(M g))`` [rad, rad, -], ``q = (e_ss, sigma, w, d0)`` the mode parameters
    of :mod:`ocp_crawl.model.statics` (``d0`` is not used), ``p`` the model's parameter vector.
    ``s = (margin, kappa/(M g L), tr K/(M g L), det K/(M g L)^2)``, all nondimensional; ``margin``
    is the stick-stick value ``kappa/(M g L)`` when ``e_ss > 0.5``, else the slip value
    ``min(tr K, det K/|tr K|)/(M g L)``.  kappa uses ``f_t = x[2] M g``; K uses the mode's friction
    law ``f_t(phi)`` (equal to ``x[2] M g`` at a solution of the slip mode).
    """
    x = cs.SX.sym("x", 3)
    q = cs.SX.sym("q", NQ)
    p = cs.SX.sym("p", NP)
    pr = params(p)
    phi = x[0:2]
    MgL = pr.M * pr.g * pr.L
    geo = _geometry(phi, p)
    Pi = geo["U_el"] + pr.sgrav * geo["U_g"]
    grad_d = cs.gradient(geo["d"], phi)
    grad_Pi = cs.gradient(Pi, phi)
    # stick-stick: Hessian of the Lagrangian Pi + f_t (d - d0) along the tangent of d = const
    ft = x[2] * pr.M * pr.g
    H_lag = cs.jacobian(grad_Pi + ft * grad_d, phi)
    v = cs.vertcat(-grad_d[1], grad_d[0]) / cs.norm_2(grad_d)
    kappa = cs.dot(v, H_lag @ v) / MgL
    # slip: stiffness of the overdamped flow with f_t following the friction limit
    K = _slip_stiffness(phi, q, p, geo) / MgL
    trK = K[0, 0] + K[1, 1]
    detK = K[0, 0] * K[1, 1] - K[0, 1] * K[1, 0]
    slip_margin = cs.fmin(trK, detK / cs.fmax(cs.fabs(trK), 1e-300))
    margin = cs.if_else(q[0] > 0.5, kappa, slip_margin)
    return cs.Function("ocp_crawl_stability", [x, q, p], [cs.vertcat(margin, kappa, trK, detK)],
                       ["x", "q", "p"], ["s"])


@compiled_function
@lru_cache(maxsize=1)
def fast_stability():
    """:func:`stability_function` as a low-overhead callable for hot loops (compiled C when a
    compiler is available, see :mod:`ocp_crawl.model.compiled`): ``fast_stability()(x, q, p)[0]`` is
    ``s[4]``."""
    from ocp_crawl.model.compiled import FastFunction

    return FastFunction(stability_function())


@compiled_function
@lru_cache(maxsize=1)
def fast_step():
    """One call per continuation step of the event-driven stepper (compiled C when available):
    ``fast_step()(x0, tau, dtau, q, p) -> (x, aux, extra)`` with ``(x, aux)`` those of
    :attr:`~ocp_crawl.model.statics._Symbolic.newton` and ``extra[7] = (s[4], a, b[2])``: the
    stability numbers of :func:`stability_function` and the coefficients of
    :attr:`~ocp_crawl.model.statics._Symbolic.ddot2` (d'' = a + b . tau''), both at the returned x.
    The same expressions as the separate functions, in one generated C function (one ctypes call
    instead of three)."""
    from ocp_crawl.model.compiled import FastFunction

    sym = symbolic()
    x0, tau, dtau = cs.SX.sym("x0", 3), cs.SX.sym("tau", 2), cs.SX.sym("dtau", 2)
    q, p = cs.SX.sym("q", NQ), cs.SX.sym("p", NP)
    x, aux = sym.newton(x0, tau, dtau, q, p)
    extra = cs.vertcat(stability_function()(x, q, p), sym.ddot2(x, tau, dtau, q, p))
    return FastFunction(cs.Function("ocp_crawl_step", [x0, tau, dtau, q, p], [x, aux, extra],
                                    ["x0", "tau", "dtau", "q", "p"], ["x", "aux", "extra"]))


@lru_cache(maxsize=1)
def slip_stiffness_function() -> cs.Function:
    """CasADi function ``(phi[2], q[4], p) -> K[2x2]`` [N m/rad]: the slip-mode stiffness (see
    module doc)."""
    phi = cs.SX.sym("phi", 2)
    q = cs.SX.sym("q", NQ)
    p = cs.SX.sym("p", NP)
    K = _slip_stiffness(phi, q, p, _geometry(phi, p))
    return cs.Function("ocp_crawl_slip_stiffness", [phi, q, p], [K], ["phi", "q", "p"], ["K"])


def _slip_stiffness(phi, q, p, geo):
    """Symbolic K = d/dphi [grad Pi + f_t(phi) grad d] [N m/rad], f_t(phi) = sigma (w mu1 fn1 +
    (1-w) mu2 fn2)."""
    pr = params(p)
    ft_slip = q[1] * (q[2] * pr.mu1 * geo["fn1"] + (1 - q[2]) * pr.mu2 * geo["fn2"])
    F = cs.gradient(geo["U_el"] + pr.sgrav * geo["U_g"], phi) + ft_slip * cs.gradient(geo["d"], phi)
    return cs.jacobian(F, phi)


def _mode_vector(q) -> np.ndarray:
    """q as the 4-vector (e_ss, sigma, w, d0): accepts (e_ss, sigma, w) or the full q."""
    q = np.asarray(q, dtype=float)
    if q.shape == (3,):
        q = np.append(q, 0.0)
    if q.shape != (NQ,) or not np.all(np.isfinite(q)):
        raise ValueError(f"q must be finite (e_ss, sigma, w[, d0]), got {q.tolist()}")
    return q


def _state_vector(x) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if x.shape != (3,) or not np.all(np.isfinite(x)):
        raise ValueError(f"x must be finite (phi1 [rad], phi2 [rad], f_t/(M g)), got {x.tolist()}")
    return x


def stability(model, x, q) -> dict[str, float]:
    """All stability numbers of one equilibrium (nondimensional, see :func:`stability_function`).

    ``model``: a :class:`~ocp_crawl.model.statics.Model`;
    ``x = (phi1 [rad], phi2 [rad], f_t/(M g))``; ``q = (e_ss, sigma, w[, d0])``.  Returns
    ``{"margin", "kappa", "trK", "detK"}``.
    """
    s = np.asarray(stability_function()(_state_vector(x), _mode_vector(q), model.p)).ravel()
    return dict(zip(STABILITY_NAMES, (float(v) for v in s)))


def stability_margin(model, x, q) -> float:
    """Nondimensional stability margin of the equilibrium ``x`` of mode ``q``; > 0 <=> stable.

    ``model``: a Model; ``x = (phi1 [rad], phi2 [rad], f_t/(M g))``; ``q = (e_ss, sigma, w[, d0])``
    as in :mod:`ocp_crawl.model.statics` (stick-stick ``(1, 0, 0)``; foot 1 slipping with sign(d') =
    sigma: ``(0, sigma, 1)``; foot 2: ``(0, sigma, 0)``).  Returns ``kappa/(M g L)`` in stick-stick
    and ``min(tr K, det K/|tr K|)/(M g L)`` in slip modes (module docstring).
    """
    return stability(model, x, q)["margin"]


def stability_margins(model, x: np.ndarray, q: np.ndarray) -> np.ndarray:
    """:func:`stability_margin` at n points in one call: ``x`` (3, n), ``q`` (4, n) or one (4,)
    vector."""
    x = np.asarray(x, dtype=float)
    q = np.asarray(q, dtype=float)
    if x.ndim != 2 or x.shape[0] != 3 or q.shape[0] != NQ or q.ndim > 2:
        raise ValueError(f"x must have shape (3, n) and q (4,) or (4, n); got {x.shape} and "
                         f"{q.shape}")
    return call_mapped(stability_function(), x, q, model.p)[0]


def reduced_stiffness(model, phi, f_t: float) -> float:
    """Stick-stick reduced stiffness kappa = v^T (hess Pi + f_t hess d) v [N m/rad] at ``phi``
    [rad], ``f_t`` [N]."""
    r = model.robot
    x = np.array([*np.asarray(phi, float), float(f_t) / (r.M * r.g)])
    return stability(model, x, (1.0, 0.0, 0.0))["kappa"] * r.MgL


def slip_stiffness(model, phi, sigma: float, w: float) -> np.ndarray:
    """Slip-mode stiffness K = d/dphi [grad Pi + f_t(phi) grad d] [N m/rad], shape (2, 2).

    ``sigma``: sign of d' (+1/-1); ``w``: 1 when foot 1 slips, 0 when foot 2 slips.
    """
    q = _mode_vector((0.0, float(sigma), float(w)))
    return np.asarray(slip_stiffness_function()(np.asarray(phi, float), q, model.p))
