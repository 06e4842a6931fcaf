"""The indentation trace: time, tip height and force in SI units, plus metadata.

Conventions (docs/design.md §5): z is *up* in the robot base frame, so pressing moves the tip
down and depth is d = z_surf - z; force is the compressive normal force, positive when pressing.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from .contact import Tip
from .errors import DataFileError, InputError, NoContactError
from .units import format_force, format_length

__all__ = ["IndentationTrace", "SEGMENTS", "parse_segments"]

#: Names of the segments of one palpation cycle, in the order they happen; the codes stored in
#: :attr:`IndentationTrace.segment` index this tuple.
SEGMENTS = ("approach", "hold", "retract")


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
    segment
        Per-sample segment code, an index into :data:`SEGMENTS` (0 approach, 1 hold,
        2 retract), non-decreasing in time (one cycle); None when not known (the trace is read
        as one loading segment, hold and retract told apart by the motion alone).

    Raises
    ------
    DataFileError
        If arrays differ in length, have fewer than 3 samples, hold NaN/inf, or time is not
        strictly increasing; if ``segment`` is not a code of :data:`SEGMENTS` per sample in
        time order; if ``thickness`` or ``rest_time`` is not a positive (non-negative)
        number or ``repetition`` not a whole number.  The message names ``source``.

    Notes
    -----
    The arrays are stored read-only.  An array the caller can still write to is copied first,
    so the caller's own arrays are never frozen (nor can they change the trace afterwards).
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
    segment: np.ndarray | None = None

    def __post_init__(self) -> None:
        where = self.source or f"trace {self.trace_id!r}"
        arrays = {}
        for name in ("time", "z", "force"):
            a = np.asarray(getattr(self, name), dtype=float)
            if not (a.flags.c_contiguous and _frozen(a)):
                a = np.array(a, dtype=float, order="C")  # our own copy, safe to freeze
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
        if self.segment is not None:
            object.__setattr__(self, "segment", _segment_codes(self.segment, arrays["time"].size,
                                                               where))
        for name, must, example in (("thickness", "positive", "0.02 [m]"),
                                    ("rest_time", "non-negative", "60.0 [s]")):
            v = getattr(self, name)
            if v is None:
                continue
            if isinstance(v, bool) or not isinstance(v, numbers.Real):
                raise DataFileError(where, f"{name} {v!r} is not a number",
                                    f"give it as a number, e.g. {name}={example}")
            if not (np.isfinite(v) and (v > 0 if must == "positive" else v >= 0)):
                unit = "m" if name == "thickness" else "s"
                raise DataFileError(where, f"{name} {v!r} {unit} must be {must}")
            object.__setattr__(self, name, float(v))
        rep = self.repetition
        if rep is not None:
            if isinstance(rep, bool) or not isinstance(rep, numbers.Real) or \
                    not (np.isfinite(rep) and float(rep) == round(float(rep))):
                raise DataFileError(where, f"repetition {rep!r} is not a whole number",
                                    "number the repetitions 1, 2, 3 ...")
            object.__setattr__(self, "repetition", int(rep))

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
        held for several samples, the segment ends at the first of them.  A trace that records
        its segments ends its loading within the approach (a tip that sinks on during a hold,
        as under force control, would otherwise take the hold into the loading).
        """
        z = self.z
        if self.segment is not None and np.any(self.segment == 0):
            z = z[: int(np.flatnonzero(self.segment == 0)[-1]) + 1]
        end = int(np.argmin(z)) + 1
        if end < 3:
            raise NoContactError(
                f"{self.source or self.trace_id}: the tip never moves down (deepest point at "
                f"sample {end - 1}); is z down-positive? flip it with --z-sign -1 (z_sign=-1 "
                "in the API)"
            )
        return self._slice(slice(0, end))

    def depth_window(
        self, z_surf: float, depth_min: float = 0.0, depth_max: float = np.inf
    ) -> IndentationTrace:
        """Samples whose depth d = z_surf - z lies in [depth_min, depth_max] [m].

        Raises
        ------
        InputError
            If fewer than 3 samples lie in the window (the message names the window).
        """
        d = z_surf - self.z
        keep = (d >= depth_min) & (d <= depth_max)
        window = (f"of at least {format_length(depth_min, 4)}" if np.isposinf(depth_max) else
                  f"in [{format_length(depth_min, 4)}, {format_length(depth_max, 4)}]")
        self._check_window(keep, f"have a depth {window} below z_surf = "
                           f"{format_length(z_surf, 6)}")
        return self._slice(keep)

    def above(self, z_min: float) -> IndentationTrace:
        """Samples with z >= z_min [m] (drop the deepest part).

        Raises
        ------
        InputError
            If fewer than 3 samples lie above ``z_min``.
        """
        keep = self.z >= z_min
        self._check_window(keep, f"have z >= {format_length(z_min, 6)}")
        return self._slice(keep)

    def _check_window(self, keep: np.ndarray, what: str) -> None:
        n = int(np.count_nonzero(keep))
        if n < 3:
            raise InputError(
                f"{self.source or self.trace_id}: only {n} of {self.n_points} samples {what}; "
                "a trace needs at least 3: widen the window"
            )

    def _slice(self, index) -> IndentationTrace:
        return replace(
            self, time=self.time[index], z=self.z[index], force=self.force[index],
            segment=None if self.segment is None else self.segment[index],
        )

    @property
    def segment_names(self) -> tuple[str, ...]:
        """The segments the trace holds, in time order (``()`` when :attr:`segment` is None)."""
        if self.segment is None:
            return ()
        return tuple(SEGMENTS[c] for c in np.unique(self.segment))

    def segments(self, names: tuple[str, ...] | list[str] | str) -> IndentationTrace:
        """The samples of the named segments (e.g. ``("approach", "hold")``, ``"hold"`` or
        ``"all"``: :func:`parse_segments`), in time order.

        Raises
        ------
        InputError
            If a name is not one of :data:`SEGMENTS`, or the trace does not record segments,
            or lacks one of them (the message names what is missing and what the trace has).
        """
        where = self.source or f"trace {self.trace_id!r}"
        names = parse_segments(names)
        if self.segment is None:
            raise InputError(f"{where}: the trace does not record its segments, so the "
                             f"{', '.join(names)} samples cannot be told apart; give the "
                             "file a 'segment' column (approach, hold, retract) or read it "
                             "with segments from the motion")
        missing = [n for n in names if n not in self.segment_names]
        if missing:
            has = ", ".join(self.segment_names) or "none"
            raise InputError(f"{where}: asked for the {' and '.join(missing)} segment"
                             f"{'s' if len(missing) > 1 else ''}, but the trace has only "
                             f"{has}; record a {missing[0]} or leave it out of --segments")
        keep = np.isin(self.segment, [SEGMENTS.index(n) for n in names])
        self._check_window(keep, f"lie in the {', '.join(names)} segments")
        return self._slice(keep)

    def max_depth(self, z_surf: float) -> float:
        """[m] Deepest indentation for a given surface height."""
        return float(z_surf - self.z.min())

    def __repr__(self) -> str:
        tip = self.tip.describe() if self.tip else "no tip"
        return (
            f"IndentationTrace({self.trace_id!r}, {self.n_points} points, {tip}, "
            f"z {format_length(self.z.min(), 6)}..{format_length(self.z.max(), 6)}, "
            f"F {format_force(self.force.min())}..{format_force(self.force.max())})"
        )


