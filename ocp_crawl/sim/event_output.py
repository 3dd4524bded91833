"""Output of the event-driven stepper: dense output of a segment, the cycle integrals by adaptive
Gauss-Legendre panels, and the result (through :mod:`ocp_crawl.sim.assemble`).

:class:`OutputMixin` is a part of :class:`~ocp_crawl.sim.event.HybridStepper`; it uses the
stepper's ``_solve``, ``model``, ``opt``, ``torque``, ``p``, ``breakpoints`` and ``nfev``.
"""
from __future__ import annotations

import math

import numpy as np

from ocp_crawl.model.statics import AUX, solve_many
from ocp_crawl.sim.assemble import default_phases, energy_gate, failure_message, new_result, set_cycle_metrics, \
    set_samples, stability_gate, success_message
from ocp_crawl.sim.event_state import _Failure, _Point, _Run, _Segment, hermite, phase_owners
from ocp_crawl.sim.quadrature import gauss_nodes, legendre_roots
from ocp_crawl.sim.result import CrawlResult, energy_balance
from ocp_crawl.status import Status

#: adaptive quadrature of the cycle integrals: tolerance on the Legendre tail of a panel's
#: integrand (relative to the segment's largest value) and the number of halvings allowed (16: panels
#: down to quad_h/65536; near a fold phi' grows like 1/kappa, and 8 halvings left an energy residual of
#: 9e-6 and W+ off by 8e-5 at k = 0.43325 M g L on the paper gait; only the panels that need it are halved)
QUAD_TOL = 1e-4
QUAD_DEPTH = 16
#: 5-point Gauss-Legendre nodes and weights on [-1, 1]; Legendre coefficients of the degree-4
#: interpolant through values at the nodes (c = values @ _LEG_FIT) and its values at -1 and 1
_XG, _WG = np.polynomial.legendre.leggauss(5)
_LEG_FIT = np.linalg.inv(np.polynomial.legendre.legvander(_XG, 4)).T
_LEG_ENDS = _LEG_FIT @ np.polynomial.legendre.legvander(np.array([-1.0, 1.0]), 4).T
#: the columns of _LEG_FIT of the two highest coefficients (the tail of a panel's interpolant)
_LEG_TAIL = _LEG_FIT[:, 3:]
#: rows of the actuators' rates phi1', phi2' in aux (adjacent)
_DPHI12 = slice(AUX["dphi1"], AUX["dphi2"] + 1)


