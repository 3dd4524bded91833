"""The vocabulary of the problem schema: a key (type, unit, default, rule, choices, variants), a
section of keys, a rule on a value, and the one error of bad problem input.

:mod:`ocp_crawl.problem.schema` lists the sections of a problem file in these terms.
"""
from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from typing import Any, Callable


class ProblemError(ValueError):
    """Bad problem input. The message is a single line naming the file, key, value and what is
    valid."""

    def __init__(self, message: str):
        # one line whatever the user typed (file names, string values)
        super().__init__(" ".join(str(message).split("\n")))


def field_default(cls: type, name: str) -> Any:
    """The default of the dataclass field ``name`` of ``cls`` (the one place a default is
    defined)."""
    for f in dataclasses.fields(cls):
        if f.name == name:
            if f.default is not dataclasses.MISSING:
                return f.default
            if f.default_factory is not dataclasses.MISSING:
                return f.default_factory()
            break
    raise AttributeError(f"{cls.__name__} has no field {name!r} with a default")


@dataclass(frozen=True)
class Rule:
    """A value constraint: ``test(value)`` must hold; ``text`` says what is valid (e.g. "> 0");
    ``why`` gives the reason of a bound (key reference and error messages)."""

    test: Callable[[Any], bool]
    text: str
    why: str = ""

    @property
    def explained(self) -> str:
        """``text`` followed by the reason, if any."""
        return f"{self.text} ({self.why})" if self.why else self.text


def _num(x: float) -> str:
    """A bound as the rule's text writes it: ``1e-12``, ``0.25``, ``500`` (no ``+`` in
    exponents)."""
    if isinstance(x, int) or x == 0 or not (abs(x) < 1e-3 or abs(x) >= 1e4):
        return format(x, "g")
    mantissa, exponent = f"{x:e}".split("e")
    return f"{mantissa.rstrip('0').rstrip('.')}e{int(exponent)}"


def within(low: float, high: float, why: str) -> Rule:
    """The rule ``low <= value <= high`` ("in [low, high]") with the reason of the bounds."""
    return Rule(lambda v: low <= v <= high, f"in [{_num(low)}, {_num(high)}]", why)


GT0 = Rule(lambda v: v > 0, "> 0")
GE0 = Rule(lambda v: v >= 0, ">= 0")
ANGLE = Rule(lambda v: 0 < v < 360, "in (0, 360)")
PHASE = Rule(lambda v: -360 <= v <= 360, "in [-360, 360]")
#: a Fourier coefficient of a reference angle [deg]: larger ones cannot keep the angle in (0, 360)
#: deg
COEFFICIENT = Rule(lambda v: -360 <= v <= 360, "in [-360, 360]",
                   "a reference angle lies in (0, 360) deg")


class Tables:
    """The type of a key whose value is an array of tables (``[[ocp.constraint]]``)."""


TYPE_WORDS = {float: "a number", int: "an integer", str: "a string", list: "an array of numbers",
              Tables: "an array of tables", dict: "a table"}
#: most entries of an array key (inline samples, Fourier coefficients)
MAX_ARRAY = 100_000


@dataclass(frozen=True)
class Key:
    """One key of a section: type, unit, description, default, validator and cross-key rules."""

    name: str
    type: type
    """float, int, str or list (an array of numbers; ints are accepted for floats; bools are never
    numbers)"""
    unit: str
    help: str
    required: bool = False
    default: Any = None
    """value used when the key is absent (None: absent stays absent)"""
    rule: Rule | None = None
    choices: tuple[str, ...] = ()
    required_unless: tuple[str, ...] = ()
    """the key is not required when all of these keys are given"""
    exclusive_with: tuple[str, ...] = ()
    requires: tuple[str, ...] = ()
    """keys that must be given together with this one"""
    variants: tuple[str, ...] = ()
    """the values of the section's selector key (``[gait] waveform``) this key belongs to; () for
    every one"""

    def __post_init__(self) -> None:
        if self.type not in TYPE_WORDS:
            raise TypeError(f"Key {self.name}: type must be one of float, int, str, list, Tables, "
                            f"dict, got {self.type!r}")

    @property
    def what(self) -> str:
        """Description with unit, used at the end of error messages."""
        return f"{self.help}, {self.unit}" if self.unit and self.unit != "-" else self.help

    @property
    def valid_text(self) -> str:
        """What is valid, in words (key reference and error messages)."""
        if self.choices:
            return "one of " + ", ".join(json.dumps(c) for c in self.choices)
        if self.type is list:
            return "an array of numbers, each " + (self.rule.text if self.rule is not None
                                                   else "finite")
        if self.type is Tables:
            return "an array of tables, each " + (self.rule.text if self.rule is not None
                                                  else "a table")
        if self.type is dict:
            return (self.rule.text if self.rule is not None
                    else "a table of names and numbers or strings")
        if self.rule is not None:
            return self.rule.text
        return "any finite number" if self.type in (float, int) else "any string"


@dataclass(frozen=True)
class Section:
    """A ``[section]`` of a problem file and its keys."""

    name: str
    help: str
    keys: tuple[Key, ...]
    required: bool = False
    selector: str | None = None
    """the key whose value selects which of the keys with ``variants`` apply (``[gait] waveform``,
    ``[ocp] objective``)"""

    @property
    def key_map(self) -> dict[str, Key]:
        return {k.name: k for k in self.keys}

    def applies(self, key: Key, variant: str | None) -> bool:
        """Whether ``key`` belongs to the section when its selector has the value ``variant``."""
        return not key.variants or variant in key.variants
