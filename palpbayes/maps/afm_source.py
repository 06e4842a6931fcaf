"""An AFM force map as the rows of a map: one row per lattice node, pointing at its curve.

``palpbayes map FILE.jpk-force-map`` (any force map afmformats reads: JPK force maps and QI
data, AFM Workshop zips) needs what a map manifest gives (:func:`palpbayes.maps.run.make_map`):
a position per trace and a way to read it.  :func:`afm_map_rows` reads the curves' metadata
once (afmformats ``position x``/``position y`` [m], ``grid index x``/``grid index y``) and
returns a manifest-like table whose rows name the file and the curve index; the Dask workers
read their curves themselves (:func:`load_point_trace`), so no arrays travel.

Holes: a force map whose curves carry grid indices (JPK) is placed on those indices; every
node of the grid spanned by the curves read that has no curve (an extracted or interrupted
map) becomes a row with ``error`` set, so it stays a hole on the lattice, neither dropped nor
filled.  A curve that fails to read or fit becomes a hole in the same way
(:func:`palpbayes.maps.pertrace.fit_point` puts the reason in ``points.csv``).

Positions are the file's own (afmformats converts them to metres; a span of
:data:`MAX_SPAN` or more is rejected as not metres); a curve without one is an error naming
the file and the curve.  A hole's position is its grid index times the step fitted to the
curves read.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from ..contact import Tip
from ..errors import DataFileError
from ..io.afm import curve_metadata, load_afm_curves, read_afm
from ..io.manifest import load_trace, tip_columns, tip_from_row
from ..trace import IndentationTrace

__all__ = ["AFM_ROW_COLUMNS", "MAX_SPAN", "NO_CURVE", "afm_map_rows", "load_point_trace",
           "read_afm_rows", "is_afm_row"]

#: [m] Largest extent of an AFM map's positions: a larger one is not in metres.
MAX_SPAN = 0.05

#: How the ``error`` of a hole (a grid node without a curve in the file) starts.
NO_CURVE = "no curve at grid index"

#: Columns of the rows made from an AFM map, besides the tip-size columns.
AFM_ROW_COLUMNS = ["trace_id", "file", "material", "tip", "curve_index", "grid_ix",
                   "grid_iy", "x_m", "y_m", "error"]


def _grid_step(index: np.ndarray, pos: np.ndarray) -> tuple[float, float]:
    """Origin and step [m] of pos = origin + step × index (least squares; step NaN when the
    indices take one value)."""
    if np.unique(index).size < 2:
        return float(np.mean(pos)), float("nan")
    step, origin = np.polyfit(index.astype(float), pos, 1)
    return float(origin), float(step)


def afm_map_rows(path: str | os.PathLike, tip: Tip, *, meta_override: dict | None = None
                 ) -> pd.DataFrame:
    """The rows of a map made from the curves of an AFM force map.

    Parameters
    ----------
    path
        A force map afmformats reads (:func:`palpbayes.io.afm.is_afm_file`).
    tip
        The indenter (no AFM file records it), put in every row.
    meta_override
        afmformats metadata the file lacks (SI units), e.g. an AFM Workshop map's
        ``{"spring constant": [N/m], "sensitivity": [m/V], "rate approach": [Hz]}``.

    Returns
    -------
    pandas.DataFrame
        One row per curve, then one per hole (a grid node without a curve, ``error`` says so;
        ``curve_index`` -1): :data:`AFM_ROW_COLUMNS` and the tip-size columns, ``x_m``,
        ``y_m`` [m].

    Raises
    ------
    DataFileError
        The file cannot be read, holds one curve, a curve has no position (naming the
        curve), or the positions span :data:`MAX_SPAN` or more (not metres).
    """
    curves, source = load_afm_curves(path, meta_override)
    if len(curves) < 2:
        raise DataFileError(source, "holds one curve: it is not a force map",
                            "fit it with palpbayes fit FILE --tip ...")
    stem = Path(path).name.split(".")[0] or "curve"
    rows = []
    for i, curve in enumerate(curves):
        meta = curve_metadata(curve)
        if "x_m" not in meta or "y_m" not in meta:
            raise DataFileError(source, f"curve {i} has no position (afmformats metadata "
                                "'position x'/'position y'); it is not a force map",
                                "fit its curves with palpbayes fit FILE --tip ... instead")
        rows.append({"trace_id": f"{stem}-{i}", "curve_index": i, "x_m": float(meta["x_m"]),
                     "y_m": float(meta["y_m"]), "grid_ix": meta.get("grid_index_x"),
                     "grid_iy": meta.get("grid_index_y"), "error": ""})
    df = pd.DataFrame(rows)
    span = max(float(np.ptp(df["x_m"])), float(np.ptp(df["y_m"])))
    if not span < MAX_SPAN:
        raise DataFileError(source, f"the curves' positions span {span:g}: not metres, the "
                            f"unit afmformats gives (an AFM map spans less than {MAX_SPAN:g} m)",
                            "check the file's position metadata")
    if df["grid_ix"].notna().all() and df["grid_iy"].notna().all():
        df = pd.concat([df, _holes(df, stem)], ignore_index=True)
    else:
        df["grid_ix"], df["grid_iy"] = np.nan, np.nan
    df["file"] = str(Path(path).resolve())
    df["material"] = ""
    df["tip"] = tip.kind
    for col, value in tip_columns(tip).items():
        df[col] = value
    df["curve_index"] = df["curve_index"].astype(int)
    return df[AFM_ROW_COLUMNS + list(tip_columns(tip))]


def _holes(df: pd.DataFrame, stem: str) -> pd.DataFrame:
    """Rows for the grid nodes (within the curves' index range) that have no curve."""
    ix, iy = df["grid_ix"].to_numpy(int), df["grid_iy"].to_numpy(int)
    x0, hx = _grid_step(ix, df["x_m"].to_numpy(float))
    y0, hy = _grid_step(iy, df["y_m"].to_numpy(float))
    have = set(zip(ix.tolist(), iy.tolist(), strict=True))
    out = []
    for j in range(iy.min(), iy.max() + 1):
        for i in range(ix.min(), ix.max() + 1):
            if (i, j) in have:
                continue
            out.append({"trace_id": f"{stem}-hole-{i}-{j}", "curve_index": -1,
                        "x_m": x0 + (0.0 if np.isnan(hx) else hx * i),
                        "y_m": y0 + (0.0 if np.isnan(hy) else hy * j),
                        "grid_ix": i, "grid_iy": j,
                        "error": f"{NO_CURVE} ({i}, {j}) in the file"})
    return pd.DataFrame(out, columns=df.columns)


def is_afm_row(row: pd.Series) -> bool:
    """True for a row made by :func:`afm_map_rows` (it has a ``curve_index``)."""
    value = row.get("curve_index")
    return value is not None and not pd.isna(value)


def load_point_trace(row: pd.Series, **read_options) -> IndentationTrace:
    """The trace of one map row: its curve of the AFM file (``read_options`` go to
    :func:`palpbayes.io.afm.read_afm`: ``meta_override``, ``force_sign``, ...) or, for a
    manifest row, its trace file (:func:`palpbayes.io.manifest.load_trace`)."""
    if not is_afm_row(row):
        return load_trace(row, **read_options)
    (trace,) = read_afm_rows([row], **read_options)
    return trace


def read_afm_rows(rows: list[pd.Series], **read_options) -> list[IndentationTrace]:
    """The curves of AFM map rows that name one file and one tip, the file opened once for
    all of them (reading curve by curve re-parses its headers per curve); ``read_options`` as
    :func:`load_point_trace`."""
    first = rows[0]
    return read_afm(first["file"], tip=tip_from_row(first),
                    curves=[int(r["curve_index"]) for r in rows], **read_options)
