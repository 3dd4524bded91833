"""The ``[design]`` section of a problem file: the robot parameters that ``ocp-crawl codesign``
chooses with the gait, their bounds and the search's sizes (:data:`DESIGN`; the schema's other
sections: :mod:`~ocp_crawl.problem.schema`)."""
from __future__ import annotations

from ocp_crawl.model.robot import MAGNITUDE
from ocp_crawl.ocp.design import Design
from ocp_crawl.ocp.design_search import ROUNDS
from ocp_crawl.problem.keys import Key, Rule, Section, field_default, within

#: the bounds' magnitudes: those of the robot's parameters they bound
_MAGNITUDE = within(*MAGNITUDE, "the magnitudes of the robot's parameters ([robot] k, lengths)")

#: designs scanned by ocp-crawl codesign by default (the robot's own included)
DESIGN_SCAN = 9
#: the ``[design]`` section
DESIGN = Section("design", "robot parameters that ocp-crawl codesign chooses with the gait, "
                 "and their bounds (the other keys of the problem fixed)", keys=(
    Key("stiffness_min", list, "N m/rad", "lowest stiffness of each joint (one entry: every "
        "joint)", rule=_MAGNITUDE, requires=("stiffness_max",)),
    Key("stiffness_max", list, "N m/rad", "highest stiffness of each joint (one entry: every "
        "joint)", rule=_MAGNITUDE, requires=("stiffness_min",)),
    Key("lengths_min", list, "m", "shortest length of each link (one entry: every link); the "
        "total length stays the robot's, the masses follow the lengths (a uniform body)",
        rule=_MAGNITUDE, requires=("lengths_max",)),
    Key("lengths_max", list, "m", "longest length of each link (one entry: every link)",
        rule=_MAGNITUDE, requires=("lengths_min",)),
    Key("min_reduced_stiffness", float, "-", "smallest stick-stick reduced stiffness of the "
        "equilibrium at every step of the chosen gait, over M g L (0: any short of a fold; soft "
        "joints reach folds, where the robot snaps through)",
        default=field_default(Design, "min_reduced_stiffness"),
        rule=Rule(lambda v: 0 <= v < 1, "in [0, 1)")),
    Key("scan", int, "-", "designs scanned, each with its best harmonic gait, the robot's own "
        "first; the co-design NLP starts from the best", default=DESIGN_SCAN,
        rule=within(1, 256, "each design is a search of its harmonic gaits")),
    Key("search_rounds", int, "-", "rounds of the local search after the co-design NLP (0: "
        "none; most of the time after the scan)", default=ROUNDS,
        rule=within(0, 20, "each round is a few OCP solves")),
))
