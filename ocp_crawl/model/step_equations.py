"""The incremental (time-stepping) equations of one quasistatic step, as CasADi expressions.

Shared by the MPCC step solver (:mod:`ocp_crawl.sim.mpcc`) and the periodic-gait optimal control
problem (:mod:`ocp_crawl.ocp.transcription`), so both use the same compiled model functions and the
same complementarity formulation.

Scaled step variables (forces by M g, lengths by L, torques by M g L):

    w = (phi1, phi2, f_t1/Mg, f_t2/Mg, s1+/L, s1-/L, s2+/L, s2-/L, c1+, c1-, c2+, c2-)

with the friction margins c_j lifted into variables: c = (mu1 fn1 + ft1, mu1 fn1 - ft1,
mu2 fn2 + ft2, mu2 fn2 - ft2)/(M g) evaluated at the end of the step, and the complementarity
pairs 0 <= s_j _|_ c_j >= 0 (MODEL_NOTES, incremental Coulomb law).
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as cs

from ocp_crawl.model.statics import KIN, params, symbolic

NW = 12
"""number of step variables"""
NEQ = 4
"""equations: joint balance (2), horizontal balance, kinematic closure"""
NPAIR = 4
PAIR_NAMES = ("s1+", "s1-", "s2+", "s2-")


@dataclass(frozen=True)
class StepRows:
    """The rows of the step variables w of a robot of m joints by name: the m joint angles, the
    tangential forces, the four slips and the four friction margins,
    w = (phi_1 .. phi_m, f_t1, f_t2, s1+, s1-, s2+, s2-, c1+, c1-, c2+, c2-) (the n-link chain's
    layout, :func:`ocp_crawl.sim.chain_mpcc.chain_step_nlp`; m = 2 is this module's)."""

    m: int

    @property
    def nw(self) -> int:
        """number of step variables, m + 10"""
        return self.m + 10

    @property
    def phi(self) -> slice:
        return slice(0, self.m)

    @property
    def ft1(self) -> int:
        return self.m

    @property
    def ft2(self) -> int:
        return self.m + 1

    @property
    def s1p(self) -> int:
        """the first slip row (s1+; then s1-, s2+, s2-)"""
        return self.m + 2

    @property
    def c1p(self) -> int:
        """the first margin row (c1+; then c1-, c2+, c2-)"""
        return self.m + 6

    @property
    def slips(self) -> slice:
        return slice(self.s1p, self.s1p + NPAIR)

    @property
    def margins(self) -> slice:
        return slice(self.c1p, self.c1p + NPAIR)


def rows_of(w) -> StepRows:
    """The row layout of step variables ``w`` (m + 10 rows, any array or CasADi matrix)."""
    return StepRows(int(w.shape[0]) - 10)


#: the rows of w by name for the three-link robot (m = 2): the joint angles, the tangential forces,
#: the slips and the friction margins
PHI_ROWS, FT1, FT2 = slice(0, 2), 2, 3
SLIP_ROWS, MARGIN_ROWS = slice(4, 8), slice(8, 12)
S1P, S1M, S2P, S2M = 4, 5, 6, 7
C1P, C1M, C2P, C2M = 8, 9, 10, 11


def other_foot(pair: int) -> tuple[int, int]:
    """The complementarity pairs (indices into :data:`PAIR_NAMES`) of the foot that pair ``pair``
    is not of."""
    return (2, 3) if pair in (0, 1) else (0, 1)


def friction_margins(mu1, fn1, ft1, mu2, fn2, ft2) -> tuple:
    """The four Coulomb margins (mu1 fn1 + ft1, mu1 fn1 - ft1, mu2 fn2 + ft2, mu2 fn2 - ft2).

    ``ft_j`` is the tangential force on the robot at foot j along +x, ``fn_j`` the normal force (any
    consistent unit: N, or scaled by M g); all four are >= 0 inside the friction cones, and margin
    ``2 (j-1) + 0`` (``+ 1``) is zero when foot j is at its limit against -x (+x).  Works on floats,
    numpy arrays and CasADi expressions alike.
    """
    return (mu1 * fn1 + ft1, mu1 * fn1 - ft1, mu2 * fn2 + ft2, mu2 * fn2 - ft2)


def step_equations(phi_prev, w, tau_hat, p):
    """Equations of one step from the angles ``phi_prev`` to the step variables ``w``.

    Returns ``(g_eq, g_lift, s, c)``: the scaled equilibrium/balance/closure residuals (NEQ), the
    lifting residuals c - margins (NPAIR), and the complementarity pairs s (slips / L) and c.
    ``tau_hat`` is the torque at the end of the step divided by M g L; ``p`` the model parameters.
    """
    sym = symbolic()
    phi, ft1, ft2, s, c = w[0:2], w[2], w[3], w[4:8], w[8:12]
    P = params(p)
    L, mu1, mu2 = P.L, P.mu1, P.mu2
    Mg = P.M * P.g
    kin1 = sym.kin(phi, p)
    kin0 = sym.kin(phi_prev, p)
    F = sym.residual(phi, tau_hat * Mg * L, ft1 * Mg, p) / (Mg * L)
    dx1, dx2 = s[0] - s[1], s[2] - s[3]
    closure = (kin1[KIN["d"]] - kin0[KIN["d"]]) / L - (dx2 - dx1)
    g_eq = cs.vertcat(F, ft1 + ft2, closure)
    fn1, fn2 = kin1[KIN["fn1"]] / Mg, kin1[KIN["fn2"]] / Mg
    margins = cs.vertcat(*friction_margins(mu1, fn1, ft1, mu2, fn2, ft2))
    return g_eq, c - margins, s, c
