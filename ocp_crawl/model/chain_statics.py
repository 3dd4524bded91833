"""Symbolic statics of an n-link chain (:class:`~ocp_crawl.model.chain.Chain`), any n >= 3.

The construction is that of :mod:`ocp_crawl.model.statics` for three links, generalised: the
potential energy is written once and the joint balance, the mode equations and their Jacobian
follow by CasADi automatic differentiation (virtual work).

Configuration and coordinates
    Reduced coordinates ``(x1, phi_1 .. phi_{n-1})``: the position of foot 1 and the interior joint
    angles (``pi`` = straight); ``x2 = x1 + d(phi)``.  Link i (1-based) has the absolute angle
    ``alpha_i`` from +x, pointing from its foot-1 end to its foot-2 end, and
    ``alpha_{i+1} = alpha_i + phi_i - pi``.  Both feet on the ground fix the remaining rotation:
    with the angles ``r_i`` relative to a reference link (link ``n // 2 + 1``; the body for
    n = 3), ``A = sum l_i cos r_i`` and ``B = sum l_i sin r_i``, the reference angle is
    ``atan2(-B, A)`` (for n = 3 the paper's eq. (theta), same branch) and ``d = sum l_i cos
    alpha_i > 0``.
Statics
    ``Pi = U_el + sgrav U_g - tau . phi`` with ``U_el = sum k_j (phi_j - pi - rest_j)^2 / 2``;
    friction works ``-f_t grad d . dphi``, so ``F = -grad Pi - f_t grad d`` [N m].  Normal forces
    ``f_n2 = (x_c/d) M g``, ``f_n1 = M g - f_n2``; ``f_t`` is the tangential force on the chain at
    foot 1 along +x (at foot 2: ``-f_t``).
Modes
    ``x = (phi_1 .. phi_{n-1}, f_t/(M g))`` and ``q = (e_ss, sigma, w, d0)`` as in
    :data:`ocp_crawl.model.statics.Q_NAMES`: ``G = (F/(M g L), c_mode)`` with
    ``c_mode = (d - d0)/L`` in stick-stick (``e_ss = 1``), else
    ``f_t/(M g) - sigma (w mu1 f_n1 + (1-w) mu2 f_n2)/(M g)``.

The parameter vector ``p`` of every function is :func:`chain_parameters`; entries by name with
:func:`chain_params`.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any, NamedTuple

import casadi as cs
import numpy as np

from ocp_crawl.model.chain import Chain
from ocp_crawl.model.statics import NQ


class ChainParams(NamedTuple):
    """The parameter vector of an n-link chain by name (lists of CasADi symbols or floats)."""

    lengths: list
    masses: list
    com: list
    stiffness: list
    rest: list
    mu1: Any
    mu2: Any
    g: Any
    sgrav: Any


def n_params(n: int) -> int:
    """Length of the parameter vector of an n-link chain: 5 n."""
    return 3 * n + 2 * (n - 1) + 4


def chain_params(p, n: int) -> ChainParams:
    """The entries of an n-link chain's parameter vector (CasADi or numpy, length 5 n) by name."""
    blocks = []
    start = 0
    for size in (n, n, n, n - 1, n - 1):
        blocks.append([p[i] for i in range(start, start + size)])
        start += size
    lengths, masses, com, stiffness, rest = blocks
    return ChainParams(lengths, masses, com, stiffness, rest, p[start], p[start + 1],
                       p[start + 2], p[start + 3])


def chain_parameters(chain: Chain, sgrav: float) -> np.ndarray:
    """The parameter vector ``p`` of ``chain`` [SI units] with gravity sign ``sgrav`` (+1:
    physical, -1: the paper's printed sign)."""
    return np.array([*chain.lengths, *chain.masses, *chain.com, *chain.stiffness, *chain.rest,
                     *chain.mu, chain.g, float(sgrav)], dtype=float)


def kin_names(n: int) -> tuple[str, ...]:
    """Names of the rows of :attr:`ChainSymbolic.kin` for n links (``alpha1`` .. ``alphan``: link
    angles [rad]; ``zj1`` ..: joint heights [m]; for n = 3, ``alpha2`` is the body angle theta)."""
    j = range(1, n)
    return (*(f"alpha{i}" for i in range(1, n + 1)), "d", "xc", "Delta", "fn1", "fn2",
            *(f"grad_d{i}" for i in j), *(f"grad_Ug{i}" for i in j), "U_el", "U_g",
            *(f"zj{i}" for i in j), "lim1", "lim2")


