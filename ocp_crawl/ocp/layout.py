"""The layout of an NLP under construction: its variables and constraints in named blocks, so that
the transcription, its sub-steps and its solver address them by name, not by row numbers; each
constraint block carries the kinds the solver asks for (:data:`KINDS`), not a naming convention."""
from __future__ import annotations

import casadi as cs
import numpy as np


#: the kinds of constraint blocks: the model's equations (equilibrium, closure, periodicity, the
#: running sums' definitions: residual reports); the complementarity products and the cross
#: conditions, relaxed to sigma per homotopy stage; the optimiser's own rules (friction tolerance,
#: held ties, slip onsets on sub-step boundaries, joint rates) and the requirements on cycle
#: quantities, which a profile given to be simulated need not meet
KINDS = ("equation", "complementarity", "cross", "rule", "requirement")


class Layout:
    """Variables and constraints of an NLP under construction, each block with its named slice."""

    def __init__(self, sym=cs.MX.sym) -> None:
        self.sym = sym
        """the symbol constructor of the NLP's variables (cs.SX.sym or cs.MX.sym)"""
        self.xs, self.lbx, self.ubx, self.g, self.lbg, self.ubg = [], [], [], [], [], []
        self.slices: dict[str, slice] = {}
        self.kinds: dict[str, tuple[str, ...]] = {}

    def var(self, name: str, sym, lb, ub) -> None:
        """Add the variables ``sym`` (bounds broadcast) as the block ``name``."""
        start = sum(v.numel() for v in self.xs)
        self.xs.append(sym)
        self.lbx.append(np.broadcast_to(lb, (sym.numel(),)).astype(float))
        self.ubx.append(np.broadcast_to(ub, (sym.numel(),)).astype(float))
        self.slices[name] = slice(start, start + sym.numel())

    def con(self, name: str, expr, lb, ub, kinds: tuple[str, ...] = ()) -> None:
        """Add the constraints lb <= ``expr`` <= ub as the block ``"g_" + name`` of the ``kinds``
        (of :data:`KINDS`)."""
        if not set(kinds) <= set(KINDS):
            raise ValueError(f"Layout.con: kinds must be of {KINDS}, got {kinds!r}")
        self.kinds["g_" + name] = tuple(kinds)
        start = sum(e.numel() for e in self.g)
        self.g.append(expr)
        self.lbg.append(np.broadcast_to(lb, (expr.numel(),)).astype(float))
        self.ubg.append(np.broadcast_to(ub, (expr.numel(),)).astype(float))
        self.slices["g_" + name] = slice(start, start + expr.numel())


def rows_of(layout_slices: dict[str, slice], kinds: dict[str, tuple], kind: str) -> list[slice]:
    """The constraint blocks' slices of the kind ``kind``, in the order they were added."""
    return [layout_slices[name] for name, own in kinds.items() if kind in own]


def fourier_basis(N: int, K: int) -> np.ndarray:
    """(2K+1, N) values of 1, cos(2 pi n t), sin(2 pi n t), n = 1..K, at the node phases t = k/N."""
    t = np.arange(N) / N
    return np.vstack([np.ones(N)]
                     + [f(2 * np.pi * n * t) for n in range(1, K + 1) for f in (np.cos, np.sin)])
