"""The cycle integrals of the event-driven stepper: input work, gross work, friction dissipation and
each actuator's positive work over a stretch of a run, by adaptive Gauss-Legendre panels on the
smooth pieces of its segments.

:class:`CycleQuadrature` solves the panels' nodes by a
:class:`~ocp_crawl.sim.event_dense.DenseOutput`.
"""
from __future__ import annotations

import math

import numpy as np

from ocp_crawl.model.statics import AUX
from ocp_crawl.sim.event_context import StepperContext
from ocp_crawl.sim.event_dense import DenseOutput
from ocp_crawl.sim.quadrature import LEG_FIT5 as _LEG_FIT, sign_split

#: adaptive quadrature of the cycle integrals: tolerance on the Legendre tail of a panel's integrand
#: (relative to the segment's largest value) and the number of halvings allowed (16: panels down to
#: quad_h/65536; near a fold phi' grows like 1/kappa, and 8 halvings left an energy residual of 9e-6
#: and W+ off by 8e-5 at k = 0.43325 M g L on the paper gait; only the panels that need it are
#: halved)
QUAD_TOL = 1e-4
QUAD_DEPTH = 16
#: the tail of a segment whose integrands are round-off of the cycle's largest integrand value (a
#: hold: the joints at rest, their powers ~1e-15 W) is accepted below this fraction of that value
#: (its noise never meets QUAD_TOL of itself: every panel would be halved QUAD_DEPTH times)
QUAD_FLOOR = 1e-12
#: 5-point Gauss-Legendre nodes and weights on [-1, 1]
_XG, _WG = np.polynomial.legendre.leggauss(5)
#: the columns of _LEG_FIT of the two highest coefficients (the tail of a panel's interpolant)
_LEG_TAIL = _LEG_FIT[:, 3:]
#: rows of the actuators' rates phi1', phi2' in aux (adjacent)
_DPHI12 = slice(AUX["dphi1"], AUX["dphi2"] + 1)


