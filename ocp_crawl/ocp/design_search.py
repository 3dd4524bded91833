"""The local search of the co-design NLP after its homotopy (:class:`DesignSearch`): the
optimum's own branches, then its neighbouring designs.

The co-design NLP is an MPCC: each local optimum holds on its branches (which foot slips in which
sub-step), and the homotopy's polish fixes those its relaxed point identifies.  Two moves look
beyond them, each kept only when it improves the objective:

- **the simulated branches**: the optimum's profile simulated on the design it chose starts the
  fixed robot's NLP on the branches of the simulation; that point, with the design free again,
  starts the co-design NLP on those branches (the paper robot, stiffness pair, N = 20: 88.45 mm/s
  after the homotopy, 89.77 mm/s on the simulated branches);
- **the neighbouring designs**: each design variable moved by a factor 1 -+ :data:`PROBE_STEP`
  (within its bounds), the fixed robot's NLP solved there by the homotopy from the optimum's
  profile (its reference angles kept: each joint's torque scaled with its stiffness); the best
  neighbour better than the optimum starts the co-design NLP on its branches (the same robot,
  N = 20: the optimum at 89.77 mm/s, the fixed robot with k1 1.3 times larger at 89.91 mm/s).

Both repeat until neither improves (at most ``rounds``, default :data:`ROUNDS`); every probe is
recorded.
"""
from __future__ import annotations

import numpy as np

from ocp_crawl.model.chain import Chain
from ocp_crawl.ocp.judge import replay_signal
from ocp_crawl.ocp.quantities import minimises
from ocp_crawl.ocp.result import OCPResult
from ocp_crawl.ocp.solve import fill_solution
from ocp_crawl.ocp.solver import GaitSolver
from ocp_crawl.ocp.transcription import GaitOCP
from ocp_crawl.status import Status

#: rounds of the local search at most, by default
ROUNDS = 4
#: the relative improvement of the objective that keeps a move
GAIN = 1e-6
#: the relative move of a design variable to each of its neighbours
PROBE_STEP = 0.25


def nlp_value(solver: GaitSolver, x: np.ndarray) -> float:
    """The objective's value at the NLP point x (a speed [m/s] or CoT+ [-], without the
    regularisation)."""
    trial = OCPResult(False, Status.SOLVER_FAILURE, "", solver.settings.objective,
                      solver.settings)
    fill_solution(trial, solver, x)
    return trial.value_ocp


