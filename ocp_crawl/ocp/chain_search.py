"""The baselines of an n-link chain: the best travelling wave of each shape in the OCP's envelope
and bandwidth (:func:`best_chain_baselines`); the harmonic one is the chain's first start, and the
optimum's gain is measured against the best of them.

A member is the reference gait phi_ref,j = c_j + A u(t + lead_j / (2 pi)) of every joint j, with
c_j the envelope's centre of joint j (``gamma_joints_deg``), one amplitude A in (0, A_max], each
joint leading the next by psi (lead_j = psi ((m - 1)/2 - j), as a chain's ``[gait]`` reads
``psi_deg``) and the unit wave u of its shape (:data:`SHAPES`): ``harmonic`` a sine, ``triangle``
straight ramps up and down, each half a cycle (the reference rate saturated all cycle).  It is
driven as the torque tau_j = k_j (phi_ref,j - pi - rest_j)
(:class:`~ocp_crawl.model.chain_inputs.ChainReferenceTorque`).  Its period is the shortest the
bandwidth allows, 2 pi A / R for the sine and 4 A / R for the triangle (a quasistatic gait is
time-scale invariant: see :mod:`ocp_crawl.ocp.family`), and it counts when it simulates in every
friction scenario, as the three-link families' members.

The search works in the box coordinates (u, p) in [0, 1] x [-1, 1], A = u A_max and psi = 180 p: a
grid of ``harmonic_A`` amplitudes and ``harmonic_psi`` phases, then bounded Nelder-Mead from the
``baseline_starts`` best grid points at least 6/harmonic_psi apart, each within
:func:`local_budget` simulated members.  The grid is simulated on worker processes; every
simulation is deterministic, so the result does not depend on their number.
"""
from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from typing import cast

import numpy as np

from ocp_crawl.checks import real
from ocp_crawl.io.files import jsonable
from ocp_crawl.model.chain import Chain
from ocp_crawl.model.chain_inputs import ChainReferenceTorque, JointFourier
from ocp_crawl.model.inputs import PeriodicSignal
from ocp_crawl.model.pulse import JointPulse
from ocp_crawl.model.statics import GravityConvention
from ocp_crawl.ocp.baseline import FAIL_RANK, Baselines, search_rank, speeds, value_of
from ocp_crawl.ocp.family import A_MIN_DEG, Evaluation, allowed_period
from ocp_crawl.ocp.plant import Plant, envelope_centres
from ocp_crawl.ocp.quantities import PROFILE_QUANTITIES, profile_of_signal
from ocp_crawl.ocp.search import NM_TOL, first_simplex, seeds
from ocp_crawl.ocp.settings import OCPSettings
from ocp_crawl.workers import default_jobs, worker_pool

#: the shapes of a chain's travelling waves, in the order of reports
SHAPES = ("harmonic", "triangle")
#: the box of the coordinates (u, p)
BOX = ((0.0, 1.0), (-1.0, 1.0))
#: Nelder-Mead's first simplex: the steps in u and p
STEPS = (0.05, 0.02)
#: most simulated members of one local search (a chain's simulation costs 10 to 30 times the
#: three-link robot's; in two coordinates Nelder-Mead gains little after this many)
LOCAL_FEV = 60


def family_shapes(settings: OCPSettings, chain: bool) -> tuple[str, ...]:
    """The waveform families an optimisation searches: the settings' (``baseline_shapes``); a
    chain's (``chain`` True) are its travelling waves, :data:`SHAPES`."""
    return tuple(s for s in settings.baseline_shapes if not chain or s in SHAPES)


def local_budget(settings: OCPSettings) -> int:
    """Most simulated members of each local search: ``baseline_evaluations``, at most
    :data:`LOCAL_FEV`."""
    return min(settings.baseline_evaluations, LOCAL_FEV)


@dataclass(frozen=True)
class ChainWave:
    """One travelling wave of the chain family: its amplitude and phase lead [deg]."""

    A_deg: float
    """amplitude of every joint's reference angle [deg]"""
    psi_deg: float
    """phase lead of each joint over the next [deg], in (-180, 180]"""
    shape: str = "harmonic"
    """one of :data:`SHAPES`"""

    def gait(self, settings: OCPSettings, chain: Chain) -> PeriodicSignal:
        """The reference angles [rad] of the m joints (1-periodic in the phase)."""
        m = chain.n_joints
        lead = np.radians([self.psi_deg * ((m - 1) / 2 - j) for j in range(m)])
        centres, A = envelope_centres(settings, chain), np.full(m, math.radians(self.A_deg))
        if self.shape == "triangle":   # a pulse without a held level
            return JointPulse(centres, A, lead, rise=0.5, hold=0.0)
        return JointFourier.harmonic(centres, A, lead)

    def torque(self, settings: OCPSettings, chain: Chain) -> ChainReferenceTorque:
        """The torque input [N m] of the gait on ``chain`` (its stiffness and rest bends)."""
        return ChainReferenceTorque(self.gait(settings, chain), chain)

    def period(self, settings: OCPSettings) -> float:
        """The shortest period the bandwidth allows [s], slope A / R (the unit wave's largest
        slope: 2 pi per cycle for the sine, 4 for the triangle)."""
        slope = 4.0 if self.shape == "triangle" else 2.0 * math.pi
        return slope * self.A_deg / settings.max_rate_deg_s

    @classmethod
    def from_box(cls, settings: OCPSettings, z, shape: str = "harmonic") -> "ChainWave":
        """The member of ``shape`` at box coordinates ``z`` = (u, p), clipped into :data:`BOX`."""
        u, p = (min(max(float(v), lo), hi) for v, (lo, hi) in zip(z, BOX))
        psi = 180.0 * p
        return cls(u * settings.A_max_deg, 180.0 if psi == -180.0 else psi, shape)

    def as_dict(self) -> dict:
        return {"A_deg": self.A_deg, "psi_deg": self.psi_deg, "shape": self.shape}


