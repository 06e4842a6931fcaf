"""The indentation trace: time, tip height and force in SI units, plus metadata.

Conventions (DESIGN §5): z is *up* in the robot base frame, so pressing moves the tip down and
depth is d = z_surf - z; force is the compressive normal force, positive when pressing.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .contact import Tip
from .errors import DataFileError, NoContactError

__all__ = ["IndentationTrace"]


@dataclass(frozen=True, eq=False)
class IndentationTrace:
    """One palpation: arrays in SI units plus what is known about the measurement.

    Parameters
    ----------
    time
        [s] Sample times, strictly increasing.
    z
        [m] Tip height in the robot base frame (up is positive).
    force
        [N] Compressive normal force (positive when pressing).
    tip
        The indenter, or None when not yet known.
    trace_id
        Identifier used in tables and file names.
    specimen, material
        Labels.
    thickness
        [m] Specimen thickness, or None.
    repetition
        Repetition number within the (material, tip) pair.
    rest_time
        [s] Rest time before this indentation (multi-palpation stiffening), or None.
    source
        File the trace was read from, used in error messages.
    metadata
        Anything else (free-form).

    Raises
    ------
    DataFileError
        If arrays differ in length, have fewer than 3 samples, hold NaN/inf, or time is not
        strictly increasing.  The message names ``source``.
    """

    time: np.ndarray
    z: np.ndarray
    force: np.ndarray
    tip: Tip | None = None
    trace_id: str = "trace"
    specimen: str = ""
    material: str = ""
    thickness: float | None = None
    repetition: int | None = None
    rest_time: float | None = None
    source: str | None = None
    metadata: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        where = self.source or f"trace {self.trace_id!r}"
        arrays = {}
        for name in ("time", "z", "force"):
            a = np.ascontiguousarray(getattr(self, name), dtype=float)
            if a.ndim != 1:
                raise DataFileError(where, f"column '{name}' must be one-dimensional")
            bad = ~np.isfinite(a)
            if bad.any():
                i = int(np.argmax(bad))
                raise DataFileError(
                    where,
                    f"column '{name}' has {int(bad.sum())} non-finite value(s) (NaN/inf), "
                    f"first at data row {i + 1}",
                    "remove or repair those rows",
                )
            a.setflags(write=False)
            arrays[name] = a
            object.__setattr__(self, name, a)
        n = {len(a) for a in arrays.values()}
        if len(n) != 1:
            raise DataFileError(where, "columns time, z and force have different lengths")
        if len(arrays["time"]) < 3:
            raise DataFileError(
                where,
                f"only {len(arrays['time'])} data row(s); a trace needs at least 3",
                "check that the file holds the whole recording",
            )
        dt = np.diff(arrays["time"])
        if np.any(dt <= 0):
            i = int(np.argmax(dt <= 0))
            kind = "repeats" if dt[i] == 0 else "decreases"
            raise DataFileError(
                where,
                f"time {kind} at data row {i + 2} "
                f"({arrays['time'][i]:g} s -> {arrays['time'][i + 1]:g} s); time must be "
                "strictly increasing",
                "sort the rows by time and drop duplicated samples",
            )
        if self.thickness is not None and not (np.isfinite(self.thickness) and self.thickness > 0):
            raise DataFileError(where, f"thickness {self.thickness!r} m must be positive")

    # ------------------------------------------------------------------ properties
    @property
    def n_points(self) -> int:
        """Number of samples."""
        return int(self.time.size)

    @property
    def sample_rate(self) -> float:
        """[Hz] Median sample rate."""
        return float(1.0 / np.median(np.diff(self.time)))

    def replace(self, **changes) -> IndentationTrace:
        """A copy with some fields changed (arrays are re-validated)."""
        return replace(self, **changes)

    # ------------------------------------------------------------------ segments
    def loading_segment(self) -> IndentationTrace:
        """Approach and indentation only: samples up to the deepest point (lowest z).

        The hold and the retract (tip moving up again) are dropped.  If the deepest point is
        held for several samples, the segment ends at the first of them.
        """
        end = int(np.argmin(self.z)) + 1
        if end < 3:
            raise NoContactError(
                f"{self.source or self.trace_id}: the tip never moves down (deepest point at "
                f"sample {end - 1}); is z up-positive? use the z sign option"
            )
        return self._slice(slice(0, end))

    def depth_window(
        self, z_surf: float, depth_min: float = 0.0, depth_max: float = np.inf
    ) -> IndentationTrace:
        """Samples whose depth d = z_surf - z lies in [depth_min, depth_max] [m]."""
        d = z_surf - self.z
        keep = (d >= depth_min) & (d <= depth_max)
        return self._slice(keep)

    def above(self, z_min: float) -> IndentationTrace:
        """Samples with z >= z_min [m] (drop the deepest part)."""
        return self._slice(self.z >= z_min)

    def _slice(self, index) -> IndentationTrace:
        return replace(
            self, time=self.time[index], z=self.z[index], force=self.force[index]
        )

    def max_depth(self, z_surf: float) -> float:
        """[m] Deepest indentation for a given surface height."""
        return float(z_surf - self.z.min())

    def __repr__(self) -> str:
        tip = self.tip.describe() if self.tip else "no tip"
        return (
            f"IndentationTrace({self.trace_id!r}, {self.n_points} points, {tip}, "
            f"z {self.z.min() * 1e3:.3f}..{self.z.max() * 1e3:.3f} mm, "
            f"F {self.force.min():.3g}..{self.force.max():.3g} N)"
        )
