"""The solver of the periodic-gait NLP: IPOPT along the relaxation homotopy, the polish on the
identified branches, the tightened NLP alone, and the profile-fixed check.

A :class:`GaitSolver` is built on a :class:`~ocp_crawl.ocp.transcription.GaitOCP` (the NLP, its
bounds, its relaxation and its branches) and its settings' solver options (IPOPT options from the
problem file's ``[ocp.ipopt]``, the homotopy's schedule, stage tolerances and barrier): the
transcription says what the NLP is, the solver how it is solved.  The homotopy engine is the
package's one (:mod:`ocp_crawl.nlp.homotopy`), shared with the MPCC step.
"""
from __future__ import annotations

import numpy as np

from ocp_crawl.nlp import ipopt as nlp_ipopt
from ocp_crawl.nlp.homotopy import Homotopy, Solve, Stage, Start, schedule
from ocp_crawl.nlp.ipopt import Solvers, call_ipopt, ipopt_solvers
from ocp_crawl.ocp.endgame import Endgame
from ocp_crawl.ocp.transcription import GaitOCP


#: the largest move of a variable (scaled: a friction margin by M g) that fixing the ties of the
#: identified foot switches may make for the polish to try it
#: (:meth:`GaitSolver._polish_candidates`); at a tie of the relaxation's point the margin is of the
#: order of sigma / s (about 1e-5 at the three-link optima)
TIE_GAP = 1e-2


