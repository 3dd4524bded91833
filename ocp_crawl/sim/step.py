"""One incremental step of the time-stepping: its state, its result and the result's assembly.

Shared by the MPCC step solver (:mod:`ocp_crawl.sim.mpcc`) and the mode-enumeration oracle
(:mod:`ocp_crawl.sim.oracle`): both solve the step equations of
:mod:`ocp_crawl.model.step_equations` for the scaled point z = (phi, f_t1/Mg, f_t2/Mg, s/L) and
report it as a :class:`StepResult` built by :func:`step_result_from_w` (or
:func:`failed_step_result`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import casadi as cs
import numpy as np

from ocp_crawl.model.statics import KIN, NP, Model, params, symbolic
from ocp_crawl.model.step_equations import NPAIR, step_equations
from ocp_crawl.sim.result import Mode


@dataclass(frozen=True)
class StepState:
    """State after step k: joint angles [rad], foot positions [m], and the tangential force [N]
    (the force only seeds initial guesses; it is not part of the step problem's data)."""

    phi: np.ndarray
    x1: float
    x2: float
    f_t: float = 0.0

    def __post_init__(self) -> None:
        phi = np.asarray(self.phi, dtype=float).reshape(-1)
        if phi.shape != (2,) or not np.all(np.isfinite(phi)):
            raise ValueError(f"StepState.phi must be 2 finite angles [rad], got {self.phi!r}")
        object.__setattr__(self, "phi", phi)
        for name in ("x1", "x2", "f_t"):
            v = getattr(self, name)
            if isinstance(v,
                          bool) or not isinstance(v, (int, float, np.integer,
                                                      np.floating)) or not math.isfinite(v):
                raise ValueError(f"StepState.{name} must be a finite real number, got {v!r}")
            object.__setattr__(self, name, float(v))




@dataclass(frozen=True)
class StepResult:
    """Outcome of one step.  Forces [N] act on the robot; slips [m]; ``mode`` from the slips/forces.

    ``status`` is the IPOPT return status of the decisive solve (for the mode-enumeration oracle a
    status of its own); ``comp_residual`` = max over the four pairs of |min(s_j/L, c_j/(M g))|.
    """

    success: bool
    status: str
    """IPOPT return status (see :data:`~ocp_crawl.nlp.ipopt.IPOPT_RETURN_STATUS`) or the oracle's
    own status"""
    message: str
    phi: np.ndarray
    """joint angles after the step [rad], shape (2,)"""
    f_t: float
    """tangential force on the robot at foot 1 along +x [N] (at foot 2 it is -f_t)"""
    f_n1: float
    """normal force at foot 1 after the step [N]"""
    f_n2: float
    """normal force at foot 2 after the step [N]"""
    s1p: float
    """slip of foot 1 towards +x [m] (>= 0)"""
    s1m: float
    """slip of foot 1 towards -x [m] (>= 0)"""
    s2p: float
    """slip of foot 2 towards +x [m] (>= 0)"""
    s2m: float
    """slip of foot 2 towards -x [m] (>= 0)"""
    dx1: float
    """displacement of foot 1 [m] = s1p - s1m"""
    dx2: float
    """displacement of foot 2 [m] = s2p - s2m"""
    x1: float
    """position of foot 1 after the step [m]"""
    x2: float
    """position of foot 2 after the step [m]"""
    d: float
    """d(phi) after the step [m]"""
    mode: Mode
    """contact mode from the slips and friction margins (:func:`mode_from_pairs`)"""
    comp_residual: float
    """max_j |min(s_j/L, c_j/(M g))| [-]"""
    eq_residual: float
    """largest scaled residual of the equilibrium, balance and closure equations and the bounds
    [-]"""
    iterations: int
    """IPOPT iterations (Newton iterations for the oracle), all attempts"""
    solve_time: float
    """wall time of the step [s]"""
    homotopy: tuple = ()
    """:class:`~ocp_crawl.nlp.homotopy.Stage` records of every IPOPT call, all attempts"""
    attempts: int = 1
    """attempts used (1 = no retry)"""
    w: np.ndarray | None = None
    """scaled primal solution (warm start of the next step)"""
    lam_x: np.ndarray | None = None
    """multipliers of the variable bounds (warm start)"""
    lam_g: np.ndarray | None = None
    """multipliers of the constraints (warm start)"""
    extra: dict = field(default_factory=dict)

    @property
    def slips(self) -> np.ndarray:
        return np.array([self.s1p, self.s1m, self.s2p, self.s2m])

    def next_state(self) -> StepState:
        """The state after this step (input of the next one)."""
        return StepState(self.phi, self.x1, self.x2, self.f_t)


#: a scaled slip below this is no slip (round-off of the solvers); classifies modes at a corner s =
#: c = 0
SLIP_EPS = 1e-12
SLIP_PAIR_MODES = (Mode.SLIP1_POS, Mode.SLIP1_NEG, Mode.SLIP2_POS, Mode.SLIP2_NEG)
#: both feet count as slipping (SLIP_BOTH_*) when the smaller foot slip is at least this part of the
#: larger
BOTH_RATIO = 1e-3


@lru_cache(maxsize=1)
def step_outputs() -> cs.Function:
    """(z[8], P[4+NP]) -> out[10]: f_n1/Mg, f_n2/Mg, d [m], d_k [m], margins[4]/Mg, equation
    residual, complementarity residual, for a point z = (phi, f_t1/Mg, f_t2/Mg, s/L) of the step
    from phi_k with P = (phi_k, tau/(M g L), p).  Built once per process from the shared step
    equations."""
    z = cs.SX.sym("z", 8)
    P = cs.SX.sym("P", 4 + NP)
    phi_k, tau_hat, p = P[0:2], P[2:4], P[4:4 + NP]
    # with the lifted margins set to zero, the lifting residual is minus the margins
    g_eq, g_lift, s, _ = step_equations(phi_k, cs.vertcat(z, cs.SX.zeros(NPAIR)), tau_hat, p)
    c = -g_lift
    sym = symbolic()
    Mg = params(p).M * params(p).g
    kin1 = sym.kin(z[0:2], p)
    kin0 = sym.kin(phi_k, p)
    eq = cs.fmax(cs.mmax(cs.fabs(g_eq)), cs.fmax(cs.mmax(cs.fmax(-s, 0)), cs.mmax(cs.fmax(-c, 0))))
    comp = cs.mmax(cs.fabs(cs.fmin(s, c)))
    out = cs.vertcat(kin1[KIN["fn1"]] / Mg, kin1[KIN["fn2"]] / Mg, kin1[KIN["d"]], kin0[KIN["d"]],
                     c, eq, comp)
    return cs.Function("step_outputs", [z, P], [out], ["z", "P"], ["out"])


def mode_from_pairs(s: np.ndarray, c: np.ndarray) -> tuple[Mode, int]:
    """Contact mode from the scaled pairs (s1+, s1-, s2+, s2-): pair j slips when s_j > max(c_j,
    SLIP_EPS).

    Returns (mode, number of slipping pairs).  Both feet slipping (possible only when the friction
    limits are equal, e.g. mirror-symmetric gaits) is ``SLIP_BOTH_*`` when the smaller foot slip is
    at least ``BOTH_RATIO`` of the larger and the two move the feet the same way in d; otherwise the
    pair with the largest slip gives the mode.
    """
    slipping = [j for j in range(NPAIR) if s[j] > c[j] and s[j] > SLIP_EPS]
    if not slipping:
        return Mode.STICK, 0
    j = max(slipping, key=lambda i: s[i])
    feet = {0 if i < 2 else 1: i for i in slipping}
    if len(feet) == 2:
        i1, i2 = feet[0], feet[1]
        # d' sign of each foot's slip: foot 1 moving -x (s1-) and foot 2 moving +x (s2+) open the
        # feet
        sig1, sig2 = (-1 if i1 == 0 else 1), (1 if i2 == 2 else -1)
        if sig1 == sig2 and min(s[i1], s[i2]) >= BOTH_RATIO * max(s[i1], s[i2]):
            return (Mode.SLIP_BOTH_POS if sig1 > 0 else Mode.SLIP_BOTH_NEG), len(slipping)
    return SLIP_PAIR_MODES[j], len(slipping)


def step_params(model: Model, state: StepState, tau: np.ndarray) -> np.ndarray:
    """Parameter vector (phi_k, tau/(M g L), p) of the scaled step equations."""
    r = model.robot
    return np.concatenate([state.phi, tau / (r.M * r.g * r.L), model.p])


def step_result_from_w(model: Model, state: StepState, z: np.ndarray, tau: np.ndarray,
                       **fields) -> StepResult:
    """Physical step result from a scaled solution z = (phi, f_t1/Mg, f_t2/Mg, s/L, ...) (MPCC and
    oracle)."""
    r = model.robot
    Mg, L = r.M * r.g, r.L
    z = np.asarray(z, float)
    out = np.asarray(step_outputs()(z[:8], step_params(model, state, tau))).ravel()
    s, c = z[4:8], out[4:8]
    mode, nslip = mode_from_pairs(s, c)
    sl = s * L
    dx1, dx2 = float(sl[0] - sl[1]), float(sl[2] - sl[3])
    extra = dict(fields.pop("extra", {}), slipping_pairs=nslip, margins=c.tolist())
    return StepResult(phi=z[:2].copy(), f_t=float(z[2] * Mg), f_n1=float(out[0] * Mg),
                      f_n2=float(out[1] * Mg),
                      s1p=float(sl[0]), s1m=float(sl[1]), s2p=float(sl[2]), s2m=float(sl[3]),
                      dx1=dx1, dx2=dx2, x1=state.x1 + dx1, x2=state.x2 + dx2, d=float(out[2]),
                      mode=mode,
                      comp_residual=float(out[9]), eq_residual=float(out[8]), extra=extra, **fields)


def check_tau(tau) -> np.ndarray:
    tau = np.asarray(tau, dtype=float).reshape(-1)
    if tau.shape != (2,) or not np.all(np.isfinite(tau)):
        raise ValueError(f"tau must be 2 finite joint torques [N m], got {tau!r}")
    return tau



#: the numeric fields of a StepResult that a successful step must have finite
RESULT_FIELDS = ("f_t", "f_n1", "f_n2", "s1p", "s1m", "s2p", "s2m", "dx1", "dx2", "x1", "x2", "d",
                 "comp_residual", "eq_residual")


def finite_result(res: StepResult) -> bool:
    return (bool(np.all(np.isfinite(res.phi)))
            and all(math.isfinite(getattr(res, f)) for f in RESULT_FIELDS))


def failed_step_result(model: Model, state: StepState, tau: np.ndarray, **fields) -> StepResult:
    """A failed :class:`StepResult`: every solution field is NaN, so that nothing can pass for a
    solution."""
    nan = float("nan")
    return StepResult(success=False, phi=np.full(2, nan), f_t=nan, f_n1=nan, f_n2=nan, s1p=nan,
                      s1m=nan,
                      s2p=nan, s2m=nan, dx1=nan, dx2=nan, x1=nan, x2=nan, d=nan, mode=Mode.STICK,
                      comp_residual=nan, eq_residual=nan, **fields)
