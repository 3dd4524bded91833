"""The batched roots of the W+ sign split (ocp_crawl.sim.quadrature.legendre_roots) against numpy's
legroots, row by row, including rows whose leading coefficients vanish (lower degree)."""
import numpy as np
from numpy.polynomial import legendre

from ocp_crawl.sim.quadrature import legendre_roots


def test_legendre_roots_are_numpys_legroots_row_by_row():
    rng = np.random.default_rng(12)
    coefs = rng.normal(size=(300, 5))
    coefs[3, -1] = 0.0           # degree 3
    coefs[8, -2:] = 0.0          # degree 2
    coefs[11] = [1.0, 0.0, 0.0, 0.0, 1e-300]  # huge roots
    roots = legendre_roots(coefs)
    assert roots.shape == (300, 4)
    for row, r in zip(coefs, roots):
        ref = legendre.legroots(row)
        got = np.sort(r[~np.isnan(r)])
        assert got.shape == ref.shape
        assert np.array_equal(got, ref)
    # the roots are zeros of the series (an independent check of the companion matrices)
    for row, r in zip(coefs[20:40], roots[20:40]):
        assert np.all(np.abs(legendre.legval(r, row))
                      <= 1e-9 * np.sum(np.abs(row)) * (1 + np.abs(r)) ** 4)