def aux_names(n: int) -> tuple[str, ...]:
    """Names of the rows of :attr:`ChainSymbolic.evaluate` for n links: those of
    :data:`ocp_crawl.model.statics.AUX_NAMES` without ``det`` (the front end computes it
    numerically) and with the body angle replaced by every link angle."""
    j = range(1, n)
    return (*(f"alpha{i}" for i in range(1, n + 1)), "d", "xc", "Delta", "fn1", "fn2", "ft",
            "ddot", *(f"dphi{i}" for i in j), "dft", "res", "lim1", "lim2",
            *(f"zj{i}" for i in j), "dfn1", "dfn2", *(f"dzj{i}" for i in j))


def chain_geometry(phi, p, n: int) -> dict[str, Any]:
    """Link angles, feet distance, centre of mass, potentials, normal forces and joint heights of
    the n-link chain at joint angles ``phi`` (CasADi expressions; see the module docstring)."""
    P = chain_params(p, n)
    ls = P.lengths
    bend = [phi[j] - cs.pi for j in range(n - 1)]
    ref = n // 2
    r: list[Any] = [cs.SX(0.0)] * n
    for i in range(ref + 1, n):
        r[i] = r[i - 1] + bend[i - 1]
    for i in range(ref - 1, -1, -1):
        r[i] = r[i + 1] - bend[i]
    A = sum(ls[i] * cs.cos(r[i]) for i in range(n))
    B = sum(ls[i] * cs.sin(r[i]) for i in range(n))
    alpha_ref = cs.atan2(-B, A)
    alpha = [alpha_ref + ri for ri in r]
    dx = [ls[i] * cs.cos(alpha[i]) for i in range(n)]
    dz = [ls[i] * cs.sin(alpha[i]) for i in range(n)]
    x_end = [cs.SX(0.0)]
    for i in range(n):
        x_end.append(x_end[-1] + dx[i])
    # end heights from the nearer foot (both feet at height 0; the middle joint of an even chain
    # as the mean of both sums): the same functions of phi, with a reversal-symmetric rounding
    z_left, z_right = [cs.SX(0.0)], [cs.SX(0.0)]
    for i in range(n):
        z_left.append(z_left[-1] + dz[i])
        z_right.insert(0, z_right[0] - dz[n - 1 - i])
    z_end = [z_left[j] if j < n - j else z_right[j] if j > n - j
             else 0.5 * (z_left[j] + z_right[j]) for j in range(n + 1)]
    z_end[0] = z_end[n] = cs.SX(0.0)
    M = sum(P.masses)
    xc = sum(P.masses[i] * (x_end[i] + P.com[i] * dx[i]) for i in range(n)) / M
    z_com = [(1 - P.com[i]) * z_end[i] + P.com[i] * z_end[i + 1] for i in range(n)]
    U_g = P.g * sum(P.masses[i] * z_com[i] for i in range(n))
    U_el = 0.5 * sum(P.stiffness[j] * (bend[j] - P.rest[j]) ** 2 for j in range(n - 1))
    d = x_end[n]
    fn2 = xc / d * M * P.g
    fn1 = M * P.g - fn2
    return dict(alpha=alpha, d=d, xc=xc, U_g=U_g, U_el=U_el, fn1=fn1, fn2=fn2, M=M,
                L=sum(ls), zj=z_end[1:n], lim1=P.mu1 * fn1, lim2=P.mu2 * fn2)


@dataclass(frozen=True)
class ChainSymbolic:
    """The CasADi functions of the n-link chain's statics (inputs ``p`` of length 5 n)."""

    n: int
    """number of links"""
    kin: cs.Function
    """(phi[n-1], p) -> rows :func:`kin_names`"""
    residual: cs.Function
    """(phi[n-1], tau[n-1], f_t, p) -> F[n-1]: joint equilibrium residual [N m]"""
    hold_torque: cs.Function
    """(phi[n-1], f_t, p) -> tau[n-1]: torques holding phi in equilibrium with f_t [N m]"""
    system: cs.Function
    """(x[n], tau[n-1], q[4], p) -> (G[n], J[n x n]): scaled mode equations and Jacobian"""
    evaluate: cs.Function
    """(x[n], tau[n-1], dtau[n-1], q[4], p) -> rows :func:`aux_names`, without solving"""
    ddot2: cs.Function
    """(x[n], tau[n-1], dtau[n-1], q[4], p) -> (a, b[n-1]): d'' = a + b . tau'' along the mode's
    solution"""


