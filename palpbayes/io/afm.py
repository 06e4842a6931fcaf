"""Read AFM force curves and force maps (JPK, Igor, afmformats HDF5) through ``afmformats``.

Every curve of the file becomes one :class:`~palpbayes.trace.IndentationTrace`, by default of
its **approach** (``segments=("approach",)``), or of the segments asked for
(``segments="all"``: approach, hold and retract), with their codes in ``trace.segment``:

  =======================  ====================================================  ==========
  trace                    from afmformats                                       unit
  =======================  ====================================================  ==========
  ``time``                 ``time`` (else sample index / ``rate approach``),     [s]
                           minus the first kept sample's time
  ``z``                    ``tip position`` if the file has it, else             [m]
                           ``height (measured)`` + ``force`` / ``spring
                           constant`` (nanite's ``compute_tip_position``)
  ``force``                ``force`` (deflection × spring constant)              [N]
  ``segment``              afmformats' ``segment`` numbers classified as          codes
                           approach / hold / retract (below)
  ``metadata["x_m"]``,     ``position x``, ``position y`` of the curve (force     [m]
  ``metadata["y_m"]``      maps: where on the sample it was taken)
  =======================  ====================================================  ==========

Modalities: force-distance (approach, retract), stress-relaxation (approach, hold at constant
height, retract) and creep-compliance (approach, hold at constant force, retract) curves are
read; ``metadata["afm_modality"]`` says which.  The approach of all three is a force-distance
approach and fits as one.

Segments: afmformats numbers the segments of a curve (0, 1, 2 ...) without saying what they
are (JPK stress-relaxation files start with a pause before the approach), so each segment is
classified by its **motion**, the height (``height (measured)``, else ``height (piezo)``, else
the tip position) relative to the height range of the whole curve: *descending* when it goes
more than :data:`MOTION_FRACTION` (10 %) of the range below its start (its 1st percentile
below the median of its first twentieth), else *ascending* when it ends more than 10 % above
its start (medians of its last and first twentieth), else *flat* (approach and retract move
through 70-100 % of the range in the files seen, pauses and holds 0-5 %).  Then, in time
order:

1. **approach**: every segment up to and including the first descending one (a flat segment
   before it is the pre-contact baseline, e.g. the pause of a stress-relaxation file), and the
   descending segments directly after it (an approach in several speeds), except in a
   creep-compliance curve, where the segment after the approach is the hold;
2. **hold**: the following segments up to the first ascending one, whatever their motion
   (constant height in stress relaxation; at constant force the height creeps down);
3. **retract**: the first ascending segment and the ascending or flat ones after it (a pause
   after the retract);
4. a descending segment after the retract starts a second cycle: it and the rest of the curve
   are not read (``metadata["afm_segments_ignored"]`` counts their samples).

A curve without a descending segment has no approach (its segments before the first ascending
one are hold).  A curve recorded as one segment (or without a ``segment`` column) that goes
down and up again is descending, so it is read whole as its approach, as before segments were
classified; split such a trace with
:func:`palpbayes.io.motion_segments.segments_from_motion`.  Force-distance curves come out as
afmformats labels them (segment 0 approach, segment 1 retract), so their default read is
segment 0, as before segments were classified.

Units and signs: afmformats gives SI units.  The height is that of the cantilever base, up
(away from the sample) positive, and a cantilever pushed up by the sample gives a positive
force, so z is up and pressing is positive as palpbayes wants; ``force_sign``/``z_sign`` flip
them for a file that says otherwise.  The force is raw: not tared, its baseline is fitted.

A single-curve file gives a trace named after the file (``force-save-example``); a force map
(``.jpk-force-map``, QI data) gives one trace per curve, ``<stem>-<index>``, a campaign whose
traces carry their x, y.  Needs the optional extra ``afm`` (afmformats: ``pip install -e
'.[afm]' -c requirements/constraints.txt`` in a clone of the repository, ``pip install
'palpbayes[afm]'`` from a package index; the error when it is missing says which).
"""

# Long module: one job, reading AFM files through afmformats; segment classification, arrays and
#   calibration are the three steps of one read.

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..contact import Tip
from ..errors import DataFileError, InputError
from ..trace import SEGMENTS, IndentationTrace, parse_segments
from .afm_load import AFM_SUFFIXES, load_afm_curves
from .afm_workshop import is_afm_workshop_zip
from .motion_segments import segment_durations
from .tabular import check_plausible, split_trace_metadata, validate_force_sign

