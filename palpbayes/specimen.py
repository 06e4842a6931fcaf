"""The specimen as tested: a block L × W × H (or a cylinder D × H) lying on a plate.

A :class:`Specimen` is what a user measures with a caliper.  The finite-element twin
(:mod:`palpbayes.twin.palpation`, :mod:`palpbayes.twin.compression`) models it
axisymmetrically, as the cylinder of equal footprint area (radius sqrt(L·W/pi)); for a cuboid
that is an approximation whose error against a 3-D model is measured in
``benchmarks/bench_twin_3d.py`` and docs/design.md (the specimen twin).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import GeometryError
from .units import format_length

__all__ = ["Specimen", "parse_specimen", "check_specimen_plausible", "specimen_from_sizes",
           "SPECIMEN_KINDS", "MAX_SPECIMEN_SIZE_M", "FOOTPRINT_COLUMNS"]

#: Footprints a specimen may have.
SPECIMEN_KINDS = ("cuboid", "cylinder")
#: [m] Largest plausible specimen dimension; a larger one was almost surely given in mm.
MAX_SPECIMEN_SIZE_M = 2.0


def _size(value, what: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise GeometryError(f"specimen {what} {value!r} is not a number (metres)") from None
    if not (math.isfinite(v) and v > 0):
        raise GeometryError(f"specimen {what} {value!r} m must be a positive number of metres")
    return v


def check_specimen_plausible(specimen: Specimen) -> None:
    """Reject a specimen larger than :data:`MAX_SPECIMEN_SIZE_M` in any dimension: a size in
    millimetres given as metres.

    Raises
    ------
    GeometryError
        Naming the size and the value in metres it probably should be.
    """
    for what in ("height", "length", "width", "diameter"):
        v = getattr(specimen, what)
        if v is not None and v > MAX_SPECIMEN_SIZE_M:
            raise GeometryError(
                f"specimen {what} {format_length(v, 6)} is implausibly large (more than "
                f"{format_length(MAX_SPECIMEN_SIZE_M)}); sizes are in metres: did you mean "
                f"{v * 1e-3:g}?")


@dataclass(frozen=True)
class Specimen:
    """A block of ``length`` × ``width`` × ``height``, or a cylinder of ``diameter`` ×
    ``height`` [m], pressed on its top face; ``height`` is the thickness under the tip.

    Parameters
    ----------
    height
        [m] Thickness H (the compression test's loading direction).
    length, width
        [m] Footprint of a cuboid (give both, or neither and ``diameter``).
    diameter
        [m] Footprint of a cylinder.

    Raises
    ------
    GeometryError
        A size that is not a positive number of metres, or an incomplete footprint.
    """

    height: float
    length: float | None = None
    width: float | None = None
    diameter: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "height", _size(self.height, "height"))
        box = (self.length is not None, self.width is not None)
        if self.diameter is not None:
            if any(box):
                raise GeometryError("a specimen is a cuboid (length, width) or a cylinder "
                                    "(diameter), not both")
            object.__setattr__(self, "diameter", _size(self.diameter, "diameter"))
        elif all(box):
            object.__setattr__(self, "length", _size(self.length, "length"))
            object.__setattr__(self, "width", _size(self.width, "width"))
        else:
            raise GeometryError("a specimen needs its footprint: length and width (a cuboid) "
                                "or a diameter (a cylinder), besides its height")

    @property
    def kind(self) -> str:
        """``"cuboid"`` or ``"cylinder"``."""
        return "cylinder" if self.diameter is not None else "cuboid"

    @property
    def area(self) -> float:
        """[m²] Footprint area."""
        if self.diameter is not None:
            return math.pi * self.diameter**2 / 4.0
        return self.length * self.width

    @property
    def radius(self) -> float:
        """[m] Radius of the axisymmetric twin: the cylinder of equal footprint area."""
        return math.sqrt(self.area / math.pi)

    @property
    def half_width(self) -> float:
        """[m] Shortest distance from the centre of the top face to its edge."""
        if self.diameter is not None:
            return self.diameter / 2.0
        return min(self.length, self.width) / 2.0

    @property
    def aspect(self) -> float:
        """Longest over shortest side of the footprint [-] (1 for a cylinder or a square)."""
        if self.diameter is not None:
            return 1.0
        return max(self.length, self.width) / min(self.length, self.width)

    @property
    def shape_factor(self) -> float:
        """S = loaded area / free lateral area [-] (D/(4H) for a cylinder, L·W/(2H·(L+W))
        for a cuboid): what sets how much bonded platens stiffen a compression test."""
        if self.diameter is not None:
            return self.diameter / (4.0 * self.height)
        return self.length * self.width / (2.0 * self.height * (self.length + self.width))

    def scaled(self, factor: float) -> Specimen:
        """The same specimen with every length multiplied by ``factor``."""
        if self.diameter is not None:
            return Specimen(self.height * factor, diameter=self.diameter * factor)
        return Specimen(self.height * factor, length=self.length * factor,
                        width=self.width * factor)

    def with_height(self, height: float) -> Specimen:
        """The same footprint with another height [m]."""
        return Specimen(height, self.length, self.width, self.diameter)

    def describe(self) -> str:
        """``'50 × 50 × 20 mm block'`` or ``'cylinder D 50 × H 30 mm'``."""
        def mm(v: float) -> str:
            return f"{v * 1e3:.4g}"
        if self.diameter is not None:
            return f"cylinder D {mm(self.diameter)} × H {mm(self.height)} mm"
        return f"{mm(self.length)} × {mm(self.width)} × {mm(self.height)} mm block"

    def as_text(self) -> str:
        """The command-line form ``L,W,H`` or ``D,H`` in metres (:func:`parse_specimen`)."""
        sizes = ((self.diameter, self.height) if self.diameter is not None
                 else (self.length, self.width, self.height))
        return ",".join(f"{v:.10g}" for v in sizes)


def parse_specimen(text: str) -> Specimen:
    """A :class:`Specimen` from ``"L,W,H"`` (a cuboid) or ``"D,H"`` (a cylinder) in metres.

    Raises
    ------
    GeometryError
        Not two or three comma-separated positive numbers of metres, or a size above
        :data:`MAX_SPECIMEN_SIZE_M` (millimetres given as metres).
    """
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) not in (2, 3) or not all(parts):
        raise GeometryError(
            f"specimen {text!r}: give L,W,H (a block, e.g. 0.05,0.05,0.02) or D,H (a "
            "cylinder, e.g. 0.05,0.03), in metres")
    if len(parts) == 2:
        spec = Specimen(parts[1], diameter=parts[0])
    else:
        spec = Specimen(parts[2], length=parts[0], width=parts[1])
    check_specimen_plausible(spec)
    return spec


#: Manifest columns of a specimen's footprint [m] (its height is ``thickness_m``).
FOOTPRINT_COLUMNS = ("length_m", "width_m", "diameter_m")


def specimen_from_sizes(height: float | None, length: float | None = None,
                        width: float | None = None, diameter: float | None = None
                        ) -> Specimen | None:
    """The :class:`Specimen` of a manifest row or a trace's metadata: None without a
    footprint; an error for a footprint without a height or an incomplete one.

    Raises
    ------
    GeometryError
        A footprint without ``height``, a length without a width (or the reverse), both a
        box and a diameter, or a non-positive size.
    """
    if length is None and width is None and diameter is None:
        return None
    if height is None:
        raise GeometryError("a specimen's footprint (length_m, width_m or diameter_m) needs "
                            "its height: give thickness_m (--thickness)")
    return Specimen(height, length, width, diameter)
