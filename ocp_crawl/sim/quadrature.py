"""Quadrature over piecewise-smooth trajectories (integrals per cycle: work, dissipation, W+)."""
from __future__ import annotations

from functools import lru_cache

import numpy as np

_GL = {n: np.polynomial.legendre.leggauss(n) for n in (3, 5, 8)}


def gauss_nodes(a: float, b: float, h: float = 1.0 / 64, order: int = 5):
    """Gauss-Legendre nodes and weights on [a, b] split into pieces no longer than h."""
    if b <= a:
        return np.zeros(0), np.zeros(0)
    n = max(1, int(np.ceil((b - a) / h - 1e-12)))
    edges = np.linspace(a, b, n + 1)
    x, w = _GL[order]
    mid = 0.5 * (edges[1:] + edges[:-1])[:, None]
    half = 0.5 * (edges[1:] - edges[:-1])[:, None]
    return (mid + half * x).ravel(), (half * w).ravel()


def positive_part_integral(a: float, b: float, f_vec, f_scalar, h: float = 1.0 / 64, order: int = 5,
                           n_probe: int = 17) -> float:
    """Integral of max(0, f) over [a, b] for a smooth f, splitting at the sign changes of f.

    ``f_vec(t_array)`` evaluates f on many points at once; ``f_scalar(t)`` one point (root
    refinement).
    """
    from scipy.optimize import brentq  # scipy only where used (start-up time)

    if b <= a:
        return 0.0
    n_pieces = max(1, int(np.ceil((b - a) / h - 1e-12)))
    probes = np.linspace(a, b, n_pieces * (n_probe - 1) + 1)
    fp = f_vec(probes)
    roots = []
    for j in np.nonzero(np.sign(fp[:-1]) * np.sign(fp[1:]) < 0)[0]:
        roots.append(brentq(f_scalar, probes[j], probes[j + 1], xtol=1e-14,
                            rtol=4 * np.finfo(float).eps))
    edges = [a] + roots + [b]
    nodes, weights = [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        t, w = gauss_nodes(lo, hi, h, order)
        nodes.append(t)
        weights.append(w)
    t = np.concatenate(nodes)
    w = np.concatenate(weights)
    return float(np.sum(w * np.maximum(f_vec(t), 0.0)))


#: the Legendre coefficients of the degree-4 interpolant through values at the 5-point
#: Gauss-Legendre nodes on [-1, 1] (c = values @ LEG_FIT5)
LEG_FIT5 = np.linalg.inv(np.polynomial.legendre.legvander(_GL[5][0], 4)).T


#: the values at -1 and 1 of the degree-4 interpolant through values at the 5 Gauss-Legendre nodes
LEG_ENDS5 = LEG_FIT5 @ np.polynomial.legendre.legvander(np.array([-1.0, 1.0]), 4).T
_XG5, _WG5 = _GL[5]


def sign_split(edges: np.ndarray, pw: np.ndarray, h: float, dips: bool = False):
    """The W+ sign split of Gauss panels: which panels keep each actuator's power >= 0, and extra
    Gauss nodes on the panels where it changes sign.

    Parameters
    ----------
    edges : ndarray, shape (npan, 2)
        The panels (lo, hi) [cycles].
    pw : ndarray, shape (m, npan, 5)
        Each of the m actuators' power at each panel's 5 Gauss-Legendre nodes [J/cycle].
    h : float
        The largest panel [cycles] of the pieces' Gauss nodes (:func:`gauss_nodes`).
    dips : bool
        Split also the panels of one sign at those values whose interpolant changes sign between
        them (where its Legendre coefficients allow it, ``|c_0| <= sum |c_k|``, and it has a real
        root in the panel): for fixed panels; adaptive ones are refined where the interpolant
        bends.

    Returns
    -------
    tuple
        (phases, weights, actuator, panel index) of the extra nodes, each (k,): the panels on which
        the power's values at the nodes and at the edges (from the panel's degree-4 interpolant, so
        that a sign change between an edge and the nearest node is not missed) have both signs,
        split at the real roots in the panel of that interpolant; and whether each actuator's
        power keeps a positive sign on each panel ((m, npan) bool).
    """
    m, npan = pw.shape[0], len(edges)
    ends = (pw.reshape(-1, 5) @ LEG_ENDS5).reshape(m, npan, 2)
    allv = np.concatenate([pw, ends], axis=2)
    positive_panels = np.all(allv >= 0, axis=2)
    mixed = ~positive_panels & ~np.all(allv <= 0, axis=2)
    maybe = np.zeros_like(mixed)
    if dips:   # (|P_k| <= 1 on the panel: the interpolant stays within c_0 -+ sum |c_k|)
        c = pw @ LEG_FIT5
        reach = np.abs(c[..., 1:]).sum(axis=2)
        maybe = ~mixed & (c[..., 0] - reach <= 0) & (c[..., 0] + reach >= 0)
    ii, jj = np.nonzero(mixed | maybe)
    if not ii.size:
        return np.zeros(0), np.zeros(0), np.zeros(0, int), np.zeros(0, int), positive_panels
    # the power changes sign inside the panel: split at the roots of its degree-4 interpolant
    roots = legendre_roots(pw[ii, jj] @ LEG_FIT5)  # (the interpolants' Legendre coefficients)
    r = np.where((np.abs(roots.imag) < 1e-9) & (np.abs(roots.real) < 1), roots.real, np.nan)
    if dips:   # (a panel of one sign at its values without a root inside keeps that sign)
        split = ~maybe[ii, jj] | ~np.all(np.isnan(r), axis=1)
        ii, jj, r = ii[split], jj[split], r[split]
        positive_panels[ii, jj] = False
        if not ii.size:
            return np.zeros(0), np.zeros(0), np.zeros(0, int), np.zeros(0, int), positive_panels
    lo, hi = edges[jj, 0][:, None], edges[jj, 1][:, None]
    r.sort(axis=1)  # (the real roots in the panel in increasing order, then nan)
    # cuts lo, the roots, hi (hi also in place of the missing roots: the pieces of length 0 are
    # dropped)
    cuts = np.concatenate([lo, lo + (r + 1) * (hi - lo) / 2, hi], axis=1)
    cuts = np.where(np.isnan(cuts), hi, cuts)
    c0, c1 = cuts[:, :-1], cuts[:, 1:]
    keep = c1 - c0 > 0
    c0, c1 = c0[keep], c1[keep]
    rows = np.nonzero(keep)[0]  # (the row of each kept piece, in the order of c0[keep])
    owner, panel = ii[rows], jj[rows]
    if np.all(c1 - c0 <= h * (1 - 1e-9)):
        # each piece is one Gauss panel: the nodes and weights of gauss_nodes(c0, c1, h, 5), at
        # once
        mid, half = 0.5 * (c1 + c0)[:, None], 0.5 * (c1 - c0)[:, None]
        return ((mid + half * _XG5).ravel(), (half * _WG5).ravel(), np.repeat(owner, _XG5.size),
                np.repeat(panel, _XG5.size), positive_panels)
    pieces = [gauss_nodes(a, b, h, 5) for a, b in zip(c0, c1)]
    return (np.concatenate([tt for tt, _ in pieces]), np.concatenate([w2 for _, w2 in pieces]),
            np.concatenate([np.full(len(tt), i) for (tt, _), i in zip(pieces, owner)]),
            np.concatenate([np.full(len(tt), j) for (tt, _), j in zip(pieces, panel)]),
            positive_panels)


def legendre_roots(coefs: np.ndarray) -> np.ndarray:
    """Roots (complex, (k, m - 1), padded with nan) of the Legendre series with the coefficients in
    the rows of ``coefs`` (k, m), m >= 3: the values of ``numpy.polynomial.legendre.legroots`` of
    each row (the eigenvalues of its rotated companion matrix, built here as ``legcompanion`` does,
    for all rows at once, and taken in one batched call); a row whose leading coefficient is 0 goes
    through legroots itself."""
    coefs = np.atleast_2d(np.asarray(coefs, float))
    full = coefs[:, -1] != 0
    out = np.full((len(coefs), coefs.shape[1] - 1), np.nan, dtype=complex)
    if np.any(full):
        c = coefs[full]
        n = c.shape[1] - 1
        base, ratio = _companion_base(n)
        comp = np.repeat(base[None], len(c), axis=0)
        comp[:, :, -1] -= (c[:, :-1] / c[:, -1:]) * ratio * (n / (2 * n - 1))
        out[full] = np.linalg.eigvals(comp[:, ::-1, ::-1])
    for j in np.nonzero(~full)[0]:
        r = np.polynomial.legendre.legroots(coefs[j])
        out[j, :r.size] = r
    return out


@lru_cache(maxsize=8)
def _companion_base(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The part of the scaled Legendre companion matrix (n, n) of ``legcompanion`` that does not
    depend on the coefficients, and the ratios scl/scl[-1] (n,) of the last column's coefficient
    term (read-only: shared)."""
    scl = 1. / np.sqrt(2 * np.arange(n) + 1)
    base = np.zeros((n, n))
    top = base.reshape(-1)[1::n + 1]
    top[...] = np.arange(1, n) * scl[:n - 1] * scl[1:n]
    base.reshape(-1)[n::n + 1] = top
    ratio = scl / scl[-1]
    base.flags.writeable = ratio.flags.writeable = False
    return base, ratio
