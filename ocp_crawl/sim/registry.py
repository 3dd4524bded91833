"""One entry to every simulator: :func:`simulate` and the solver registry :data:`SOLVERS`.

In the manner of scipy's ``solve_ivp`` and its ``METHODS`` table: a solver is a name, the drive it
simulates, its options dataclass and a function ``run(model, signal, options, t_eval)``. Adding a
solver is adding a module and one row here; the problem files, the command line and the sweep look
solvers up in this table and nowhere else. A row that can also simulate an n-link chain (a
:class:`~ocp_crawl.model.chain_model.ChainModel`) names its chain function, ``chain``. Every solver
builds its result with :mod:`ocp_crawl.sim.assemble`, so every row returns a
:class:`~ocp_crawl.sim.result.CrawlResult` whose ``status`` is a :class:`~ocp_crawl.status.Status`.
"""
from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any, Callable

from ocp_crawl.model.chain_model import ChainModel
from ocp_crawl.model.statics import Model
from ocp_crawl.sim.angles import simulate_angles
from ocp_crawl.sim.dynamic import INSTALL, MujocoOptions, mujoco_available, simulate_mujoco
from ocp_crawl.sim.event import HybridOptions, simulate_torque
from ocp_crawl.sim.options import count
from ocp_crawl.sim.result import CrawlResult
from ocp_crawl.sim.timestepping import TimeSteppingOptions, simulate_mpcc


@dataclass(frozen=True)
class Solver:
    """A row of the registry."""

    name: str
    drive: str
    """the input it takes: ``"torque"`` (joint torques [N m]) or ``"angles"`` (prescribed joint
    angles [rad])"""
    options: type
    """its options dataclass (``options()`` gives the defaults)"""
    run: Callable[[Model, Any, Any, Any], CrawlResult]
    """``run(model, signal, options, t_eval) -> CrawlResult`` (``status`` a
    :class:`~ocp_crawl.status.Status`)"""
    description: str
    available: Callable[[], bool] = lambda: True
    """whether its optional dependency can be imported (``install`` says how to get it otherwise)"""
    install: str = ""
    """the command that installs its optional dependency ("" for none)"""
    chain: Callable[[Any, Any, Any, Any], CrawlResult] | None = None
    """``chain(chain_model, signal, options, t_eval)``: the same simulator for an n-link chain
    (the signal with n - 1 rows); None: the solver simulates the three-link robot only"""


def _run_event(model, signal, options, t_eval):
    return simulate_torque(model, signal, options, t_eval=t_eval)


def _run_mpcc(model, signal, options, t_eval):
    return simulate_mpcc(model, signal, options.steps, options=options, t_eval=t_eval)


def _run_mujoco(model, signal, options, t_eval):
    return simulate_mujoco(model, signal, options, t_eval=t_eval)


def _run_mujoco_angles(model, signal, options, t_eval):
    return simulate_mujoco(model, signal, options, t_eval=t_eval, drive="angles")


def _run_angles(model, signal, options, t_eval):
    return simulate_angles(model, signal, t_eval=t_eval, n_scan=options.n_scan)


def _chain_event(model, signal, options, t_eval):
    from ocp_crawl.sim.chain_torque import simulate_chain_torque

    return simulate_chain_torque(model, signal, cycles_max=options.max_cycles, t_eval=t_eval,
                                 max_step=options.max_step, event_xtol=options.event_xtol,
                                 periodic_tol=options.periodic_tol)


def _chain_mpcc(model, signal, options, t_eval):
    from ocp_crawl.sim.chain_mpcc import simulate_chain_mpcc

    return simulate_chain_mpcc(model, signal, steps=options.steps, cycles_max=options.max_cycles,
                               periodic_tol=options.periodic_tol,
                               switch_exact=options.switch_exact, t_eval=t_eval)


def _chain_angles(model, signal, options, t_eval):
    from ocp_crawl.sim.chain_angles import simulate_chain_angles

    return simulate_chain_angles(model, signal, t_eval=t_eval, n_scan=options.n_scan)


@dataclass(frozen=True)
class AnglesOptions:
    """Options of the prescribed-angle solver."""

    n_scan: int = 512
    """scan points per cycle used to bracket the events (each then located to round-off)"""

    def __post_init__(self) -> None:
        object.__setattr__(self, "n_scan", count("AnglesOptions.n_scan", self.n_scan, 8))