__all__ = ["AFM_SUFFIXES", "AFM_MODALITIES", "MOTION_FRACTION", "IGNORED", "AFMCurveInfo",
           "is_afm_file", "read_afm", "describe_afm", "classify_segments", "parse_segments",
           "load_afm_curves", "curve_metadata", "CALIBRATION_KEYS", "afm_calibration"]

#: afmformats modalities read: each starts with a force-distance approach.
AFM_MODALITIES = ("force-distance", "stress-relaxation", "creep-compliance")

#: A segment whose height changes by more than this fraction of the curve's height range is
#: descending (approach) or ascending (retract); otherwise it is flat (pause or hold).
MOTION_FRACTION = 0.10

#: Name given (by :func:`classify_segments`) to the segments of a second cycle, not read.
IGNORED = "ignored"

#: afmformats metadata -> trace metadata key (SI units).
_META = {"position x": "x_m", "position y": "y_m", "grid index x": "grid_index_x",
         "grid index y": "grid_index_y", "spring constant": "spring_constant_n_per_m",
         "sensitivity": "sensitivity_m_per_v", "curve id": "curve_id",
         "speed approach": "speed_approach_m_per_s", "format": "afm_format"}


@dataclass(frozen=True)
class AFMCurveInfo:
    """What ``palpbayes inspect`` shows of one curve: index, modality, columns, points per
    afmformats segment, position [m] (None when the file has none), what each afmformats
    segment is (``{0: "approach", 1: "retract"}``; :func:`classify_segments`), and how long
    each lasts [s], measured on the curve's time column
    (:func:`~palpbayes.io.motion_segments.segment_durations`; empty without one)."""

    index: int
    modality: str
    columns: tuple[str, ...]
    segments: dict[int, int]
    x_m: float | None
    y_m: float | None
    segment_names: dict[int, str] = field(default_factory=dict)
    durations: dict[int, float] = field(default_factory=dict)


def is_afm_file(path: str | os.PathLike) -> bool:
    """True when the file name ends with one of :data:`AFM_SUFFIXES`, or it is an AFM
    Workshop force map (:func:`palpbayes.io.afm_workshop.is_afm_workshop_zip`)."""
    name = Path(path).name.lower()
    return any(name.endswith(s) for s in AFM_SUFFIXES) or is_afm_workshop_zip(path)


def _suffix(path: Path) -> str:
    name = path.name.lower()
    return next((s for s in sorted(AFM_SUFFIXES, key=len, reverse=True) if name.endswith(s)),
                path.suffix)


def _stem(path: Path) -> str:
    return path.name[: len(path.name) - len(_suffix(path))] or path.name


def curve_metadata(curve) -> dict:
    """The curve's afmformats metadata palpbayes keeps, under trace metadata names (SI)."""
    meta = {}
    source = curve.metadata  # afmformats builds a copy of the whole metadata on each access
    have = dict.keys(source)  # its __getitem__ raises for keys it lacks
    for key, name in _META.items():
        if key not in have:
            continue
        value = source[key]
        if isinstance(value, np.generic):
            value = value.item()
        if isinstance(value, float) and not np.isfinite(value):
            continue
        meta[name] = value
    return meta


def _is_all(segments) -> bool:
    return isinstance(segments, str) and segments.strip().lower() == "all"


def _segment_ids(curve) -> np.ndarray:
    cols = set(curve.columns)
    return np.asarray(curve["segment"]) if "segment" in cols else np.zeros(len(curve), int)


def _height(curve) -> np.ndarray | None:
    """The column whose motion tells the segments apart (base height, else tip position)."""
    cols = set(curve.columns)
    name = next((c for c in ("height (measured)", "height (piezo)", "tip position")
                 if c in cols), None)
    return None if name is None else np.asarray(curve[name], dtype=float)


