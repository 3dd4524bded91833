"""The input as the steps of the MPCC time-stepping see it: where its rate jumps and where it holds
still, in the phases and step fractions the step split (:mod:`ocp_crawl.sim.step_split`) reads.

The kinks bound the differences that give a slip's rate (a difference across a kink would average
the rates of both sides); a step inside a hold moves nothing, and its mode holds with the input.
"""
from __future__ import annotations

import math

import numpy as np

from ocp_crawl.model.inputs import PeriodicSignal, input_knots
from ocp_crawl.sim.event_kinks import hold_spans, input_holds, input_kinks
from ocp_crawl.sim.step_split import RATE_DELTA


class StepInput:
    """The kinks and holds of a periodic input ``torque`` (phases in cycles)."""

    def __init__(self, torque: PeriodicSignal):
        knots = input_knots(torque)
        self.kinks = input_kinks(torque, knots)[0]
        """phases in [0, 1) where the input's rate jumps"""
        self.holds = [tuple(h) for h in input_holds(torque, knots).tolist()]
        """[start, end) phases of the stretches where the input holds still"""

    def held(self, ta: float, tb: float) -> bool:
        """Whether the input holds still over the phases [ta, tb] (inside one of its holds)."""
        return any(a - 1e-12 <= ta and tb <= b + 1e-12 and a < b
                   for a, b in hold_spans(self.holds, ta))

    def kinks_in(self, ta: float, tb: float, lo: float = 0.0) -> tuple[float, ...]:
        """The kinks from a little below ``ta + lo (tb - ta)`` (the reach of the slip rate's
        differences) to ``tb``, as fractions of the step from ``ta`` to ``tb`` (within 1e-9 of
        ``lo``, 0 or 1: that fraction)."""
        if not self.kinks.size:
            return ()
        h, below = tb - ta, lo - 2 * RATE_DELTA
        cycles = np.arange(math.floor(ta + below * h), math.floor(tb) + 1)
        fractions = ((self.kinks[None, :] + cycles[:, None]).ravel() - ta) / h
        out = set()
        for f in fractions:
            snapped = next((e for e in (lo, 0.0, 1.0) if abs(f - e) <= 1e-9), float(f))
            if below <= snapped <= 1.0:
                out.add(snapped)
        return tuple(sorted(out))
