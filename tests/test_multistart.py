"""Multi-start: the starts lie in the envelope and the bandwidth, are reproducible, and the reported
optimum is the best start by replay among those the judge accepts, with the spread of the others.

The solve itself is replaced by a stand-in (the "optimum" of a start is the start itself, its S
computed by the other simulator, the MPCC time-stepping) so that these checks of the orchestration
run in seconds; the transcription's own tests solve the real NLP.
"""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from ocp_crawl import Model, Robot
from ocp_crawl.model.inputs import Harmonic, ReferenceTorque
from ocp_crawl.model.sampled import PeriodicLinear
from ocp_crawl.ocp import solve
from ocp_crawl.ocp.baseline import Baselines
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.ocp.starts import start_guesses
from ocp_crawl.sim import simulate
from ocp_crawl.sim.timestepping import TimeSteppingOptions
from ocp_crawl.status import Status

ROBOT = Robot.paper()
N = 40


def baseline(settings):
    """The envelope's full harmonic gait at its shortest period (peak rate = the bandwidth)."""
    gait = Harmonic.from_degrees(settings.gamma_deg, settings.A_max_deg, 45.0)
    return ReferenceTorque(gait, ROBOT.k), settings.min_period(settings.A_max_deg,
                                                               settings.A_max_deg)


def test_starts_are_in_the_envelope_and_the_bandwidth_and_reproducible():
    st = OCPSettings(starts=6, nodes=N)
    signal, T = baseline(st)
    base = signal(np.arange(N) / N)
    guesses = start_guesses(st, ROBOT, base, T)
    assert [g.label for g in guesses] == ["harmonic baseline",
                                          "second harmonic"] + [f"perturbed {i}" for i in
                                                                                      range(1, 5)]
    # the baseline's nodes, shifted so that node 0 is tau_1's largest (the phase pin): the same
    # samples
    shift = int(np.argmax(base[0]))
    assert guesses[0].T == T and np.array_equal(guesses[0].tau,
                                                np.roll(base, -shift, axis=1)) and shift > 0
    lo, hi = st.torque_bounds(ROBOT)
    rate = ROBOT.k * math.radians(st.max_rate_deg_s)  # k R [N m/s]
    for g in guesses:
        assert np.all(g.tau >= lo) and np.all(g.tau <= hi), g.label
        steepest = np.max(np.abs(np.diff(np.c_[g.tau, g.tau[:, :1]], axis=1))) * N / g.T
        assert steepest <= rate * (1 + 1e-12), g.label
        assert g.T >= T
        assert g.tau[0, 0] == np.max(g.tau[0]), g.label
    # the starts differ from the baseline and from each other; the same settings give the same
    # starts
    for a, b in zip(guesses, guesses[1:]):
        assert np.max(np.abs(a.tau - b.tau)) > 1e-3 * (hi - lo)
    again = start_guesses(st, ROBOT, base, T)
    assert all(np.array_equal(a.tau, b.tau) and a.T == b.T for a, b in zip(guesses, again))
    assert len(start_guesses(OCPSettings(starts=1, nodes=N), ROBOT, base, T)) == 1


def test_a_start_the_simulator_does_not_follow_is_drawn_again_smaller():
    from ocp_crawl.ocp.starts import ATTEMPTS, perturbed_start, pinned, second_harmonic_start

    st = OCPSettings(starts=3, nodes=N)
    signal, T = baseline(st)
    base = signal(np.arange(N) / N)
    calls = []

    def follows(tau):  # refuses the first two draws of every start
        calls.append(tau)
        return len(calls) % 3 == 0
    guesses = start_guesses(st, ROBOT, base, T, follows)
    assert len(calls) == 6
    assert np.array_equal(guesses[1].tau, second_harmonic_start(st, ROBOT, pinned(base), T, 2).tau)
    assert np.array_equal(guesses[2].tau, perturbed_start(st, ROBOT, pinned(base), T, 1, 2).tau)
    # the third draw is nearer the baseline than the first
    first = perturbed_start(st, ROBOT, pinned(base), T, 1, 0).tau
    assert np.max(np.abs(guesses[2].tau - pinned(base))) < np.max(np.abs(first - pinned(base)))
    # never followed: ATTEMPTS draws, the last kept
    calls.clear()
    never = start_guesses(st, ROBOT, base, T, lambda tau: calls.append(tau) and False)
    assert len(calls) == 2 * ATTEMPTS
    assert np.array_equal(never[2].tau,
                          perturbed_start(st, ROBOT, pinned(base), T, 1, ATTEMPTS - 1).tau)


