"""Dense output of the event-driven stepper: the modes of a run's segments solved at any phases, in
one batched compiled call, from the Hermite interpolants of their stored points.

:class:`DenseOutput` solves through a :class:`~ocp_crawl.sim.event_solve.ModeSolver` (which counts
the solves) with the context's input.
"""
from __future__ import annotations

import numpy as np

from ocp_crawl.model.statics import AUX
from ocp_crawl.sim.event_context import StepperContext
from ocp_crawl.sim.event_solve import ModeSolver
from ocp_crawl.sim.event_state import _Failure, _Point, _Segment, hermite
from ocp_crawl.status import Status


class DenseOutput:
    """Solutions of the segments' modes at phases between their stored points."""

    def __init__(self, ctx: StepperContext, solver: ModeSolver):
        self._torque, self._solver = ctx.torque, solver

    def evaluate_many(self, seg: _Segment, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Solve the segment's mode at many phases: (x (3, n), aux (NAUX, n)); see
        :meth:`evaluate_batch`."""
        return self.evaluate_batch([(seg, ts)])[0]

    def evaluate_batch(self, requests) -> list[tuple[np.ndarray, np.ndarray]]:
        """:meth:`evaluate_joined`, split by request: [(x (3, n), aux (NAUX, n)), ...] in the order
        of the requests."""
        xs, aux = self.evaluate_joined(requests)
        ends = np.cumsum([len(ts) for _, ts in requests]).tolist()
        return [(xs[:, a:b], aux[:, a:b]) for a, b in zip([0] + ends[:-1], ends)]

    def evaluate_joined(self, requests) -> tuple[np.ndarray, np.ndarray]:
        """Solve each segment's mode at many phases, ``requests`` = [(segment, phases), ...], in one
        batched compiled call (each column is an independent Newton solve); the guesses are the
        Hermite interpolants of the segments' points.  Returns x (3, n) and aux (NAUX, n), the
        requests' columns one after the other.

        Points that the batched Newton does not converge, or converges off the segment's branch (phi
        farther from the guess than 0.05 rad + half the change of phi between the stored points
        around it, the acceptance rule of a continuation step: near a fold Newton from a poor guess
        can land on another root), are solved again one by one, by continuation from the stored
        point before them.
        """
        counts = [len(ts) for _, ts in requests]
        ts = np.concatenate([np.asarray(t, float) for _, t in requests])
        guesses, reach = self._guesses(requests, ts)
        owner = np.repeat(np.arange(len(requests)), counts)
        n = len(ts)
        Q = np.repeat(np.stack([seg.q for seg, _ in requests], axis=1), counts, axis=1)
        xs, aux = self._solver.solve_many(guesses, self._torque(ts).reshape(2, n),
                                          self._torque.derivative(ts).reshape(2, n), Q)
        off = ~(np.max(np.abs(xs[:2] - guesses[:2]), axis=0) <= reach)  # also NaN
        bad = ~(aux[AUX["res"]] <= self._solver.res_tol) | off | ~np.all(np.isfinite(xs), axis=0)
        for j in np.nonzero(bad)[0]:
            seg = requests[owner[j]][0]
            pt = None
            if not off[j]:
                x0 = xs[:, j] if np.all(np.isfinite(xs[:, j])) else guesses[:, j]
                pt = self._solver.solve(ts[j], x0, seg.q)
            if pt is None or not np.max(np.abs(pt.x[:2] - guesses[:2, j])) <= reach[j]:
                pt = self._continue_to(seg, float(ts[j]))
            if pt is None:
                raise _Failure(Status.NO_CONVERGENCE, float(ts[j]), seg.mode,
                               "dense output solve failed")
            xs[:, j], aux[:, j] = pt.x, pt.aux
        return xs, aux

    @staticmethod
    def _guesses(requests, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Newton guesses (3, n) at the phases ``ts`` (the requests' phases in order) by Hermite
        interpolation of each request's segment points (a segment of one point: that point), and the
        largest accepted move of phi from each guess [rad] (see :meth:`evaluate_batch`).

        The points of the requests' segments are joined into one table, and the interval of each
        phase in its segment is found by one ``searchsorted`` on the keys (segment, phase) (complex
        numbers, which numpy orders lexicographically): the same interval as a search in the
        segment's own phases."""
        which: dict[int, int] = {}
        tables = []
        for seg, _ in requests:
            if id(seg) not in which:
                which[id(seg)] = len(tables)
                tp, X, XD = seg.arrays()
                # (Hermite between two copies of the point (h = 0) gives the point, reach 0.05)
                if tp.size == 1:
                    tp, X, XD = np.repeat(tp, 2), np.repeat(X, 2, axis=1), np.zeros((3, 2))
                tables.append((tp, X, XD))
        sizes = np.array([tp.size for tp, _, _ in tables])
        offsets = np.cumsum(sizes) - sizes
        tp = np.concatenate([t[0] for t in tables])
        X = np.concatenate([t[1] for t in tables], axis=1)
        XD = np.concatenate([t[2] for t in tables], axis=1)
        keys = np.empty(tp.size, complex)
        keys.real, keys.imag = np.repeat(np.arange(len(tables)), sizes), tp
        k = np.repeat([which[id(seg)] for seg, _ in requests], [len(t) for _, t in requests])
        query = np.empty(ts.size, complex)
        query.real, query.imag = k, ts
        off = offsets[k]
        i = np.searchsorted(keys, query, side="right") - off
        i = off + np.minimum(np.maximum(i - 1, 0), sizes[k] - 2)  # (np.clip of i - 1, cheaper)
        j = i + 1
        X0, X1 = X.take(i, axis=1), X.take(j, axis=1)  # (take: the same as X[:, i], faster)
        guesses = hermite(tp[i], X0, XD.take(i, axis=1), tp[j], X1, XD.take(j, axis=1), ts)
        reach = 0.05 + 0.5 * np.max(np.abs(X1[:2] - X0[:2]), axis=0)
        return guesses, reach

    def _continue_to(self, seg: _Segment, t: float) -> _Point | None:
        """Solve the segment's mode at t by continuation from the last stored point before t, in 4,
        16, then 64 sub-steps (when the interpolated guess alone does not converge or leaves the
        branch); a sub-step whose solution moves phi farther from its guess than 0.05 rad + half the
        guess's change (the rule of a continuation step) counts as failed."""
        pts = seg.points
        i = max(0, int(np.searchsorted([p.t for p in pts], t, side="right")) - 1)
        for n in (4, 16, 64):
            cur = pts[i]
            for s in np.linspace(cur.t, t, n + 1)[1:]:
                guess = cur.x + (s - cur.t) * cur.xdot
                nxt = self._solver.solve(float(s), guess, seg.q)
                if nxt is None or not np.max(np.abs(nxt.x[:2] - guess[:2])) <= \
                        0.05 + 0.5 * np.max(np.abs(guess[:2] - cur.x[:2])):
                    break
                cur = nxt
            else:
                return cur
        return None

    @staticmethod
    def segment_at(segments, t: float):
        """The last segment whose span holds the phase t (its end within 1e-15: a cycle can end
        2e-16 short of its phase)."""
        for seg in reversed(segments):
            if seg.points[0].t <= t <= seg.points[-1].t + 1e-15:
                return seg
        raise ValueError(t)

    def state_at(self, segments, t: float) -> _Point:
        """The state at phase t [cycles] of the last segment that holds it: its stored point there,
        else solved."""
        seg = self.segment_at(segments, t)
        for p in seg.points:
            if abs(p.t - t) < 1e-15:
                return p
        xs, aux = self.evaluate_many(seg, np.array([t]))
        return _Point(t, xs[:, 0], aux[:, 0])
