"""Is the optimum quasistatic at its own period?  Its dynamic margin, measured in MuJoCo.

The OCP models a quasistatic crawler: its optimum's period T [s] is as short as the bandwidth
``max_rate_deg_s`` lets it be, and nothing in the OCP says that the robot's inertia is still
negligible there.  With ``[ocp] dynamic_margin = c`` (absent: not computed, not required) the
optimum's replay signal (:func:`~ocp_crawl.ocp.judge.replay_signal`, the ``optimal_gait.toml`` of
``optimize --out``) is played in MuJoCo (:func:`~ocp_crawl.sim.dynamic.simulate_mujoco`) at a few
periods, and S of each is compared with the quasistatic replay's S (the friction scenario
nearest mu1/mu2 = 1).  A period is *within* when that run succeeds and
|S_dyn / S_qs - 1| <= :data:`TOLERANCE`.

The rule: the optimum is accepted only when S is within at T / c, i.e. when T is at least c
times the shortest period within 5 %; else ``replay_mismatch``, the gait not quasistatic at its
period (lower ``max_rate_deg_s``: a longer period).  The first run is at T / c and decides; the
next runs locate the shortest period within, T_min: by factors of :data:`SPAN` away from T / c
until a period on the other side is found, then by bisection in log T, at most :data:`MAX_RUNS`
runs in all (stopping when the bracket is narrower than :data:`BRACKET`).  T_min is the shortest
period found within and longer than every period found outside (S is assumed to approach S_qs as
T grows); f_5pct = 1/T_min.  Only the reported optimum is checked (not every start).

Cost: at most 5 MuJoCo runs of 3 to 12 cycles of T / 5e-4 steps each.  Measured: 2.9 s of CPU
for the 5 runs (0.54 to 8.6 s) of a max_speed profile of ``problems/ocp_max_speed.toml`` by the
homotopy (N = 30, ``start_solve = "homotopy"``, T = 0.539 s), about 2 % of its solve; 3 runs of
the paper gait (5, 2.5, 1.25 s) about 2 s.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ocp_crawl.io import units
from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.model.statics import Model
from ocp_crawl.status import Status

#: relative deviation of S from the quasistatic S that still counts as quasistatic [-] (the
#: ``dynamics`` command's default tolerance)
TOLERANCE = 0.05
#: most MuJoCo runs of one check
MAX_RUNS = 5
#: factor [-] between the periods of the search before a bracket is found
SPAN = 2.0
#: the search stops when the bracket's periods differ by less than this factor [-]
BRACKET = 1.2
#: longest period [s] run per MuJoCo time step [s] (MujocoOptions allows 1e6 steps per cycle)
MAX_STEPS = 1e6


@dataclass
class MarginCheck:
    """MuJoCo's S of the optimum at a few periods, the shortest period within :data:`TOLERANCE`."""

    period_s: float
    """the optimum's period T [s]"""
    factor: float
    """``dynamic_margin`` c [-]: S must be within at T / c"""
    S_quasistatic: float
    """the quasistatic replay's S [m]"""
    runs: list = field(default_factory=list)
    """(period [s], S [m] or NaN, status label) of each MuJoCo run, in the order run"""

    def _within(self, run) -> bool:
        return run[2] == "success" and abs(run[1] / self.S_quasistatic - 1) <= TOLERANCE

    @property
    def T_out_s(self) -> float:
        """The longest period run at which S is not within [s] (0 if none)."""
        return max((r[0] for r in self.runs if not self._within(r)), default=0.0)

    @property
    def T_min_s(self) -> float | None:
        """The shortest period run at which S is within, longer than every one not within [s]."""
        out = self.T_out_s
        return min((r[0] for r in self.runs if self._within(r) and r[0] > out), default=None)

    @property
    def ok(self) -> bool:
        """True when S is within at T / c (and at every longer period run)."""
        t_min = self.T_min_s
        return t_min is not None and t_min <= self.period_s / self.factor * (1 + 1e-12)

    def to_dict(self) -> dict:
        """JSON-safe: f_5pct_Hz = 1/T_min_s, T_min_s and T_out_s [s] (None: not found), period_s,
        the factor, the quasistatic S [m], the runs and whether the rule holds."""
        t_min = self.T_min_s
        return {"f_5pct_Hz": None if t_min is None else 1.0 / t_min, "T_min_s": t_min,
                "T_out_s": self.T_out_s or None, "period_s": self.period_s,
                "dynamic_margin": self.factor, "ratio": None if t_min is None else
                self.period_s / t_min, "tolerance": TOLERANCE, "S_quasistatic": self.S_quasistatic,
                "runs": [{"period_s": p, "S": s if math.isfinite(s) else None, "status": st}
                         for p, s, st in self.runs], "ok": self.ok}


def _next_period(check: MarginCheck) -> float | None:
    """The next period to run [s], None when the bracket is narrow enough."""
    t_min, t_out = check.T_min_s, check.T_out_s
    if t_min is not None and t_out > 0:
        return None if t_min / t_out < BRACKET else math.sqrt(t_min * t_out)
    return t_min / SPAN if t_min is not None else t_out * SPAN


