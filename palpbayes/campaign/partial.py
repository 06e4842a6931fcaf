"""One trace inside a campaign run, and its record in ``.partial/`` that makes a run resumable.

:func:`fit_and_record` is what a worker process runs for one trace: it fits the trace
(:func:`palpbayes.campaign.fitjob.fit_trace`), writes its posterior and, atomically, the JSON
record ``.partial/<trace_id>.json`` (options, palpbayes version, a fingerprint of the data,
the summary rows).  :func:`read_partial` reads a record back, and only if it still matches the
options, the version and the data (:func:`trace_fingerprint`): that is how ``--resume`` and a
re-run of ``palpbayes report`` keep finished traces, and refit an edited one.  Used by
:mod:`palpbayes.campaign.run` only (not part of the package's public API).
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import numpy as np

from .. import __version__, outputs
from .. import errors as _errors
from ..errors import InputError
from ..fitdata import FitData
from ..io.atomic import write_text_atomic
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


def _canonical(value) -> object:
    """A stable, hashable stand-in for a metadata value: arrays by dtype, shape and a digest of
    their bytes, containers item by item, numbers and text as themselves; any other object by
    its type's name (its repr may hold a memory address that changes from run to run)."""
    if isinstance(value, np.ndarray):
        a = np.ascontiguousarray(value)
        return ("array", a.dtype.str, a.shape, hashlib.sha256(a.tobytes()).hexdigest())
    if isinstance(value, np.generic):
        value = value.item()
    if value is None or isinstance(value, bool | int | float | str | complex):
        return value
    if isinstance(value, list | tuple):
        return tuple(_canonical(v) for v in value)
    if isinstance(value, dict):
        return tuple(sorted((str(k), _canonical(v)) for k, v in value.items()))
    return ("object", type(value).__qualname__)


def trace_fingerprint(trace: IndentationTrace) -> str:
    """SHA-256 of everything a fit of ``trace`` and its summary rows depend on: the time, z,
    force and segment arrays (the numbers read from the file), the tip, the thickness, the
    labels the rows carry (trace id, specimen, material, repetition, rest time) and the
    metadata (a manifest's per-row nu, the specimen's footprint ``length_m``, ``width_m``,
    ``diameter_m``, ...).  Not the file's path: a moved campaign is the same data.  A re-run
    refits a trace whose fingerprint changed (an edited file or manifest row) instead of
    reusing its recorded rows."""
    h = hashlib.sha256()
    for a in (trace.time, trace.z, trace.force):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    h.update(b"segment")
    if trace.segment is not None:
        h.update(np.ascontiguousarray(trace.segment, dtype=np.int64).tobytes())
    labels = (trace.trace_id, trace.specimen, trace.material, trace.repetition,
              trace.rest_time)
    h.update(repr((trace.tip, trace.thickness, labels,
                   _canonical(trace.metadata or {}))).encode("utf-8"))
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
              "palpbayes_version": __version__, "data_sha256": trace_fingerprint(trace),
              "rows": rows}
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
    """The recorded rows of a finished trace, or None when it must be (re)fitted: no record,
    or one of other options, of another palpbayes version or of other data
    (:func:`trace_fingerprint`)."""
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
    if rec.get("palpbayes_version") != __version__:
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
