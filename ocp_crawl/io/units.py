"""Numbers with their units as text: the one formatting layer of every command's text output.

The package computes in SI units (S [m], W+ [J], times [s]); text output shows S in mm, W+ in mJ,
CoT+ to 3 significant digits and times in s, and a number that could not be computed (None, NaN)
as "-".  JSON output keeps SI numbers and names their units with :data:`UNITS`.
"""
from __future__ import annotations

import math
from typing import Any

#: SI unit of each number of a summary (JSON output and data frames carry these)
UNITS = {"S": "m", "W_plus": "J", "W_plus_joint": "J", "CoT_plus": "-", "t": "cycles",
         "energy": "J", "energy.balance_residual": "-",
         "tau": "N m", "solve_time_s": "s", "elapsed_s": "s", "T": "s", "v": "m/s",
         "peak_joint_rate_deg_s": "deg/s", "peak_slip_speed_m_s": "m/s",
         "harmonic_peak_joint_rate_deg_s": "deg/s", "harmonic_peak_slip_speed_m_s": "m/s"}
#: what stands for a number that could not be computed
MISSING = "-"


def _value(x: Any) -> float | None:
    """x as a float, or None for None and non-numbers (NaN stays NaN)."""
    if x is None or isinstance(x, bool):
        return None
    try:
        return float(x)
    except (TypeError, ValueError):
        return None


def fixed(x: Any, decimals: int = 3, scale: float = 1.0, sign: bool = False) -> str:
    """``scale * x`` with ``decimals`` decimals; "-" for None or NaN, "inf"/"-inf" for infinities.

    A value that rounds to zero prints as 0 (never "-0.000"); ``sign``: always show the sign of a
    non-zero value.
    """
    v = _value(x)
    if v is None or math.isnan(v):
        return MISSING
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    # + 0.0 turns a rounded -0.0 into 0.0
    v = round(scale * v, decimals) + 0.0
    return format(v, f"{'+' if sign and v != 0 else ''}.{decimals}f")


def significant(x: Any, digits: int = 3) -> str:
    """x to ``digits`` significant digits, trailing zeros kept (20.3, 0.500, 1.23e+04); "-" if
    missing."""
    v = _value(x)
    if v is None or math.isnan(v):
        return MISSING
    if math.isinf(v):
        return "inf" if v > 0 else "-inf"
    text = format(v + 0.0, f"#.{digits}g")
    return text[:-1] if text.endswith(".") else text


def distance(S: Any, decimals: int = 3, sign: bool = False) -> str:
    """A distance [m] in mm, e.g. ``distance(-0.0558)`` -> "-55.800 mm"."""
    text = fixed(S, decimals, 1e3, sign)
    return text if text == MISSING else f"{text} mm"


def speed(v: Any, decimals: int = 3) -> str:
    """A speed [m/s] in mm/s, e.g. ``speed(-0.0124)`` -> "-12.400 mm/s"."""
    text = fixed(v, decimals, 1e3)
    return text if text == MISSING else f"{text} mm/s"


def work(W: Any, decimals: int = 3) -> str:
    """A work or energy [J] in mJ, e.g. ``work(0.579)`` -> "579.000 mJ"."""
    text = fixed(W, decimals, 1e3)
    return text if text == MISSING else f"{text} mJ"


def cot(x: Any, digits: int = 3) -> str:
    """A cost of transport [-] to ``digits`` significant digits, e.g. "20.3"."""
    return significant(x, digits)


def seconds(t: Any) -> str:
    """A duration [s]: one decimal from 1 s on, 3 significant digits below, e.g. "4.1 s", "0.0415
    s"."""
    v = _value(t)
    if v is None or not math.isfinite(v):
        return MISSING
    return f"{v:.1f} s" if abs(v) >= 1.0 else f"{significant(v)} s"


def ratio(x: Any, digits: int = 3) -> str:
    """A relative difference or gain [-] as a signed percentage, e.g. "+1.62 %"; "-" if missing."""
    v = _value(x)
    if v is None or not math.isfinite(v):
        return MISSING
    return f"{significant(100 * v, digits) if v < 0 else '+' + significant(100 * v, digits)} %"


def scientific(x: Any, digits: int = 2) -> str:
    """A residual or tolerance in scientific notation, e.g. "1.6e-09"; "-" if missing."""
    v = _value(x)
    if v is None or math.isnan(v):
        return MISSING
    return format(v, f".{digits - 1}e")


def plural(n: int, noun: str, nouns: str | None = None) -> str:
    """A count with its noun in the right number: ``plural(1, "point")`` -> "1 point",
    ``plural(3, "point")`` -> "3 points" (``nouns``: the plural when it is not noun + "s")."""
    return f"{n} {noun if n == 1 else nouns or noun + 's'}"
