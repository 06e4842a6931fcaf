"""One trace inside a campaign run, and its record in ``.partial/`` that makes a run resumable.

:func:`fit_and_record` is what a worker process runs for one trace: it fits the trace
(:func:`palpbayes.campaign.fitjob.fit_trace`), writes its posterior and, atomically, the JSON
record ``.partial/<trace_id>.json`` (options, a fingerprint of the data, the summary rows).
:func:`read_partial` reads a record back, and only if it still matches the options and the
data (:func:`trace_fingerprint`): that is how ``--resume`` keeps finished traces.  Used by
:mod:`palpbayes.campaign.run` only (not part of the package's public API).
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import numpy as np

from .. import errors as _errors
from .. import outputs
from ..errors import InputError
from ..fitdata import FitData
from ..io.atomic import write_text_atomic
from ..specimen import FOOTPRINT_COLUMNS
from ..trace import IndentationTrace
from .fitjob import FitOptions, fit_trace_rows, fitted_methods
from .settings import options_record

__all__ = ["fit_and_record", "read_partial", "raise_input", "trace_fingerprint"]


def _jsonable(v):
    if isinstance(v, np.generic):
        v = v.item()
    if v is None or isinstance(v, bool | int | str):
        return v
    if isinstance(v, float):
        return v
    return str(v)


def trace_fingerprint(trace: IndentationTrace) -> str:
    """SHA-256 of what a fit of ``trace`` depends on: the time, z and force arrays, the tip,
    the thickness, a manifest's per-row nu and the specimen's footprint (``length_m``,
    ``width_m``, ``diameter_m``).  ``--resume`` refits a trace whose fingerprint changed (an
    edited file or row) instead of reusing its recorded rows."""
    h = hashlib.sha256()
    for a in (trace.time, trace.z, trace.force):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    meta = trace.metadata or {}
    footprint = tuple(meta.get(c) for c in FOOTPRINT_COLUMNS)
    h.update(repr((trace.tip, trace.thickness, meta.get("nu"))).encode("utf-8"))
    if any(v is not None for v in footprint):  # traces without one keep their old fingerprint
        h.update(repr(footprint).encode("utf-8"))
    return h.hexdigest()


def fit_and_record(trace: IndentationTrace, options: FitOptions, out: str,
                   data: FitData | None = None) -> dict:
    """Fit one trace, write its posterior and partial JSON; never raises PalpbayesErrors.

    ``data``: the trace's fit data from :func:`~palpbayes.campaign.fitjob.check_fittable`
    (prepared once; None: prepared here).

    Returns ``{"rows": [...]}`` or, for bad input, ``{"error": (class name, message)}`` (custom
    exception classes do not all survive pickling between processes).
    """
    post_dir = Path(out) / outputs.POSTERIOR_DIR
    try:
        rows = fit_trace_rows(trace, options, post_dir, data=data).rows
    except InputError as exc:
        msg = str(exc)
        if trace.trace_id not in msg:
            msg = f"trace {trace.trace_id!r}: {msg}"
        return {"error": (type(exc).__name__, msg)}
    rows = [{k: _jsonable(v) for k, v in r.items()} for r in rows]
    record = {"trace_id": trace.trace_id, "options": options_record(options)["repr"],
              "data_sha256": trace_fingerprint(trace), "rows": rows}
    write_text_atomic(json.dumps(record, indent=1),
                      outputs.partial_path(out, trace.trace_id))
    return {"rows": rows}


def raise_input(error: tuple[str, str]) -> None:
    """Raise the input error a worker reported as (class name, message) (an
    :class:`~palpbayes.errors.InputError` subclass; InputError for anything else)."""
    name, msg = error
    cls = getattr(_errors, name, InputError)
    if not (isinstance(cls, type) and issubclass(cls, InputError)):
        cls = InputError
    if cls is _errors.DataFileError:
        raise _errors.DataFileError(None, msg)
    raise cls(msg)


def read_partial(out: Path, trace: IndentationTrace, options: FitOptions) -> list[dict] | None:
    """The recorded rows of a finished trace, or None when it must be (re)fitted."""
    path = outputs.partial_path(out, trace.trace_id)
    if not path.is_file():
        return None
    try:
        rec = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError):
        return None
    rows = rec.get("rows", [])
    if rec.get("options") != options_record(options)["repr"]:
        return None
    if rec.get("data_sha256") != trace_fingerprint(trace):
        return None
    if sorted(r.get("method") for r in rows) != sorted(fitted_methods(options)):
        return None
    for r in rows:
        ok = r.get("E_pa") is not None and not (isinstance(r["E_pa"], float)
                                                and math.isnan(r["E_pa"]))
        if r["method"] == "bayes" and ok and \
                not outputs.posterior_path(out, trace.trace_id).is_file():
            return None
    return rows