class StandInOCP:
    """The interfaces of GaitOCP and of its GaitSolver in one (``ocp`` is itself); the "optimum" of
    a start is the start (its node torques and period), its S by the MPCC time-stepping; ``claims``
    scales the claimed S of the i-th solve (a forged claim)."""

    claims = {}

    def __init__(self, robot, gravity, settings):
        self.settings, self.robot = settings, robot
        self.scen = [Model(robot, gravity=gravity)]
        self.n_joints = 2
        self.kept_run, self.calls = [], 0
        self.ocp = self

    def prepare(self):
        pass

    def initial_guess(self, signal, T):
        n = self.settings.nodes
        return {"tau": np.asarray(signal(np.arange(n) / n)).reshape(2, n), "T": T}

    def solve(self, x0, endgame=None):
        self.calls += 1
        return dict(x0, claim=self.claims.get(self.calls, 1.0)), [], None, "Solve_Succeeded"

    def unpack(self, x):
        n = self.settings.nodes
        res = simulate(self.scen[0], PeriodicLinear(np.arange(n) / n, x["tau"]), "mpcc",
                       TimeSteppingOptions(steps=n, s_error_tol=0.0))
        S = res.S * x["claim"]
        sc = {"phi": res.phi, "x1": res.x1, "f_t": res.f_t, "modes": [], "theta": np.full(n, 0.5),
              "S": S,
              "v": self.settings.direction * S / x["T"], "W_plus": res.W_plus, "comp": 0.0,
              "periodic": 0.0}
        return {"tau": x["tau"], "T": x["T"], "scen": [sc]}

    def equation_residual(self, x):
        return 0.0


@pytest.mark.slow
def test_best_start_by_replay_is_reported_with_the_spread(monkeypatch):
    st = OCPSettings(starts=4, nodes=N, direction=-1)
    signal, T = baseline(st)
    harm_S = simulate(Model(ROBOT, gravity="physical"), signal).S
    harm = SimpleNamespace(signal_for=lambda robot, settings: signal, T=T, value=-harm_S / T,
                           shape="harmonic", feasible=True, to_dict=lambda: {"value": -harm_S / T})
    monkeypatch.setattr(solve, "best_baselines",  # (the other families: none simulates)
                        lambda robot, gravity, settings, shapes, **kw: Baselines(
                            settings.objective,
                            {s: harm if s == "harmonic" else None for s in shapes}))
    monkeypatch.setattr(solve, "GaitOCP", StandInOCP)
    monkeypatch.setattr(solve, "GaitSolver", lambda ocp: ocp)
    # the second start solved overclaims by 20 %
    monkeypatch.setattr(StandInOCP, "claims", {2: 1.2})
    res = solve.optimize_gait(ROBOT, "physical", st)
    assert len(res.starts) == 4 and res.starts[0].label == "harmonic baseline"
    statuses = [s.status for s in res.starts]
    # a start whose gait the simulator cannot follow is not solved; the second one solved is forged;
    # a start whose "optimum" (here the start itself) is worse than the baseline beyond replay_tol
    # is not an optimum
    assert set(statuses) <= {Status.SUCCESS, Status.REPLAY_MISMATCH, Status.WORSE_THAN_BASELINE,
                             Status.NO_INITIAL_GUESS}
    solved = [s for s in res.starts if s.status != Status.NO_INITIAL_GUESS]
    # every start followed (redrawn if not)
    assert len(solved) == 4 and solved[1].status == Status.REPLAY_MISMATCH
    assert solved[0].status == Status.SUCCESS  # the baseline itself
    for s in solved[2:]:
        worse = s.value_replay < harm.value - st.replay_tol * abs(harm.value)
        assert s.status == (Status.WORSE_THAN_BASELINE if worse else Status.SUCCESS), s.message
    accepted = [s.value_replay for s in res.starts if s.status == Status.SUCCESS]
    assert res.success and res.value_replay == max(accepted)  # speeds: larger is better
    low, high, converged = res.spread
    assert converged == len(solved) and low == min(s.value_replay for s in solved)
    assert high == max(s.value_replay for s in solved)
    assert f"best of 4 starts ({len(solved)} converged" in res.message
    starts = {s.label: s for s in res.starts}
    # the baseline start replays the harmonic gait's linear interpolant: its speed is the harmonic
    # one to O(1/N^2)
    assert starts["harmonic baseline"].value_replay == pytest.approx(harm.value, rel=5e-3)
    assert res.gain == pytest.approx((res.value_replay - harm.value) / abs(harm.value), rel=1e-12)
    assert res.gain_significant == (abs(res.gain) > st.replay_tol)
    summary = res.summary()
    assert (summary["starts_converged"] == len(solved)
            and summary["gain_significant"] == res.gain_significant)
    assert [s["label"] for s in summary["starts"]][0] == "harmonic baseline"
