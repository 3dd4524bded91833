"""The outcome of the periodic-gait OCP: :class:`OCPResult` (the optimal profile, its residuals, its
replay, its baselines and gains, every start) and :class:`StartRecord` (one start of the
multi-start)."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from ocp_crawl.io.files import jsonable
from ocp_crawl.ocp.baseline import Baselines, WaveChoice
from ocp_crawl.ocp.chain_search import ChainWaveChoice
from ocp_crawl.ocp.judge import scenario_labels
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.status import Status


@dataclass
class StartRecord:
    """One start of the multi-start OCP and what became of it."""

    label: str
    """which start: 'harmonic baseline', 'second harmonic', 'perturbed i', 'given start', or a
    family's best member solved by the tightened NLP, 'SHAPE baseline, tightened'"""
    status: Status
    T_start: float
    """the start's period [s]"""
    value_ocp: float = float("nan")
    value_replay: float = float("nan")
    message: str = ""
    iterations: int = 0
    """IPOPT iterations of the start's homotopies (or of its tightened NLP)"""

    @property
    def converged(self) -> bool:
        """The OCP converged from this start and its optimum was replayed (judged or not)."""
        return math.isfinite(self.value_replay) and self.status in (Status.SUCCESS,
                                                                    Status.REPLAY_MISMATCH,
                                                                     Status.WORSE_THAN_BASELINE)

    def to_dict(self) -> dict:
        """JSON-able (the status as its lower-case label)."""
        return jsonable(dict(asdict(self), status=self.status.label, converged=self.converged))


