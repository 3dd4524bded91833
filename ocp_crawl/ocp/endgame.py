"""The endgame of the relaxation homotopy: from a relaxed stage, the simulated profile's own
branches.

A relaxed stage's profile (torques and period) is already a gait: simulated in every friction
scenario it gives a complementary point of the transcription whose branches (which foot slips in
each sub-step) are those of the real gait
(:meth:`~ocp_crawl.ocp.transcription.GaitOCP.initial_guess`).  The tightened NLP on those branches
(:meth:`~ocp_crawl.ocp.solver.GaitSolver.solve_tightened`) is then solved at once, with an
iteration cap, instead of the remaining stages at ever smaller sigma.  Its point is kept only when
the caller's judge accepts it (its replay) and it is at least as good as the stage's profile by
replay; otherwise the homotopy goes on from the stage's point, as without an endgame.  Or both
paths run, the endgame here and the rest of the homotopy in a forked process, and the better by
replay is kept.  The path decides which local optimum is reached (:class:`Endgame` says which was
taken, and against what).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ocp_crawl.nlp.homotopy import observed_elsewhere
from ocp_crawl.workers import overlap

#: a stage's sigma at most this far (relative) from the endgame's counts as it (round-off)
SIGMA_RTOL = 1e-6


@dataclass
class Endgame:
    """The endgame after the homotopy's stage at ``sigma`` (see the module docstring).

    ``guess(x_stage)``: the complementary point of the stage's simulated profile, or None when a
    simulation fails; ``solve(x_sim, max_iter)``: the tightened NLP on its branches, (x, records,
    failed, status) as :meth:`~ocp_crawl.ocp.solver.GaitSolver.solve_tightened`;
    ``keep(x, x_ref, against)``: whether the endgame's point x is kept over the point x_ref, named
    ``against`` (the caller's judge: x accepted by replay and at least as good as x_ref's profile by
    replay), with the comparison in words.  ``both``: the endgame and the rest of the homotopy both
    run, in parallel where a process can be forked, and the better by replay is kept (False: the
    endgame first, the rest of the homotopy only when it is not kept)."""

    sigma: float
    max_iter: int
    guess: Callable[[np.ndarray], np.ndarray | None]
    solve: Callable[[np.ndarray, int], tuple]
    keep: Callable[[np.ndarray, np.ndarray, str], tuple[bool, str]]
    both: bool = False
    outcome: list[str] = field(default_factory=list)
    """what each endgame did, in words (kept, or why not)"""

    def head(self, sigmas: tuple[float, ...]) -> tuple[float, ...]:
        """The stages of ``sigmas`` up to the endgame's sigma; () when it is not one of them before
        the last (then the homotopy runs whole)."""
        for k, sigma in enumerate(sigmas[:-1]):
            if abs(sigma - self.sigma) <= SIGMA_RTOL * self.sigma:
                return sigmas[:k + 1]
        return ()

    def race(self, x_stage: np.ndarray, records: list, rest: Callable[[], tuple]) -> tuple:
        """The outcome (x, failed, status) after the endgame's stage, whose point is ``x_stage``:
        the endgame's point when kept, else ``rest()`` (the homotopy from the stage on).  IPOPT
        calls are added to ``records`` (the endgame's first)."""
        if not self.both:
            kept = self(x_stage, records)
            return kept if kept is not None else rest()

        def homotopy() -> tuple:
            n0 = len(records)
            return rest(), records[n0:]
        task, forward = observed_elsewhere(homotopy)
        n_stage = len(records)
        (out, tail), ended = overlap(task, lambda: self._solve(x_stage, []), forward)
        # (where no process could be forked the homotopy ran here, after the endgame, into records)
        records[:] = [*records[:n_stage], *ended[1], *tail]
        x_ref = out[0] if out[1] is None and out[0] is not None else x_stage
        kept = self._verdict(ended, x_ref, "the homotopy's optimum" if x_ref is not x_stage
                             else "the stage profile")
        return kept if kept is not None else out

    def __call__(self, x_stage: np.ndarray, records: list) -> tuple | None:
        """The endgame from the stage's point: (x, None, status) when kept over the stage's own
        profile, else None.  Its IPOPT calls are added to ``records``."""
        return self._verdict(self._solve(x_stage, records), x_stage, "the stage profile")

    def _solve(self, x_stage: np.ndarray, records: list) -> tuple:
        """(x or None, the endgame's IPOPT records, failed or None, status); the records also added
        to ``records``."""
        x_sim = self.guess(x_stage)
        if x_sim is None:
            return None, [], "the stage's profile fails in the simulator", ""
        x, hist, failed, status = self.solve(x_sim, self.max_iter)
        records.extend(hist)
        return x, hist, failed, status

    def _verdict(self, ended: tuple, x_ref: np.ndarray, against: str) -> tuple | None:
        """(x, None, status) when the endgame's point is kept over ``x_ref`` (named ``against``),
        else None; the outcome in words either way."""
        x, hist, failed, status = ended
        head = f"endgame after sigma = {self.sigma:.0e}"
        iterations = sum(stage.iterations for stage in hist)
        if failed is not None or x is None:
            self.outcome.append(f"{head} not kept: {failed} ({iterations} IPOPT iterations)")
            return None
        kept, why = self.keep(x, x_ref, against)
        verdict = "kept" if kept else "not kept"
        self.outcome.append(f"{head} {verdict} ({iterations} IPOPT iterations: {why})")
        return (x, None, status) if kept else None