def parse_segments(segments: str | Sequence[str]) -> tuple[str, ...]:
    """The segment names asked for, in :data:`~palpbayes.trace.SEGMENTS` order.

    Parameters
    ----------
    segments
        ``"all"`` (every name), a comma-separated string (``"approach,hold"``) or a sequence
        of names of :data:`~palpbayes.trace.SEGMENTS`.

    Raises
    ------
    InputError
        For an unknown name or none at all.
    """
    if isinstance(segments, str):
        if segments.strip().lower() == "all":
            return SEGMENTS
        names = [n.strip().lower() for n in segments.split(",")]
    else:
        try:
            names = [str(n).strip().lower() for n in segments]
        except TypeError:
            raise InputError(f"segments {segments!r} must be 'all', names separated by commas "
                             f"or a list of names ({', '.join(SEGMENTS)})") from None
    names = [n for n in names if n]
    bad = [n for n in names if n not in SEGMENTS]
    if bad or not names:
        what = f"unknown segment {bad[0]!r}" if bad else "no segment given"
        raise InputError(f"{what}; give 'all' or names from {', '.join(SEGMENTS)}, e.g. "
                         "segments='approach,hold'")
    return tuple(n for n in SEGMENTS if n in names)


def _segment_codes(segment, n: int, where: str) -> np.ndarray:
    """``segment`` (codes or names of :data:`SEGMENTS`) as a read-only int8 array of length n."""
    raw = np.asarray(segment)
    if raw.ndim != 1 or raw.size != n:
        raise DataFileError(where, f"column 'segment' has {raw.size} value(s) for {n} samples")
    if raw.dtype.kind in "OUS":
        names = np.char.strip(np.char.lower(raw.astype(str)))
        bad = ~np.isin(names, SEGMENTS)
        if bad.any():
            i = int(np.argmax(bad))
            raise DataFileError(where, f"column 'segment' has {raw.tolist()[i]!r} at data "
                                f"row {i + 1}",
                                f"use {', '.join(SEGMENTS)}")
        codes = np.zeros(n, dtype=np.int8)
        for c, name in enumerate(SEGMENTS):
            codes[names == name] = c
    else:
        values = raw.astype(float)
        bad = ~np.isin(values, np.arange(len(SEGMENTS)))
        if bad.any():
            i = int(np.argmax(bad))
            raise DataFileError(where, f"column 'segment' has {raw.tolist()[i]!r} at data "
                                f"row {i + 1}",
                                f"use the codes 0 ({SEGMENTS[0]}), 1 ({SEGMENTS[1]}), "
                                f"2 ({SEGMENTS[2]}) or the names")
        codes = values.astype(np.int8)
    back = np.diff(codes) < 0
    if back.any():
        i = int(np.argmax(back)) + 1
        raise DataFileError(where, f"segment goes back from {SEGMENTS[codes[i - 1]]} to "
                            f"{SEGMENTS[codes[i]]} at data row {i + 1}; a trace holds one "
                            "cycle (approach, hold, retract in that order)",
                            "split the recording into one trace per cycle")
    codes = np.ascontiguousarray(codes, dtype=np.int8)
    codes.setflags(write=False)
    return codes


def _frozen(a: np.ndarray) -> bool:
    """True if neither ``a`` nor any array it views can be written to (safe to keep)."""
    while isinstance(a, np.ndarray):
        if a.flags.writeable:
            return False
        if a.base is None:
            return True
        a = a.base
    return False  # a view of a foreign buffer (bytes, mmap): copy to be safe