def _gauss_nodes(pending: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """5-point Gauss-Legendre nodes (npan, 5) of the panels (lo, hi) ``pending`` (npan, 2), and
    their half widths (npan, 1)."""
    mid = 0.5 * (pending[:, 0] + pending[:, 1])[:, None]
    half = 0.5 * (pending[:, 1] - pending[:, 0])[:, None]
    return mid + half * _XG, half


def segment_spans(segments, ta: float, tb: float) -> list:
    """[(segment, a, b), ...]: the stretches of positive length of the segments inside [ta, tb]
    [cycles]."""
    spans = [(seg, max(ta, seg.points[0].t), min(tb, seg.points[-1].t)) for seg in segments]
    return [sp for sp in spans if sp[2] > sp[1]]


class CycleQuadrature:
    """Adaptive Gauss-Legendre integrals over the segments of a run, with panels no longer than the
    context's ``quad_h`` and the input's knots as panel edges."""

    def __init__(self, ctx: StepperContext, dense: DenseOutput):
        self._quad_h, self._breakpoints, self._torque = ctx.opt.quad_h, ctx.breakpoints, ctx.torque
        self._dense = dense
        self._first_memo = None
        """(the pieces' ends, the first depth's panels and their pieces) of the last call of
        :meth:`_first_panels`"""

    def _panels(self, spans, first: np.ndarray | None = None, positive: bool = False):
        """Adaptive Gauss-Legendre panels (5 nodes) on the smooth pieces ``spans`` = [(segment, a,
        b), ...].

        Panels start no longer than ``quad_h``; a panel is halved (up to QUAD_DEPTH times) while the
        two highest Legendre coefficients of the degree-4 interpolant of an integrand (actuator
        powers, friction power) exceed QUAD_TOL times the largest integrand value on its piece (and
        QUAD_FLOOR times the largest of all pieces), so steep stretches (low stiffness, large
        amplitudes) are resolved.  The pieces are refined
        together (one batched solve per depth).  Returns per piece the panel edges (lo, hi), nodes,
        weights and integrands (power (2, n, 5), friction power (n, 5)), and (``positive``) the W+
        sign split of all panels (:meth:`_merge_splits`; the split nodes of the panels accepted at
        one depth are solved with the next depth's nodes), else None.  ``first``: the aux of the
        first depth's nodes when they are solved already (:meth:`first_requests`, solved with the
        samples).
        """
        wg = _WG
        pending, owner = self._first_panels(spans)
        done, splits, todo = [], [], None
        scale = np.zeros(len(spans))
        for depth in range(QUAD_DEPTH + 1):
            t, half = _gauss_nodes(pending)
            aux = first if depth == 0 and first is not None else \
                self._solve_panels(spans, owner, t, todo)
            t = t.ravel()
            power = (self._torque(t).reshape(2, -1) * aux[_DPHI12]).reshape(2, -1, 5)
            fric = np.abs(aux[AUX["ft"]] * aux[AUX["ddot"]]).reshape(-1, 5)
            f = np.concatenate([power, fric[None]], axis=0)  # (3, npan, 5)
            np.maximum.at(scale, owner, np.abs(f).max(axis=(0, 2)))
            tail = np.abs(f.reshape(-1, 5) @ _LEG_TAIL).max(axis=1).reshape(3, -1)
            bound = np.maximum(QUAD_TOL * scale[owner], QUAD_FLOOR * scale.max())
            ok = np.all(tail <= bound, axis=0) | (depth == QUAD_DEPTH)
            w = (half * wg).reshape(-1, 5)
            t = t.reshape(-1, 5)
            every = bool(ok.all())  # (then the accepted panels are all of them, in order)
            acc = [owner, pending, t, w, power, fric] if every else \
                [owner[ok], pending[ok], t[ok], w[ok], power[:, ok], fric[ok]]
            if positive:  # (offset: the index of the first accepted panel among all accepted ones)
                todo = self._split_group(spans, acc[0], acc[1], acc[4],
                                         sum(len(d[0]) for d in done))
                splits.append(todo)
            done.append(acc)
            if every:
                break
            bad = pending[~ok]
            m = 0.5 * (bad[:, 0] + bad[:, 1])
            pending = np.concatenate([np.stack([bad[:, 0], m], 1), np.stack([m, bad[:, 1]], 1)])
            owner = np.concatenate([owner[~ok], owner[~ok]])
        if todo is not None and todo["pv"] is None:
            aux = self._dense.evaluate_joined(todo["requests"])[1] if todo["requests"] else None
            self._split_values(todo, aux)
        # regroup by piece, each piece's panels in the order found (depth by depth): a stable sort
        # by owner
        owner = np.concatenate([part[0] for part in done])
        order = np.argsort(owner, kind="stable")
        fields = [np.concatenate([part[k + 1] for part in done], axis=1 if k == 3 else 0)
                  for k in range(5)]
        fields = [f[:, order] if k == 3 else f[order] for k, f in enumerate(fields)]
        ends = np.cumsum(np.bincount(owner, minlength=len(spans))).tolist()
        pieces = [[np.ascontiguousarray(f[:, a:b]) if k == 3 else f[a:b]
                   for k, f in enumerate(fields)]
                  for a, b in zip([0] + ends[:-1], ends)]
        return pieces, self._merge_splits(splits, order) if positive else None

    def _split_group(self, spans, owner: np.ndarray, edges: np.ndarray, pw: np.ndarray,
                     offset: int) -> dict:
        """The W+ sign split (:func:`~ocp_crawl.sim.quadrature.sign_split`) of the panels (edges
        (n, 2), powers (2, n, 5)) of the pieces ``owner`` (n,) accepted at one depth, ``offset``:
        the index of their first among all accepted panels. Returns a dict: positive (2, n), the
        split nodes' phases te, weights we, actuators ie, accepted-panel indices c, sorted by
        piece, the requests [(segment, phases), ...] to solve them, and pv (None until
        :meth:`_split_values`)."""
        te, we, ie, je, pos = sign_split(edges, pw, self._quad_h)
        piece = owner[je]
        srt = np.argsort(piece, kind="stable")
        te, we, ie, je, piece = te[srt], we[srt], ie[srt], je[srt], piece[srt]
        bounds = np.searchsorted(piece, np.arange(len(spans) + 1)).tolist()
        requests = [(spans[k][0], te[a:b])
                    for k, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])) if b > a]
        return {"positive": pos, "te": te, "we": we, "ie": ie, "c": je + offset,
                "requests": requests, "pv": None}

    def _split_values(self, group: dict, aux: np.ndarray | None) -> None:
        """Store in ``group`` (:meth:`_split_group`) the power of its actuator at each split node,
        from the aux (NAUX, n) solved at its nodes (None: no nodes)."""
        if aux is None:
            group["pv"] = np.zeros(0)
            return
        te, ie = group["te"], group["ie"]
        p2 = self._torque(te).reshape(2, -1) * aux[_DPHI12]
        group["pv"] = p2[ie, np.arange(len(te))]

    @staticmethod
    def _merge_splits(splits: list, order: np.ndarray):
        """The sign split of all accepted panels in their final order (``order``: the accepted
        panels' stable sort by piece, see :meth:`_panels`): (positive (2, npan), te, we, ie, panel
        index, pv), the nodes in the order of actuator, then panel, then their order in the
        panel."""
        inv = np.empty_like(order)
        inv[order] = np.arange(len(order))
        pos = np.concatenate([g["positive"] for g in splits], axis=1)[:, order]
        te, we, ie, c, pv = (np.concatenate([g[k] for g in splits])
                             for k in ("te", "we", "ie", "c", "pv"))
        jf = inv[c]
        srt = np.argsort(ie * len(order) + jf, kind="stable")
        return pos, te[srt], we[srt], ie[srt], jf[srt], pv[srt]

    def _first_panels(self, spans) -> tuple[np.ndarray, np.ndarray]:
        """The panels (lo, hi) (npan, 2) of the first depth on the pieces ``spans`` and their pieces
        (npan,), piece by piece (:meth:`_panel_edges`); the last answer is kept (it depends only on
        the pieces' ends)."""
        key = [(a, b) for _, a, b in spans]
        memo = self._first_memo
        if memo is not None and memo[0] == key:
            return memo[1]
        edges = [self._panel_edges(a, b) for _, a, b in spans]
        pending = np.stack([np.concatenate([e[:-1] for e in edges]),
                            np.concatenate([e[1:] for e in edges])], axis=1)
        owner = np.repeat(np.arange(len(spans)), [len(e) - 1 for e in edges])
        self._first_memo = (key, (pending, owner))
        return self._first_memo[1]

    def first_requests(self, spans) -> list:
        """[(segment, phases), ...] of the Gauss nodes of the first depth of :meth:`_panels` on the
        pieces ``spans``, in the order of its batched solve (to be solved with other points in one
        batch)."""
        if not spans:
            return []
        pending, owner = self._first_panels(spans)
        t = _gauss_nodes(pending)[0]
        bounds = np.searchsorted(owner, np.arange(len(spans) + 1)).tolist()
        return [(spans[k][0], t[a:b].ravel())
                for k, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])) if b > a]

    def _solve_panels(self, spans, owner: np.ndarray, t: np.ndarray,
                      split: dict | None = None) -> np.ndarray:
        """aux (NAUX, 5 npan) at the Gauss nodes ``t`` (npan, 5) of panels of the pieces ``owner``
        (npan,), in the order of ``t``: one batched solve of the panels sorted by piece (already
        sorted at the first depth), with the split nodes of ``split`` (:meth:`_split_group`; their
        powers stored by :meth:`_split_values`)."""
        order = np.argsort(owner, kind="stable")
        srt = owner[order]
        bounds = np.searchsorted(srt, np.arange(len(spans) + 1)).tolist()
        ts = t[order]
        requests = [(spans[k][0], ts[a:b].ravel())
                    for k, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])) if b > a]
        extra = split["requests"] if split is not None else []
        _, aux = self._dense.evaluate_joined(requests + extra)
        if split is not None:
            self._split_values(split, aux[:, 5 * len(t):] if extra else None)
            aux = aux[:, :5 * len(t)]
        if np.all(order[1:] > order[:-1]):
            return aux
        out = np.empty_like(aux)
        out[:, (order[:, None] * 5 + np.arange(5)).ravel()] = aux
        return out

    def _panel_edges(self, a: float, b: float) -> np.ndarray:
        """Initial panel edges on [a, b]: no longer than ``quad_h``, with the input's knots as
        edges."""
        n = max(1, math.ceil((b - a) / self._quad_h - 1e-12))
        edges = np.linspace(a, b, n + 1)
        if self._breakpoints.size:
            cycles = np.arange(math.floor(a), math.ceil(b) + 1)[:, None]
            cuts = (self._breakpoints[None, :] + cycles).ravel()
            inside = cuts[(cuts > a + 1e-12) & (cuts < b - 1e-12)]
            edges = np.unique(np.concatenate([edges, inside]))
        return edges

    def integrals(self, segments, ta: float, tb: float, positive: bool,
                  first: np.ndarray | None = None) -> dict:
        """Input work, gross work, friction dissipation and per-actuator positive work over [ta,
        tb].

        Adaptive Gauss-Legendre panels (:meth:`_panels`) on each smooth segment; for W+ a panel on
        which an actuator's power changes sign is split at the roots of its interpolant.  ``first``:
        see
        :meth:`_panels`.
        """
        spans = segment_spans(segments, ta, tb)
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
        """Positive work [J] of each actuator on the panels of the pieces (:meth:`_panels`): the
        Gauss sums of the panels on which its power keeps a positive sign, plus those of the
        sub-panels of the panels on which it changes sign (``split``: :meth:`_merge_splits`, the
        powers at their nodes solved by :meth:`_panels`)."""
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
