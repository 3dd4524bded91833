"""Objectives in the vocabulary of cycle quantities: ``[ocp] objective = "<sense>:<quantity>"``.

An objective names a quantity of :data:`~ocp_crawl.ocp.quantities.QUANTITIES` and whether it is
minimised or maximised (``"min:W_plus"``, ``"max:distance"``), or is a weighted sum of them
(``"min:sum"`` with ``terms``, a mapping quantity -> weight; a negative weight maximises that
quantity).  A quantity of the friction scenarios enters as its mean over them.

Two of them are the named objectives, with the same NLP: ``"max:speed"`` is ``max_speed`` (over a
friction set, robust_speed's problem) and ``"min:CoT_plus"`` is ``min_cot``; the settings store them
under those names (:func:`canonical`), so that ``robust = "worst"`` and min_cot's own speed
requirement apply to them.  Every other one is built as a
:class:`~ocp_crawl.ocp.quantities.UserObjective` (:func:`vocabulary_objective`): its NLP expression
from the transcription's symbols, its value on a simulated gait from the same quantities' values
(:func:`~ocp_crawl.ocp.quantities.quantity_values`), so the baselines and the replay judge measure
what the optimiser does.

What is refused, and why: W+ and CoT+ are sums of slacks v >= tau dphi, v >= 0, exact only when the
objective presses them down (a positive weight in a minimised sum); the peak torque is a maximum
over nodes, which an objective cannot state without an epigraph (bound it with a constraint
instead); the worst over the scenarios is available for the two named objectives only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from ocp_crawl.ocp.quantities import QUANTITIES, Cycle, Physical, UserObjective, quantity_values

#: the named objectives
OBJECTIVES = ("max_speed", "min_cot", "robust_speed")
#: the vocabulary's forms of the named objectives (the same NLP, stored under the name)
NAMED = {"max:speed": "max_speed", "min:CoT_plus": "min_cot"}
#: the sense each quantity may be optimised in alone: W+ and CoT+ only pressed down, the peak
#: torque not at all (a maximum over nodes: bound it with a constraint); the senses that only
#: stop the robot, slow it or lengthen its period alone (min:distance, max:period, ...) are left
#: out: the baselines run at the shortest period the bandwidth allows and would not measure them
SENSES = {"speed": ("max",), "distance": ("max",), "W_plus": ("min",), "CoT_plus": ("min",),
          "mean_torque_sq": ("min",), "period": ("min",)}
#: the weighted sum of ``terms``
SUM = "min:sum"
#: every objective of the vocabulary
VOCABULARY = tuple(f"{sense}:{q}" for q, senses in SENSES.items() for sense in senses) + (SUM,)
#: quantities whose weight in a sum must be positive (pressed down) or that cannot be a term
_POSITIVE_ONLY = ("W_plus", "CoT_plus")


def canonical(objective: str) -> str:
    """The name under which the settings keep ``objective``: max_speed for "max:speed", min_cot for
    "min:CoT_plus", itself otherwise."""
    return NAMED.get(objective, objective)


def check_terms(terms) -> tuple[tuple[str, float], ...]:
    """``terms`` (a mapping quantity -> weight, e.g. a problem file's ``[ocp.terms]`` table) as
    sorted (quantity, weight) pairs; ValueError naming what is wrong."""
    if not isinstance(terms, Mapping) or not terms:
        raise ValueError("OCPSettings.terms: objective 'min:sum' needs terms, a table quantity = "
                         f"weight (e.g. {{W_plus = 1.0, mean_torque_sq = 10.0}}), got {terms!r}")
    out = []
    for name, weight in sorted(terms.items()):
        if name not in SENSES:
            allowed = ", ".join(SENSES)
            why = (" (a maximum over nodes: bound it with [[ocp.constraint]] instead)"
                   if name == "peak_torque" else "")
            raise ValueError(f"OCPSettings.terms: {name!r} cannot be a term{why}; one of {allowed}")
        if (isinstance(weight, bool) or not isinstance(weight, (int, float))
                or not math.isfinite(weight) or weight == 0):
            raise ValueError(f"OCPSettings.terms: the weight of {name} must be a nonzero finite "
                             f"number, got {weight!r}")
        if name in _POSITIVE_ONLY and weight < 0:
            raise ValueError(f"OCPSettings.terms: the weight of {name} must be positive (a sum of "
                             "slacks is exact only where the objective presses it down)")
        out.append((name, float(weight)))
    return tuple(out)


def _per_scenario(name: str, q: Physical) -> list:
    """The NLP expressions of a quantity, one per scenario (the profile's quantities once)."""
    d = q.direction
    if name == "speed":
        return [d * S / q.T for S in q.S]
    if name == "distance":
        return [d * S for S in q.S]
    if name == "W_plus":
        return list(q.W_plus)
    if name == "CoT_plus":
        Mg = q.sizes["W_plus"] / q.sizes["distance"]  # M g L / L
        return [W / (Mg * d * S) for W, S in zip(q.W_plus, q.S)]
    return [q.mean_torque_sq if name == "mean_torque_sq" else q.T]


@dataclass(frozen=True)
class TermsNLP:
    """The NLP expression of a vocabulary objective: sum of weight * (mean over the scenarios of the
    quantity), over the sum of |weight| times each quantity's reference size on the robot (an
    objective of order one, as the named ones)."""

    terms: tuple

    def __call__(self, q: Physical):
        total, size = 0, 0.0
        for name, weight in self.terms:
            rows = _per_scenario(name, q)
            total = total + weight * sum(rows) / len(rows)
            size += abs(weight) * q.sizes[name]
        return total / size


@dataclass(frozen=True)
class TermsValue:
    """The value of a vocabulary objective on a simulated gait: sum of weight * (mean over the
    scenarios of the quantity) in the quantities' units."""

    terms: tuple

    def __call__(self, cycle: Cycle) -> float:
        return float(sum(w * np.mean(quantity_values(name, cycle)) for name, w in self.terms))

    def magnitude(self, cycle: Cycle) -> float:
        """Sum of |weight * term|: the size a difference of the value is relative to (a sum of
        terms of both signs may be near zero where none of its terms is)."""
        return float(sum(abs(w * np.mean(quantity_values(name, cycle))) for name, w in self.terms))


def vocabulary_objective(objective: str, terms=None) -> UserObjective:
    """The :class:`~ocp_crawl.ocp.quantities.UserObjective` of a vocabulary objective other than the
    named ones ("min:W_plus", "min:sum" with ``terms``, ...); ValueError naming what is wrong."""
    if objective not in VOCABULARY or objective in NAMED:
        raise ValueError(f"vocabulary_objective: {objective!r} is not one of {VOCABULARY}")
    if objective == SUM:
        pairs = check_terms(terms)
        units = {QUANTITIES[n].unit for n, _ in pairs}
        unit = units.pop() if len(units) == 1 else "-"
        sense = "min"
    else:
        if terms:
            raise ValueError(f"OCPSettings.terms: only objective {SUM!r} takes terms, not "
                             f"{objective!r}")
        sense, name = objective.split(":")
        pairs = ((name, 1.0),)
        unit = QUANTITIES[name].unit
    work = any(n in _POSITIVE_ONLY for n, _ in pairs)
    return UserObjective(objective.split(":")[1], TermsNLP(pairs), TermsValue(pairs), sense, unit,
                         1.0, work)


def terms_text(terms) -> str:
    """E.g. "1 W_plus + 10 mean_torque_sq" (the quantities in their SI units)."""
    return " + ".join(f"{w:g} {n}" for n, w in terms).replace("+ -", "- ")


def resolve_objective(objective: str, user: UserObjective | None, terms, robust: str) -> tuple:
    """The settings' (objective, user_objective, terms) from what was given: a vocabulary form of a
    named objective under its name, another vocabulary objective built as a user objective, a user
    objective under its label; ValueError (naming the ``OCPSettings`` field) for a combination that
    says two things or that the objective cannot take."""
    choices = OBJECTIVES + VOCABULARY
    if user is not None and isinstance(user.nlp, TermsNLP):
        user = None  # built from an earlier objective (dataclasses.replace): built again below
    if objective not in choices and (user is None or objective != user.label):
        raise ValueError(f"OCPSettings.objective must be one of {choices}, got {objective!r}")
    if terms is not None and objective != SUM:
        raise ValueError(f"OCPSettings.terms: only objective {SUM!r} takes terms, not "
                         f"{objective!r}")
    if user is not None and objective not in (user.label, "max_speed"):  # default, or its label
        raise ValueError(f"OCPSettings: objective {objective!r} and user_objective {user.label!r}: "
                         "give one")
    objective = canonical(objective)  # the same NLP under its name
    if user is None:
        if objective not in VOCABULARY:
            return objective, None, None
        if robust != "mean":
            raise ValueError(f"OCPSettings.robust: the objective {objective!r} is the mean over "
                             "the friction scenarios; the worst is available for max:speed and "
                             "min:CoT_plus (bound the others in every scenario with constraints)")
        return objective, vocabulary_objective(objective, terms), terms and dict(terms)
    if not isinstance(user, UserObjective):
        raise ValueError(f"OCPSettings.user_objective must be a UserObjective, got {user!r}")
    if robust != "mean":
        raise ValueError("OCPSettings.robust: a user objective takes the scenarios' numbers itself "
                         "(Physical.S, Cycle.S are per scenario); robust must stay 'mean'")
    return user.label, user, terms
