"""Options shared by the simulators that run cycle after cycle until the gait is periodic.

:class:`CycleOptions` holds ``max_cycles``, ``min_cycles`` and ``periodic_tol`` once; the options of
the event-driven stepper (:class:`~ocp_crawl.sim.event.HybridOptions`) and of the MPCC
time-stepping (:class:`~ocp_crawl.sim.timestepping.TimeSteppingOptions`) derive from it, so
``options.max_cycles`` and ``HybridOptions(max_cycles=...)`` work for both.
"""
from __future__ import annotations

from dataclasses import dataclass

from ocp_crawl.checks import real


def count(name: str, value, low: int) -> int:
    """``value`` as an integer >= ``low`` (:func:`~ocp_crawl.checks.real`); a bool is refused as not an integer.

    Raises ValueError for a bool, a non-integer or a value below ``low``, TypeError for a non-number.
    """
    if isinstance(value, bool):
        raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")
    return real(name, value, integer=True, low=low)


@dataclass(frozen=True)
class CycleOptions:
    """When a run of cycles stops: periodic after ``min_cycles``, or not periodic after ``max_cycles``."""

    max_cycles: int = 12
    """cycles to run before declaring the gait non-periodic"""
    min_cycles: int = 2
    """cycles always run (the first one is a transient from the released start)"""
    periodic_tol: float = 1e-8
    """periodicity: max |phi change| [rad] and |f_t change|/(M g) over one cycle"""

    def __post_init__(self) -> None:
        owner = type(self).__name__
        self._set("periodic_tol", real(f"{owner}.periodic_tol", self.periodic_tol, positive=True))
        self._set("max_cycles", count(f"{owner}.max_cycles", self.max_cycles, 2))
        self._set("min_cycles", count(f"{owner}.min_cycles", self.min_cycles, 1))
        if self.min_cycles > self.max_cycles:
            raise ValueError(f"{owner}.min_cycles must be an integer in [1, max_cycles], got {self.min_cycles!r}")

    def _set(self, name: str, value) -> None:
        object.__setattr__(self, name, value)

    def cycle_verdict(self, cycle: int, deviation: float, same_mode: bool) -> bool | None:
        """After ``cycle`` cycles whose last two ends differ by ``deviation`` (``same_mode``: in the same
        contact mode): True if the gait is periodic, None to run on, False if it is not periodic."""
        if cycle >= self.min_cycles and deviation <= self.periodic_tol and same_mode:
            return True
        return False if cycle >= self.max_cycles else None