def margin_check(model: Model, signal, period: float, S_quasistatic: float, factor: float,
                 options=None, runs: int = MAX_RUNS, simulate=None) -> MarginCheck:
    """Run ``signal`` in MuJoCo at T / c, then locate the shortest period within (module docstring).

    Parameters
    ----------
    model : Model
        The robot (physical gravity).
    signal : PeriodicSignal
        Joint torques tau(phase) [N m], phase in cycles.
    period : float
        The optimum's period T [s].
    S_quasistatic : float
        The quasistatic S [m] (non-zero).
    factor : float
        dynamic_margin c [-] (>= 1).
    options : MujocoOptions, optional
        Time step, cone and cycles (the period replaced); None: the defaults.
    runs : int
        Most MuJoCo runs.
    simulate : callable, optional
        ``simulate(model, signal, options) -> CrawlResult``; None: the MuJoCo solver.

    Returns
    -------
    MarginCheck
    """
    from ocp_crawl.sim.dynamic import MujocoOptions, simulate_mujoco

    options = MujocoOptions() if options is None else options
    simulate = simulate_mujoco if simulate is None else simulate
    check = MarginCheck(float(period), float(factor), float(S_quasistatic))
    longest = MAX_STEPS * options.timestep
    p: float | None = period / factor
    while p is not None and len(check.runs) < runs and p <= longest:
        res = simulate(model, signal, dataclasses.replace(options, period=float(p)))
        S = float(res.S) if res.success else float("nan")
        check.runs.append((float(p), S, res.status_name))
        p = _next_period(check)
    return check


def margin_text(d: dict | None) -> list[str]:
    """The text line of ``optimize``'s summary for its ``dynamic_margin`` entry ([] without)."""
    if not d:
        return []
    if d.get("runs") is None:
        return [f"dynamic     not checked: {d.get('message', '')}"]
    t_min, t_out = d["T_min_s"], d["T_out_s"]
    tol = f"{d['tolerance'] * 100:g} %"
    if t_min is None:
        found = f"S within {tol} at none of the periods run (up to {t_out:.3g} s)"
    else:
        below = "" if t_out is None else f" (not at {t_out:.3g} s)"
        found = (f"S within {tol} of quasistatic down to T = {t_min:.3g} s{below}, "
                 f"f = {1 / t_min:.3g} Hz")
    return [f"dynamic     MuJoCo: {found}; period T = {d['period_s']:.3g} s, required T >= "
            f"{d['dynamic_margin']:g} T_min: {'met' if d['ok'] else 'not met'} "
            f"({len(d['runs'])} runs)"]


def _nominal(settings) -> int:
    """Index of the friction scenario nearest mu1/mu2 = 1 at the robot's level (0 without a friction
    set)."""
    if not settings.friction_set:
        return 0
    return int(np.argmin([abs(math.log(r or 1.0))
                          + abs(math.log(lv)) for lv, r in settings.scenario_pairs()]))


def check_dynamic_margin(res, models: list) -> None:
    """With ``[ocp] dynamic_margin``: check a judged optimum ``res`` (an OCPResult) in MuJoCo, set
    ``res.dynamic_margin`` and refuse it (``replay_mismatch``) when it is not quasistatic at its
    period; nothing without the setting or without a confirmed optimum."""
    from ocp_crawl.ocp.judge import replay_signal

    factor = res.settings.dynamic_margin
    if factor is None or not res.success:
        return
    i = _nominal(res.settings)
    model = getattr(models[i], "model", models[i])   # a Plant's statics, or the model itself
    if isinstance(model, ChainModel):
        res.dynamic_margin = {"message": "MuJoCo models the three-link robot only"}
        _refuse(res, "dynamic_margin needs the three-link robot (MuJoCo models it only)")
        return
    if models[i].gravity != "physical":
        res.dynamic_margin = {"message": "MuJoCo simulates physical gravity only"}
        _refuse(res, "dynamic_margin needs [model] gravity = \"physical\" (MuJoCo has no other)")
        return
    N = res.tau.shape[1]
    check = margin_check(model, replay_signal(np.arange(N) / N, res.tau), res.T_ocp,
                         res.S_replay[i], factor)
    res.dynamic_margin = check.to_dict()
    if check.ok:
        res.message += (f"; quasistatic in MuJoCo at T / {factor:g} (S within "
                        f"{TOLERANCE * 100:g} %)")
        return
    t_min = check.T_min_s
    where = f"at none of the periods run (up to {units.seconds(check.T_out_s)})" if t_min is None \
        else f"only from T_min = {units.seconds(t_min)}"
    _refuse(res, f"the gait is not quasistatic at its period T = {units.seconds(res.T_ocp)}: "
            f"MuJoCo's S is within {TOLERANCE * 100:g} % of the quasistatic S {where}, and "
            f"dynamic_margin = {factor:g} asks T >= {factor:g} T_min; lower max_rate_deg_s "
            f"(now {units.significant(res.settings.max_rate_deg_s)} deg/s) for a longer period"
            + ("" if t_min is not None else "; if S misses also at long periods the cause is "
               "not inertia but the contact, e.g. a slip a friction tie decides (ask for a "
               "friction set: mu_ratio_eps with robust = \"worst\")"))


def _refuse(res, text: str) -> None:
    res.success = False
    res.status = Status.REPLAY_MISMATCH
    res.message = f"{Status.REPLAY_MISMATCH.text}: {text}"
