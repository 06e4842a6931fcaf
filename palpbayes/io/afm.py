"""Read AFM force curves and force maps (JPK, Igor, afmformats HDF5) through ``afmformats``.

Every force-distance curve of the file becomes one :class:`~palpbayes.trace.IndentationTrace`
of its **approach segment** (``segment == 0``):

  =======================  ====================================================  ==========
  trace                    from afmformats                                       unit
  =======================  ====================================================  ==========
  ``time``                 ``time`` (else sample index / ``rate approach``)      [s]
  ``z``                    ``tip position`` if the file has it, else             [m]
                           ``height (measured)`` + ``force`` / ``spring
                           constant`` (nanite's ``compute_tip_position``)
  ``force``                ``force`` (deflection × spring constant)              [N]
  ``metadata["x_m"]``,     ``position x``, ``position y`` of the curve (force     [m]
  ``metadata["y_m"]``      maps: where on the sample it was taken)
  =======================  ====================================================  ==========

Units and signs: afmformats gives SI units.  The height is that of the cantilever base, up
(away from the sample) positive, and a cantilever pushed up by the sample gives a positive
force, so z is up and pressing is positive as palpbayes wants; ``force_sign``/``z_sign`` flip
them for a file that says otherwise.  The force is raw: not tared, its baseline is fitted.

A single-curve file gives a trace named after the file (``force-save-example``); a force map
(``.jpk-force-map``, QI data) gives one trace per curve, ``<stem>-<index>``, a campaign whose
traces carry their x, y.  Needs the optional extra ``pip install 'palpbayes[afm]'``.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..contact import Tip
from ..errors import DataFileError, InputError
from ..trace import IndentationTrace
from .extras import import_extra
from .tabular import check_file, check_plausible, split_trace_metadata, validate_force_sign

__all__ = ["AFM_SUFFIXES", "AFMCurveInfo", "is_afm_file", "read_afm", "describe_afm"]

#: File suffixes read through afmformats (its .txt/.csv/.tab/.zip formats are not claimed:
#: palpbayes reads those as its own tables).
AFM_SUFFIXES = (".jpk-force", ".jpk-force-map", ".jpk-qi-data", ".jpk-qi-series", ".ibw",
                ".h5")

#: afmformats metadata -> trace metadata key (SI units).
_META = {"position x": "x_m", "position y": "y_m", "grid index x": "grid_index_x",
         "grid index y": "grid_index_y", "spring constant": "spring_constant_n_per_m",
         "sensitivity": "sensitivity_m_per_v", "curve id": "curve_id",
         "speed approach": "speed_approach_m_per_s", "format": "afm_format"}


@dataclass(frozen=True)
class AFMCurveInfo:
    """What ``palpbayes inspect`` shows of one curve: index, modality, columns, points per
    segment, position [m] (None when the file has none)."""

    index: int
    modality: str
    columns: tuple[str, ...]
    segments: dict[int, int]
    x_m: float | None
    y_m: float | None


def is_afm_file(path: str | os.PathLike) -> bool:
    """True when the file name ends with one of :data:`AFM_SUFFIXES`."""
    name = Path(path).name.lower()
    return any(name.endswith(s) for s in AFM_SUFFIXES)


def _suffix(path: Path) -> str:
    name = path.name.lower()
    return next((s for s in sorted(AFM_SUFFIXES, key=len, reverse=True) if name.endswith(s)),
                path.suffix)


def _stem(path: Path) -> str:
    return path.name[: len(path.name) - len(_suffix(path))] or path.name


def _load(path: str | os.PathLike) -> tuple[list, str]:
    """afmformats' curves of a file, every library error wrapped."""
    path = Path(path)
    source = str(path)
    afmformats = import_extra("afm", f"reading {_suffix(path)} files")
    check_file(path, source)
    try:
        curves = afmformats.load_data(path)
    except (KeyboardInterrupt, SystemExit, GeneratorExit):
        raise
    except BaseException as exc:  # afmformats' own errors derive from BaseException
        raise DataFileError(source, f"afmformats cannot read it ({type(exc).__name__}: "
                            f"{exc})".replace("\n", " "),
                            "check that the file is complete and of the kind its name says; "
                            f"afmformats reads {', '.join(AFM_SUFFIXES)}") from None
    if not curves:
        raise DataFileError(source, "holds no curves", "check the file")
    return list(curves), source


def _metadata(curve) -> dict:
    meta = {}
    have = dict.keys(curve.metadata)  # its __getitem__ raises for keys it lacks
    for key, name in _META.items():
        if key not in have:
            continue
        value = curve.metadata[key]
        if isinstance(value, np.generic):
            value = value.item()
        if isinstance(value, float) and not np.isfinite(value):
            continue
        meta[name] = value
    return meta