def classify_segments(seg: np.ndarray, height: np.ndarray | None,
                      modality: str = "force-distance") -> dict[int, str]:
    """What each afmformats segment of a curve is: approach, hold, retract or ``"ignored"``.

    See the module docstring for the rule: motion (descending / flat / ascending by more than
    :data:`MOTION_FRACTION` of the curve's height range), then order.

    Parameters
    ----------
    seg
        afmformats' ``segment`` number per sample.
    height
        [m] Height per sample (up positive); None (no height column) classifies the segments
        by their order alone: the first is the approach, the last (of two or more) the
        retract, any between them hold.
    modality
        afmformats' modality: in ``"creep-compliance"`` the segment after the approach is the
        hold (it creeps down at constant force).

    Returns
    -------
    dict
        afmformats segment number -> name, in time order.
    """
    seg = np.asarray(seg)
    # segments in time order (afmformats numbers them in time order; sort by first sample)
    ids, first = np.unique(seg, return_index=True)
    ids = ids[np.argsort(first)]
    if height is None:
        names = ["approach"] + ["hold"] * (len(ids) - 2) + ["retract"] * (len(ids) > 1)
        return {int(i): n for i, n in zip(ids, names, strict=True)}
    height = np.asarray(height, dtype=float)
    span = float(np.ptp(height)) if height.size else 0.0
    motion = []
    limit = MOTION_FRACTION * span
    for i in ids:
        h = height[seg == i]
        k = max(1, h.size // 20)
        start = float(np.median(h[:k]))
        descent = start - float(np.quantile(h, 0.01))
        rise = float(np.median(h[-k:])) - start
        motion.append(-1 if span > 0 and descent > limit else
                      1 if span > 0 and rise > limit else 0)
    names: list[str] = []
    state = "approach"  # approach before its descent, "descended" after it, hold, retract
    for m in motion:
        if state == "approach":
            names.append("approach")
            if m < 0:
                state = "descended"
            elif m > 0:  # ascending before any descent: no approach in this curve
                names[:] = ["hold"] * (len(names) - 1) + ["retract"]
                state = "retract"
        elif state == "descended":
            if m < 0 and modality != "creep-compliance":
                names.append("approach")
            elif m > 0:
                names.append("retract")
                state = "retract"
            else:
                names.append("hold")
                state = "hold"
        elif state == "hold":
            names.append("retract" if m > 0 else "hold")
            state = "retract" if m > 0 else "hold"
        elif state == "retract":
            if m < 0:
                state = IGNORED
            names.append("retract" if m >= 0 else IGNORED)
        else:
            names.append(IGNORED)
    if state == "approach":  # flat throughout: no approach
        names = ["hold"] * len(names)
    return {int(i): n for i, n in zip(ids, names, strict=True)}


def _curve_arrays(curve, index: int, source: str, wanted: tuple[str, ...] | None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
    """time [s], z [m], force [N] and segment codes of the wanted segments (None: all the
    curve has), and how they were made (trace metadata)."""
    where = f"curve {index}"
    if curve.modality not in AFM_MODALITIES:
        raise DataFileError(source, f"{where} is a {curve.modality} measurement",
                            f"palpbayes reads {', '.join(AFM_MODALITIES)} curves")
    cols = set(curve.columns)
    if "force" not in cols:
        raise DataFileError(source, f"{where} has no force column; it has "
                            f"{', '.join(sorted(cols))}")
    seg = _segment_ids(curve)
    kinds = classify_segments(seg, _height(curve), curve.modality)
    has = [n for n in SEGMENTS if n in kinds.values()]
    if wanted is None:
        wanted = tuple(has)
    missing = [n for n in wanted if n not in has]
    if missing:
        listing = ", ".join(f"{i} {n}" for i, n in kinds.items())
        raise DataFileError(
            source, f"{where} ({curve.modality}) has no {' and no '.join(missing)} segment; it "
            f"has {', '.join(has) or 'no approach, hold or retract'} (afmformats segments: "
            f"{listing})", f"read segments={','.join(has) or 'all'} instead"
            if has else "check the curve")
    ids = np.unique(seg)
    name_of = np.array([kinds[int(i)] for i in ids], dtype=object)
    code_of = np.array([SEGMENTS.index(n) if n in SEGMENTS else -1 for n in name_of], np.int8)
    where_id = np.searchsorted(ids, seg)
    sample_names = name_of[where_id]
    keep = np.isin(sample_names, wanted)
    n_keep = int(np.count_nonzero(keep))
    if n_keep < 3:
        raise DataFileError(source, f"{where}: the {', '.join(wanted)} segment(s) have "
                            f"{n_keep} point(s)", "check the curve")
    codes = code_of[where_id[keep]]
    force = np.asarray(curve["force"], dtype=float)[keep]
    how = {"afm_modality": str(curve.modality),
           "afm_segments": ", ".join(f"{i} {n}" for i, n in kinds.items())}
    ignored = int(np.count_nonzero(sample_names == IGNORED))
    if ignored:
        how["afm_segments_ignored"] = ignored
    if "tip position" in cols:
        z = np.asarray(curve["tip position"], dtype=float)[keep]
        how["z_column"] = "tip position"
    else:
        height = next((c for c in ("height (measured)", "height (piezo)") if c in cols), None)
        k = dict.get(curve.metadata, "spring constant")
        if height is None or not k or not np.isfinite(k):
            missing_what = "a height column" if height is None else "the spring constant"
            raise DataFileError(source, f"{where}: cannot compute the tip position without "
                                f"{missing_what}",
                                "export the curve with height and spring constant")
        z = np.asarray(curve[height], dtype=float)[keep] + force / float(k)
        how["z_column"] = f"{height} + force / spring constant"
    if "time" in cols:
        t = np.asarray(curve["time"], dtype=float)[keep]
        how["time_column"] = "time"
    else:
        rate = dict.get(curve.metadata, "rate approach")
        if not rate or not np.isfinite(rate):
            raise DataFileError(source, f"{where} has neither a time column nor a sample rate",
                                "export it with its time column, or give the sample rate "
                                "(palpbayes map --sample-rate HZ)")
        t = np.flatnonzero(keep) / float(rate)
        how["time_column"] = f"index / rate approach ({float(rate):g} Hz)"
    return t, z, force, codes, how


def read_afm(
    path: str | os.PathLike,
    *,
    tip: Tip | None = None,
    curves: Sequence[int] | None = None,
    segments: str | Sequence[str] = ("approach",),
    force_sign: float = 1.0,
    z_sign: float = 1.0,
    check: bool = True,
    meta_override: dict | None = None,
    **metadata,
) -> list[IndentationTrace]:
    """Read the curves of an AFM file into traces (SI units, z up, pressing positive).

    Parameters
    ----------
    path
        A file afmformats reads: ``.jpk-force``, ``.jpk-force-map``, ``.jpk-qi-data``,
        ``.jpk-qi-series``, Igor ``.ibw``, afmformats ``.h5``.
    tip
        The indenter (an AFM file does not record its geometry), stored in every trace.
    curves
        Indices of the curves to read (default all).
    segments
        Which segments of each curve to keep: names of :data:`~palpbayes.trace.SEGMENTS` as
        a sequence or a comma-separated string (``"approach,hold"``), or ``"all"`` (every
        segment the curve has).  Default the approach only.  The segments are classified by
        their motion (module docstring); ``trace.segment`` holds the code of every kept
        sample.
    force_sign, z_sign
        +1 or -1 multiplying force and z.
    check
        Reject implausible traces (:func:`palpbayes.io.tabular.check_plausible`).
    meta_override
        afmformats metadata the file lacks, SI units (an AFM Workshop map needs
        ``{"spring constant": [N/m], "sensitivity": [m/V]}``).
    **metadata
        Trace fields (``material``, ``thickness`` ...) and free metadata for every trace;
        ``trace_id`` is taken as the stem of the ids.

    Returns
    -------
    list of IndentationTrace
        One per curve; ``trace_id`` the file stem for a single curve, ``<stem>-<index>`` for a
        map; time [s] from the first kept sample, on the file's time axis (a segment left out
        leaves a gap); ``metadata`` has ``curve_index``, ``afm_modality``, ``afm_segments``
        (each afmformats segment and its name), ``x_m``/``y_m`` [m] when the file gives the
        position, the spring constant and how z and time were made.

    Raises
    ------
    DataFileError
        Missing or unreadable file, a modality other than :data:`AFM_MODALITIES`, missing
        columns, a segment asked for that the curve lacks (naming the curve, what it has and
        what is missing), a curve index out of range, implausible sign or units (naming the
        curve).
    InputError
        An unknown segment name or sign.
    MissingExtraError
        afmformats is not installed: "reading .jpk-force files needs the optional extra afm
        (afmformats is not installed): pip install ..."
        (:func:`palpbayes.io.extras.install_command`).
    """
    force_sign = validate_force_sign(force_sign, allow_auto=False)
    if z_sign not in (1, -1):
        raise InputError(f"z_sign must be +1 or -1, got {z_sign!r}")
    wanted = None if _is_all(segments) else parse_segments(segments)
    if "segment" in metadata:
        raise InputError("metadata may not set 'segment'; it comes from the file (choose the "
                         "segments with segments=...)")
    data, source = load_afm_curves(path, meta_override)
    stem = str(metadata.pop("trace_id", None) or _stem(Path(path)))
    chosen = range(len(data)) if curves is None else list(curves)
    bad = [i for i in chosen if not 0 <= i < len(data)]
    if bad:
        raise DataFileError(source, f"has {len(data)} curve(s), no curve {bad[0]}",
                            f"give an index from 0 to {len(data) - 1}")
    traces = []
    for i in chosen:
        t, z, force, codes, how = _curve_arrays(data[i], i, source, wanted)
        kwargs, free = split_trace_metadata(metadata, {
            "reader": "afm", "curve_index": i, "n_curves": len(data), **curve_metadata(data[i]),
            **how, "force_sign": force_sign, "z_sign": float(z_sign)})
        tid = stem if len(data) == 1 else f"{stem}-{i}"
        trace = IndentationTrace(time=t - t[0], z=z_sign * z, force=force_sign * force, tip=tip,
                                 trace_id=tid, source=source, metadata=free, segment=codes,
                                 **kwargs)
        if check:
            try:
                check_plausible(trace)
            except DataFileError as exc:
                if len(data) == 1:
                    raise
                raise DataFileError(source, f"curve {i}: {exc.problem}", exc.fix) from None
        traces.append(trace)
    return traces


def describe_afm(path: str | os.PathLike, meta_override: dict | None = None
                 ) -> list[AFMCurveInfo]:
    """The curves of an AFM file: modality, columns, points per segment, what each segment is
    (:func:`classify_segments`), position, and each segment's duration measured on the time
    column (not the header's ``duration`` fields)."""
    data, _ = load_afm_curves(path, meta_override)
    out = []
    for i, c in enumerate(data):
        seg = _segment_ids(c)
        values, counts = np.unique(seg, return_counts=True)
        meta = curve_metadata(c)
        durations = (segment_durations(np.asarray(c["time"], dtype=float), seg)
                     if "time" in set(c.columns) else {})
        out.append(AFMCurveInfo(i, c.modality, tuple(c.columns),
                                {int(v): int(n) for v, n in zip(values, counts, strict=True)},
                                meta.get("x_m"), meta.get("y_m"),
                                classify_segments(seg, _height(c), c.modality), durations))
    return out


#: afmformats metadata keys of a curve's calibration and acquisition settings (SI units):
#: what :func:`afm_calibration` reads and ``palpbayes inspect`` shows.
CALIBRATION_KEYS = ("spring constant", "sensitivity", "setpoint", "speed approach",
                    "rate approach", "duration approach", "duration intermediate")


def afm_calibration(path: str | os.PathLike, meta_override: dict | None = None
                    ) -> list[dict[str, float]]:
    """The calibration and settings the file records, per curve (read only).

    Parameters
    ----------
    path
        An AFM file afmformats reads.
    meta_override
        afmformats metadata filling what the file lacks (as for :func:`describe_afm`); its
        keys are left out of the result, since they are not the file's.

    Returns
    -------
    list of dict
        One dict per curve, in file order: the keys of :data:`CALIBRATION_KEYS` the curve
        has with a finite value, in afmformats' SI units (spring constant [N/m], sensitivity
        [m/V], setpoint [N], speed approach [m/s], rate approach [Hz], durations [s]).
    """
    data, _ = load_afm_curves(path, meta_override)
    given = set(meta_override or {})
    out = []
    for c in data:
        source = c.metadata  # a copy of the whole metadata on each access: once per curve
        have = dict.keys(source)  # its __getitem__ raises for keys it lacks
        values = {}
        for key in CALIBRATION_KEYS:
            if key in given or key not in have:
                continue
            try:
                value = float(source[key])
            except (TypeError, ValueError):
                continue
            if np.isfinite(value):
                values[key] = value
        out.append(values)
    return out
