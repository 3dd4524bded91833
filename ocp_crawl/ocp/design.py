"""Robot parameters that the periodic-gait OCP chooses together with the gait (co-design):
:class:`Design`.

A design frees, within bounds, the joint stiffnesses of a chain and (or) its link lengths at a
fixed total length.  The lengths keep the body uniform: each link's mass is the total mass times
its share of the total length (a chain whose masses are not proportional to its lengths is
refused: its material would have to be redistributed by a rule the user has not given), each
centre of mass keeps its fraction of its link.  The total mass and length, and so the scales
M g L of the torques and L of the slips, are those of the given chain.

In the NLP the design is a block of scaled variables z = value / initial value (1 at the given
robot), one per free stiffness and per link length, with the row sum(lengths) = L; each scenario's
parameter vector is an expression of z (:meth:`Design.parameters`), and so are the torque
envelope (phi_ref = pi + rest + tau/k inside centre +- A_max, rows linear in tau and k) and the
bandwidth |dtau| <= k R T / N (:meth:`Design.stiffness_expr`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import casadi as cs
import numpy as np

from ocp_crawl.checks import real
from ocp_crawl.model.chain import LENGTH_RATIO_MAX, Chain

#: masses proportional to the lengths to this relative tolerance count as a uniform body
UNIFORM_RTOL = 1e-9


def _bounds(name: str, pairs, size: int) -> tuple[tuple[float, float], ...]:
    """``pairs`` as ``size`` (low, high) pairs of positive floats, low <= high; a single pair is
    used for every entry."""
    pairs = [tuple(p) for p in pairs]
    if len(pairs) == 1 and size > 1:
        pairs = pairs * size
    if len(pairs) != size:
        raise ValueError(f"{name} must give {size} (low, high) pairs, or one for all, got "
                         f"{len(pairs)}")
    out = []
    for i, pair in enumerate(pairs):
        if len(pair) != 2:
            raise ValueError(f"{name}[{i}] must be a (low, high) pair, got {pair!r}")
        lo = real(f"{name}[{i}] low", pair[0], positive=True)
        hi = real(f"{name}[{i}] high", pair[1], positive=True)
        if lo > hi:
            raise ValueError(f"{name}[{i}]: low {lo!r} is above high {hi!r}")
        out.append((lo, hi))
    return tuple(out)


@dataclass(frozen=True)
class Design:
    """The robot parameters the OCP may choose, with their bounds (SI units).

    Parameters
    ----------
    stiffness : sequence of (float, float), optional
        Bounds (low, high) of each joint's stiffness [N m/rad], one pair per joint or one pair for
        every joint; None: the stiffnesses are the robot's.
    lengths : sequence of (float, float), optional
        Bounds (low, high) of each link's length [m], one pair per link or one for every link; the
        total length stays the robot's, the masses follow the lengths (a uniform body); None: the
        lengths are the robot's.
    min_reduced_stiffness : float
        The smallest stick-stick reduced stiffness of the equilibrium at every sub-step end, over
        M g L [-], in [0, 1) (default 0.05): soft joints let the optimiser reach folds of the
        equilibrium (the paper robot at k = 0.028 and 0.022 N m/rad: a fold, the robot snaps
        through), which the quasistatic model cannot follow.
    """

    stiffness: Sequence | None = None
    lengths: Sequence | None = None
    min_reduced_stiffness: float = 0.05

    def __post_init__(self) -> None:
        if self.stiffness is None and self.lengths is None:
            raise ValueError("Design: give stiffness or lengths bounds (nothing to choose)")
        kappa = real("min_reduced_stiffness", self.min_reduced_stiffness, nonneg=True)
        if kappa >= 1.0:
            raise ValueError(f"min_reduced_stiffness must lie in [0, 1) (a fraction of M g L), "
                             f"got {kappa!r}")

    # ------------------------------------------------------------------ the variables
    def checked(self, chain: Chain) -> "Design":
        """This design with its bounds expanded to ``chain``'s joints and links and checked: the
        given robot inside them, a total length the bounds can reach, a uniform body where the
        lengths are free.  Raises ValueError naming the bound."""
        k = None if self.stiffness is None else _bounds("stiffness", self.stiffness,
                                                         chain.n_joints)
        lengths = None if self.lengths is None else _bounds("lengths", self.lengths, chain.n)
        for name, pairs, values in (("stiffness", k, chain.stiffness),
                                    ("lengths", lengths, chain.lengths)):
            for i, (pair, v) in enumerate(zip(pairs or (), values)):
                if not pair[0] <= v <= pair[1]:
                    raise ValueError(f"{name}[{i}]: the robot's {v:.6g} is outside the bounds "
                                     f"[{pair[0]:.6g}, {pair[1]:.6g}]")
        if lengths is not None:
            longest, shortest = max(h for _, h in lengths), min(lo for lo, _ in lengths)
            if longest > LENGTH_RATIO_MAX * shortest:
                raise ValueError(f"lengths: the bounds allow a link of {longest:.6g} m and one of "
                                 f"{shortest:.6g} m, more than {LENGTH_RATIO_MAX:g} times shorter "
                                 "(a chain's longest link is at most that many times its "
                                 "shortest)")
            rho = np.asarray(chain.masses) / np.asarray(chain.lengths)
            if np.ptp(rho) > UNIFORM_RTOL * np.max(rho):
                raise ValueError("lengths: a design of link lengths needs a uniform body (masses "
                                 "proportional to the lengths); the robot's masses per length "
                                 f"range {np.min(rho):.6g} to {np.max(rho):.6g} kg/m")
        return Design(k, lengths, self.min_reduced_stiffness)

    def names(self, chain: Chain) -> list[str]:
        """The design variables' names: ``stiffness[j]`` [N m/rad], ``lengths[i]`` [m]."""
        out = [f"stiffness[{j}]" for j in range(chain.n_joints)] if self.stiffness else []
        return out + ([f"lengths[{i}]" for i in range(chain.n)] if self.lengths else [])

    def initial(self, chain: Chain) -> np.ndarray:
        """The robot's values of the design variables (SI units), the scales of z."""
        return np.array((list(chain.stiffness) if self.stiffness else [])
                        + (list(chain.lengths) if self.lengths else []), float)

    def limits(self) -> tuple[np.ndarray, np.ndarray]:
        """The design variables' bounds (low, high) in SI units (of a :meth:`checked` design)."""
        pairs = list(self.stiffness or ()) + list(self.lengths or ())
        return np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])

    def chain_of(self, chain: Chain, values) -> Chain:
        """``chain`` with the design variables set to ``values`` (SI units, :meth:`names` order);
        the masses follow free lengths."""
        values = np.asarray(values, float)
        changes = {}
        m = chain.n_joints if self.stiffness else 0
        if self.stiffness:
            changes["stiffness"] = tuple(float(v) for v in values[:m])
        if self.lengths:
            lengths = values[m:m + chain.n]
            lengths = lengths * chain.L / math.fsum(lengths)  # the total, to round-off
            changes["lengths"] = tuple(float(v) for v in lengths)
            changes["masses"] = tuple(float(v) for v in chain.M * lengths / chain.L)
        return chain.replace(**changes)

    # ------------------------------------------------------------------ the NLP's expressions
    def stiffness_expr(self, chain: Chain, z):
        """The joint stiffnesses (m,) [N m/rad] as expressions of the scaled variables z (the
        robot's numbers where they are not free)."""
        if not self.stiffness:
            return cs.DM(chain.stiffness)
        return cs.DM(chain.stiffness) * z[:chain.n_joints]

    def lengths_expr(self, chain: Chain, z):
        """The link lengths (n,) [m] as expressions of z (the robot's where they are not free)."""
        if not self.lengths:
            return cs.DM(chain.lengths)
        m = chain.n_joints if self.stiffness else 0
        return cs.DM(chain.lengths) * z[m:m + chain.n]

    def parameters(self, chain: Chain, p: np.ndarray, z):
        """The parameter vector ``p`` of one scenario (:func:`~ocp_crawl.model.chain_statics.
        chain_parameters`: lengths, masses, centres of mass, stiffnesses, rest bends, friction,
        g, gravity sign) with the free entries as expressions of z."""
        n, m = chain.n, chain.n_joints
        lengths = self.lengths_expr(chain, z)
        masses = lengths * (chain.M / chain.L) if self.lengths else cs.DM(p[n:2 * n])
        return cs.vertcat(lengths, masses, cs.DM(p[2 * n:3 * n]), self.stiffness_expr(chain, z),
                          cs.DM(p[3 * n + m:]))

    def total_row(self, chain: Chain, z):
        """The fixed total length as a row (sum(lengths) - L) / L = 0, or None."""
        if not self.lengths:
            return None
        return (cs.sum1(self.lengths_expr(chain, z)) - chain.L) / chain.L