class GaitSolver:
    """IPOPT on one transcription: its solvers are built once (each on first use) and serve every
    start; :meth:`solve` and :meth:`solve_tightened` return (x, history, failed, status)."""

    def __init__(self, ocp: GaitOCP):
        self.ocp = ocp
        self.settings = ocp.settings
        self.solvers = self._solvers("gait_ocp", ocp.nlp, stage_tol=self.settings.stage_tol)
        self.kept_run: list[Stage] = []
        """records of the homotopy whose result :meth:`solve` returned (empty if none succeeded)"""
        self._fixed_solvers: Solvers | None = None
        self._fixed: np.ndarray | None = None  # the profile-fixed check's fixed variables, or None
        self._fixed_x = np.zeros(0)

    def _solvers(self, name: str, nlp: dict, stage_tol: float | None = None) -> Solvers:
        """The IPOPT solvers of an NLP: the optimiser's with loose intermediate stages
        (``stage_tol``), the profile-fixed check's (parameters: the interior points' reference; a
        simulation) tight throughout."""
        s = self.settings
        return ipopt_solvers(name, nlp, nlp_ipopt.OCP_IPOPT, nlp_ipopt.OCP_WARM_IPOPT, s.ipopt,
                             "OCPSettings.ipopt", s.verbose, stage_tol,
                             warm_over={"mu_strategy": s.warm_barrier})

    def unpack(self, x: np.ndarray) -> dict:
        """The solution x in physical units (:meth:`~ocp_crawl.ocp.transcription.GaitOCP.unpack`),
        its residuals those of the NLP last solved (the profile-fixed one has no onset rule)."""
        return self.ocp.unpack(x, onset=self._fixed is None)

    def solve(self, x0: np.ndarray, fix_profile: bool = False,
              endgame: Endgame | None = None) -> tuple[np.ndarray | None, list[Stage], str | None,
                                                       str]:
        """Homotopies from x0, one per sigma0; returns the best accepted (x, history, failed stage,
        status).

        ``endgame``: after the relaxed stages down to its sigma, its solve from there (kept when it
        says so: :class:`~ocp_crawl.ocp.endgame.Endgame`), else the rest of the homotopy.

        ``fix_profile``: the torques and the period are fixed to those of x0 by their bounds and the
        objective is only the regularisation of the interior points (the transcription then
        simulates the profile: a check against the event-driven simulator).  ``status`` is the
        return status (see :data:`~ocp_crawl.nlp.ipopt.IPOPT_RETURN_STATUS`) of the solve that
        decided: the last accepted stage or polish of the kept homotopy, else the failed stage of
        the last homotopy, whose ``failed`` then names the stage (``x`` is that homotopy's last
        accepted iterate or None).
        """
        ocp = self.ocp
        self._fixed = None
        if fix_profile:
            self._fixed = np.zeros(ocp.nx, bool)
            self._fixed[ocp.slices["tau"]] = self._fixed[ocp.slices["T_hat"]] = True
            self._fixed_x = np.asarray(x0, float)
        if fix_profile and self._fixed_solvers is None:
            self._fixed_solvers = self._solvers("gait_ocp_fixed", ocp.fixed_nlp)
        solvers = self._fixed_solvers if fix_profile else self.solvers
        assert solvers is not None
        hom = Homotopy.of(solvers, self._call, loose_at=None if fix_profile else self._loose_at)
        best = None
        runs = []
        f0 = ocp.objective(x0)  # objective of the (nearly feasible) initial guess
        for sigma0 in self.settings.sigma0:
            n0 = len(hom.records)
            x, failed, status = self._homotopy(hom, x0, sigma0, None if fix_profile else endgame)
            runs.append((x, hom.records[n0:], failed, status))
            if x is not None and failed is None:
                f = ocp.objective(x)
                if best is None or f < best[0]:
                    best = (f, x, hom.records[n0:], status)
            if best is not None and best[0] < f0:
                break  # improved on the initial guess: the next (tighter) start is not needed
        if not fix_profile and best is not None and best[0] >= f0:
            best = self._start_branches(x0, best, hom.records)
        self.kept_run = best[2] if best is not None else []
        if best is not None:
            return best[1], hom.records, None, best[3]
        x, _, failed, status = runs[-1]
        if len(runs) > 1:
            failed = "; ".join(f"start sigma0 = {sigma0:.0e}: {r[2]} ({r[3]})"
                               for sigma0, r in zip(self.settings.sigma0, runs))
        return x, hom.records, failed, status

    def _start_branches(self, x0: np.ndarray, best: tuple, records: list) -> tuple:
        """When the homotopy ended but not better than x0 (e.g. a previous optimum: the relaxation
        let the point wander to another branch, 0.2 % to 5 % lower at N = 20), the tightened NLP on
        x0's own branches; the better of the two (objective, x, records, status)."""
        x, hist, failed, status = self.solve_tightened(x0)
        records.extend(hist)
        if x is None or failed is not None:
            return best
        if max(sc["comp"] for sc in self.unpack(x)["scen"]) > self.settings.comp_tol:
            return best  # not complementary
        f = self.ocp.objective(x)
        return (f, x, hist, status) if f < best[0] else best

    def solve_tightened(self, x0: np.ndarray, max_iter: int | None = None, kind: str = "polish"
                        ) -> tuple[np.ndarray | None, list[Stage], str | None, str]:
        """The tightened NLP alone, no homotopy: each pair fixed to the branch that x0 identifies
        (x0 complementary, e.g. the simulated guess of a coarser N's optimum,
        :func:`~ocp_crawl.ocp.convergence.converge_in_nodes`), solved by the tight warm solver from
        zero multipliers, each polish candidate in turn, in reverse order (the branches alone first:
        the guess's foot-switch ties need not sit where the finer N puts them; robust_speed N = 100
        from N = 50: with the ties fixed, Restoration_Failed after 560 iterations, the branches
        alone 236 to the same optimum), until one that IPOPT accepts is complementary to comp_tol.
        Returns (x, history, failed, status) as :meth:`solve` does: that candidate's point; else the
        first point IPOPT accepted (its residual then fails the caller's check); else x None and
        ``failed`` naming every candidate's IPOPT status.  ``max_iter``: at most this many IPOPT
        iterations per candidate (None: the solvers' own limit); ``kind``: the records' kind."""
        self._fixed = None
        hom = Homotopy.of(self.solvers, self._call)
        if max_iter is not None:
            assert self.solvers.capped is not None  # ipopt_solvers sets it
            hom.warm = self.solvers.capped(max_iter)
        start = Solve(x0, np.zeros(self.ocp.nx), np.zeros(self.ocp.ng), "", True, 0)
        kept = None
        for data in self._polish_candidates(x0)[::-1]:
            pol = hom.polish(start, [data], lambda p: True, kind=kind)
            if pol is not None and (kept is None or pol.comp <= self.settings.comp_tol):
                kept = pol  # the first accepted point, unless a later one is complementary
            if kept is not None and kept.comp <= self.settings.comp_tol:
                break
        self.kept_run = hom.records
        if kept is not None:
            return kept.x, hom.records, None, kept.status
        statuses = ", ".join(r.return_status for r in hom.records)
        return (None, hom.records, f"the tightened NLP on the start's branches ({statuses})",
                hom.records[-1].return_status)

    def prepare(self) -> None:
        """Build the solver of the first homotopy stage now rather than at the first solve (the
        first build generates the derivative functions, which every later solver reuses: about 0.8 s
        at N = 50, 8 s at N = 400), e.g. while the harmonic baseline's worker processes search.  The
        same solvers, the same results."""
        s = self.settings
        sigmas = schedule(s.sigma0[0], s.sigma_factor, s.sigma_min)
        (self.solvers.cold if len(sigmas) == 1 else self._loose_at(sigmas[0])[0]).function()

    def _loose_at(self, sigma: float) -> tuple:
        """The (cold, warm) solvers of a loose stage at sigma: tol = stage_tol, or min(stage_tol,
        stage_tol_ratio sigma) (the tight pair where that is not looser than the tight
        tolerance)."""
        s = self.settings
        tol = s.stage_tol if s.stage_tol_ratio is None else min(s.stage_tol,
                                                                s.stage_tol_ratio * sigma)
        assert self.solvers.loose is not None  # ipopt_solvers sets it
        return self.solvers.loose(tol)

    def _call(self, solver, start: Start, data: dict) -> Solve:
        """One IPOPT call of the homotopy and the residuals of its point."""
        args = dict(data, x0=start.x)
        if start.warm:
            args.update(lam_x0=start.lam_x, lam_g0=start.lam_g)
        ng = self.ocp.ng if self._fixed is None else self.ocp.fixed_rows.size
        call = call_ipopt(solver, self.ocp.nx, ng, **args)
        scen = self.unpack(call.x)["scen"]
        return Solve.of(call, comp=max(sc["comp"] for sc in scen), S=tuple(sc["S"] for sc in scen))

    def _bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Variable bounds, with the profile fixed when :meth:`solve` was asked to."""
        lbx, ubx = self.ocp.lbx.copy(), self.ocp.ubx.copy()
        if self._fixed is not None:
            lbx[self._fixed] = ubx[self._fixed] = self._fixed_x[self._fixed]
        return lbx, ubx

    def _stage_data(self, sigma: float, cross_sigma: float | None = None) -> dict:
        """Bounds of a relaxation stage
        (:meth:`~ocp_crawl.ocp.transcription.GaitOCP.relaxed_ubg`)."""
        ocp = self.ocp
        ubg = ocp.relaxed_ubg(sigma, cross_sigma)
        lbx, ubx = self._bounds()
        data = {"lbx": lbx, "ubx": ubx, "lbg": ocp.lbg, "ubg": ubg}
        if self._fixed is not None:  # the profile-fixed NLP has only the rows fixed_rows
            data.update(lbg=ocp.lbg[ocp.fixed_rows], ubg=ubg[ocp.fixed_rows])
            data["p"] = np.concatenate([self._fixed_x[ocp.slices[f"theta_{j}"]]
                                        for j in range(len(ocp.scen))])
        return data

    def _polish_candidates(self, x: np.ndarray) -> list[dict]:
        """The tightened NLPs tried in turn: the pairs' branches with the ties of the identified
        foot switches fixed, then the pairs' branches alone (the cross products keep the bound
        sigma_min); the second only if it is another NLP (else it would fail the same way), and
        alone where fixing the ties would move a variable of x by more than :data:`TIE_GAP`.  In
        the optimiser's NLP the onset pairs on their branches already fix the ties (the new foot
        slips from a zero margin), so there is usually one; the profile-fixed NLP has no onset rule
        and two where the slipping foot changes."""
        first, second = self._polish_data(x), self._polish_data(x, ties=False)
        if np.array_equal(first["ubx"], second["ubx"]):
            return [first]
        # a tie fixed where the margin is far from zero is none: the switch is the round-off of a
        # pair at zero on both sides (s, c ~ 1e-12) next to the slip of the other foot; fixed,
        # it made the polish infeasible (a four-link max_speed optimum: a margin of 0.39 set to
        # 0, 2000 iterations)
        moved = float(np.max(np.where(first["ubx"] < second["ubx"], x - first["ubx"], 0.0)))
        return [second] if moved > TIE_GAP else [first, second]

    def _polish_data(self, x: np.ndarray, ties: bool = True) -> dict:
        """The tightened NLP from x: each pair on its identified branch
        (:meth:`~ocp_crawl.ocp.transcription.GaitOCP.branch_ubx`), the cross products at
        sigma_min."""
        data = self._stage_data(0.0, cross_sigma=self.settings.sigma_min)
        ubx = self.ocp.branch_ubx(x, data["ubx"], ties, onset=self._fixed is None)
        return dict(data, ubx=ubx, x0=np.minimum(x, ubx))

    def _homotopy(self, hom: Homotopy, x0: np.ndarray, sigma0: float,
                  endgame: Endgame | None = None) -> tuple[np.ndarray | None, str | None, str]:
        """One relaxation homotopy from x0, then the polish (kept only if IPOPT accepts it and it
        does not raise the complementarity residual; after a failed stage, only if it is within
        comp_tol; none when the last stage is within comp_tol already): (x or None, failed stage or
        None, status).  With ``loose_last`` (and loose stages) the last stage is loose too; if the
        polish from it fails, that stage is solved again tightly and polished once more.  With an
        ``endgame`` whose sigma is a stage, the stages down to it, then the endgame and (or) the
        rest of the homotopy as the endgame decides
        (:meth:`~ocp_crawl.ocp.endgame.Endgame.race`)."""
        s = self.settings
        sigmas = schedule(sigma0, s.sigma_factor, s.sigma_min)
        head = endgame.head(sigmas) if endgame is not None else ()
        loose_last = s.loose_last and self._fixed is None
        if not head:
            return self._finish(hom, hom.relax(sigmas, Start(x0), self._stage_data,
                                               loose_last=loose_last), sigmas)
        run = hom.relax(head, Start(x0), self._stage_data, loose_last=True)
        if not run.ok:
            run.stages = len(sigmas)
            return self._finish(hom, run, sigmas)
        last = run.last
        assert endgame is not None and last is not None  # a head, each of its stages accepted

        def rest() -> tuple:  # the homotopy from the endgame's stage on
            tail = hom.relax(sigmas[len(head):], last.start(), self._stage_data,
                             loose_last=loose_last)
            tail.last = tail.last or last
            tail.stage, tail.stages = tail.stage + len(head), len(sigmas)
            return self._finish(hom, tail, sigmas)
        return endgame.race(last.x, hom.records, rest)

    def _finish(self, hom: Homotopy, run, sigmas: tuple) -> tuple[np.ndarray | None, str | None,
                                                                  str]:
        """The end of a homotopy's ``run`` along ``sigmas``: the polish, or the failure (see
        :meth:`_homotopy`)."""
        s = self.settings
        loose_last = run.loose_last
        if not run.ok:
            if run.last is not None:
                # a later stage failed (degenerate pairs, e.g. a foot resting at its friction limit
                # without slipping): the polish from the last accepted stage, kept only if
                # complementary
                pol = hom.polish(run.last, self._polish_candidates(run.last.x),
                                 lambda p: p.comp <= s.comp_tol)
                if pol is not None:
                    return pol.x, None, pol.status
            x = run.last.x if run.last is not None else None
            return (x, f"homotopy stage {run.stage + 1}/{run.stages} (sigma = {run.sigma:.1e})",
                    run.failed.status)
        sol = run.last
        if sol.comp <= s.comp_tol and not loose_last and self._fixed is None:
            # a tight point complementary to comp_tol: no polish needed
            return sol.x, None, sol.status
        pol = hom.polish(sol, self._polish_candidates(sol.x), lambda p: p.comp <= sol.comp)
        if pol is None and loose_last:
            tight = hom.tighten(sol, sigmas[-1], self._stage_data(sigmas[-1]))
            if tight.accepted:
                sol = tight
                pol = hom.polish(sol, self._polish_candidates(sol.x), lambda p: p.comp <= sol.comp)
        return (pol.x, None, pol.status) if pol is not None else (sol.x, None, sol.status)