#: the simulators by name (``simulate(..., solver=NAME)``, ``[simulation] solver``)
SOLVERS: dict[str, Solver] = {
    "event": Solver("event", "torque", HybridOptions, _run_event,
                    "event-driven hybrid stepper: equilibrium continuation, "
                    "events located to 1e-13 of a cycle", chain=_chain_event),
    "mpcc": Solver("mpcc", "torque", TimeSteppingOptions, _run_mpcc,
                   "MPCC time-stepping: one IPOPT solve of the incremental Coulomb problem per "
                   "step", chain=_chain_mpcc),
    "angles": Solver("angles", "angles", AnglesOptions, _run_angles,
                     "prescribed joint angles: kinematic contact modes, "
                     "events by bracketing and root finding", chain=_chain_angles),
    "mujoco": Solver("mujoco", "torque", MujocoOptions, _run_mujoco,
                     "dynamic simulation in MuJoCo: the torques played at a period T [s]",
                     available=mujoco_available, install=INSTALL),
    "mujoco_angles": Solver("mujoco_angles", "angles", MujocoOptions, _run_mujoco_angles,
                            "dynamic simulation in MuJoCo: the angles held by position "
                            "servos, played at a period T [s]",
                            available=mujoco_available, install=INSTALL),
}
#: the solvers that simulate a chain too, as messages list them
CHAIN_SOLVERS = ", ".join(name for name, spec in SOLVERS.items() if spec.chain is not None)
#: the MuJoCo solver of each drive (``[simulation] solver = "mujoco"`` names both)
MUJOCO_SOLVERS = {"torque": "mujoco", "angles": "mujoco_angles"}


def unusable(name: str, gravity: str, values=None, chain: bool = False) -> str:
    """Why the solver ``name`` cannot simulate a model of the ``gravity`` convention with the
    options ``values`` (a mapping of ``[simulation]`` keys, None: not checked), or a chain if
    ``chain``; "" if it can.  Its optional dependency is missing (the message names the install
    command), the convention is the paper's printed one, which MuJoCo's gravity is not, the robot
    is a chain, which it does not simulate, or the options break a rule between them."""
    spec = solver_named(name)
    if chain and spec.chain is None:
        return ("is invalid with a chain ([robot] lengths): it simulates the three-link robot "
                f"only; a chain's solvers: {CHAIN_SOLVERS}")
    if not spec.available():
        return f"needs an optional dependency that is not installed: {spec.install}"
    if name in MUJOCO_SOLVERS.values() and gravity != "physical":
        return (f"is invalid with [model] gravity = {gravity!r}: MuJoCo simulates physical "
                "gravity only")
    try:
        if values is not None:
            names = {f.name for f in fields(spec.options)}
            spec.options(**{k: v for k, v in values.items() if k in names})
    except ValueError as exc:
        return f"is invalid with these [simulation] values: {exc}"
    return ""


def unavailable_solvers() -> dict[str, str]:
    """The solvers whose optional dependency cannot be imported, each with its install command."""
    return {name: spec.install for name, spec in SOLVERS.items() if not spec.available()}

#: the solver used for each drive when none is named
DEFAULT_SOLVER = {"torque": "event", "angles": "angles"}


def solver_named(name: str) -> Solver:
    """The registry row of ``name``; ValueError naming the valid solvers otherwise."""
    try:
        return SOLVERS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown solver {name!r}; valid: {', '.join(SOLVERS)}") from None


def simulate(model: Model | ChainModel, signal, solver: str = "event", options=None,
             t_eval=None) -> CrawlResult:
    """Simulate the crawler ``model`` driven by ``signal`` with the solver ``solver``.

    Parameters
    ----------
    model : Model or ChainModel
        robot and gravity convention; a ChainModel (an n-link chain) with the solvers whose row
        has a ``chain`` function ("event", "mpcc", "angles").
    signal : PeriodicSignal or callable
        the periodic input over one cycle (phase t in cycles): joint torques [N m] for the torque
        solvers (``"event"``, ``"mpcc"``), joint angles [rad] for ``"angles"``; a row per joint.
    solver : str
        a name of :data:`SOLVERS`.
    options : the solver's options dataclass, optional
        ``SOLVERS[solver].options``; None for its defaults.
    t_eval : array_like, optional
        output phases [cycles] inside the reported steady cycle; None for the solver's default
        sampling.

    Returns
    -------
    CrawlResult
        ``success``/``status``/``message`` and, on success, S [m], W+ [J], CoT+ [-] and the sampled
        trajectories.
    """
    spec = solver_named(solver)
    if options is None:
        options = spec.options()
    elif not isinstance(options, spec.options):
        raise TypeError(f"options of solver {solver!r} must be {spec.options.__name__}, "
                        f"got {type(options).__name__}")
    if isinstance(model, ChainModel):
        if spec.chain is None:
            raise ValueError(f"solver {solver!r} simulates the three-link robot only; for a chain: "
                             f"{CHAIN_SOLVERS}")
        return spec.chain(model, signal, options, t_eval)
    return spec.run(model, signal, options, t_eval)
