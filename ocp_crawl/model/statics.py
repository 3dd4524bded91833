"""Three-link crawler: parameters, kinematics and statics.

The statics are derived once, symbolically, from the potential energy by virtual work
(CasADi automatic differentiation) and compiled into CasADi functions that every solver
shares.  The paper's closed forms are kept out of this module on purpose: they live in the
tests as independent oracles.

Conventions (see ``shared/MODEL_NOTES.md``):

* ``phi = (phi1, phi2)`` are the interior joint angles below the body, ``pi`` = flat.
* ``theta`` is the body angle, ``a = phi1 - theta`` and ``c = phi2 + theta`` the leg angles.
* ``x`` points from foot 1 (left) to foot 2 (right); ``x2 = x1 + d(phi)``.
* ``f_t`` is the tangential force on the robot at foot 1 along ``+x``; at foot 2 it is ``-f_t``.
* Gravity convention ``"physical"`` uses the virtual-work sign (``-grad U_g`` in the joint
  balance); ``"paper"`` uses the sign printed in the paper's eq. (intEq) (``+grad U_g``), which
  is the same as a gravitational potential ``-U_g``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any, Literal, NamedTuple

import casadi as cs
import numpy as np

from ocp_crawl.model.compiled import FastFunction, compiled_function
from ocp_crawl.model.robot import Robot  # noqa: F401 - the model's robot, imported from here too

GravityConvention = Literal["physical", "paper"]
GRAVITY_CONVENTIONS = ("physical", "paper")

#: indices of the parameter vector ``p`` passed to every compiled function
P_NAMES = ("M", "L", "beta", "k", "mu1", "mu2", "g", "sgrav")
NP = len(P_NAMES)


class Params(NamedTuple):
    """The parameter vector ``p`` by name (CasADi symbols or floats): read ``params(p).mu1``, never
    ``p[4]``."""

    M: Any
    L: Any
    beta: Any
    k: Any
    mu1: Any
    mu2: Any
    g: Any
    sgrav: Any


def params(p) -> Params:
    """The entries of a parameter vector (CasADi or numpy, length NP) by name."""
    return Params(*(p[i] for i in range(NP)))

#: indices of the mode-parameter vector ``q``: stick-stick flag, slip direction of d, slipping
#: foot weight (1 = foot 1, 0 = foot 2), stick distance d0 [m]
Q_NAMES = ("e_ss", "sigma", "w", "d0")
NQ = len(Q_NAMES)


PAPER_PRESSURE_COEFFS = {"a1": 0.092, "a2": 0.089, "b1": 0.127, "b2": 0.144}
"""Table I pressure-to-bending map a_i p^2 + b_i p [rad/bar^2, rad/bar]."""


# --------------------------------------------------------------------------------------------
# symbolic model, built once per process
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Symbolic:
    kin: cs.Function
    """(phi[2], p) -> [theta, d, xc, Delta, fn1, fn2, grad_d[2], grad_Ug[2], U_el, U_g, zj1, zj2]"""
    residual: cs.Function
    """(phi[2], tau[2], f_t, p) -> F[2]: joint equilibrium residual [N m]"""
    hold_torque: cs.Function
    """(phi[2], f_t, p) -> tau[2]: torque that holds phi in equilibrium with f_t [N m]"""
    evaluate: cs.Function
    """(x[3], tau[2], dtau[2], q[4], p) -> aux[NAUX] without solving"""
    system: cs.Function
    """(x[3], tau[2], q[4], p) -> (G[3], J[3x3]) scaled mode equations and Jacobian"""
    fold: cs.Function
    """(z[7], v0[3], tau0[2], dtau[2], q, p) -> (H[7], dH[7x7]): fold system, see the hybrid
    module"""
    newton: cs.Function
    """(x0[3], tau[2], dtau[2], q[4], p) -> (x[3], aux[NAUX]): NEWTON_ITERS unrolled Newton steps +
    outputs; pure SX, so it can be compiled to C (see :mod:`ocp_crawl.model.compiled`)"""
    ddot2: cs.Function
    """(x[3], tau[2], dtau[2], q[4], p) -> (a, b[2]): d'' = a + b . tau'' along the mode's
    solution"""


#: names of the auxiliary outputs returned with every mode solve
AUX_NAMES = (
    "theta", "d", "xc", "Delta", "fn1", "fn2", "ft", "ddot",
    "dphi1", "dphi2", "dft", "det", "res", "lim1", "lim2", "zj1", "zj2",
    # time derivatives along the mode's solution (d/dt = grad . x'), for event detection inside a
    # step
    "dfn1", "dfn2", "dzj1", "dzj2",
)
AUX = {n: i for i, n in enumerate(AUX_NAMES)}
NAUX = len(AUX_NAMES)


def _geometry(phi, p):
    M, L, beta, k, mu1, mu2, g, sgrav = params(p)
    l = L / (2 + beta)
    m = M / (2 + beta)
    phi1, phi2 = phi[0], phi[1]
    # branch of eq. (theta) that contains the flat configuration (theta = 0 at phi = pi)
    theta = cs.atan2(cs.sin(phi2) - cs.sin(phi1), beta - cs.cos(phi1) - cs.cos(phi2))
    a = phi1 - theta
    c = phi2 + theta
    d = l * (beta * cs.cos(theta) - cs.cos(a) - cs.cos(c))
    # centre of mass from the link centres (not the paper's printed formula, which is an oracle)
    x_left = -0.5 * l * cs.cos(a)
    x_body = -l * cs.cos(a) + 0.5 * beta * l * cs.cos(theta)
    x_right = -l * cs.cos(a) + beta * l * cs.cos(theta) - 0.5 * l * cs.cos(c)
    xc = (m * x_left + beta * m * x_body + m * x_right) / M
    z_left = 0.5 * l * cs.sin(a)
    z_body = 0.5 * l * (cs.sin(a) + cs.sin(c))
    z_right = 0.5 * l * cs.sin(c)
    U_g = g * (m * z_left + beta * m * z_body + m * z_right)
    U_el = 0.5 * k * ((phi1 - cs.pi) ** 2 + (phi2 - cs.pi) ** 2)
    # normal forces from the external balance (workless constraint forces)
    fn2 = xc / d * M * g
    fn1 = M * g - fn2
    return dict(l=l, m=m, theta=theta, a=a, c=c, d=d, xc=xc, U_g=U_g, U_el=U_el, fn1=fn1, fn2=fn2,
                zj1=l * cs.sin(a), zj2=l * cs.sin(c))


@lru_cache(maxsize=1)
def symbolic() -> _Symbolic:
    """Build (once) and return the compiled CasADi functions of the model."""
    phi, tau, dtau, ft = cs.SX.sym("phi",
                                   2), cs.SX.sym("tau", 2), cs.SX.sym("dtau", 2), cs.SX.sym("ft")
    p, q = cs.SX.sym("p", NP), cs.SX.sym("q", NQ)
    kin, residual, hold, F, grad_d = _statics(phi, tau, ft, p)
    x = cs.SX.sym("x", 3)
    G, J, evaluate, ddot2 = _mode_system(x, phi, tau, dtau, ft, p, q, F, grad_d)
    system = cs.Function("system", [x, tau, q, p], [G, J], ["x", "tau", "q", "p"], ["G", "J"])
    xn = cs.SX.sym("x0", 3)
    xk = xn
    for _ in range(NEWTON_ITERS):
        Gk, Jk = system(xk, tau, q, p)
        xk = xk - cs.solve(Jk, Gk)
    newton = cs.Function("ocp_crawl_newton", [xn, tau, dtau, q, p],
                         [xk, evaluate(xk, tau, dtau, q, p)],
                         ["x0", "tau", "dtau", "q", "p"], ["x", "aux"])
    return _Symbolic(kin=kin, residual=residual, hold_torque=hold, evaluate=evaluate, system=system,
                     fold=_fold_system(x, tau, dtau, p, q, G, J), newton=newton, ddot2=ddot2)


def _statics(phi, tau, ft, p):
    """The kinematics, the joint residual F and the holding torque as functions; F and grad d as
    expressions.

    Virtual work: Pi(phi; tau) = U_el + sgrav U_g - tau.phi; friction does virtual work
    f_t dx1 - f_t (dx1 + grad d . dphi) = -f_t grad d . dphi, so F = -dPi/dphi - f_t grad d.
    """
    sgrav = params(p).sgrav
    geo = _geometry(phi, p)
    d = geo["d"]
    grad_d = cs.gradient(d, phi)
    grad_Ug = cs.gradient(geo["U_g"], phi)
    Delta = geo["xc"] - d / 2
    Pi = geo["U_el"] + sgrav * geo["U_g"] - cs.dot(tau, phi)
    F = -cs.gradient(Pi, phi) - ft * grad_d
    kin = cs.Function(
        "kin", [phi, p],
        [cs.vertcat(geo["theta"], d, geo["xc"], Delta, geo["fn1"], geo["fn2"], grad_d, grad_Ug,
                    geo["U_el"], geo["U_g"], geo["zj1"], geo["zj2"])],
        ["phi", "p"], ["kin"],
    )
    residual = cs.Function("residual", [phi, tau, ft, p], [F], ["phi", "tau", "ft", "p"], ["F"])
    hold = cs.Function("hold_torque", [phi, ft, p],
                       [cs.gradient(geo["U_el"] + sgrav * geo["U_g"], phi) + ft * grad_d],
                       ["phi", "ft", "p"], ["tau"])
    return kin, residual, hold, F, grad_d


def _mode_system(x, phi, tau, dtau, ft, p, q, F, grad_d):
    """The unified mode system in x = (phi1, phi2, f_t/(M g)): (G, J) as expressions, ``evaluate``
    and ``ddot2``.

    q selects the mode: stick-stick (e_ss = 1): d(phi) = d0; slip (e_ss = 0):
    f_t = sigma (w mu1 fn1 + (1-w) mu2 fn2), sigma = sign(d').
    """
    M, L, _, _, mu1, mu2, g, _ = params(p)
    e_ss, sigma, w, d0 = q[0], q[1], q[2], q[3]
    Mg = M * g
    geo_x = _geometry(x[0:2], p)
    grad_d_x = cs.substitute(grad_d, phi, x[0:2])
    F_x = cs.substitute(F, cs.vertcat(phi, ft), cs.vertcat(x[0:2], x[2] * Mg))
    lim1 = mu1 * geo_x["fn1"]
    lim2 = mu2 * geo_x["fn2"]
    c_mode = e_ss * (geo_x["d"] - d0) / L + (1 - e_ss) * (x[2] - sigma
                                                          * (w * lim1 + (1 - w) * lim2) / Mg)
    G = cs.vertcat(F_x / (Mg * L), c_mode)
    J = cs.jacobian(G, x)
    G_tau = cs.jacobian(G, tau)
    xdot = -cs.solve(J, G_tau @ dtau)
    ddot = cs.dot(grad_d_x, xdot[0:2])
    detJ = cs.det(J)
    Delta_x = geo_x["xc"] - geo_x["d"] / 2
    rates = [cs.dot(cs.gradient(geo_x[n], x[0:2]), xdot[0:2]) for n in ("fn1", "fn2", "zj1", "zj2")]
    aux = cs.vertcat(
        geo_x["theta"], geo_x["d"], geo_x["xc"], Delta_x, geo_x["fn1"], geo_x["fn2"], x[2] * Mg,
        ddot, xdot[0], xdot[1], xdot[2] * Mg, detJ, cs.norm_inf(G), lim1, lim2, geo_x["zj1"],
        geo_x["zj2"], *rates,
    )
    assert aux.shape[0] == NAUX
    evaluate = cs.Function("evaluate", [x, tau, dtau, q, p], [aux], ["x", "tau", "dtau", "q", "p"],
                           ["aux"])
    # d'' along the mode's solution, d'' = a + b . tau'' (the caller supplies the torque's second
    # derivative); separate from ``evaluate`` because only event detection in slip modes needs it
    ddot2 = cs.Function("ocp_crawl_ddot2", [x, tau, dtau, q, p],
                        [cs.vertcat(cs.dot(cs.gradient(ddot, x), xdot)
                                    + cs.dot(cs.gradient(ddot, tau), dtau),
                                    cs.gradient(ddot, dtau))],
                        ["x", "tau", "dtau", "q", "p"], ["ab"])
    return G, J, evaluate, ddot2


def _fold_system(x, tau, dtau, p, q, G, J):
    """Fold point: G(x, tau(t)) = 0 and J v = 0, |v| = 1, with tau(t) linearised around t0:
    tau = tau0 + (t - t0) dtau0 (the caller iterates, re-linearising at the new t)."""
    z = cs.SX.sym("z", 7)  # x[3], s = t - t0, v[3]
    v0 = cs.SX.sym("v0", 3)
    tau0 = cs.SX.sym("tau0", 2)
    xz, sz, vz = z[0:3], z[3], z[4:7]
    Gz = cs.substitute(G, cs.vertcat(x, tau), cs.vertcat(xz, tau0 + sz * dtau))
    Jz = cs.substitute(J, cs.vertcat(x, tau), cs.vertcat(xz, tau0 + sz * dtau))
    Hz = cs.vertcat(Gz, Jz @ vz, cs.dot(v0, vz) - 1)
    return cs.Function("fold", [z, v0, tau0, dtau, q, p], [Hz, cs.jacobian(Hz, z)],
                       ["z", "v0", "tau0", "dtau", "q", "p"], ["H", "dH"])


#: Newton iterations unrolled in ``newton``; callers repeat the call until the residual is small
NEWTON_ITERS = 4


@compiled_function
@lru_cache(maxsize=1)
def fast_newton():
    """The unrolled Newton solve as a low-overhead callable (compiled C when a compiler is
    available)."""
    return FastFunction(symbolic().newton)


@compiled_function
@lru_cache(maxsize=1)
def fast_ddot2():
    """:attr:`_Symbolic.ddot2` as a low-overhead callable (compiled C when available)."""
    return FastFunction(symbolic().ddot2)


@compiled_function
@lru_cache(maxsize=1)
def fast_kin():
    """:attr:`_Symbolic.kin` as a low-overhead callable (compiled C when available), for the scalar
    :meth:`Model.kinematics` calls of the stepper (start check, potential at the cycle ends)."""
    return FastFunction(symbolic().kin)


#: width of the compiled vectorised Newton solve, and of a narrow one for the last few columns (a
#: call costs about 1 us per column, padding included)
BATCH = 64
SMALL_BATCH = 16


@compiled_function
@lru_cache(maxsize=2)
def fast_newton_batch(width: int = BATCH):
    """``newton`` mapped over ``width`` columns, compiled like :func:`fast_newton` (inputs flattened
    column-major)."""
    # MX symbols keep the map as a loop over one copy of the SX kernel in the generated C
    # (SX symbols would inline BATCH copies: a large library that takes long to compile)
    f = symbolic().newton.map(width)
    x0 = cs.MX.sym("x0", 3, width)
    tau = cs.MX.sym("tau", 2, width)
    dtau = cs.MX.sym("dtau", 2, width)
    q = cs.MX.sym("q", NQ, width)
    p = cs.MX.sym("p", NP)
    xs, aux = f(x0, tau, dtau, q, cs.repmat(p, 1, width))
    name = "ocp_crawl_newton_batch" if width == BATCH else f"ocp_crawl_newton_batch{width}"
    return FastFunction(cs.Function(name, [x0, tau, dtau, q, p], [xs, aux]))


@compiled_function
@lru_cache(maxsize=1)
def fast_newton_batch_small():
    """The narrow (:data:`SMALL_BATCH` columns) :func:`fast_newton_batch`, registered so that
    warm-up builds it."""
    return fast_newton_batch(SMALL_BATCH)


def solve_many(x0: np.ndarray, tau: np.ndarray, dtau: np.ndarray, q: np.ndarray, p: np.ndarray):
    """Mode solves at n points (columns; q may be one vector for all): returns x (3, n) and aux
    (NAUX, n).

    Each column is the same compiled Newton kernel as :func:`fast_newton` (results independent of
    the batching); chunks of BATCH columns, the last ones in chunks of SMALL_BATCH (less
    padding)."""
    n = x0.shape[1]
    # wide chunks while more than three narrow ones remain, then narrow ones
    n_wide = max(0, -(-(n - 3 * SMALL_BATCH) // BATCH))
    widths = [BATCH] * n_wide + [SMALL_BATCH] * max(0, -(-(n - n_wide * BATCH) // SMALL_BATCH))
    total = sum(widths)
    # the inputs padded with copies of the last column, column-major
    last = np.full(total - n, n - 1, dtype=int)
    q = np.asarray(q, float)
    Q = np.repeat(q[:, None], total, axis=1) if q.ndim == 1 else np.concatenate([q, q[:, last]],
                                                                                axis=1)
    cols = [np.concatenate([np.asarray(a, float), np.asarray(a, float)[:, last]], axis=1).ravel("F")
            for a in (x0, tau, dtau)]
    cols.append(Q.ravel("F"))
    xs = np.empty(3 * total)
    aux = np.empty(NAUX * total)
    s = 0
    wide, narrow = fast_newton_batch(), fast_newton_batch_small()  # one cache key each (built once)
    for width in widths:
        xi, ai = (wide if width == BATCH else narrow)(*(c[r * s:r * (s + width)]
                                                        for c, r in zip(cols, (3, 2, 2, NQ))), p)
        xs[3 * s:3 * (s + width)] = xi
        aux[NAUX * s:NAUX * (s + width)] = ai
        s += width
    return xs.reshape(3, total, order="F")[:, :n], aux.reshape(NAUX, total, order="F")[:, :n]


_MAPS: dict[tuple[str, int], cs.Function] = {}


def call_mapped(fun: cs.Function, *args) -> Any:
    """Evaluate ``fun`` column-wise over n columns in one call: an array (rows, n), or a list of
    them when ``fun`` has several outputs (hence ``Any``: the caller knows which).

    Matrix arguments are (rows, n); 1-D arguments (e.g. the parameter vector) are broadcast.
    Sizes are padded to powers of two so that only a few mapped functions are ever compiled.
    """
    n = max(a.shape[1] for a in args if np.ndim(a) == 2)
    size = max(16, 1 << (n - 1).bit_length())
    key = (fun.name(), size)
    f = _MAPS.get(key)
    if f is None:
        f = _MAPS[key] = fun.map(size)
    cols = []
    for a in args:
        a = np.asarray(a, float)
        if a.ndim == 1:
            cols.append(np.tile(a[:, None], (1, size)))
        else:
            cols.append(np.concatenate([a, np.repeat(a[:, -1:], size - n, axis=1)], axis=1)
                        if size > n else a)
    out = f(*cols)
    if isinstance(out, (list, tuple)):
        return [np.asarray(o)[:, :n] for o in out]
    return np.asarray(out)[:, :n]


KIN_NAMES = ("theta", "d", "xc", "Delta", "fn1", "fn2", "grad_d1", "grad_d2", "grad_Ug1",
             "grad_Ug2", "U_el", "U_g", "zj1", "zj2")
KIN = {n: i for i, n in enumerate(KIN_NAMES)}


@dataclass(frozen=True)
class Model:
    """A robot together with the gravity convention; numeric front end to the compiled functions.

    Parameters
    ----------
    robot : Robot
        The physical parameters (default: the paper's Table I robot).
    gravity : {"physical", "paper"}
        Sign of the gravity term: "physical" (virtual work, the default) or "paper" (as printed in
        the paper; see docs/guide/model.md, "Gravity conventions").

    The model is what every simulator takes: ``simulate(Model(robot), signal, solver)``.
    """

    robot: Robot = field(default_factory=Robot.paper)
    gravity: GravityConvention = "physical"

    def __post_init__(self) -> None:
        if not isinstance(self.robot, Robot):
            raise TypeError(f"robot must be a Robot, got {type(self.robot).__name__}")
        if self.gravity not in GRAVITY_CONVENTIONS:
            raise ValueError(f"gravity must be one of {GRAVITY_CONVENTIONS}, got {self.gravity!r}")

    @property
    def sgrav(self) -> float:
        """+1: physical (gravity potential +U_g); -1: the paper's printed sign (potential -U_g)."""
        return 1.0 if self.gravity == "physical" else -1.0

    @property
    def p(self) -> np.ndarray:
        r = self.robot
        return np.array([r.M, r.L, r.beta, r.k, r.mu1, r.mu2, r.g, self.sgrav])

    @property
    def sym(self) -> _Symbolic:
        return symbolic()

    # ---------------------------------------------------------------- kinematics and statics
    def kinematics(self, phi) -> dict[str, np.ndarray]:
        """theta, d, x_c, Delta, normal forces, grad d, grad U_g, U_el, U_g at phi (shape (2,) or
        (2, N))."""
        phi = np.asarray(phi, dtype=float)
        if phi.ndim == 1:
            out = fast_kin()(phi, self.p)[0]
            return {n: out[i] for n, i in KIN.items()}
        out = call_mapped(self.sym.kin, phi, self.p)
        return {n: out[i] for n, i in KIN.items()}

    def normal_forces(self, phi) -> tuple[np.ndarray, np.ndarray]:
        kin = self.kinematics(phi)
        return kin["fn1"], kin["fn2"]

    def equilibrium_residual(self, phi, tau, f_t) -> np.ndarray:
        """Joint balance residual F(phi, tau, f_t) [N m] (eq. intEq with this model's gravity
        sign)."""
        return np.asarray(self.sym.residual(np.asarray(phi, float), np.asarray(tau, float),
                                            float(f_t), self.p)).ravel()

    def hold_torque(self, phi, f_t) -> np.ndarray:
        """Joint torques that hold the configuration phi in equilibrium with tangential force f_t [N
        m]."""
        phi = np.asarray(phi, float)
        if phi.ndim == 1:
            return np.asarray(self.sym.hold_torque(phi, float(f_t), self.p)).ravel()
        return call_mapped(self.sym.hold_torque, phi, np.asarray(f_t, float).reshape(1, -1), self.p)

    def potential(self, phi) -> np.ndarray:
        """Elastic plus gravitational potential of this convention [J] (input torques excluded)."""
        kin = self.kinematics(phi)
        return kin["U_el"] + self.sgrav * kin["U_g"]

    def check_contact(self, phi, *, where: str = "configuration") -> None:
        """Raise ValueError if phi has a foot off the ground (f_n <= 0) or the feet crossed (d <=
        0)."""
        kin = self.kinematics(np.asarray(phi, float))
        if not kin["d"] > 0:
            raise ValueError(f"{where}: feet crossed or coincident (d = {kin['d']:.4g} m <= 0) at "
                             f"phi = {np.degrees(phi).round(3).tolist()} deg")
        for i in (1, 2):
            if not kin[f"zj{i}"] > 0:
                raise ValueError(f"{where}: joint {i} at or below the ground (height "
                                 f"{kin[f'zj{i}'] * 1e3:.4g} mm) at phi = "
                                 f"{np.degrees(phi).round(3).tolist()} deg; the legs must stand "
                                 "above the ground")
            if not kin[f"fn{i}"] > 0:
                raise ValueError(f"{where}: foot {i} off the ground (f_n{i} = {kin[f'fn{i}']:.4g} "
                                 f"N <= 0) at phi = {np.degrees(phi).round(3).tolist()} deg; valid "
                                 "configurations keep the centre of mass between the feet")