@dataclass
class OCPResult:
    """Outcome of :func:`optimize_gait`: the optimal profile, its residuals, the harmonic baseline,
    the replay that judges it (per scenario lists: one entry without a friction set) and the
    starts."""

    success: bool
    status: Status
    """the result's :class:`~ocp_crawl.status.Status` (written as its lower-case label in JSON)"""
    message: str
    objective: str
    settings: OCPSettings
    phase: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tau: np.ndarray = field(default_factory=lambda: np.zeros((2, 0)))
    """optimal torques [N m] at the node phases (m, N), a row per joint"""
    phi: list = field(default_factory=list)
    """per scenario: angles (m, N+1) [rad] at phases k/N, k = 0..N"""
    x1: list = field(default_factory=list)
    f_t: list = field(default_factory=list)
    modes: list = field(default_factory=list)
    S_ocp: list = field(default_factory=list)
    T_ocp: float = float("nan")
    """period of the optimal gait [s]"""
    v_ocp: list = field(default_factory=list)
    """per scenario: mean speed direction * S / T [m/s]"""
    theta: list = field(default_factory=list)
    """per scenario: the interior points of the intervals (N,) [fraction of the interval]"""
    W_plus_ocp: list = field(default_factory=list)
    CoT_plus_ocp: list = field(default_factory=list)
    value_ocp: float = float("nan")
    """the OCP's objective value (max_speed, robust_speed: a speed [m/s]; min_cot: CoT+ [-])"""
    complementarity_residual: float = float("nan")
    periodicity_residual: float = float("nan")
    equation_residual: float = float("nan")
    homotopy: list = field(default_factory=list)
    """:class:`~ocp_crawl.nlp.homotopy.Stage` records of every IPOPT call (of the reported start)"""
    failed_stage: str | None = None
    path: str = ""
    """with ``endgame_sigma``: what the endgame did (kept, or why not and the homotopy went on)"""
    solve_time_s: float = float("nan")
    harmonic: WaveChoice | ChainWaveChoice | None = None
    """the best harmonic gait of the family (a chain's: its best harmonic travelling wave): the
    first start"""
    baselines: Baselines | None = None
    """the best member of each waveform family searched (``settings.baseline_shapes``)"""
    replay: list = field(default_factory=list)
    """per scenario: CrawlResult of the event-driven replay"""
    S_replay: list = field(default_factory=list)
    v_replay: list = field(default_factory=list)
    """per scenario: replayed mean speed direction * S / T [m/s]"""
    W_plus_replay: list = field(default_factory=list)
    CoT_plus_replay: list = field(default_factory=list)
    value_replay: float = float("nan")
    rel_diff_replay: float = float("nan")
    envelope_excess: float = float("nan")
    """largest excursion of the torques beyond the envelope, relative to its half-width (<= 0:
    inside)"""
    rate_ratio: float = float("nan")
    """largest torque rate of the replayed profile over the bandwidth k R (<= 1: within)"""
    accel_ratio: float = float("nan")
    """largest second difference over the bound of max_accel_deg_s2 (<= 1: within; NaN: no such
    bound)"""
    peak_joint_rate_deg_s: list = field(default_factory=list)
    """per scenario: the replay's peak actual joint rates |d phi_i/dt| of each joint [deg/s]
    (:mod:`~ocp_crawl.ocp.rates`)"""
    peak_slip_speed_m_s: list = field(default_factory=list)
    """per scenario: the replay's peak sliding speeds |d x_i/dt| of feet 1, 2 [m/s]"""
    joint_rate_ratio: float = float("nan")
    """the replay's peak joint rate over max_joint_rate_deg_s (<= 1: within; NaN: no such bound)"""
    requirements: list = field(default_factory=list)
    """per requirement (min_cot's speed, each ``constraints`` bound): its ``text`` and table
    (``constraint``) and the ``replay``'s values (one per scenario, or one)"""
    harmonic_peak_joint_rate_deg_s: list = field(default_factory=list)
    """per scenario: the harmonic baseline's peak joint rates [deg/s] (its own replay; empty if not
    measured)"""
    harmonic_peak_slip_speed_m_s: list = field(default_factory=list)
    """per scenario: the harmonic baseline's peak foot sliding speeds [m/s]"""
    gain: float = float("nan")
    """relative gain by replay over the best baseline of every family searched (positive: better)"""
    gains: dict = field(default_factory=dict)
    """relative gain by replay over each family's best member, by shape (NaN: none, or
    infeasible)"""
    baseline_at_nodes: dict | None = None
    """where another family's best member beats the optimum: that member sampled at the N nodes
    (``shape``, ``nodes``, ``value`` [the objective's unit];
    :func:`~ocp_crawl.ocp.sampling.best_sampling`)"""
    starts: list = field(default_factory=list)
    """:class:`StartRecord` of every start of the multi-start (the reported one among them)"""
    dynamic_margin: dict | None = None
    """with ``[ocp] dynamic_margin``: the MuJoCo check (:mod:`ocp_crawl.ocp.dynamic_margin`)"""
    friction_asymmetry: dict | None = None
    """of a confirmed optimum: its S replayed in each scenario at mu1/mu2 moved by -+
    :data:`~ocp_crawl.ocp.asymmetry.ASYMMETRY` and the largest relative change
    (:func:`~ocp_crawl.ocp.asymmetry.friction_asymmetry`)"""

    @property
    def gain_significant(self) -> bool:
        """Whether the gain exceeds the replay tolerance (|gain| > replay_tol)."""
        return math.isfinite(self.gain) and abs(self.gain) > self.settings.replay_tol

    def _best_baseline(self) -> dict | None:
        best = self.baselines.best if self.baselines else self.harmonic
        return {"shape": best.shape, "value": best.value,
                "feasible": best.feasible} if best else None

    @property
    def spread(self) -> tuple[float, float, int]:
        """(min, max) of the replayed objective over the converged starts and how many converged
        (NaNs if none)."""
        values = [s.value_replay for s in self.starts if s.converged]
        return (min(values), max(values), len(values)) if values else (float("nan"), float("nan"),
                                                                       0)

    def summary(self) -> dict:
        """The result as strict JSON types (non-finite numbers None; the status as its lower-case
        label)."""
        one = len(self.S_ocp) == 1

        def per_scenario(values):
            return (values[0] if one else values) if values else None

        low, high, converged = self.spread
        return jsonable({
            "status": self.status.label, "success": bool(self.success), "message": self.message,
            "objective": self.objective, "objective_unit": self.settings.objective_unit,
            "nodes": self.settings.nodes,
            "parametrization": self.settings.parametrization,
            "S_ocp": per_scenario(self.S_ocp), "S_replay": per_scenario(self.S_replay),
            "T_ocp": self.T_ocp, "v_ocp": per_scenario(self.v_ocp),
            "v_replay": per_scenario(self.v_replay),
            "W_plus_ocp": self.W_plus_ocp, "W_plus_replay": self.W_plus_replay,
            "CoT_plus_ocp": self.CoT_plus_ocp,
            "CoT_plus_replay": per_scenario(self.CoT_plus_replay),
            "objective_value_ocp": self.value_ocp, "objective_value_replay": self.value_replay,
            "rel_diff_replay": self.rel_diff_replay, "replay_tol": self.settings.replay_tol,
            "envelope_excess": self.envelope_excess, "rate_ratio": self.rate_ratio,
            "accel_ratio": self.accel_ratio,
            "peak_joint_rate_deg_s": per_scenario(self.peak_joint_rate_deg_s),
            "peak_slip_speed_m_s": per_scenario(self.peak_slip_speed_m_s),
            "max_joint_rate_deg_s": self.settings.max_joint_rate_deg_s,
            "joint_rate_ratio": self.joint_rate_ratio, "requirements": self.requirements,
            "harmonic_peak_joint_rate_deg_s": per_scenario(self.harmonic_peak_joint_rate_deg_s),
            "harmonic_peak_slip_speed_m_s": per_scenario(self.harmonic_peak_slip_speed_m_s),
            "best_harmonic": self.harmonic.to_dict() if self.harmonic else None,
            "baselines": self.baselines.table() if self.baselines else None,
            "best_baseline": self._best_baseline(),
            "gain": self.gain, "gain_significant": self.gain_significant, "gains": self.gains,
            "best_baseline_at_nodes": self.baseline_at_nodes,
            "starts": [s.to_dict() for s in self.starts], "starts_converged": converged,
            "endgame": self.path or None,
            "objective_value_replay_min": low, "objective_value_replay_max": high,
            "solve_time_s": self.solve_time_s, "dynamic_margin": self.dynamic_margin,
            "friction_asymmetry": self.friction_asymmetry,
            "complementarity_residual": self.complementarity_residual,
            "periodicity_residual": self.periodicity_residual,
            "equation_residual": self.equation_residual, "failed_stage": self.failed_stage,
            "homotopy": [asdict(h) for h in self.homotopy], "scenarios": self.scenarios(),
        })

    def scenarios(self) -> list[dict] | None:
        """Over a friction set: per scenario, in the order of the per-scenario lists, its ratio
        ``mu1_mu2``, its friction ``level``, its ``label``
        (:func:`~ocp_crawl.ocp.judge.scenario_labels`) and its values (S, speed, W+, CoT+ of the OCP
        and the replay; None where not computed); None without a set (one scenario, the robot's)."""
        if not self.settings.friction_set:
            return None
        pairs = self.settings.scenario_pairs()
        names = ("S_ocp", "S_replay", "v_ocp", "v_replay", "W_plus_ocp", "W_plus_replay",
                 "CoT_plus_ocp", "CoT_plus_replay")
        lists = [getattr(self, name) for name in names]
        return jsonable([{"mu1_mu2": r, "level": level, "label": label,
                          **{n: values[j] if j < len(values)
                             else None for n, values in zip(names, lists)}}
                         for j, ((level, r),
                                 label) in enumerate(zip(pairs, scenario_labels(self.settings)))])