class ChainWaveFamily:
    """The travelling waves of one shape in ``settings``' envelope and bandwidth on ``chain``,
    simulated by the chain's event-driven stepper in every friction scenario; evaluations cached by
    member."""

    def __init__(self, chain: Chain, gravity: GravityConvention, settings: OCPSettings,
                 shape: str = "harmonic"):
        if shape not in SHAPES:
            raise ValueError(f"a chain's travelling waves are of the shapes {SHAPES}, got "
                             f"{shape!r}")
        self.chain, self.settings, self.shape = chain, settings, shape
        self.plants = [Plant(c, gravity) for c in settings.scenarios(chain)]
        self.evaluations = 0
        self._cache: dict[tuple, Evaluation] = {}

    def evaluate(self, wave: ChainWave) -> Evaluation:
        """The member's simulations at its shortest period (cached)."""
        key = (round(wave.A_deg, 12), round(wave.psi_deg, 12))
        if key not in self._cache:
            self._cache[key] = self._simulate(wave)
        return self._cache[key]

    def _simulate(self, wave: ChainWave) -> Evaluation:
        T = wave.period(self.settings)
        nan = (math.nan,) * len(self.plants)
        if wave.A_deg < A_MIN_DEG:
            return Evaluation(wave, T, nan, nan, nan, False, "zero amplitude: no gait")
        self.evaluations += 1
        sims = []
        for plant in self.plants:
            try:
                r = plant.simulate(wave.torque(self.settings, cast(Chain, plant.robot)))
            except (ValueError, IndexError) as exc:   # the stepper refuses the input (as the
                # three-link family's members)
                return Evaluation(wave, T, nan, nan, nan, False, f"{type(exc).__name__}: {exc}")
            if not r.success:
                return Evaluation(wave, T, nan, nan, nan, False, r.message)
            sims.append(r)
        S = tuple(r.S for r in sims)
        profile = (math.nan, math.nan)
        if (self.settings.user_objective is not None
                or any(c.quantity in PROFILE_QUANTITIES for c in self.settings.requirements)):
            profile = profile_of_signal(wave.torque(self.settings, self.chain))
        return Evaluation(wave, allowed_period(self.settings, T, S), S,
                          tuple(r.W_plus for r in sims), tuple(r.CoT_plus for r in sims), True,
                          profile=profile)

    def rank(self, z) -> float:
        """The search rank (:func:`~ocp_crawl.ocp.baseline.search_rank`) of the member at z."""
        return search_rank(self.settings, self.evaluate(self.member(z)))

    def member(self, z) -> ChainWave:
        """The member of this family's shape at box coordinates z."""
        return ChainWave.from_box(self.settings, z, self.shape)

    def absorb(self, evaluations) -> None:
        """Add evaluations made by a worker's family of the same problem."""
        for ev in evaluations:
            key = (round(ev.params.A_deg, 12), round(ev.params.psi_deg, 12))
            if key not in self._cache:
                self._cache[key] = ev
                self.evaluations += ev.params.A_deg >= A_MIN_DEG

    def evaluated(self) -> list[Evaluation]:
        return list(self._cache.values())


@dataclass
class ChainWaveChoice:
    """The best travelling wave of a chain for the objective (as
    :class:`~ocp_crawl.ocp.baseline.WaveChoice` for the three-link robot): amplitude and phase
    lead [deg], the envelope centres [deg], T [s], per scenario S [m], W+ [J], CoT+ [-] and the
    mean speed v [m/s], the objective ``value`` and whether it meets the requirements."""

    A_deg: float
    psi_deg: float
    gamma_joints_deg: list
    T: float
    S: list
    W_plus: list
    CoT_plus: list
    v: list
    value: float
    feasible: bool
    objective: str
    evaluated: int = 0
    starts: list = field(default_factory=list)
    time_s: float = 0.0
    shape: str = "harmonic"

    def signal_for(self, chain, settings: OCPSettings) -> ChainReferenceTorque:
        """The torque input tau(t) [N m] of the gait on ``chain`` (a :class:`Chain`; the interface
        it shares with :class:`~ocp_crawl.ocp.baseline.WaveChoice`) at the phase t [cycles]."""
        return ChainWave(self.A_deg, self.psi_deg, self.shape).torque(settings, chain)

    def to_dict(self) -> dict:
        return jsonable(asdict(self))


