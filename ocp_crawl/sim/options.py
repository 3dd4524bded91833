"""Options shared by the simulators that run cycle after cycle until the gait is periodic.

:class:`CycleOptions` holds ``max_cycles``, ``min_cycles`` and ``periodic_tol`` once; the options of
the event-driven stepper (:class:`~ocp_crawl.sim.event.HybridOptions`) and of the MPCC
time-stepping (:class:`~ocp_crawl.sim.timestepping.TimeSteppingOptions`) derive from it, so
``options.max_cycles`` and ``HybridOptions(max_cycles=...)`` work for both.
"""
from __future__ import annotations

from dataclasses import dataclass

from ocp_crawl.checks import real

#: bounds on the options that size a run's work (docs/guide/problem_files.md, "Bounds"), checked
#: here and read by the problem schema:
#: the event solver's largest step and quadrature panel [cycles] (at most 1e4 per cycle), the cycles
#: a run may take, and the MPCC's steps per cycle (each an IPOPT solve of about 2 ms)
MAX_STEP_BOUNDS = (1e-4, 0.25)
MAX_CYCLES_BOUNDS = (2, 500)
STEPS_BOUNDS = (4, 10_000)
#: events per cycle before a run ends as too_many_events (each costs a few event locations)
MAX_EVENTS_BOUNDS = (1, 100_000)


def count(name: str, value, low: int, high: int | None = None) -> int:
    """``value`` as an integer in [``low``, ``high``] (:func:`~ocp_crawl.checks.real`); a bool is
    refused as not an integer.

    Raises ValueError for a bool, a non-integer or a value out of range, TypeError for a non-number.
    """
    if isinstance(value, bool):
        raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")
    return int(real(name, value, integer=True, low=low, high=high))  # an int already


@dataclass(frozen=True)
class CycleOptions:
    """When a run of cycles stops: periodic after ``min_cycles``, or not periodic after
    ``max_cycles``."""

    max_cycles: int = 12
    """cycles to run before declaring the gait non-periodic"""
    min_cycles: int = 2
    """cycles always run (the first one is a transient from the released start)"""
    periodic_tol: float = 1e-8
    """periodicity: max |phi change| [rad] and |f_t change|/(M g) over one cycle"""

    def __post_init__(self) -> None:
        owner = type(self).__name__
        self._set("periodic_tol", real(f"{owner}.periodic_tol", self.periodic_tol, positive=True))
        self._set("max_cycles", count(f"{owner}.max_cycles", self.max_cycles, MAX_CYCLES_BOUNDS[0],
                                      MAX_CYCLES_BOUNDS[1]))
        self._set("min_cycles", count(f"{owner}.min_cycles", self.min_cycles, 1))
        if self.min_cycles > self.max_cycles:
            raise ValueError(f"{owner}.min_cycles must be an integer in [1, max_cycles], "
                             f"got {self.min_cycles!r}")

    def _set(self, name: str, value) -> None:
        object.__setattr__(self, name, value)

    def cycle_verdict(self, cycle: int, deviation: float, same_mode: bool) -> bool | None:
        """After ``cycle`` cycles whose last two ends differ by ``deviation`` (``same_mode``: in the
        same contact mode): True if the gait is periodic, None to run on, False if it is not
        periodic."""
        if cycle >= self.min_cycles and deviation <= self.periodic_tol and same_mode:
            return True
        return False if cycle >= self.max_cycles else None
