"""The traces of a campaign: read a manifest (or take a list of traces) and check their ids.

:func:`load_source` is the first step of :func:`palpbayes.campaign.run.fit_campaign`: every trace
is read, and its id checked to be usable as a file name, before anything is fitted or written.
:func:`traces_table` is the ``traces.csv`` table of a results folder (geometry and labels).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import InputError
from ..io.manifest import MANIFEST_COLUMNS, load_trace, read_manifest, tip_columns
from ..trace import IndentationTrace

__all__ = ["load_source", "traces_table", "POSITION_COLUMNS"]


def load_source(source: str | os.PathLike | Sequence[IndentationTrace],
                read_options: dict | None = None,
                ) -> tuple[list[IndentationTrace], Path | None]:
    """Traces of a manifest path or a list of traces, and the manifest path (None for a list).

    Parameters
    ----------
    source
        Campaign manifest path, or a sequence of :class:`~palpbayes.trace.IndentationTrace`.
    read_options
        Reader options applied to every trace file of a manifest (``columns``, ``units``,
        ``force_sign``, ``z_sign``; see :func:`palpbayes.io.trace_csv.read_trace`).  Only for
        a manifest: traces given as objects are already read.

    Raises
    ------
    InputError
        Duplicate or unusable trace ids, a trace without tip geometry, an empty source, read
        options with a list of traces, or any error of
        :func:`palpbayes.io.manifest.read_manifest` / the trace reader.
    """
    read_options = dict(read_options or {})
    if isinstance(source, str | os.PathLike):
        path = Path(source).resolve()
        df = read_manifest(path)
        traces = [load_trace(row, **read_options) for _, row in df.iterrows()]
    else:
        if read_options:
            raise InputError("read options (columns, units, signs) apply to a manifest's "
                             "files; read the traces with them instead")
        path = None
        traces = list(source)
        bad = [t for t in traces if not isinstance(t, IndentationTrace)]
        if bad:
            raise InputError(f"source must be a manifest path or IndentationTrace objects, got "
                             f"{type(bad[0]).__name__}")
    if not traces:
        raise InputError("the campaign has no traces")
    seen: set[str] = set()
    for t in traces:
        tid = t.trace_id
        if not tid or tid in (".", "..") or any(c in tid for c in '/\\:*?"<>|') or \
                tid.startswith("."):
            raise InputError(f"trace id {tid!r} cannot be used as a file name; use letters, "
                             "digits, '_', '-' and '.'")
        if tid in seen:
            raise InputError(f"trace id {tid!r} appears more than once; ids must be unique")
        seen.add(tid)
        if t.tip is None:
            raise InputError(f"trace {tid!r} has no tip geometry; give the tip in the manifest")
    return traces, path


#: Where on the sample a trace was taken [m] (AFM force maps), added to ``traces.csv`` when
#: some trace has it in its metadata.
POSITION_COLUMNS = ("x_m", "y_m")


def traces_table(traces: Sequence[IndentationTrace]) -> pd.DataFrame:
    """``traces.csv``: the geometry and labels of every trace, in the manifest's columns, and
    its position ``x_m, y_m`` [m] when a trace has one (the curves of an AFM force map)."""
    columns = list(MANIFEST_COLUMNS)
    if any(c in t.metadata for t in traces for c in POSITION_COLUMNS):
        columns += POSITION_COLUMNS
    rows = [{**_geometry_row(t), **{c: t.metadata.get(c, np.nan) for c in POSITION_COLUMNS}}
            for t in traces]
    return pd.DataFrame(rows, columns=columns)


def _geometry_row(t: IndentationTrace) -> dict:
    tip = t.tip
    return {
        "trace_id": t.trace_id, "file": t.source or "", "specimen": t.specimen,
        "material": t.material, "tip": tip.kind,
        **tip_columns(tip),
        "thickness_m": np.nan if t.thickness is None else t.thickness,
        "repetition": np.nan if t.repetition is None else t.repetition,
        "rest_time_s": np.nan if t.rest_time is None else t.rest_time,
    }
