"""The W+ sign split: the batched roots (ocp_crawl.sim.quadrature.legendre_roots) against numpy's
legroots, row by row, including rows whose leading coefficients vanish (lower degree); the positive
part of a panel's power (sign_split) against its closed form."""
import numpy as np
import pytest
from numpy.polynomial import legendre

from ocp_crawl.sim.quadrature import gauss_nodes, legendre_roots, sign_split


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


@pytest.mark.parametrize("c, delta", [(0.27, 0.05), (0.27, 0.07), (0.75, 0.01), (0.0, 0.01),
                                      (-0.4, 0.2)])
def test_positive_part_of_a_panel_equals_its_closed_form(c, delta):
    """The positive part of f = (x - c)^2 - delta on one panel [0, h] (x the panel on [-1, 1]):
    with ``dips`` (the chain's fixed panels) to 1e-12 of the closed form, also where f dips below
    zero between the Gauss nodes only (its values there all positive: c = 0.27, 0.75); the rule
    without ``dips`` (the three-link stepper's adaptive panels) splits only panels whose values
    have both signs, and misses those dips."""
    h = 1 / 32
    t, w = gauss_nodes(0.0, h, h, 5)
    x = 2 * t / h - 1
    pw = ((x - c) ** 2 - delta)[None, None, :]
    r = np.sqrt(delta)

    def F(z):   # an antiderivative of f in x, clipped to the panel
        z = min(max(z, -1.0), 1.0)
        return (z - c) ** 3 / 3 - delta * z
    exact = (F(c - r) - F(-1.0) + F(1.0) - F(c + r)) * h / 2

    def positive_part(dips: bool) -> float:
        te, we, _, _, pos = sign_split(np.array([[0.0, h]]), pw, h, dips=dips)
        xe = 2 * te / h - 1
        return float(np.sum(np.where(pos[:, :, None], pw * w, 0.0))
                     + np.sum(np.maximum((xe - c) ** 2 - delta, 0.0) * we))

    assert abs(positive_part(True) - exact) <= 1e-12 * exact
    dip_between_nodes = bool(np.all(pw > 0))
    assert (abs(positive_part(False) - exact) > 1e-4 * exact) == dip_between_nodes
