"""Stability of the quasistatic equilibria of an n-link chain in each contact mode, any n >= 3.

The criteria of :mod:`ocp_crawl.model.stability` (three links) for ``m = n - 1`` joints.  With the
torques held fixed the joint balance is ``F = -grad Pi_tau - f_t grad d = 0``,
``Pi_tau = U_el + sgrav U_g - tau . phi``; the torque term is linear in ``phi`` and drops out of
every second derivative, so below ``Pi = U_el + sgrav U_g`` [J].

Stick-stick (both feet fixed, ``d(phi) = d0``, ``f_t`` the Lagrange multiplier)
    A strict minimum of ``Pi_tau`` on the (m - 1)-dimensional manifold ``d(phi) = d0``: with ``Z``
    (m, m - 1) an orthonormal basis of the null space of ``grad d``, the *reduced stiffness*

        K_red = Z^T (hess Pi + f_t hess d) Z        [N m/rad]  (symmetric, (m - 1) x (m - 1))

    is positive definite; ``kappa`` is its smallest eigenvalue (basis-free).  For m = 2, ``Z`` is
    the unit tangent ``v`` of :mod:`~ocp_crawl.model.stability` (up to sign) and ``kappa`` its
    ``v^T (hess Pi + f_t hess d) v``.  With the mode Jacobian ``J`` of
    :class:`~ocp_crawl.model.chain_model.ChainModel` (x = (phi, f_t/(M g))):
    ``det J = (-1)^(m-1) |grad d|^2 det K_red / (L^2 (M g L)^(m-1))``.
Slip (one foot at its friction limit, ``f_t(phi) = sigma (w mu1 fn1 + (1-w) mu2 fn2)``)
    Linear stability of the overdamped flow ``phi' = -(grad Pi_tau + f_t(phi) grad d)`` with the
    torques held fixed, identity mobility (equal, uncoupled viscous damping of the joints):
    ``dphi' = -K dphi`` with

        K = d/dphi [grad Pi + f_t(phi) grad d]      [N m/rad]  (m x m, not symmetric)

    stable iff every eigenvalue of ``K`` has a positive real part, i.e. iff the polynomial
    ``det(s I + K) = s^m + a_1 s^(m-1) + ... + a_m`` (``a_k`` the sum of the k x k principal minors
    of ``K``) is Hurwitz: the first column ``r_k = D_k / D_(k-1)`` of its Routh array (``D_k`` the
    leading principal minors of its Hurwitz matrix, ``D_0 = 1``) is positive.  ``det J = (-1)^m
    det K / (M g L)^m``: the sign of ``det K`` does not depend on the mobility metric, the real
    parts can.  The slipping foot is assumed to keep slipping along ``sigma`` during the
    perturbation.

Margins (nondimensional, > 0 <=> stable; ``K_red`` and ``K`` scaled by ``M g L``)
    stick-stick: ``kappa/(M g L)``; slip: ``min_k r_k/|r_(k-1)|`` over k = 1..m (``r_0 = 1``).  For
    m = 2, ``r_1 = tr K`` and ``r_2 = det K``: the three-link margin ``min(tr K, det K/|tr K|)``;
    each ratio is a stiffness.
"""
from __future__ import annotations

from functools import lru_cache
from itertools import combinations

import casadi as cs
import numpy as np

from ocp_crawl.model.chain_statics import chain_geometry, chain_params, n_params
from ocp_crawl.model.statics import NQ

#: names of the numbers of :func:`chain_stability` (those of
#: :data:`ocp_crawl.model.stability.STABILITY_NAMES`, then the smallest real part of eig K)
CHAIN_STABILITY_NAMES = ("margin", "kappa", "trK", "detK", "min_real")
#: largest number of joints whose characteristic polynomial is summed from principal minors
#: (2^m - 1 determinants); above it, from the eigenvalues
_MINOR_JOINTS = 10