def _choice(settings: OCPSettings, chain: Chain, ev: Evaluation) -> ChainWaveChoice:
    value = value_of(settings, ev)
    gamma = np.degrees(envelope_centres(settings, chain)).tolist()
    return ChainWaveChoice(ev.params.A_deg, ev.params.psi_deg, gamma, ev.T, list(ev.S),
                           list(ev.W_plus), list(ev.CoT_plus), speeds(settings, ev.S, ev.T),
                           value, math.isfinite(value), settings.objective, shape=ev.params.shape)


def scan_points(settings: OCPSettings) -> list[np.ndarray]:
    """The grid of the scan: ``harmonic_A`` amplitudes by ``harmonic_psi`` phases."""
    n_a, n_p = settings.harmonic_A, settings.harmonic_psi
    return [np.array([u, p]) for u in np.linspace(1.0 / n_a, 1.0, n_a)
            for p in np.linspace(-1.0, 1.0, n_p + 1)[1:]]


def _local(fam: ChainWaveFamily, z0: np.ndarray, maxfev: int) -> dict:
    """Bounded Nelder-Mead from z0 within ``maxfev`` simulated members; its summary."""
    from scipy.optimize import minimize

    n0 = fam.evaluations
    out = minimize(fam.rank, z0, method="Nelder-Mead", bounds=BOX,
                   options={**NM_TOL, "maxfev": maxfev,
                            "initial_simplex": first_simplex(z0, STEPS, BOX)})
    seed, end = (fam.evaluate(fam.member(x)) for x in (z0, out.x))
    return {"seed": seed.params.as_dict(), "seed_value": value_of(fam.settings, seed),
            "end": end.params.as_dict(), "end_value": value_of(fam.settings, end),
            "evaluations": fam.evaluations - n0}


_WORKER: dict = {}


def _init_worker(chain: Chain, gravity: GravityConvention, settings: OCPSettings,
                 shapes: tuple) -> None:
    _WORKER.update({s: ChainWaveFamily(chain, gravity, settings, s) for s in shapes})


def _scan_chunk(chunk) -> list:
    shape, points = chunk
    fam = _WORKER[shape]
    return [fam.evaluate(fam.member(z)) for z in points]


def best_chain_baselines(chain: Chain, gravity: GravityConvention, settings: OCPSettings,
                         shapes=("harmonic",), jobs: int | None = None,
                         meanwhile=None) -> Baselines:
    """The best travelling wave of each shape (see the module docstring).

    Parameters
    ----------
    chain : Chain
        The robot (SI units); ``settings.scenarios(chain)`` gives the friction scenarios.
    gravity : str
        Its gravity convention ("physical" or "paper").
    settings : OCPSettings
        The envelope (gamma_joints_deg or gamma_deg, A_max_deg), the bandwidth, the objective, the
        scan sizes (harmonic_A, harmonic_psi) and the local searches (baseline_starts,
        baseline_evaluations: at most :data:`LOCAL_FEV` each).
    shapes : sequence of str
        The shapes searched, of :data:`SHAPES` (default: the harmonic one, the OCP's start).
    jobs : int, optional
        Worker processes of the scans (None: the CPUs this process may use).
    meanwhile : callable, optional
        Called in this process while the workers scan (e.g. the OCP's solvers built).

    Returns
    -------
    Baselines
        Per shape the best member found (a :class:`ChainWaveChoice`; None when no member simulates
        successfully).
    """
    t0 = time.perf_counter()
    shapes = tuple(shapes)
    jobs = default_jobs() if jobs is None else int(real("jobs", jobs, integer=True, low=1))
    fams = {s: ChainWaveFamily(chain, gravity, settings, s) for s in shapes}
    points = scan_points(settings)
    if jobs > 1:
        pool = worker_pool(jobs, _init_worker, (chain, gravity, settings, shapes))
        try:
            chunks = [(s, list(c)) for s in shapes for c in np.array_split(points, 4 * jobs)]
            scanned = pool.map(_scan_chunk, chunks)
            if meanwhile is not None:
                meanwhile()
            for (s, _), evs in zip(chunks, scanned):
                fams[s].absorb(evs)
        finally:
            pool.shutdown(cancel_futures=True)
    elif meanwhile is not None:
        meanwhile()
    choices = {}
    for s, fam in fams.items():
        scored = [(fam.rank(z), z) for z in points]
        summaries = [_local(fam, z, local_budget(settings)) for z in
                     seeds(scored, settings.baseline_starts, 6.0 / settings.harmonic_psi)]
        rank, best = min(((search_rank(settings, ev), ev) for ev in fam.evaluated()),
                         key=lambda x: x[0], default=(FAIL_RANK, None))
        choice = None
        if best is not None and rank < FAIL_RANK:
            choice = _choice(settings, chain, best)
            choice.evaluated, choice.starts = fam.evaluations, summaries
        choices[s] = choice
    dt = time.perf_counter() - t0
    for c in choices.values():
        if c is not None:
            c.time_s = dt
    return Baselines(settings.objective, choices, dt)
