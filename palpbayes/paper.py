"""The paper's published numbers (docs/design.md §2): specimens, tips, robot estimates.

UR3e robotic palpation of polyethylene foam with an Instron 4502 compression test as ground
truth.  Used by the simulator (to reproduce the campaign) and by the comparison tables (the
column of published robot numbers).
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import NamedTuple

import pandas as pd

from .contact import Tip

__all__ = [
    "Material",
    "RobotEstimate",
    "PAPER_MATERIALS",
    "PAPER_TIPS",
    "PAPER_ROBOT_ESTIMATES",
    "PAPER_SURFACE_ERROR_M",
    "paper_robot_estimates_frame",
]


@dataclass(frozen=True)
class Material:
    """A foam specimen material with its ground truth.

    Attributes
    ----------
    name
        Label (used in file names).
    E_pa, E_sd_pa
        [Pa] Young's modulus (Instron mean) and its between-specimen sd.
    thickness_m
        [m] Specimen height h.
    width_m, length_m
        [m] Block footprint.
    """

    name: str
    E_pa: float
    E_sd_pa: float
    thickness_m: float
    width_m: float = 0.05
    length_m: float = 0.05


class RobotEstimate(NamedTuple):
    """One published robot estimate (docs/design.md §2); err_pct = (GT - E)/GT·100."""

    material: str
    tip: str
    E_kPa: float
    sd_kPa: float
    err_pct: float


#: The paper's foam specimens (docs/design.md §2): Instron 4502 E ± sd (50 mm/min, 25 Hz, up
#: to 5 mm), polyethylene foam blocks 50 × 50 mm, White 30 mm, Pink and Grey 20 mm thick.
PAPER_MATERIALS: MappingProxyType[str, Material] = MappingProxyType({
    "White": Material("White", 111e3, 13e3, 0.030),
    "Pink": Material("Pink", 136e3, 14e3, 0.020),
    "Grey": Material("Grey", 194e3, 17e3, 0.020),
})

#: The paper's tips (docs/design.md §2): flat punch radius 10 mm, sphere radius 10 mm
#: (simulated with the exact Sneddon law; the paper fitted it with Hertz), paraboloid radius
#: 11.7 mm.
PAPER_TIPS: MappingProxyType[str, Tip] = MappingProxyType({
    "flat": Tip("flat", radius=0.010),
    "sphere": Tip("sphere", radius=0.010),
    "paraboloid": Tip("paraboloid", radius=0.0117),
})

#: The paper's published robot estimates E ± sd [kPa] and error vs ground truth [%]
#: (docs/design.md §2), as printed (err = (GT - E)/GT).
#: ``pandas.DataFrame(PAPER_ROBOT_ESTIMATES)`` gives the table.
#: Caution: the printed sphere errors do not follow from the printed E and GT: recomputed they
#: are -11.5 / -5.9 / -4.2 % against the printed -10.8 / -4.1 / -5.9 % (Pink and Grey look
#: swapped); flat and paraboloid agree to 0.1 %.  Tables should recompute err from E_kPa.
PAPER_ROBOT_ESTIMATES: tuple[RobotEstimate, ...] = (
    RobotEstimate("White", "flat", 119.6, 10.8, -7.7),
    RobotEstimate("Pink", "flat", 154.5, 9.4, -13.6),
    RobotEstimate("Grey", "flat", 227.5, 7.4, -17.2),
    RobotEstimate("White", "sphere", 123.8, 7.4, -10.8),
    RobotEstimate("Pink", "sphere", 144.0, 12.7, -4.1),
    RobotEstimate("Grey", "sphere", 202.2, 20.3, -5.9),
    RobotEstimate("White", "paraboloid", 104.8, 6.3, 5.5),
    RobotEstimate("Pink", "paraboloid", 123.2, 10.8, 9.4),
    RobotEstimate("Grey", "paraboloid", 174.0, 19.6, 10.3),
)

#: The paper's mean surface-position error [m] by tip (docs/design.md §2).
PAPER_SURFACE_ERROR_M: MappingProxyType[str, float] = MappingProxyType(
    {"sphere": 0.38e-3, "paraboloid": 0.39e-3}
)


def paper_robot_estimates_frame() -> pd.DataFrame:
    """A fresh table of :data:`PAPER_ROBOT_ESTIMATES`: material, tip, E_kPa, sd_kPa, err_pct."""
    return pd.DataFrame(PAPER_ROBOT_ESTIMATES, columns=RobotEstimate._fields)
