"""How a kind's amounts read in words: a depth inside a threshold, a limit crossed.

Reasons and records state an amount in the unit of the kind that owns the
constraint: a length in mm, an angle in deg, a joint's value as it is (rad or m).
Each :class:`~clik.constraints.kind.ConstraintKind` says which
(:attr:`~clik.constraints.kind.ConstraintKind.depth_measure`,
:attr:`~clik.constraints.kind.ConstraintKind.limit_words`), and nothing else switches
on a kind to write them: :mod:`clik.constraints.recovery` and
:mod:`clik.constraints.violations` read them through the registry.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Measure:
    """How an amount is written: ``amount * scale`` in ``unit``, to ``digits``.

    Attributes:
        unit: The unit written after the number (``"mm"``, ``"deg"``), or ``""``: the
            amount as it is, in the kind's own unit (rad or m, m^p).
        scale: The written number per unit of the amount (1e3 for [m] in mm).
        digits: The number's format (``".3g"``).
    """

    unit: str = ""
    scale: float = 1.0
    digits: str = ".4g"

    def format(self, amount: float) -> str:
        """``"8.8 mm"`` (``0.0088`` in :data:`MILLIMETRES`), ``"0.01273"`` (:data:`AS_IS`)."""
        number = f"{amount * self.scale:{self.digits}}"
        return f"{number} {self.unit}" if self.unit else number


AS_IS = Measure()
"""The amount in the kind's own unit, four digits (rad or m, m^p)."""
MILLIMETRES = Measure("mm", 1e3, ".3g")
"""A length [m] written in mm."""
DEGREES = Measure("deg", 180.0 / math.pi, ".3g")
"""An angle [rad] written in deg."""


@dataclass(frozen=True)
class LimitWords:
    """How a crossed limit of a kind reads in a reason (a violation record's words).

    Attributes:
        phrase: What happened, ``{}`` where the amount goes: ``"crossed by {}"``,
            ``"penetrated {} deep"``.
        measure: How the amount (the worst excursion past the limit) is written.
        penetration: The limit is a surface the robot went into (an obstacle, another
            link): such a record is the worst of a run before any excursion.
    """

    phrase: str
    measure: Measure
    penetration: bool = False

    def describe(self, constraint: str, worst: float) -> str:
        """``"obstacle:ball:link4 penetrated 3.2 mm deep"``."""
        return f"{constraint} {self.phrase.format(self.measure.format(worst))}"


CROSSED = LimitWords("crossed by {}", AS_IS)
"""A limit crossed, the excursion in the kind's own unit (a joint's: rad or m)."""
PENETRATED = LimitWords("penetrated {} deep", MILLIMETRES, penetration=True)
"""A surface gone into, the depth in mm (an obstacle, a link pair)."""