@lru_cache(maxsize=None)
def chain_symbolic(n: int) -> ChainSymbolic:
    """Build (once per n and process) and return the CasADi functions of the n-link chain."""
    if int(n) != n or n < 3:
        raise ValueError(f"chain_symbolic: n must be an integer >= 3 (links), got {n!r}")
    nj = n - 1
    phi, tau, dtau = cs.SX.sym("phi", nj), cs.SX.sym("tau", nj), cs.SX.sym("dtau", nj)
    ft, p, q = cs.SX.sym("ft"), cs.SX.sym("p", n_params(n)), cs.SX.sym("q", NQ)
    P = chain_params(p, n)
    geo = chain_geometry(phi, p, n)
    grad_d = cs.gradient(geo["d"], phi)
    grad_Ug = cs.gradient(geo["U_g"], phi)
    V = geo["U_el"] + P.sgrav * geo["U_g"]
    F = -cs.gradient(V - cs.dot(tau, phi), phi) - ft * grad_d
    kin = cs.Function(f"chain{n}_kin", [phi, p], [cs.vertcat(
        *geo["alpha"], geo["d"], geo["xc"], geo["xc"] - geo["d"] / 2, geo["fn1"], geo["fn2"],
        grad_d, grad_Ug, geo["U_el"], geo["U_g"], *geo["zj"], geo["lim1"], geo["lim2"])],
        ["phi", "p"], ["kin"])
    residual = cs.Function(f"chain{n}_residual", [phi, tau, ft, p], [F],
                           ["phi", "tau", "ft", "p"], ["F"])
    hold = cs.Function(f"chain{n}_hold_torque", [phi, ft, p],
                       [cs.gradient(V, phi) + ft * grad_d], ["phi", "ft", "p"], ["tau"])
    x = cs.SX.sym("x", n)
    Mg = geo["M"] * P.g
    sub = cs.vertcat(phi, ft)
    by_x = cs.vertcat(x[0:nj], x[nj] * Mg)
    geo_x = {k: cs.substitute(cs.vertcat(*v) if isinstance(v, list) else v, phi, x[0:nj])
             for k, v in geo.items()}
    e_ss, sigma, w, d0 = q[0], q[1], q[2], q[3]
    c_mode = e_ss * (geo_x["d"] - d0) / geo["L"] + (1 - e_ss) * (
        x[nj] - sigma * (w * geo_x["lim1"] + (1 - w) * geo_x["lim2"]) / Mg)
    G = cs.vertcat(cs.substitute(F, sub, by_x) / (Mg * geo["L"]), c_mode)
    J = cs.jacobian(G, x)
    system = cs.Function(f"chain{n}_system", [x, tau, q, p], [G, J], ["x", "tau", "q", "p"],
                         ["G", "J"])
    evaluate, ddot2 = _mode_outputs(n, x, tau, dtau, q, p, G, J, geo_x,
                                    cs.substitute(grad_d, phi, x[0:nj]), Mg)
    return ChainSymbolic(n=n, kin=kin, residual=residual, hold_torque=hold, system=system,
                         evaluate=evaluate, ddot2=ddot2)


def _mode_outputs(n, x, tau, dtau, q, p, G, J, geo_x, grad_d_x, Mg):
    """``evaluate`` and ``ddot2`` of :class:`ChainSymbolic`: the outputs and rates along the mode's
    solution, ``x' = -J^{-1} G_tau tau'``."""
    nj = n - 1
    xdot = -cs.solve(J, cs.jacobian(G, tau) @ dtau)
    ddot = cs.dot(grad_d_x, xdot[0:nj])
    zj = geo_x["zj"]
    rates = [cs.dot(cs.gradient(e, x[0:nj]), xdot[0:nj])
             for e in (geo_x["fn1"], geo_x["fn2"], *(zj[i] for i in range(nj)))]
    aux = cs.vertcat(geo_x["alpha"], geo_x["d"], geo_x["xc"], geo_x["xc"] - geo_x["d"] / 2,
                     geo_x["fn1"], geo_x["fn2"], x[nj] * Mg, ddot, xdot[0:nj], xdot[nj] * Mg,
                     cs.norm_inf(G), geo_x["lim1"], geo_x["lim2"], zj, *rates)
    assert aux.shape[0] == len(aux_names(n))
    evaluate = cs.Function(f"chain{n}_evaluate", [x, tau, dtau, q, p], [aux],
                           ["x", "tau", "dtau", "q", "p"], ["aux"])
    ddot2 = cs.Function(f"chain{n}_ddot2", [x, tau, dtau, q, p],
                        [cs.vertcat(cs.dot(cs.gradient(ddot, x), xdot)
                                    + cs.dot(cs.gradient(ddot, tau), dtau),
                                    cs.gradient(ddot, dtau))],
                        ["x", "tau", "dtau", "q", "p"], ["ab"])
    return evaluate, ddot2