def _gauss_nodes(pending: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """5-point Gauss-Legendre nodes (npan, 5) of the panels (lo, hi) ``pending`` (npan, 2), and their half widths
    (npan, 1)."""
    mid = 0.5 * (pending[:, 0] + pending[:, 1])[:, None]
    half = 0.5 * (pending[:, 1] - pending[:, 0])[:, None]
    return mid + half * _XG, half


def _spans(segments, ta: float, tb: float) -> list:
    """[(segment, a, b), ...]: the stretches of positive length of the segments inside [ta, tb] [cycles]."""
    spans = [(seg, max(ta, seg.points[0].t), min(tb, seg.points[-1].t)) for seg in segments]
    return [sp for sp in spans if sp[2] > sp[1]]


class OutputMixin:
    """Dense output, cycle integrals and the result of :class:`~ocp_crawl.sim.event.HybridStepper`."""

    def _evaluate_many(self, seg: _Segment, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Solve the segment's mode at many phases: (x (3, n), aux (NAUX, n)); see :meth:`_evaluate_batch`."""
        return self._evaluate_batch([(seg, ts)])[0]

    def _evaluate_batch(self, requests) -> list[tuple[np.ndarray, np.ndarray]]:
        """:meth:`_evaluate_joined`, split by request: [(x (3, n), aux (NAUX, n)), ...] in the order of the requests."""
        xs, aux = self._evaluate_joined(requests)
        ends = np.cumsum([len(ts) for _, ts in requests]).tolist()
        return [(xs[:, a:b], aux[:, a:b]) for a, b in zip([0] + ends[:-1], ends)]

    def _evaluate_joined(self, requests) -> tuple[np.ndarray, np.ndarray]:
        """Solve each segment's mode at many phases, ``requests`` = [(segment, phases), ...], in one batched
        compiled call (each column is an independent Newton solve); the guesses are the Hermite interpolants
        of the segments' points.  Returns x (3, n) and aux (NAUX, n), the requests' columns one after the other.

        Points that the batched Newton does not converge, or converges off the segment's branch (phi
        farther from the guess than 0.05 rad + half the change of phi between the stored points around
        it, the acceptance rule of a continuation step: near a fold Newton from a poor guess can land on
        another root), are solved again one by one, by continuation from the stored point before them.
        """
        counts = [len(ts) for _, ts in requests]
        ts = np.concatenate([np.asarray(t, float) for _, t in requests])
        guesses, reach = self._guesses(requests, ts)
        owner = np.repeat(np.arange(len(requests)), counts)
        n = len(ts)
        Q = np.repeat(np.stack([seg.q for seg, _ in requests], axis=1), counts, axis=1)
        xs, aux = solve_many(guesses, self.torque(ts).reshape(2, n), self.torque.derivative(ts).reshape(2, n), Q,
                             self.p)
        self.nfev += n
        off = ~(np.max(np.abs(xs[:2] - guesses[:2]), axis=0) <= reach)  # also NaN
        for j in np.nonzero(~(aux[AUX["res"]] <= self.res_tol) | off | ~np.all(np.isfinite(xs), axis=0))[0]:
            seg = requests[owner[j]][0]
            pt = None
            if not off[j]:
                pt = self._solve(ts[j], xs[:, j] if np.all(np.isfinite(xs[:, j])) else guesses[:, j], seg.q)
            if pt is None or not np.max(np.abs(pt.x[:2] - guesses[:2, j])) <= reach[j]:
                pt = self._continue_to(seg, float(ts[j]))
            if pt is None:
                raise _Failure(Status.NO_CONVERGENCE, float(ts[j]), seg.mode, "dense output solve failed")
            xs[:, j], aux[:, j] = pt.x, pt.aux
        return xs, aux

    @staticmethod
    def _guesses(requests, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Newton guesses (3, n) at the phases ``ts`` (the requests' phases in order) by Hermite interpolation of
        each request's segment points (a segment of one point: that point), and the largest accepted move of phi
        from each guess [rad] (see :meth:`_evaluate_batch`).

        The points of the requests' segments are joined into one table, and the interval of each phase in its
        segment is found by one ``searchsorted`` on the keys (segment, phase) (complex numbers, which numpy orders
        lexicographically): the same interval as a search in the segment's own phases."""
        which: dict[int, int] = {}
        tables = []
        for seg, _ in requests:
            if id(seg) not in which:
                which[id(seg)] = len(tables)
                tp, X, XD = seg.arrays()
                if tp.size == 1:  # Hermite between two copies of the point (h = 0) gives the point, reach 0.05
                    tp, X, XD = np.repeat(tp, 2), np.repeat(X, 2, axis=1), np.zeros((3, 2))
                tables.append((tp, X, XD))
        sizes = np.array([tp.size for tp, _, _ in tables])
        offsets = np.cumsum(sizes) - sizes
        tp = np.concatenate([t[0] for t in tables])
        X, XD = np.concatenate([t[1] for t in tables], axis=1), np.concatenate([t[2] for t in tables], axis=1)
        keys = np.empty(tp.size, complex)
        keys.real, keys.imag = np.repeat(np.arange(len(tables)), sizes), tp
        k = np.repeat([which[id(seg)] for seg, _ in requests], [len(t) for _, t in requests])
        query = np.empty(ts.size, complex)
        query.real, query.imag = k, ts
        off = offsets[k]
        i = np.searchsorted(keys, query, side="right") - off  # (the np.clip of i - 1 to [0, n - 2], cheaper)
        i = off + np.minimum(np.maximum(i - 1, 0), sizes[k] - 2)
        j = i + 1
        X0, X1 = X.take(i, axis=1), X.take(j, axis=1)  # (take: the same as X[:, i], faster)
        guesses = hermite(tp[i], X0, XD.take(i, axis=1), tp[j], X1, XD.take(j, axis=1), ts)
        reach = 0.05 + 0.5 * np.max(np.abs(X1[:2] - X0[:2]), axis=0)
        return guesses, reach

    def _continue_to(self, seg: _Segment, t: float) -> _Point | None:
        """Solve the segment's mode at t by continuation from the last stored point before t, in 4,
        16, then 64 sub-steps (when the interpolated guess alone does not converge or leaves the branch);
        a sub-step whose solution moves phi farther from its guess than 0.05 rad + half the guess's change
        (the rule of a continuation step) counts as failed."""
        pts = seg.points
        i = max(0, int(np.searchsorted([p.t for p in pts], t, side="right")) - 1)
        for n in (4, 16, 64):
            cur = pts[i]
            for s in np.linspace(cur.t, t, n + 1)[1:]:
                guess = cur.x + (s - cur.t) * cur.xdot
                nxt = self._solve(float(s), guess, seg.q)
                if nxt is None or not np.max(np.abs(nxt.x[:2] - guess[:2])) <= \
                        0.05 + 0.5 * np.max(np.abs(guess[:2] - cur.x[:2])):
                    break
                cur = nxt
            else:
                return cur
        return None

    def _panels(self, spans, first: np.ndarray | None = None, positive: bool = False):
        """Adaptive Gauss-Legendre panels (5 nodes) on the smooth pieces ``spans`` = [(segment, a, b), ...].

        Panels start no longer than ``quad_h``; a panel is halved (up to QUAD_DEPTH times) while the
        two highest Legendre coefficients of the degree-4 interpolant of an integrand (actuator
        powers, friction power) exceed QUAD_TOL times the largest integrand value on its piece, so
        steep stretches (low stiffness, large amplitudes) are resolved.  The pieces are refined together
        (one batched solve per depth).  Returns per piece the panel edges (lo, hi), nodes, weights and
        integrands (power (2, n, 5), friction power (n, 5)), and (``positive``) the W+ sign split of all
        panels (:meth:`_merge_splits`; the split nodes of the panels accepted at one depth are solved with
        the next depth's nodes), else None.  ``first``: the aux of the first depth's nodes when they are
        solved already (:meth:`_first_requests`, solved with the samples).
        """
        wg = _WG
        pending, owner = self._first_panels(spans)
        done, splits, todo = [], [], None
        scale = np.zeros(len(spans))
        for depth in range(QUAD_DEPTH + 1):
            t, half = _gauss_nodes(pending)
            aux = first if depth == 0 and first is not None else self._solve_panels(spans, owner, t, todo)
            t = t.ravel()
            power = (self.torque(t).reshape(2, -1) * aux[_DPHI12]).reshape(2, -1, 5)
            fric = np.abs(aux[AUX["ft"]] * aux[AUX["ddot"]]).reshape(-1, 5)
            f = np.concatenate([power, fric[None]], axis=0)  # (3, npan, 5)
            np.maximum.at(scale, owner, np.abs(f).max(axis=(0, 2)))
            tail = np.abs(f.reshape(-1, 5) @ _LEG_TAIL).max(axis=1).reshape(3, -1)
            ok = np.all(tail <= QUAD_TOL * scale[owner], axis=0) | (depth == QUAD_DEPTH)
            w = (half * wg).reshape(-1, 5)
            t = t.reshape(-1, 5)
            every = bool(ok.all())  # (then the accepted panels are all of them, in order: no selection)
            acc = [owner, pending, t, w, power, fric] if every else \
                [owner[ok], pending[ok], t[ok], w[ok], power[:, ok], fric[ok]]
            if positive:  # (offset: the index of the first accepted panel among all accepted ones)
                todo = self._split_group(spans, acc[0], acc[1], acc[4], sum(len(d[0]) for d in done))
                splits.append(todo)
            done.append(acc)
            if every:
                break
            bad = pending[~ok]
            m = 0.5 * (bad[:, 0] + bad[:, 1])
            pending = np.concatenate([np.stack([bad[:, 0], m], 1), np.stack([m, bad[:, 1]], 1)])
            owner = np.concatenate([owner[~ok], owner[~ok]])
        if todo is not None and todo["pv"] is None:
            self._split_values(todo, self._evaluate_joined(todo["requests"])[1] if todo["requests"] else None)
        # regroup by piece, each piece's panels in the order found (depth by depth): a stable sort by owner
        owner = np.concatenate([part[0] for part in done])
        order = np.argsort(owner, kind="stable")
        fields = [np.concatenate([part[k + 1] for part in done], axis=1 if k == 3 else 0) for k in range(5)]
        fields = [f[:, order] if k == 3 else f[order] for k, f in enumerate(fields)]
        ends = np.cumsum(np.bincount(owner, minlength=len(spans))).tolist()
        pieces = [[np.ascontiguousarray(f[:, a:b]) if k == 3 else f[a:b] for k, f in enumerate(fields)]
                  for a, b in zip([0] + ends[:-1], ends)]
        return pieces, self._merge_splits(splits, order) if positive else None

    def _split_group(self, spans, owner: np.ndarray, edges: np.ndarray, pw: np.ndarray, offset: int) -> dict:
        """The W+ sign split (:meth:`_sign_split`) of the panels (edges (n, 2), powers (2, n, 5)) of the pieces
        ``owner`` (n,) accepted at one depth, ``offset``: the index of their first among all accepted panels.
        Returns a dict: positive (2, n), the split nodes' phases te, weights we, actuators ie, accepted-panel
        indices c, sorted by piece, the requests [(segment, phases), ...] to solve them, and pv (None until
        :meth:`_split_values`)."""
        te, we, ie, je, pos = self._sign_split(edges, pw)
        piece = owner[je]
        srt = np.argsort(piece, kind="stable")
        te, we, ie, je, piece = te[srt], we[srt], ie[srt], je[srt], piece[srt]
        bounds = np.searchsorted(piece, np.arange(len(spans) + 1)).tolist()
        requests = [(spans[k][0], te[a:b]) for k, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])) if b > a]
        return {"positive": pos, "te": te, "we": we, "ie": ie, "c": je + offset, "requests": requests, "pv": None}

    def _split_values(self, group: dict, aux: np.ndarray | None) -> None:
        """Store in ``group`` (:meth:`_split_group`) the power of its actuator at each split node, from the aux
        (NAUX, n) solved at its nodes (None: no nodes)."""
        if aux is None:
            group["pv"] = np.zeros(0)
            return
        te, ie = group["te"], group["ie"]
        p2 = self.torque(te).reshape(2, -1) * aux[_DPHI12]
        group["pv"] = p2[ie, np.arange(len(te))]

    @staticmethod
    def _merge_splits(splits: list, order: np.ndarray):
        """The sign split of all accepted panels in their final order (``order``: the accepted panels' stable
        sort by piece, see :meth:`_panels`): (positive (2, npan), te, we, ie, panel index, pv), the nodes in
        the order of actuator, then panel, then their order in the panel."""
        inv = np.empty_like(order)
        inv[order] = np.arange(len(order))
        pos = np.concatenate([g["positive"] for g in splits], axis=1)[:, order]
        te, we, ie, c, pv = (np.concatenate([g[k] for g in splits]) for k in ("te", "we", "ie", "c", "pv"))
        jf = inv[c]
        srt = np.argsort(ie * len(order) + jf, kind="stable")
        return pos, te[srt], we[srt], ie[srt], jf[srt], pv[srt]

    def _first_panels(self, spans) -> tuple[np.ndarray, np.ndarray]:
        """The panels (lo, hi) (npan, 2) of the first depth on the pieces ``spans`` and their pieces (npan,), piece
        by piece (:meth:`_panel_edges`); the last answer is kept (it depends only on the pieces' ends)."""
        key = [(a, b) for _, a, b in spans]
        memo = getattr(self, "_first_memo", None)
        if memo is not None and memo[0] == key:
            return memo[1]
        edges = [self._panel_edges(a, b) for _, a, b in spans]
        pending = np.stack([np.concatenate([e[:-1] for e in edges]), np.concatenate([e[1:] for e in edges])], axis=1)
        owner = np.repeat(np.arange(len(spans)), [len(e) - 1 for e in edges])
        self._first_memo = (key, (pending, owner))
        return self._first_memo[1]

    def _first_requests(self, spans) -> list:
        """[(segment, phases), ...] of the Gauss nodes of the first depth of :meth:`_panels` on the pieces
        ``spans``, in the order of its batched solve (to be solved with other points in one batch)."""
        if not spans:
            return []
        pending, owner = self._first_panels(spans)
        t = _gauss_nodes(pending)[0]
        bounds = np.searchsorted(owner, np.arange(len(spans) + 1)).tolist()
        return [(spans[k][0], t[a:b].ravel()) for k, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])) if b > a]

    def _solve_panels(self, spans, owner: np.ndarray, t: np.ndarray, split: dict | None = None) -> np.ndarray:
        """aux (NAUX, 5 npan) at the Gauss nodes ``t`` (npan, 5) of panels of the pieces ``owner`` (npan,), in the
        order of ``t``: one batched solve of the panels sorted by piece (already sorted at the first depth), with
        the split nodes of ``split`` (:meth:`_split_group`; their powers stored by :meth:`_split_values`)."""
        order = np.argsort(owner, kind="stable")
        srt = owner[order]
        bounds = np.searchsorted(srt, np.arange(len(spans) + 1)).tolist()
        ts = t[order]
        requests = [(spans[k][0], ts[a:b].ravel()) for k, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])) if b > a]
        extra = split["requests"] if split is not None else []
        _, aux = self._evaluate_joined(requests + extra)
        if split is not None:
            self._split_values(split, aux[:, 5 * len(t):] if extra else None)
            aux = aux[:, :5 * len(t)]
        if np.all(order[1:] > order[:-1]):
            return aux
        out = np.empty_like(aux)
        out[:, (order[:, None] * 5 + np.arange(5)).ravel()] = aux
        return out

    def _panel_edges(self, a: float, b: float) -> np.ndarray:
        """Initial panel edges on [a, b]: no longer than ``quad_h``, with the input's knots as edges."""
        n = max(1, math.ceil((b - a) / self.opt.quad_h - 1e-12))
        edges = np.linspace(a, b, n + 1)
        if self.breakpoints.size:
            cuts = (self.breakpoints[None, :] + np.arange(math.floor(a), math.ceil(b) + 1)[:, None]).ravel()
            edges = np.unique(np.concatenate([edges, cuts[(cuts > a + 1e-12) & (cuts < b - 1e-12)]]))
        return edges

    def _cycle_integrals(self, segments, ta: float, tb: float, positive: bool, first: np.ndarray | None = None) -> dict:
        """Input work, gross work, friction dissipation and per-actuator positive work over [ta, tb].

        Adaptive Gauss-Legendre panels (:meth:`_panels`) on each smooth segment; for W+ a panel on
        which an actuator's power changes sign is split at the roots of its interpolant.  ``first``: see
        :meth:`_panels`.
        """
        spans = _spans(segments, ta, tb)
        panels, split = self._panels(spans, first, positive) if spans else ([], None)
        w_in = 0.0
        w_abs = 0.0
        diss = 0.0
        for _, _, ww, pw, fric in panels:  # (x.sum(): np.sum(x) without its Python wrapper)
            w_in += float((ww[None] * pw).sum())
            w_abs += float((ww[None] * np.abs(pw)).sum())
            diss += float((ww * fric).sum())
        wplus = self._positive_work(panels, split) if positive and panels else np.zeros(2)
        return {"input_work": w_in, "gross_work": w_abs, "dissipation": diss, "W_plus_joint": wplus}

    @staticmethod
    def _positive_work(panels, split) -> np.ndarray:
        """Positive work [J] of each actuator on the panels of the pieces (:meth:`_panels`): the Gauss sums of the
        panels on which its power keeps a positive sign, plus those of the sub-panels of the panels on which it
        changes sign (``split``: :meth:`_merge_splits`, the powers at their nodes solved by :meth:`_panels`)."""
        counts = [len(p[0]) for p in panels]
        first = np.cumsum([0] + counts)
        positive_panels, te, we, ie, je, pv = split
        node_span = np.searchsorted(first, je, side="right") - 1
        first = first.tolist()
        wplus = np.zeros(2)
        for k, (_, _, ww, pw, _) in enumerate(panels):
            pos = positive_panels[:, first[k]:first[k + 1]]
            wplus += np.where(pos[:, :, None], pw * ww[None], 0.0).sum(axis=(1, 2))
            sel = np.nonzero(node_span == k)[0]
            if sel.size:
                i_k, pos_k = ie[sel], we[sel] * np.maximum(pv[sel], 0.0)
                for i in range(2):
                    wplus[i] += float(pos_k[i_k == i].sum())
        return wplus

    def _sign_split(self, edges: np.ndarray, pw: np.ndarray):
        """The panels (edges (npan, 2), powers (2, npan, 5) at their Gauss nodes) on which an actuator's power stays
        >= 0, and the extra Gauss nodes (phases, weights, actuator, panel) of the panels on which it changes sign,
        split at the real roots in the panel of its degree-4 interpolant: (phases, weights, actuator, panel index,
        whether the power of each actuator (2, npan) keeps a positive sign on the panel)."""
        npan = len(edges)
        # values at the panel edges from each panel's degree-4 interpolant, so that a sign
        # change between an edge and the nearest Gauss node is not missed
        ends = (pw.reshape(-1, 5) @ _LEG_ENDS).reshape(2, npan, 2)
        allv = np.concatenate([pw, ends], axis=2)
        positive_panels = np.all(allv >= 0, axis=2)
        mixed = ~positive_panels & ~np.all(allv <= 0, axis=2)
        ii, jj = np.nonzero(mixed)
        if not ii.size:
            return np.zeros(0), np.zeros(0), np.zeros(0, int), np.zeros(0, int), positive_panels
        # the power changes sign inside the panel: split at the roots of its degree-4 interpolant
        roots = legendre_roots(pw[ii, jj] @ _LEG_FIT)  # (the interpolants' Legendre coefficients)
        lo, hi = edges[jj, 0][:, None], edges[jj, 1][:, None]
        r = np.where((np.abs(roots.imag) < 1e-9) & (np.abs(roots.real) < 1), roots.real, np.nan)
        r.sort(axis=1)  # (the real roots in the panel in increasing order, then nan)
        # cuts lo, the roots, hi (hi also in place of the missing roots: the pieces of length 0 are dropped)
        cuts = np.concatenate([lo, lo + (r + 1) * (hi - lo) / 2, hi], axis=1)
        cuts = np.where(np.isnan(cuts), hi, cuts)
        c0, c1 = cuts[:, :-1], cuts[:, 1:]
        keep = c1 - c0 > 0
        c0, c1 = c0[keep], c1[keep]
        rows = np.nonzero(keep)[0]  # (the row of each kept piece, in the order of c0[keep])
        owner, panel = ii[rows], jj[rows]
        if np.all(c1 - c0 <= self.opt.quad_h * (1 - 1e-9)):
            # each piece is one Gauss panel: the nodes and weights of gauss_nodes(c0, c1, quad_h, 5), at once
            mid, half = 0.5 * (c1 + c0)[:, None], 0.5 * (c1 - c0)[:, None]
            return ((mid + half * _XG).ravel(), (half * _WG).ravel(), np.repeat(owner, _XG.size),
                    np.repeat(panel, _XG.size), positive_panels)
        pieces = [gauss_nodes(a, b, self.opt.quad_h, 5) for a, b in zip(c0, c1)]
        return (np.concatenate([tt for tt, _ in pieces]), np.concatenate([w2 for _, w2 in pieces]),
                np.concatenate([np.full(len(tt), i) for (tt, _), i in zip(pieces, owner)]),
                np.concatenate([np.full(len(tt), j) for (tt, _), j in zip(pieces, panel)]), positive_panels)

    @staticmethod
    def _segment_at(segments, t: float):
        """The last segment whose span holds the phase t (its end within 1e-15: a cycle can end 2e-16 short of
        its phase)."""
        for seg in reversed(segments):
            if seg.points[0].t <= t <= seg.points[-1].t + 1e-15:
                return seg
        raise ValueError(t)

    def _state_at(self, segments, t: float) -> _Point:
        seg = self._segment_at(segments, t)
        for p in seg.points:
            if abs(p.t - t) < 1e-15:
                return p
        xs, aux = self._evaluate_many(seg, np.array([t]))
        return _Point(t, xs[:, 0], aux[:, 0])

    def _build_result(self, run: _Run, status: Status, detail: str, fail_t: float | None, fail_mode: str | None,
                      periodic_at: int | None, te: np.ndarray | None) -> CrawlResult:
        """The result of a run: the steady cycle [t0, t0 + 1] of a periodic run, else the cycle of the failure.

        ``te``: output phases in [0, 1] of that cycle, or None for the default ones (a failed run
        then reports its accepted steps).
        """
        segments, events = run.segments, run.events
        res = new_result(self.model, "torque", status, events=events, cycles=run.cycle, failure_t=fail_t,
                         failure_mode=fail_mode, extra=run.extra)
        success = status == Status.SUCCESS
        if success:
            t0 = float(periodic_at - 1)
            res.message = success_message(run.cycle, t0)
        else:
            t0 = float(max(0, math.floor(fail_t)))
            res.message = failure_message(status, f"{detail} at phase t = {fail_t:.10f} (cycle "
                                                  f"{int(math.floor(fail_t)) + 1}, phase {fail_t % 1:.10f}) in mode "
                                                  f"{fail_mode}")
        res.t0 = t0
        if te is None and success:
            te = default_phases([e.t - t0 for e in events if t0 <= e.t <= t0 + 1])
        first = None
        if te is None:
            blocks = self._stored_blocks(segments, t0, fail_t)
        else:  # (with the first quadrature panels of a steady cycle: one batched solve)
            blocks, first = self._sampled_blocks(segments, t0 + te,
                                                 self._first_requests(_spans(segments, t0, t0 + 1)) if success else [])
        if blocks:
            self._store_samples(res, blocks)
        if success:
            self._steady_metrics(res, segments, t0, first)
            res.periodicity_residual = run.extra.get("periodicity_deviation", float("nan"))
            stability_gate(res, self.model)
            energy_gate(res, self.opt.energy_tol, "HybridOptions.energy_tol")
        res.nfev = self.nfev
        res.nsteps = self.nsteps
        res.extra["segments"] = len(segments)
        self._segments = segments
        return res

    @staticmethod
    def _stored_blocks(segments, t0: float, t1: float) -> list:
        """(phases, x, aux, segment) of the accepted points of each segment in [t0, t1]."""
        blocks = []
        for seg in segments:
            pts = [p for p in seg.points if t0 - 1e-15 <= p.t <= t1 + 1e-15]
            if pts:
                blocks.append((np.array([p.t for p in pts]), np.stack([p.x for p in pts], axis=1),
                               np.stack([p.aux for p in pts], axis=1), seg))
        return blocks

    def _sampled_blocks(self, segments, te: np.ndarray, also=()) -> tuple[list, np.ndarray | None]:
        """(phases, x, aux, segment) of the solutions at the phases ``te`` [cycles], segment by segment
        (a phase on a segment boundary goes to the earlier segment), solved in one batch with the requests
        ``also`` [(segment, phases), ...]; and the aux (NAUX, n) of ``also`` (None if there are none)."""
        requests = phase_owners(segments, te)
        if not requests and not also:
            return [], None
        xs, aux = self._evaluate_joined(requests + list(also))
        ends = np.cumsum([len(ts) for _, ts in requests]).tolist()
        blocks = [(ts, xs[:, a:b], aux[:, a:b], seg) for (seg, ts), a, b in zip(requests, [0] + ends[:-1], ends)]
        return blocks, aux[:, (ends[-1] if ends else 0):] if also else None

    def _store_samples(self, res: CrawlResult, blocks: list) -> None:
        """Output arrays of the blocks, in the order of their phases."""
        t = np.concatenate([blk[0] for blk in blocks])
        X = np.concatenate([blk[1] for blk in blocks], axis=1)
        A = np.concatenate([blk[2] for blk in blocks], axis=1)
        feet = [blk[3].foot_positions(blk[2][AUX["d"]]) for blk in blocks]
        x1 = np.concatenate([f[0] for f in feet])
        x2 = np.concatenate([f[1] for f in feet])
        mode = np.repeat([int(blk[3].mode) for blk in blocks], [blk[0].size for blk in blocks])
        if not np.all(t[1:] >= t[:-1]):  # (the blocks of consecutive segments are in order already)
            order = np.argsort(t, kind="stable")
            t, X, A, x1, x2, mode = t[order], X[:, order], A[:, order], x1[order], x2[order], mode[order]
        set_samples(res, t, X[:2], A[AUX["theta"]], A[AUX["d"]], x1, x2, A[AUX["ft"]], A[AUX["fn1"]],
                    A[AUX["fn2"]], self.torque(t).reshape(2, -1), mode)
        res.extra["max_residual_scaled"] = float(np.max(A[AUX["res"]]))

    def _steady_metrics(self, res: CrawlResult, segments, t0: float, first: np.ndarray | None = None) -> None:
        """S, W+, CoT+ and the energy balance of the steady cycle [t0, t0 + 1] (``first``: see :meth:`_panels`)."""
        model = self.model
        pa, pb = self._state_at(segments, t0), self._state_at(segments, t0 + 1)
        sa, sb = self._segment_at(segments, t0), self._segment_at(segments, t0 + 1)
        x1a = sa.foot_positions(pa.aux[AUX["d"]])[0].item()
        x1b = sb.foot_positions(pb.aux[AUX["d"]])[0].item()
        ints = self._cycle_integrals(segments, t0, t0 + 1, positive=True, first=first)
        dV = float(model.potential(pb.x[:2]) - model.potential(pa.x[:2]))
        set_cycle_metrics(res, model.robot, x1b - x1a, ints["W_plus_joint"], ints["input_work"], dV,
                          ints["dissipation"], ints["gross_work"])

    def cycle_energy(self, cycle: int) -> dict:
        """Energy balance [J] of cycle ``cycle`` (0-based) of the last run: input work, potential change, dissipation."""
        segs = self._segments
        ta, tb = float(cycle), float(cycle + 1)
        ints = self._cycle_integrals(segs, ta, tb, positive=False)
        pa, pb = self._state_at(segs, ta), self._state_at(segs, tb)
        dV = float(self.model.potential(pb.x[:2]) - self.model.potential(pa.x[:2]))
        return energy_balance(ints["input_work"], dV, ints["dissipation"], ints["gross_work"], self.model.robot)