class DesignSearch:
    """The local search of the co-design NLP of ``solver`` (its design's variables free), for the
    chain ``chain`` whose totals the designs keep, in at most ``rounds`` rounds (0: none)."""

    def __init__(self, solver: GaitSolver, chain: Chain, rounds: int = ROUNDS):
        self.solver, self.chain, self.rounds = solver, chain, int(rounds)
        self.ocp = ocp = solver.ocp
        assert ocp.design is not None and isinstance(ocp.robot, Chain)
        self.design = ocp.design
        self.scale = ocp.design.initial(ocp.robot)
        self.stiffness = np.asarray(ocp.robot.stiffness, float)
        """the joint stiffnesses of the co-design NLP's robot [N m/rad]"""
        self.low, self.high = ocp.design.limits()
        self.phase = np.arange(solver.settings.nodes) / solver.settings.nodes
        self.iterations = 0
        """IPOPT iterations of the search"""
        self.probes: list[dict] = []
        """every neighbouring design probed: its ``values`` (SI units), its fixed robot's optimum
        ``value`` (NaN: none) and whether it was ``kept``"""

    def run(self, x: np.ndarray) -> np.ndarray:
        """The search from the co-design NLP's point x; the best point found."""
        for _ in range(self.rounds):
            x = self.simulated_branches(x)
            better = self.neighbours(x)
            if better is None:
                break
            x = better
        return x

    def _better(self, x_new, x) -> bool:
        ocp = self.ocp
        return (x_new is not None
                and max(sc["comp"] for sc in ocp.unpack(x_new)["scen"])
                <= self.solver.settings.comp_tol
                and ocp.objective(x_new) < ocp.objective(x) - GAIN * abs(ocp.objective(x)))

    def fixed_solver(self, values: np.ndarray) -> GaitSolver:
        """The solver of the fixed robot at the design ``values`` (SI units): the co-design NLP
        with the design fixed there (the same objective: its torque rates weighed as the
        co-design NLP weighs them)."""
        robot = self.design.chain_of(self.chain, values)
        weights = self.stiffness / np.asarray(robot.stiffness)
        return GaitSolver(GaitOCP(robot, self.ocp.gravity, self.solver.settings,
                                  rate_weights=weights, stability=self.ocp.stability))

    def _lift(self, fixed: GaitSolver, x_f: np.ndarray, values: np.ndarray) -> np.ndarray:
        """The fixed robot's point x_f as a point of the co-design NLP at the design ``values``."""
        lifted = np.zeros(self.ocp.nx)
        for name, sl in fixed.ocp.slices.items():
            if not name.startswith("g_"):
                lifted[self.ocp.slices[name]] = x_f[sl]
        lifted[self.ocp.slices["design"]] = values / self.scale
        return lifted

    def _guess(self, fixed: GaitSolver, tau: np.ndarray, T: float) -> np.ndarray | None:
        """The fixed robot's NLP point of the torques ``tau`` (m, N) [N m] of period T [s] simulated
        in every scenario, or None where a simulation fails."""
        signal = replay_signal(self.phase, tau)
        if not all(plant.simulate(signal).success for plant in fixed.ocp.scen):
            return None
        return fixed.ocp.initial_guess(signal, T)

    def _tightened(self, x0: np.ndarray) -> np.ndarray | None:
        x, hist, failed, _ = self.solver.solve_tightened(x0)
        self.iterations += sum(r.iterations for r in hist)
        return None if failed is not None else x

    def simulated_branches(self, x: np.ndarray) -> np.ndarray:
        """Rounds of the simulated branches (see the module docstring) while they improve."""
        for _ in range(self.rounds):
            values = self.ocp.design_values(x)
            fixed = self.fixed_solver(values)
            u = self.ocp.unpack(x)
            guess = self._guess(fixed, u["tau"], u["T"])
            if guess is None:
                break   # the profile does not simulate on its design: keep x
            x_f, hist, failed, _ = fixed.solve_tightened(guess)
            self.iterations += sum(r.iterations for r in hist)
            if x_f is None or failed is not None:
                break
            x_c = self._tightened(self._lift(fixed, x_f, values))
            if x_c is None or not self._better(x_c, x):
                break
            x = x_c
        return x

    def neighbours(self, x: np.ndarray) -> np.ndarray | None:
        """The co-design NLP's point on the branches of the best neighbouring design's fixed
        optimum, when it improves on x; else None."""
        values = self.ocp.design_values(x)
        u = self.ocp.unpack(x)
        m = self.chain.n_joints if self.design.stiffness else 0
        value = nlp_value(self.solver, x)
        best = None
        for i in range(values.size):
            for sign in (-1.0, 1.0):
                trial = self._neighbour(values, i, sign)
                if trial is None:
                    continue
                tau = u["tau"] * (trial[:m] / values[:m])[:, None] if m else u["tau"]
                found = self._probe(trial, tau, u["T"])
                if found is not None and (best is None or found[0] < best[0]):
                    best = found
        if best is None:
            return None
        key, fixed, x_f, trial, record = best
        if not key < self._key(value):
            return None
        x_c = self._tightened(self._lift(fixed, x_f, trial))
        if not self._better(x_c, x):
            return None
        record["kept"] = True
        return x_c

    def _neighbour(self, values: np.ndarray, i: int, sign: float) -> np.ndarray | None:
        """``values`` with variable i moved by a factor 1 + sign PROBE_STEP into its bounds (a
        link length: all lengths then scaled back to the total length), or None where that is no
        other design inside the bounds."""
        trial = values.copy()
        trial[i] = np.clip(values[i] * (1.0 + sign * PROBE_STEP), self.low[i], self.high[i])
        m = self.chain.n_joints if self.design.stiffness else 0
        if self.design.lengths and i >= m:
            lengths = trial[m:]
            trial[m:] = lengths * self.chain.L / lengths.sum()
        if (np.any(trial < self.low * (1 - GAIN)) or np.any(trial > self.high * (1 + GAIN))
                or np.all(np.abs(trial - values) <= GAIN * values)):
            return None
        return trial

    def _key(self, value: float) -> float:
        """A value to minimise: the objective's value, negated where it is maximised."""
        return value if minimises(self.solver.settings.objective) else -value

    def _probe(self, values: np.ndarray, tau: np.ndarray, T: float) -> tuple | None:
        """The fixed robot's optimum at the design ``values`` from the torques ``tau`` (m, N) of
        period T [s] by the homotopy: (key, solver, x, values, record), or None; recorded in
        :attr:`probes`."""
        fixed = self.fixed_solver(values)
        record = {"values": [float(v) for v in values], "value": float("nan"), "kept": False}
        self.probes.append(record)
        x0 = self._guess(fixed, tau, T)
        if x0 is None:
            return None
        x_f, hist, failed, _ = fixed.solve(x0)
        self.iterations += sum(r.iterations for r in hist)
        if (x_f is None or failed is not None
                or max(sc["comp"] for sc in fixed.unpack(x_f)["scen"])
                > self.solver.settings.comp_tol):
            return None
        record["value"] = v = nlp_value(fixed, x_f)
        return self._key(v), fixed, x_f, values, record