@lru_cache(maxsize=None)
def chain_stiffness_function(n: int) -> cs.Function:
    """CasADi function ``(phi[m], f_t, q[4], p) -> s`` of the n-link chain (built once per n).

    ``s`` stacks ``grad d`` (m) [m/rad], ``hess Pi + f_t hess d`` (m x m, column-major)
    [N m/rad] and the slip stiffness ``K`` (m x m, column-major) [N m/rad] of the mode ``q``
    (:data:`ocp_crawl.model.statics.Q_NAMES`; with ``sigma = 0``, as in stick-stick, ``K = hess
    Pi``); ``f_t`` [N]; ``p`` the parameter vector of
    :func:`~ocp_crawl.model.chain_statics.chain_parameters`.
    """
    m = n - 1
    phi, ft = cs.SX.sym("phi", m), cs.SX.sym("ft")
    q, p = cs.SX.sym("q", NQ), cs.SX.sym("p", n_params(n))
    P = chain_params(p, n)
    geo = chain_geometry(phi, p, n)
    grad_d = cs.gradient(geo["d"], phi)
    grad_Pi = cs.gradient(geo["U_el"] + P.sgrav * geo["U_g"], phi)
    H_lag = cs.jacobian(grad_Pi + ft * grad_d, phi)
    ft_slip = q[1] * (q[2] * geo["lim1"] + (1 - q[2]) * geo["lim2"])
    K = cs.jacobian(grad_Pi + ft_slip * grad_d, phi)
    out = cs.vertcat(grad_d, cs.reshape(H_lag, m * m, 1), cs.reshape(K, m * m, 1))
    return cs.Function(f"chain{n}_stiffness", [phi, ft, q, p], [out], ["phi", "ft", "q", "p"],
                       ["s"])


@lru_cache(maxsize=None)
def chain_margin_function(n: int) -> cs.Function:
    """CasADi function ``(phi[m], f_t, q[4], p) -> (A, slip)`` of the n-link chain: what
    :func:`chain_stability_margins` needs of one equilibrium, for compiling (built once per n).

    ``A = P sym(H) P + c u u^T`` (m x m, column-major) [N m/rad], ``H = hess Pi + f_t hess d``,
    ``u`` the unit ``grad d``, ``P = I - u u^T``, ``c = |sym(H)|_F + M g L``: on the tangent space
    of ``d(phi) = d0`` it is ``K_red`` and along ``u`` it is ``c``, above every eigenvalue of
    ``K_red``, so its smallest eigenvalue is ``kappa`` (basis-free).  ``slip`` is
    :func:`routh_margin` of ``K/(M g L)`` (``K`` of the mode ``q``): its characteristic
    polynomial's coefficients by the Faddeev-LeVerrier recursion and the first column of its Routh
    array by the Routh recursion (``r_k = D_k / D_(k-1)``), a zero pivot replaced by 1e-300 as
    :func:`routh_column` replaces a zero minor.
    """
    m = n - 1
    phi, ft = cs.SX.sym("phi", m), cs.SX.sym("ft")
    q, p = cs.SX.sym("q", NQ), cs.SX.sym("p", n_params(n))
    P = chain_params(p, n)
    MgL = cs.sum1(cs.vertcat(*P.masses)) * P.g * cs.sum1(cs.vertcat(*P.lengths))
    s = chain_stiffness_function(n)(phi, ft, q, p)
    grad_d = s[:m]
    H = cs.reshape(s[m:m + m * m], m, m)
    K = cs.reshape(s[m + m * m:], m, m)
    Hs = 0.5 * (H + H.T)
    u = grad_d / cs.norm_2(grad_d)
    proj = cs.SX.eye(m) - u @ u.T
    A = proj @ Hs @ proj + (cs.norm_fro(Hs) + MgL) * (u @ u.T)
    r = _routh_first_column(_char_coefficients(K / MgL))
    prev = [1.0] + [cs.fabs(v) for v in r[:-1]]
    slip = r[0] / prev[0]
    for v, w in zip(r[1:], prev[1:]):
        slip = cs.fmin(slip, v / cs.fmax(w, 1e-300))
    return cs.Function(f"chain{n}_margin", [phi, ft, q, p], [cs.reshape(A, m * m, 1), slip],
                       ["phi", "ft", "q", "p"], ["A", "slip"])


def _char_coefficients(K: cs.SX) -> list:
    """``(a_1 .. a_m)`` of ``det(s I + K) = s^m + a_1 s^(m-1) + ... + a_m`` (Faddeev-LeVerrier:
    ``M_k = -K M_(k-1) + a_(k-1) I``, ``a_k = tr(K M_k)/k``, ``M_0 = 0``, ``a_0 = 1``)."""
    m = K.size1()
    Mk, a, prev = cs.SX.zeros(m, m), [], cs.SX(1.0)
    for k in range(1, m + 1):
        Mk = -K @ Mk + prev * cs.SX.eye(m)
        prev = cs.trace(K @ Mk) / k
        a.append(prev)
    return a


