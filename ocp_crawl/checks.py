"""The one validation of numbers given by a user (floor 0: imports nothing of the package).

Every frozen dataclass of options and parameters checks its numbers with :func:`real`, so a bad
value always raises the same way: ``TypeError`` for something that is not a real number,
``ValueError`` for a number outside its range, the message naming the field and the value given.
"""
from __future__ import annotations

import math
import re

import numpy as np

_REAL_TYPES = (int, float, np.integer, np.floating)


def is_real(value) -> bool:
    """True for an int or float (numpy's too), False for bool and everything else."""
    return not isinstance(value, (bool, np.bool_)) and isinstance(value, _REAL_TYPES)


def is_finite(value) -> bool:
    """Whether a real number is finite; False for an integer too large for a float (hundreds of
    digits)."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def short_repr(value, width: int = 40) -> str:
    """``repr(value)``, cut to ``width`` characters with "..." (a 400-digit integer in a
    message)."""
    text = repr(value)
    return text if len(text) <= width else text[:width - 3] + "..."


def real(name: str, value, *, positive: bool = False, nonneg: bool = False, integer: bool = False,
         low: float | None = None, high: float | None = None) -> float | int:
    """``value`` as a finite float (an int with ``integer``), or an error naming ``name``.

    ``positive``: > 0; ``nonneg``: >= 0; ``low``/``high``: inclusive bounds.
    Raises TypeError if ``value`` is not a real number, ValueError if it is not finite, not an
    integer although ``integer`` is asked, or out of range.
    """
    if not is_real(value):
        raise TypeError(f"{name} must be a real number, got {value!r} ({type(value).__name__})")
    if not is_finite(value):
        raise ValueError(f"{name} must be finite, got {short_repr(value)}")
    if integer and int(value) != value:
        raise ValueError(f"{name} must be an integer, got {value!r}")
    v = int(value) if integer else float(value)
    if positive and v <= 0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    if nonneg and v < 0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    if low is not None and v < low:
        raise ValueError(f"{name} must be >= {low}, got {value!r}")
    if high is not None and v > high:
        raise ValueError(f"{name} must be <= {high}, got {value!r}")
    return v


def finite_or_none(x) -> float | None:
    """A float, or None when it is not finite (strict JSON has no NaN or Inf)."""
    x = float(x)
    return x if math.isfinite(x) else None


#: a number as a user writes it: ASCII decimal notation, or nan/inf (to be refused as not finite by
#: the caller); Python's ``float`` and ``int`` also take "1_0" and digits of other scripts, which no
#: file or option means
_NUMBER_TEXT = re.compile(r"[+-]?(?:(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?|inf|infinity|nan)",
                          re.ASCII | re.IGNORECASE)
_INTEGER_TEXT = re.compile(r"[+-]?\d+", re.ASCII)


def parse_number(text: str) -> float:
    """``text`` (stripped) as a float when it is a decimal number in ASCII (or nan/inf); ValueError
    otherwise."""
    if not isinstance(text, str) or not _NUMBER_TEXT.fullmatch(text.strip()):
        raise ValueError(f"not a number: {text!r}")
    return float(text)


def parse_integer(text: str) -> int:
    """``text`` (stripped) as an int when it is a decimal integer in ASCII; ValueError otherwise."""
    if not isinstance(text, str) or not _INTEGER_TEXT.fullmatch(text.strip()):
        raise ValueError(f"not an integer: {text!r}")
    return int(text)
