"""The one status vocabulary of the package: simulators, the MPCC steps, the OCP and sweep rows.

Floor 0 (imports nothing of the package).  A result's ``status`` is a :class:`Status`; its
``message`` starts with the status's text from :data:`STATUS_MESSAGES` or says more.  In JSON and
CSV a status is written as its lower-case name (``status.label``), e.g. ``"lift_off"``.
``SUCCESS`` is the only success.
"""
from __future__ import annotations

from enum import IntEnum


class Status(IntEnum):
    """Integer status of a simulation, an optimisation or a sweep row."""

    SUCCESS = 0
    LIFT_OFF = 1
    FEET_CROSSED = 2
    FOLD = 3
    NO_CONVERGENCE = 4
    NOT_PERIODIC = 5
    NO_CONSISTENT_MODE = 6
    TOO_MANY_EVENTS = 7
    SOLVER_FAILURE = 8
    JOINT_ON_GROUND = 9
    NO_START = 10
    UNSTABLE = 15
    SNAP_THROUGH = 16
    ENERGY_IMBALANCE = 17
    SET_VALUED = 23
    COARSE_STEPS = 24
    # the periodic-gait OCP
    INFEASIBLE = 11
    NOT_COMPLEMENTARY = 12
    NO_INITIAL_GUESS = 13
    REPLAY_FAILED = 14
    REPLAY_MISMATCH = 18
    WORSE_THAN_BASELINE = 19
    # sweep rows only: a point whose values break a rule, a point that raised, a point not computed
    # yet
    BAD_INPUT = 20
    ERROR = 21
    MISSING = 22

    @property
    def label(self) -> str:
        """The lower-case name used in JSON, CSV and messages (``"lift_off"``)."""
        return self.name.lower()

    @property
    def text(self) -> str:
        """What the status means, for a user."""
        return STATUS_MESSAGES[self]

    @classmethod
    def from_label(cls, label: str) -> "Status":
        """The status of a lower-case name; ValueError for an unknown one."""
        try:
            return cls[str(label).upper()]
        except KeyError:
            raise ValueError(f"unknown status {label!r}; valid: "
                             f"{', '.join(s.label for s in cls)}") from None


#: what each status means, in words (the message of a result says more)
STATUS_MESSAGES = {
    Status.SUCCESS: "periodic gait found",
    Status.LIFT_OFF: "a foot lifts off (normal force reaches zero): the two-contact model is no "
                     "longer valid",
    Status.FEET_CROSSED: "the feet meet or cross (d reaches zero)",
    Status.FOLD: "loss of equilibrium: the tracked equilibrium branch folds (singular Jacobian); "
                 "the real robot would snap through dynamically",
    Status.NO_CONVERGENCE: "the continuation of the equilibrium did not converge",
    Status.NOT_PERIODIC: "the gait did not become periodic within the maximum number of cycles",
    Status.NO_CONSISTENT_MODE: "no contact mode is consistent after a transition",
    Status.TOO_MANY_EVENTS: "too many events in one cycle (chattering input?)",
    Status.SOLVER_FAILURE: "the step solver failed",
    Status.JOINT_ON_GROUND: "a joint reaches the ground (the leg would enter it): the model with "
                            "contacts at the feet only is no longer valid",
    Status.NO_START: "no equilibrium to start from at t = 0 (the robot cannot stand on both feet "
                     "with both joints above the ground)",
    Status.UNSTABLE: "the equilibrium is unstable (the stiffness of the contact mode is not "
                     "positive definite): the real robot would leave it at once",
    Status.SNAP_THROUGH: "the state jumps across an event while the input is continuous: the robot "
                         "snaps through dynamically, which the quasistatic model cannot follow",
    Status.ENERGY_IMBALANCE: "the energy balance of the steady cycle does not close within the "
                             "tolerance (input work against potential change plus friction "
                             "dissipation)",
    Status.SET_VALUED: "more than one contact mode continues from a tie of the two feet's friction "
                       "limits: the quasistatic model leaves the motion undecided (set-valued); "
                       "mu1 != mu2 breaks the tie",
    Status.COARSE_STEPS: "the time steps are too coarse: the estimate of the discretisation error "
                         "of S (the steady cycle re-run with halved steps) exceeds its bound; "
                         "raise [simulation] steps",
    Status.INFEASIBLE: "the optimal control problem has no feasible point (locally): the "
                       "constraints cannot all be met",
    Status.NOT_COMPLEMENTARY: "the optimiser converged but the complementarity residual exceeds "
                              "the tolerance",
    Status.NO_INITIAL_GUESS: "no initial guess: the harmonic gait used to start the optimiser "
                             "failed",
    Status.REPLAY_FAILED: "the optimal profile failed when replayed in the event-driven simulator",
    Status.REPLAY_MISMATCH: "the event-driven replay of the optimal profile does not confirm the "
                            "optimiser: it misses a constraint (speed requirement, envelope, "
                            "bandwidth) or disagrees with the OCP's objective beyond the tolerance",
    Status.WORSE_THAN_BASELINE: "the optimiser's profile, confirmed by its replay, is worse than "
                                "the harmonic baseline it started from (beyond the replay "
                                "tolerance): a local optimum of the solver's path, not an "
                                "improvement; the baseline is the better gait",
    Status.BAD_INPUT: "the point's values break a rule of the problem schema",
    Status.ERROR: "an unexpected exception while computing the point (a bug: please report it)",
    Status.MISSING: "the point has not been computed",
}
