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


def interpolant_roots(values: np.ndarray) -> list[np.ndarray]:
    """The sign changes of f inside panels, from its values (k, 5) at each panel's 5 Gauss-Legendre
    nodes: for each panel the real roots in (-1, 1) (the panel mapped onto [-1, 1]), in order, of
    the degree-4 interpolant of its values (the polynomial the Gauss rule integrates)."""
    roots = legendre_roots(np.atleast_2d(np.asarray(values, float)) @ LEG_FIT5)
    inside = (np.abs(roots.imag) <= 1e-12) & (np.abs(roots.real) < 1.0)
    return [np.sort(r.real[k]) for r, k in zip(roots, inside)]


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
