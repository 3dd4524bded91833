"""Numeric front end of the n-link chain's statics: :class:`ChainModel`, the n-link
:class:`~ocp_crawl.model.statics.Model`.

Inputs and outputs in SI units; angles are the interior joint angles ``phi`` (``pi`` = straight),
``f_t`` the tangential force on the chain at foot 1 along +x (at foot 2: ``-f_t``).  The contact
modes are the vectors ``q = (e_ss, sigma, w, d0)`` of :data:`ocp_crawl.model.statics.Q_NAMES`,
built by :func:`stick_mode` and :func:`slip_mode`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from ocp_crawl.model.buffered import Buffered
from ocp_crawl.model.chain import Chain
from ocp_crawl.model.chain_statics import (ChainSymbolic, aux_names, chain_parameters,
                                           chain_symbolic, kin_names)
from ocp_crawl.model.statics import GRAVITY_CONVENTIONS, GravityConvention

#: mapped functions of :func:`call_columns`, called through their buffers
#: (:class:`~ocp_crawl.model.buffered.Buffered`), by (function name, column count, shared inputs)
_MAPS: dict = {}


def call_columns(fun, *args) -> Any:
    """Evaluate ``fun`` column-wise over n columns in one call, as
    :func:`ocp_crawl.model.statics.call_mapped`, with every 1-D argument (the parameter vector, a
    mode vector) passed once to all columns instead of tiled: converting the tiled copies dominated
    the call (about 0.25 us per entry; 5 n parameters per column for n links).

    Matrix arguments are (rows, n), padded to a power of two (at least 16) columns with their last
    column; returns an array (rows, n), or a list of them for several outputs.
    """
    n = max(a.shape[1] for a in args if np.ndim(a) == 2)
    size = max(16, 1 << (n - 1).bit_length())
    shared = [i for i, a in enumerate(args) if np.ndim(a) < 2]
    key = (fun.name(), size, tuple(shared))
    f = _MAPS.get(key)
    if f is None:
        f = _MAPS[key] = Buffered(fun.map(f"{fun.name()}_columns{size}", "serial", size, shared,
                                          []))
    cols = []
    for a in args:
        a = np.asarray(a, float)
        if a.ndim == 2 and size > n:
            a = np.concatenate([a, np.repeat(a[:, -1:], size - n, axis=1)], axis=1)
        cols.append(a)
    out = f(*cols)
    if isinstance(out, (list, tuple)):
        return [o[:, :n] for o in out]
    return np.asarray(out)[:, :n]


def stick_mode(d0: float) -> np.ndarray:
    """Mode vector of stick-stick at feet distance ``d0`` [m]."""
    return np.array([1.0, 0.0, 0.0, float(d0)])


def slip_mode(foot: int, sigma: float) -> np.ndarray:
    """Mode vector of foot ``foot`` (1 or 2) slipping at its friction limit, with ``sigma`` = +1
    when the feet move apart (d' > 0, ``f_t > 0``) and -1 when they approach."""
    if foot not in (1, 2) or sigma not in (1, -1, 1.0, -1.0):
        raise ValueError(f"slip_mode: foot must be 1 or 2 and sigma +1 or -1, got {foot!r}, "
                         f"{sigma!r}")
    return np.array([0.0, float(sigma), 1.0 if foot == 1 else 0.0, 0.0])


class ModeSolution(NamedTuple):
    """A Newton solve of a mode's equations: the state ``x = (phi [rad], f_t/(M g) [-])``, the
    outputs at it (:meth:`ChainModel.evaluate`), whether the scaled residual reached ``tol`` and the
    iterations taken."""

    x: np.ndarray
    aux: dict
    converged: bool
    iterations: int


@dataclass(frozen=True)
class ChainModel:
    """An n-link chain together with the gravity convention.

    Parameters
    ----------
    chain : Chain
        The physical parameters.
    gravity : {"physical", "paper"}
        Sign of the gravity term, as for :class:`~ocp_crawl.model.statics.Model`: "physical"
        (virtual work, potential +U_g) or "paper" (the sign printed in the paper, potential -U_g).
    """

    chain: Chain
    gravity: GravityConvention = "physical"

    def __post_init__(self) -> None:
        if not isinstance(self.chain, Chain):
            raise TypeError(f"chain must be a Chain, got {type(self.chain).__name__}")
        if self.gravity not in GRAVITY_CONVENTIONS:
            raise ValueError(f"gravity must be one of {GRAVITY_CONVENTIONS}, got {self.gravity!r}")

    @property
    def sgrav(self) -> float:
        """+1: physical (gravity potential +U_g); -1: the paper's printed sign (potential -U_g)."""
        return 1.0 if self.gravity == "physical" else -1.0

    @property
    def p(self) -> np.ndarray:
        """The parameter vector of the compiled functions (:func:`chain_parameters`)."""
        return chain_parameters(self.chain, self.sgrav)

    @property
    def sym(self) -> ChainSymbolic:
        """The CasADi functions of this chain's number of links."""
        return chain_symbolic(self.chain.n)

    @property
    def Mg(self) -> float:
        """total weight M g [N]"""
        return self.chain.M * self.chain.g

    # ---------------------------------------------------------------- column evaluation
    def _columns(self, fun, names, *args) -> dict[str, Any]:
        """``fun`` evaluated on columns (the first argument (rows, N) or (rows,)), by row name;
        scalars for 1-D input."""
        first = np.asarray(args[0], float)
        cols = [np.asarray(a, float).reshape(-1, 1) if first.ndim == 1 and np.ndim(a) > 0
                else np.asarray(a, float) for a in args]
        out = call_columns(fun, *cols, self.p)
        if first.ndim == 1:
            return {n: float(out[i, 0]) for i, n in enumerate(names)}
        return {n: out[i] for i, n in enumerate(names)}

    def _joint_vector(self, name: str, value) -> np.ndarray:
        v = np.asarray(value, float)
        if v.shape[0] != self.chain.n_joints:
            raise ValueError(f"{name} must have {self.chain.n_joints} rows (joints), got shape "
                             f"{v.shape}")
        return v

    # ---------------------------------------------------------------- kinematics and statics
    def kinematics(self, phi) -> dict:
        """Link angles ``alpha_i`` [rad], ``d``, ``xc``, ``Delta`` [m], normal forces ``fn1``,
        ``fn2`` [N], ``grad_d`` [m/rad], ``grad_Ug`` [N m/rad], ``U_el``, ``U_g`` [J], joint heights
        ``zj`` [m] and friction limits ``lim1``, ``lim2`` [N] at ``phi`` ((n-1,) or (n-1, N))."""
        phi = self._joint_vector("phi", phi)
        return self._columns(self.sym.kin, kin_names(self.chain.n), phi)

    def normal_forces(self, phi) -> tuple:
        """``(f_n1, f_n2)`` [N] at ``phi``."""
        kin = self.kinematics(phi)
        return kin["fn1"], kin["fn2"]

    def potential(self, phi):
        """Elastic plus gravitational potential of this convention [J] (input torques excluded)."""
        kin = self.kinematics(phi)
        return kin["U_el"] + self.sgrav * kin["U_g"]

    def equilibrium_residual(self, phi, tau, f_t) -> np.ndarray:
        """Joint balance residual ``F(phi, tau, f_t)`` [N m], shape (n-1,)."""
        phi = self._joint_vector("phi", phi)
        tau = self._joint_vector("tau", tau)
        return np.asarray(self.sym.residual(phi, tau, float(f_t), self.p)).ravel()

    def hold_torque(self, phi, f_t) -> np.ndarray:
        """Joint torques [N m] that hold ``phi`` ((n-1,) or (n-1, N)) in equilibrium with the
        tangential force ``f_t`` [N] (a scalar, or N values)."""
        phi = self._joint_vector("phi", phi)
        if phi.ndim == 1:
            return np.asarray(self.sym.hold_torque(phi, float(f_t), self.p)).ravel()
        return call_columns(self.sym.hold_torque, phi, np.asarray(f_t, float).reshape(1, -1),
                           self.p)

    # ---------------------------------------------------------------- contact modes
    def mode_system(self, x, tau, q) -> tuple[np.ndarray, np.ndarray]:
        """The scaled mode equations ``G`` (n,) [-] and their Jacobian ``J = dG/dx`` (n, n) at
        ``x = (phi, f_t/(M g))``, torques ``tau`` [N m] and mode ``q``."""
        G, J = self.sym.system(np.asarray(x, float), self._joint_vector("tau", tau),
                               np.asarray(q, float), self.p)
        return np.asarray(G).ravel(), np.asarray(J)

    def evaluate(self, x, tau, dtau, q) -> dict:
        """Outputs of the mode at ``x`` without solving (rows :func:`aux_names`, SI units, rates
        per unit time of ``dtau`` [N m/s] along the mode's solution) plus ``det`` = det J [-]."""
        x = np.asarray(x, float)
        tau, dtau = self._joint_vector("tau", tau), self._joint_vector("dtau", dtau)
        q = np.asarray(q, float)
        out = self._columns(self.sym.evaluate, aux_names(self.chain.n), x, tau, dtau, q)
        if x.ndim == 1:
            out["det"] = float(np.linalg.det(self.mode_system(x, tau, q)[1]))
        else:
            qs = np.broadcast_to(q.reshape(4, -1), (4, x.shape[1]))
            out["det"] = np.array([np.linalg.det(self.mode_system(x[:, i], tau[:, i], qs[:, i])[1])
                                   for i in range(x.shape[1])])
        return out

    def ddot2(self, x, tau, dtau, q) -> tuple[float, np.ndarray]:
        """``(a, b)`` with ``d'' = a + b . tau''`` along the mode's solution [m/s^2, m/(N m)]."""
        ab = np.asarray(self.sym.ddot2(np.asarray(x, float), self._joint_vector("tau", tau),
                                       self._joint_vector("dtau", dtau), np.asarray(q, float),
                                       self.p)).ravel()
        return float(ab[0]), ab[1:]

    def solve(self, x0, tau, q, *, dtau=None, tol: float = 1e-13, xtol: float = 1e-14,
              max_iter: int = 40) -> ModeSolution:
        """Equilibrium of the mode ``q`` under the torques ``tau`` [N m] by Newton's method from
        ``x0 = (phi, f_t/(M g))``.

        Converged when the largest scaled residual ``|G|`` is at most ``tol`` [-], or when a Newton
        step is at most ``xtol`` [rad, -] (the residual is then at the rounding level of its
        largest term, which for very stiff joints exceeds ``tol``); not converged after
        ``max_iter`` steps or at a singular Jacobian.  ``dtau`` [N m/s] gives the rates in ``aux``
        (zero by default).
        """
        x = np.array(x0, float)
        tau = self._joint_vector("tau", tau)
        dtau = np.zeros_like(tau) if dtau is None else self._joint_vector("dtau", dtau)
        converged = False
        it = 0
        for it in range(max_iter + 1):
            G, J = self.mode_system(x, tau, q)
            if not np.all(np.isfinite(G)):
                break
            if np.max(np.abs(G)) <= tol:
                converged = True
                break
            if it == max_iter:
                break
            try:
                step = np.linalg.solve(J, G)
            except np.linalg.LinAlgError:
                break
            x = x - step
            if np.max(np.abs(step)) <= xtol:
                converged = True
                it += 1
                break
        return ModeSolution(x, self.evaluate(x, tau, dtau, q), converged, it)

    # ---------------------------------------------------------------- prescribed angles
    def prescribed(self, phi, dphi) -> dict:
        """Forces and holding torques of prescribed joint angles ``phi`` [rad] and rates ``dphi``
        [rad/s] ((n-1,) or (n-1, N)).

        One foot slips: the one with the smaller friction limit ``mu_i f_n,i`` (foot 1 at a tie),
        in the direction of ``d'``; ``f_t = sign(d') mu_s f_n,s``.  Returns the kinematics with
        ``ddot`` [m/s], ``foot`` (1 or 2), ``ft`` [N] and ``tau`` [N m], the torques of the joint
        balance.  Where ``d' = 0`` both feet stick and ``f_t`` is not determined (0 is returned).
        """
        phi = self._joint_vector("phi", phi)
        dphi = self._joint_vector("dphi", dphi)
        out = self.kinematics(phi)
        grad = np.array([out[f"grad_d{j}"] for j in range(1, self.chain.n)])
        out["ddot"] = np.sum(grad * dphi, axis=0)
        out["foot"] = np.where(out["lim1"] <= out["lim2"], 1, 2)
        lim = np.where(out["foot"] == 1, out["lim1"], out["lim2"])
        out["ft"] = np.sign(out["ddot"]) * lim
        out["tau"] = self.hold_torque(phi, out["ft"])
        if phi.ndim == 1:
            out.update(ddot=float(out["ddot"]), foot=int(out["foot"]), ft=float(out["ft"]))
        return out