def _approach(curve, index: int, source: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """time [s], z [m], force [N] of the approach segment, and how z and time were made."""
    where = f"curve {index}"
    if curve.modality != "force-distance":
        raise DataFileError(source, f"{where} is a {curve.modality} measurement",
                            "palpbayes reads force-distance (indentation) curves")
    cols = set(curve.columns)
    if "force" not in cols:
        raise DataFileError(source, f"{where} has no force column; it has "
                            f"{', '.join(sorted(cols))}")
    seg = np.asarray(curve["segment"]) if "segment" in cols else np.zeros(len(curve), int)
    appr = seg == 0
    if np.count_nonzero(appr) < 3:
        raise DataFileError(source, f"{where}: the approach segment has "
                            f"{np.count_nonzero(appr)} point(s)", "check the curve")
    force = np.asarray(curve["force"], dtype=float)[appr]
    how = {}
    if "tip position" in cols:
        z = np.asarray(curve["tip position"], dtype=float)[appr]
        how["z_column"] = "tip position"
    else:
        height = next((c for c in ("height (measured)", "height (piezo)") if c in cols), None)
        k = dict.get(curve.metadata, "spring constant")
        if height is None or not k or not np.isfinite(k):
            missing = "a height column" if height is None else "the spring constant"
            raise DataFileError(source, f"{where}: cannot compute the tip position without "
                                f"{missing}", "export the curve with height and spring constant")
        z = np.asarray(curve[height], dtype=float)[appr] + force / float(k)
        how["z_column"] = f"{height} + force / spring constant"
    if "time" in cols:
        t = np.asarray(curve["time"], dtype=float)[appr]
        how["time_column"] = "time"
    else:
        rate = dict.get(curve.metadata, "rate approach")
        if not rate or not np.isfinite(rate):
            raise DataFileError(source, f"{where} has neither a time column nor a sample rate",
                                "export the curve with its time column")
        t = np.arange(force.size) / float(rate)
        how["time_column"] = f"index / rate approach ({float(rate):g} Hz)"
    return t, z, force, how


def read_afm(
    path: str | os.PathLike,
    *,
    tip: Tip | None = None,
    curves: Sequence[int] | None = None,
    force_sign: float = 1.0,
    z_sign: float = 1.0,
    check: bool = True,
    **metadata,
) -> list[IndentationTrace]:
    """Read the approach curves of an AFM file into traces (SI units, z up, pressing positive).

    Parameters
    ----------
    path
        A file afmformats reads: ``.jpk-force``, ``.jpk-force-map``, ``.jpk-qi-data``,
        ``.jpk-qi-series``, Igor ``.ibw``, afmformats ``.h5``.
    tip
        The indenter (an AFM file does not record its geometry), stored in every trace.
    curves
        Indices of the curves to read (default all).
    force_sign, z_sign
        +1 or -1 multiplying force and z.
    check
        Reject implausible traces (:func:`palpbayes.io.tabular.check_plausible`).
    **metadata
        Trace fields (``material``, ``thickness`` ...) and free metadata for every trace;
        ``trace_id`` is taken as the stem of the ids.

    Returns
    -------
    list of IndentationTrace
        One per curve; ``trace_id`` the file stem for a single curve, ``<stem>-<index>`` for a
        map; ``metadata`` has ``curve_index``, ``x_m``/``y_m`` [m] when the file gives the
        position, the spring constant and how z and time were made.

    Raises
    ------
    DataFileError
        Missing or unreadable file, not force-distance data, missing columns, an empty approach,
        a curve index out of range, implausible sign or units (naming the curve).
    MissingExtraError
        afmformats is not installed: "reading .jpk-force files needs the optional extra:
        pip install 'palpbayes[afm]'".
    """
    force_sign = validate_force_sign(force_sign, allow_auto=False)
    if z_sign not in (1, -1):
        raise InputError(f"z_sign must be +1 or -1, got {z_sign!r}")
    data, source = _load(path)
    stem = str(metadata.pop("trace_id", None) or _stem(Path(path)))
    chosen = range(len(data)) if curves is None else list(curves)
    bad = [i for i in chosen if not 0 <= i < len(data)]
    if bad:
        raise DataFileError(source, f"has {len(data)} curve(s), no curve {bad[0]}",
                            f"give an index from 0 to {len(data) - 1}")
    traces = []
    for i in chosen:
        t, z, force, how = _approach(data[i], i, source)
        kwargs, free = split_trace_metadata(metadata, {
            "reader": "afm", "curve_index": i, "n_curves": len(data), **_metadata(data[i]),
            **how, "force_sign": force_sign, "z_sign": float(z_sign)})
        tid = stem if len(data) == 1 else f"{stem}-{i}"
        trace = IndentationTrace(time=t - t[0], z=z_sign * z, force=force_sign * force, tip=tip,
                                 trace_id=tid, source=source, metadata=free, **kwargs)
        if check:
            try:
                check_plausible(trace)
            except DataFileError as exc:
                if len(data) == 1:
                    raise
                raise DataFileError(source, f"curve {i}: {exc.problem}", exc.fix) from None
        traces.append(trace)
    return traces


def describe_afm(path: str | os.PathLike) -> list[AFMCurveInfo]:
    """The curves of an AFM file: modality, columns, points per segment, position."""
    data, _ = _load(path)
    out = []
    for i, c in enumerate(data):
        seg = np.asarray(c["segment"]) if "segment" in c.columns else np.zeros(len(c), int)
        values, counts = np.unique(seg, return_counts=True)
        meta = _metadata(c)
        out.append(AFMCurveInfo(i, c.modality, tuple(c.columns),
                                {int(v): int(n) for v, n in zip(values, counts, strict=True)},
                                meta.get("x_m"), meta.get("y_m")))
    return out
