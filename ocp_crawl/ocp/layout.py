"""The layout of an NLP under construction: its variables and constraints in named blocks, so that
the transcription, its sub-steps and its solver address them by name, not by row numbers."""
from __future__ import annotations

import casadi as cs
import numpy as np


class Layout:
    """Variables and constraints of an NLP under construction, each block with its named slice."""

    def __init__(self, sym=cs.MX.sym) -> None:
        self.sym = sym
        """the symbol constructor of the NLP's variables (cs.SX.sym or cs.MX.sym)"""
        self.xs, self.lbx, self.ubx, self.g, self.lbg, self.ubg = [], [], [], [], [], []
        self.slices: dict[str, slice] = {}

    def var(self, name: str, sym, lb, ub) -> None:
        """Add the variables ``sym`` (bounds broadcast) as the block ``name``."""
        start = sum(v.numel() for v in self.xs)
        self.xs.append(sym)
        self.lbx.append(np.broadcast_to(lb, (sym.numel(),)).astype(float))
        self.ubx.append(np.broadcast_to(ub, (sym.numel(),)).astype(float))
        self.slices[name] = slice(start, start + sym.numel())

    def con(self, name: str, expr, lb, ub) -> None:
        """Add the constraints lb <= ``expr`` <= ub as the block ``"g_" + name``."""
        start = sum(e.numel() for e in self.g)
        self.g.append(expr)
        self.lbg.append(np.broadcast_to(lb, (expr.numel(),)).astype(float))
        self.ubg.append(np.broadcast_to(ub, (expr.numel(),)).astype(float))
        self.slices["g_" + name] = slice(start, start + expr.numel())


def fourier_basis(N: int, K: int) -> np.ndarray:
    """(2K+1, N) values of 1, cos(2 pi n t), sin(2 pi n t), n = 1..K, at the node phases t = k/N."""
    t = np.arange(N) / N
    return np.vstack([np.ones(N)] + [f(2 * np.pi * n * t) for n in range(1, K + 1) for f in (np.cos, np.sin)])