def _routh_first_column(a: list) -> list:
    """``(r_1 .. r_m)``: the first column of the Routh array of ``s^m + a_1 s^(m-1) + ... + a_m``
    below its first row (``r_k = D_k / D_(k-1)``, :func:`routh_column`)."""
    m = len(a)
    coef = [1.0, *a] + [0.0] * (m + 2)
    rows = [coef[0::2][:m // 2 + 2], coef[1::2][:m // 2 + 2]]
    for _ in range(m - 1):
        up, low = rows[-2], rows[-1]
        piv = cs.if_else(low[0] == 0, 1e-300, low[0])
        rows.append([up[j + 1] - up[0] / piv * low[j + 1] for j in range(len(low) - 1)] + [0.0])
    return [row[0] for row in rows[1:]]


def _matrices(model, phi: np.ndarray, ft: np.ndarray, Q: np.ndarray) -> tuple:
    """(grad d (N, m), H_lag (N, m, m), K (N, m, m)) at the columns ``phi`` (m, N), ``ft`` (N,)
    [N] and modes ``Q`` (4, N)."""
    from ocp_crawl.model.chain_model import call_columns

    m = model.chain.n_joints
    s = call_columns(chain_stiffness_function(model.chain.n), phi, ft.reshape(1, -1), Q, model.p)
    g = s[:m].T
    H = s[m:m + m * m].T.reshape(-1, m, m).transpose(0, 2, 1)
    K = s[m + m * m:].T.reshape(-1, m, m).transpose(0, 2, 1)
    return g, H, K


def tangent_basis(grad_d: np.ndarray) -> np.ndarray:
    """Orthonormal bases (N, m, m - 1) of the null spaces of the rows of ``grad_d`` (N, m): the
    tangent spaces of ``d(phi) = d0`` (Householder reflections of the unit gradients)."""
    g = np.asarray(grad_d, float)
    u = g / np.linalg.norm(g, axis=1, keepdims=True)
    m = g.shape[1]
    # reflection H = I - 2 w w^T mapping e_k (k the largest |u_k|) to -sign(u_k) u; its other
    # columns span u's orthogonal complement
    k = np.argmax(np.abs(u), axis=1)
    e = np.eye(m)[k]
    s = np.where(u[np.arange(len(u)), k] >= 0, 1.0, -1.0)[:, None]
    w = u + s * e
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    H = np.eye(m)[None] - 2.0 * w[:, :, None] * w[:, None, :]
    keep = np.ones((len(u), m), bool)
    keep[np.arange(len(u)), k] = False
    return H.transpose(0, 2, 1)[keep].reshape(len(u), m - 1, m).transpose(0, 2, 1)


def reduced_matrices(grad_d: np.ndarray, H_lag: np.ndarray) -> np.ndarray:
    """``Z^T sym(H_lag) Z`` (N, m - 1, m - 1) with ``Z`` = :func:`tangent_basis` of ``grad_d``."""
    Z = tangent_basis(grad_d)
    Hs = 0.5 * (H_lag + H_lag.transpose(0, 2, 1))
    return Z.transpose(0, 2, 1) @ Hs @ Z


def hurwitz_coefficients(K: np.ndarray) -> np.ndarray:
    """Coefficients ``(a_1 .. a_m)`` (N, m) of ``det(s I + K) = s^m + a_1 s^(m-1) + ... + a_m`` for
    the matrices ``K`` (N, m, m): ``a_k`` is the sum of the k x k principal minors (from the
    eigenvalues above :data:`_MINOR_JOINTS` joints).  For m = 2: ``(tr K, K00 K11 - K01 K10)``."""
    K = np.asarray(K, float)
    N, m = K.shape[0], K.shape[1]
    if m > _MINOR_JOINTS:
        return np.array([np.poly(-np.linalg.eigvals(k)).real[1:] for k in K])
    a = np.zeros((N, m))
    a[:, 0] = np.trace(K, axis1=1, axis2=2)
    for k in range(2, m + 1):
        for idx in combinations(range(m), k):
            sub = K[:, idx][:, :, idx]
            a[:, k - 1] += (sub[:, 0, 0] * sub[:, 1, 1] - sub[:, 0, 1] * sub[:, 1, 0] if k == 2
                            else np.linalg.det(sub))
    return a


def routh_column(a: np.ndarray) -> np.ndarray:
    """First column ``(r_1 .. r_m)`` (N, m) of the Routh array of ``s^m + a_1 s^(m-1) + ... +
    a_m`` (``a`` (N, m)): ``r_k = D_k / D_(k-1)`` with ``D_k`` the leading k x k minor of the
    Hurwitz matrix (entries ``a_(2j - i)``, 1-based, ``a_0 = 1``).  All positive <=> Hurwitz."""
    a = np.asarray(a, float)
    N, m = a.shape
    full = np.concatenate([np.ones((N, 1)), a, np.zeros((N, m + 1))], axis=1)
    i, j = np.meshgrid(np.arange(1, m + 1), np.arange(1, m + 1), indexing="ij")
    idx = 2 * j - i
    hurwitz = np.where((idx >= 0) & (idx <= m), full[:, np.clip(idx, 0, 2 * m + 1)], 0.0)
    D = np.ones((N, m + 1))
    for k in range(1, m + 1):
        D[:, k] = hurwitz[:, 0, 0] if k == 1 else np.linalg.det(hurwitz[:, :k, :k])
    return D[:, 1:] / _nonzero(D[:, :-1])


def _nonzero(v: np.ndarray) -> np.ndarray:
    """``v`` with its zeros replaced by 1e-300 (a divisor that keeps the numerator's sign)."""
    return np.where(v == 0, 1e-300, v)


def routh_margin(K: np.ndarray) -> np.ndarray:
    """Slip margins (N,) of the matrices ``K`` (N, m, m), in the unit of ``K``:
    ``min_k r_k/|r_(k-1)|`` (``r_0 = 1``) of :func:`routh_column`; > 0 <=> every eigenvalue of K has
    a positive real part."""
    r = routh_column(hurwitz_coefficients(K))
    prev = np.concatenate([np.ones((r.shape[0], 1)), np.abs(r[:, :-1])], axis=1)
    return np.min(r / np.maximum(prev, 1e-300), axis=1)


def chain_stability_numbers(model, X, Q) -> dict[str, np.ndarray]:
    """The stability numbers (:data:`CHAIN_STABILITY_NAMES`) of N equilibria, nondimensional.

    Parameters
    ----------
    model : ChainModel
        The chain and the gravity convention.
    X : array_like, shape (n, N)
        States ``(phi_1 .. phi_m [rad], f_t/(M g) [-])``.
    Q : array_like, shape (4,) or (4, N)
        Modes ``(e_ss, sigma, w, d0)`` (``d0`` unused).

    Returns
    -------
    dict of ndarray, shape (N,)
        ``kappa`` = smallest eigenvalue of ``K_red``/(M g L) (f_t from ``X``); ``trK`` = tr K/(M g
        L), ``detK`` = det K/(M g L)^m and ``min_real`` = the smallest real part of the eigenvalues
        of K/(M g L) (K with the mode's friction law); ``margin`` = ``kappa`` where ``e_ss > 0.5``,
        else :func:`routh_margin` of K/(M g L).
    """
    Q, (g, H, K) = _states(model, X, Q)
    MgL = model.chain.MgL
    kappa = _kappa(g, H) / MgL
    Kn = K / MgL
    a = hurwitz_coefficients(Kn)
    slip = routh_margin(Kn)
    return {"margin": np.where(Q[0] > 0.5, kappa, slip), "kappa": kappa, "trK": a[:, 0],
            "detK": a[:, -1], "min_real": np.min(np.linalg.eigvals(Kn).real, axis=1)}


def _states(model, X, Q) -> tuple[np.ndarray, tuple]:
    """The modes Q (4, N) and :func:`_matrices` of the states X (n, N), both checked."""
    X, Q = _checked(model, X, Q)
    m = model.chain.n_joints
    return Q, _matrices(model, X[:m], X[m] * model.Mg, Q)


def _checked(model, X, Q) -> tuple[np.ndarray, np.ndarray]:
    """The states X (n, N) and the modes Q (4, N, from (4,) or (4, N)), checked."""
    n = model.chain.n
    X = np.asarray(X, float)
    if X.ndim != 2 or X.shape[0] != n or not np.all(np.isfinite(X)):
        raise ValueError(f"X must be finite with shape ({n}, N) (phi [rad], f_t/(M g)), got "
                         f"{X.shape}")
    Q = np.asarray(Q, float)
    if Q.ndim == 1:
        Q = np.tile(Q.reshape(-1, 1), (1, X.shape[1]))
    if Q.shape != (NQ, X.shape[1]) or not np.all(np.isfinite(Q)):
        raise ValueError(f"Q must be finite with shape (4,) or (4, {X.shape[1]}), got {Q.shape}")
    return X, np.ascontiguousarray(Q)


def _kappa(g: np.ndarray, H: np.ndarray) -> np.ndarray:
    """The smallest eigenvalue (N,) of the reduced stiffness of the gradients g (N, m) and
    Hessians H (N, m, m) [N m/rad]."""
    if g.shape[1] == 2:
        v = np.stack([-g[:, 1], g[:, 0]], axis=1) / np.linalg.norm(g, axis=1, keepdims=True)
        return np.einsum("ni,nij,nj->n", v, H, v)
    return np.linalg.eigvalsh(reduced_matrices(g, H))[:, 0]


def chain_stability(model, x, q) -> dict[str, float]:
    """The stability numbers of one equilibrium ``x = (phi [rad], f_t/(M g))`` of mode
    ``q = (e_ss, sigma, w[, d0])`` (:func:`chain_stability_numbers`), as floats."""
    q = np.asarray(q, float)
    if q.shape == (3,):
        q = np.append(q, 0.0)
    out = chain_stability_numbers(model, np.asarray(x, float).reshape(-1, 1), q)
    return {k: float(v[0]) for k, v in out.items()}


def chain_stability_margin(model, x, q) -> float:
    """Stability margin of one equilibrium (nondimensional, > 0 <=> stable): ``kappa/(M g L)`` in
    stick-stick, :func:`routh_margin` of K/(M g L) in a slip mode."""
    q = np.asarray(q, float)
    if q.shape == (3,):
        q = np.append(q, 0.0)
    return float(chain_stability_margins(model, np.asarray(x, float).reshape(-1, 1), q)[0])


def chain_stability_margins(model, X, Q) -> np.ndarray:
    """:func:`chain_stability_margin` of N equilibria: ``X`` (n, N), ``Q`` (4,) or (4, N) (the
    ``margin`` of :func:`chain_stability_numbers`, by the compiled :func:`chain_margin_function`:
    the steppers ask for a segment's margins at every event and for each candidate mode's)."""
    from ocp_crawl.model.chain_compiled import margin_columns   # (it imports this module)

    X, Q = _checked(model, X, Q)
    m = model.chain.n_joints
    A, margin = margin_columns(model.chain.n)(X[:m], X[m:] * model.Mg, Q, model.p)
    margin = margin[0].copy()
    stick = Q[0] > 0.5
    if stick.any():
        A = A[:, stick].T.reshape(-1, m, m).transpose(0, 2, 1)
        kappa = np.full(len(A), np.nan)   # (grad d = 0, a straight chain: no tangent space)
        finite = np.isfinite(A).all(axis=(1, 2))
        kappa[finite] = np.linalg.eigvalsh(A[finite])[:, 0] / model.chain.MgL
        margin[stick] = kappa
    return margin


def reduced_stiffness_matrix(model, phi, f_t: float) -> np.ndarray:
    """Stick-stick reduced stiffness ``K_red`` (m - 1, m - 1) [N m/rad] at ``phi`` [rad] with the
    tangential force ``f_t`` [N], in the orthonormal tangent basis of :func:`tangent_basis`."""
    phi = np.asarray(phi, float).reshape(-1, 1)
    g, H, _ = _matrices(model, phi, np.array([float(f_t)]), np.zeros((NQ, 1)))
    return reduced_matrices(g, H)[0]


def reduced_stiffness(model, phi, f_t: float) -> float:
    """Smallest eigenvalue of the stick-stick reduced stiffness [N m/rad] (for three links the
    ``kappa`` of :func:`ocp_crawl.model.stability.reduced_stiffness`)."""
    return float(np.linalg.eigvalsh(reduced_stiffness_matrix(model, phi, f_t))[0])


def slip_stiffness(model, phi, sigma: float, w: float) -> np.ndarray:
    """Slip-mode stiffness ``K = d/dphi [grad Pi + f_t(phi) grad d]`` (m, m) [N m/rad] at ``phi``
    [rad]; ``sigma`` = sign(d') (+1/-1), ``w`` = 1 when foot 1 slips, 0 when foot 2 slips."""
    phi = np.asarray(phi, float).reshape(-1, 1)
    q = np.array([[0.0], [float(sigma)], [float(w)], [0.0]])
    return _matrices(model, phi, np.zeros(1), q)[2][0]
