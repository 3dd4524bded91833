"""The result of a run of the event-driven stepper: the sampled cycle, the steady cycle's metrics
and the physical gates, assembled once into a :class:`~ocp_crawl.sim.result.CrawlResult` (through
:mod:`ocp_crawl.sim.assemble`).

:class:`ResultBuilder` samples the run by a :class:`~ocp_crawl.sim.event_dense.DenseOutput` and
integrates its steady cycle by a :class:`~ocp_crawl.sim.event_quad.CycleQuadrature`.
"""
from __future__ import annotations

import math

import numpy as np

from ocp_crawl.model.statics import AUX
from ocp_crawl.sim.assemble import cycle_metrics, default_phases, failed_metrics, failure_message, \
    imbalance, new_result, success_message, unstable_sample
from ocp_crawl.sim.event_context import StepperContext
from ocp_crawl.sim.event_dense import DenseOutput
from ocp_crawl.sim.event_quad import CycleQuadrature, segment_spans
from ocp_crawl.sim.event_solve import ModeSolver
from ocp_crawl.sim.event_state import _Outcome, _Run, phase_owners
from ocp_crawl.sim.result import CrawlResult, energy_balance
from ocp_crawl.status import Status


class ResultBuilder:
    """The result of a run (:meth:`build`) and the energy balance of any of its cycles
    (:meth:`cycle_energy`)."""

    def __init__(self, ctx: StepperContext, solver: ModeSolver, dense: DenseOutput,
                 quad: CycleQuadrature):
        self._model, self._torque, self._energy_tol = ctx.model, ctx.torque, ctx.opt.energy_tol
        self._solver, self._dense, self._quad = solver, dense, quad

    def build(self, run: _Run, end: _Outcome, te: np.ndarray | None) -> CrawlResult:
        """The result of a run that ended with ``end``: the steady cycle [t0, t0 + 1] of a periodic
        run, else the cycle of the failure.

        ``te``: output phases in [0, 1] of that cycle, or None for the default ones (a failed run
        then reports its accepted steps).
        """
        segments, events = run.segments, run.events
        status, success = end.status, end.status == Status.SUCCESS
        if success:
            t0 = float(end.periodic_at - 1)
            message = success_message(run.cycle, t0)
        else:
            t0 = float(max(0, math.floor(end.t)))
            message = failure_message(status, f"{end.detail} at phase t = {end.t:.10f} (cycle "
                                              f"{int(math.floor(end.t)) + 1}, phase "
                                              f"{end.t % 1:.10f}) in mode {end.mode}")
        if te is None and success:
            te = default_phases([e.t - t0 for e in events if t0 <= e.t <= t0 + 1])
        first = None
        if te is None:
            blocks = self._stored_blocks(segments, t0, end.t)
        else:  # (with the first quadrature panels of a steady cycle: one batched solve)
            also = self._quad.first_requests(segment_spans(segments, t0, t0 + 1)) if success else []
            blocks, first = self._sampled_blocks(segments, t0 + te, also)
        fields = {"events": events, "cycles": run.cycle, "failure_t": end.t,
                  "failure_mode": end.mode, "t0": t0}
        extra = dict(run.extra)
        if blocks:
            samples, extra["max_residual_scaled"] = self._samples(blocks)
            fields.update(samples)
        if success:
            fields.update(self._steady_metrics(segments, t0, first))
            fields["periodicity_residual"] = run.extra.get("periodicity_deviation", float("nan"))
            failed = self._gates(fields, t0)
            if failed is not None:
                status, detail, t, mode = failed
                message = failure_message(status, detail)
                fields.update(failed_metrics(t, mode))
        extra["segments"] = len(segments)
        return new_result(self._model, "torque", status, message, nfev=self._solver.nfev,
                          nsteps=run.nsteps, extra=extra, **fields)

    def _gates(self, fields: dict, t0: float) -> tuple[Status, str, float, str] | None:
        """(status, detail, phase, mode) of the first physical gate that the steady cycle of
        ``fields`` fails: an unstable sampled equilibrium, then an energy balance that does not
        close; None if it passes both."""
        if fields.get("t", np.zeros(0)).size:
            unstable = unstable_sample(self._model, fields["t"], fields["phi"], fields["f_t"],
                                       fields["mode"])
            if unstable is not None:
                return (Status.UNSTABLE, *unstable)
        detail = imbalance(fields["energy"], self._energy_tol, "HybridOptions.energy_tol", t0)
        return None if detail is None else (Status.ENERGY_IMBALANCE, detail, t0, "steady cycle")

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
        """(phases, x, aux, segment) of the solutions at the phases ``te`` [cycles], segment by
        segment (a phase on a segment boundary goes to the earlier segment), solved in one batch
        with the requests ``also`` [(segment, phases), ...]; and the aux (NAUX, n) of ``also`` (None
        if there are none)."""
        requests = phase_owners(segments, te)
        if not requests and not also:
            return [], None
        xs, aux = self._dense.evaluate_joined(requests + list(also))
        ends = np.cumsum([len(ts) for _, ts in requests]).tolist()
        blocks = [(ts, xs[:, a:b], aux[:, a:b], seg)
                  for (seg, ts), a, b in zip(requests, [0] + ends[:-1], ends)]
        return blocks, aux[:, (ends[-1] if ends else 0):] if also else None

    def _samples(self, blocks: list) -> tuple[dict, float]:
        """The output arrays of the blocks, in the order of their phases (the sample fields of a
        :class:`~ocp_crawl.sim.result.CrawlResult`), and the largest scaled residual of their
        solves."""
        t = np.concatenate([blk[0] for blk in blocks])
        X = np.concatenate([blk[1] for blk in blocks], axis=1)
        A = np.concatenate([blk[2] for blk in blocks], axis=1)
        feet = [blk[3].foot_positions(blk[2][AUX["d"]]) for blk in blocks]
        x1 = np.concatenate([f[0] for f in feet])
        x2 = np.concatenate([f[1] for f in feet])
        mode = np.repeat([int(blk[3].mode) for blk in blocks], [blk[0].size for blk in blocks])
        if not np.all(t[1:] >= t[:-1]):  # (the blocks of consecutive segments are in order already)
            order = np.argsort(t, kind="stable")
            t, X, A = t[order], X[:, order], A[:, order]
            x1, x2, mode = x1[order], x2[order], mode[order]
        samples = {"t": t, "phi": X[:2], "theta": A[AUX["theta"]], "d": A[AUX["d"]], "x1": x1,
                   "x2": x2, "f_t": A[AUX["ft"]], "f_n1": A[AUX["fn1"]], "f_n2": A[AUX["fn2"]],
                   "tau": self._torque(t).reshape(2, -1), "mode": mode}
        return samples, float(np.max(A[AUX["res"]]))

    def _steady_metrics(self, segments, t0: float, first: np.ndarray | None = None) -> dict:
        """S, W+, CoT+ and the energy balance of the steady cycle [t0, t0 + 1] (``first``: the aux
        of the first quadrature panels' nodes, see
        :meth:`~ocp_crawl.sim.event_quad.CycleQuadrature.integrals`)."""
        model, dense = self._model, self._dense
        pa, pb = dense.state_at(segments, t0), dense.state_at(segments, t0 + 1)
        sa, sb = dense.segment_at(segments, t0), dense.segment_at(segments, t0 + 1)
        x1a = sa.foot_positions(pa.aux[AUX["d"]])[0].item()
        x1b = sb.foot_positions(pb.aux[AUX["d"]])[0].item()
        ints = self._quad.integrals(segments, t0, t0 + 1, positive=True, first=first)
        dV = float(model.potential(pb.x[:2]) - model.potential(pa.x[:2]))
        energy = energy_balance(ints["input_work"], dV, ints["dissipation"], ints["gross_work"],
                                model.robot)
        return cycle_metrics(model.robot, x1b - x1a, ints["W_plus_joint"], energy)

    def cycle_energy(self, segments, cycle: int) -> dict:
        """Energy balance [J] of cycle ``cycle`` (0-based) of the run of ``segments``: input work,
        potential change, dissipation."""
        ta, tb = float(cycle), float(cycle + 1)
        ints = self._quad.integrals(segments, ta, tb, positive=False)
        pa, pb = self._dense.state_at(segments, ta), self._dense.state_at(segments, tb)
        dV = float(self._model.potential(pb.x[:2]) - self._model.potential(pa.x[:2]))
        return energy_balance(ints["input_work"], dV, ints["dissipation"], ints["gross_work"],
                              self._model.robot)
