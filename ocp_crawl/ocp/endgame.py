"""The endgame of the relaxation homotopy: from a relaxed stage, the simulated profile's own branches.

A relaxed stage's profile (torques and period) is already a gait: simulated in every friction scenario
it gives a complementary point of the transcription whose branches (which foot slips in each sub-step)
are those of the real gait (:meth:`~ocp_crawl.ocp.transcription.GaitOCP.initial_guess`).  The tightened NLP
on those branches (:meth:`~ocp_crawl.ocp.transcription.GaitOCP.solve_tightened`) is then solved at once,
with an iteration cap, instead of the remaining stages at ever smaller sigma.  Its point is kept only when
the caller's judge accepts it (its replay) and it is at least as good as the stage's profile by replay;
otherwise the homotopy goes on from the stage's point, as without an endgame.  The stage decides which
local optimum the endgame reaches: the result depends on the path (:class:`Endgame` says which was taken).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

#: a stage's sigma at most this far (relative) from the endgame's counts as it (a schedule's round-off)
SIGMA_RTOL = 1e-6


@dataclass
class Endgame:
    """The endgame after the homotopy's stage at ``sigma`` (see the module docstring).

    ``keep(x, x_stage)``: whether the endgame's point x is kept over the stage's point x_stage (the
    caller's judge: x accepted by replay and at least as good as the stage's profile by replay), with a
    message saying why not; ``guess(x_stage)``: the complementary point of the stage's simulated profile,
    or None when a simulation fails; ``solve(x_sim, max_iter)``: the tightened NLP on its branches,
    (x, records, failed, status) as :meth:`~ocp_crawl.ocp.transcription.GaitOCP.solve_tightened`."""

    sigma: float
    max_iter: int
    guess: Callable[[np.ndarray], np.ndarray | None]
    solve: Callable[[np.ndarray, int], tuple]
    keep: Callable[[np.ndarray, np.ndarray], tuple[bool, str]]
    outcome: list[str] = field(default_factory=list)
    """what each endgame did, in words (kept, or why not)"""

    def head(self, sigmas: tuple[float, ...]) -> tuple[float, ...]:
        """The stages of ``sigmas`` up to the endgame's sigma; () when it is not one of them before the last
        (then the homotopy runs whole)."""
        for k, sigma in enumerate(sigmas[:-1]):
            if abs(sigma - self.sigma) <= SIGMA_RTOL * self.sigma:
                return sigmas[:k + 1]
        return ()

    def __call__(self, x_stage: np.ndarray, records: list) -> tuple | None:
        """The endgame from the stage's point: (x, None, status) when kept, else None.  Its IPOPT calls
        are added to ``records``."""
        x_sim = self.guess(x_stage)
        if x_sim is None:
            self.outcome.append(f"endgame after sigma = {self.sigma:.0e} not run: the stage's profile fails "
                                "in the simulator")
            return None
        x, hist, failed, status = self.solve(x_sim, self.max_iter)
        records.extend(hist)
        iterations = sum(stage.iterations for stage in hist)
        if failed is not None or x is None:
            self.outcome.append(f"endgame after sigma = {self.sigma:.0e} not kept: {failed} ({iterations} "
                                "IPOPT iterations); the homotopy went on")
            return None
        kept, why = self.keep(x, x_stage)
        if not kept:
            self.outcome.append(f"endgame after sigma = {self.sigma:.0e} not kept: {why}; the homotopy "
                                "went on")
            return None
        self.outcome.append(f"endgame after sigma = {self.sigma:.0e} kept ({iterations} IPOPT iterations, "
                            f"{why})")
        return x, None, status
