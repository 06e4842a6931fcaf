"""Batch fitting of a campaign: every trace of a manifest, in parallel, resumable.

:func:`fit_campaign` runs :func:`palpbayes.fitjob.fit_trace` on every trace over a process pool
and writes a results folder (docs/design.md §5, §7)::

    OUT_DIR/
      summary.csv               one row per trace × method, columns fitjob.SUMMARY_COLUMNS
      posterior/<trace_id>.nc   Bayesian posterior of each trace (arviz, h5netcdf)
      traces.csv                geometry and labels of every trace (manifest columns)
      settings.json             version, options, source, seed, campaign folder
      .partial/<trace_id>.json  per-trace rows, written as each trace finishes (for --resume)

Comparison tables (ground truth vs least squares vs Bayes) are made from this folder by
:func:`palpbayes.compare.compare_campaign` (``palpbayes compare``).

Failure policy
--------------
* Every trace is read and passes :func:`palpbayes.fitjob.check_fittable` (geometry, units,
  contact, fit window, the contact model at every depth a fit evaluates) and the output folder
  must be creatable before anything is written; only then does ``force=True`` remove the
  previous results.  Bad input found there leaves the results folder as it was.
* A trace whose *input* is bad (:class:`~palpbayes.errors.InputError`: unreadable file, no
  contact, missing geometry) fails the whole run with an error naming the trace — bad input is
  exit status 2, and a campaign silently missing traces would bias every table.  Finished traces
  are kept in ``.partial/``, so fixing the input and running again with ``resume=True`` only
  fits what is left.
* A :class:`~palpbayes.errors.FitError` on otherwise valid data (e.g. no finite posterior at the
  least-squares start) is recorded as a row with empty estimates, ``converged`` False and the
  error in ``flags``; the campaign goes on.  With ``method="both"`` the least-squares row is
  salvaged when only the Bayesian fit failed.  With ``options.strict`` (non-convergence is an
  error) the run raises :class:`~palpbayes.errors.FitError` *after* writing ``summary.csv``,
  listing the failed traces.

Reproducibility: each trace's seed is :func:`palpbayes.fitjob.trace_seed` (base seed, trace id),
results are read back from the per-trace JSON files and sorted by (trace_id, method), so the
summary is identical whatever the number of workers or the order of completion.
"""

from __future__ import annotations

import concurrent.futures as cf
import hashlib
import json
import math
import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np
import pandas as pd

from . import __version__, layout
from . import errors as _errors
from .errors import FitError, InputError, OutputExistsError
from .fitjob import SUMMARY_COLUMNS, FitOptions, check_fittable, fit_trace
from .io.atomic import write_csv_atomic, write_text_atomic
from .io.manifest import MANIFEST_COLUMNS, read_manifest, tip_columns
from .trace import IndentationTrace

__all__ = [
    "fit_campaign",
    "load_source",
    "options_record",
    "read_settings",
    "PARTIAL_DIR",
    "POSTERIOR_DIR",
    "OUTPUT_FILES",
]

PARTIAL_DIR = layout.PARTIAL_DIR
POSTERIOR_DIR = layout.POSTERIOR_DIR
#: Files a results folder may hold that depend on the fit (removed by ``force=True`` before a
#: new run; :data:`palpbayes.layout.FIT_OUTPUTS`).
OUTPUT_FILES = layout.FIT_OUTPUTS


# ----------------------------------------------------------------------------- source


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
        from .io.manifest import load_trace

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


# ----------------------------------------------------------------------------- settings


def options_record(options: FitOptions) -> dict:
    """JSON-able record of the options (progress display removed: it changes no result)."""
    opts = options.with_progress(None)
    return {"repr": repr(opts), "fields": json.loads(json.dumps(asdict(opts), default=str))}


def read_settings(out_dir: str | os.PathLike) -> dict:
    """``settings.json`` of a results folder as a dict ({} when absent)."""
    path = Path(out_dir) / layout.SETTINGS
    if not path.is_file():
        return {}
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise _errors.DataFileError(path, f"not valid JSON ({exc})",
                                    "delete it and rerun with --force") from None


def _settings(options: FitOptions, source: Path | None, out: Path, n: int,
              read_options: dict | None = None) -> dict:
    camp = None if source is None else source.parent
    rec = options_record(options)
    return {
        "palpbayes_version": __version__,
        "options": rec["repr"],
        "options_fields": rec["fields"],
        "method": options.method,
        "seed": int(options.seed),
        "source": None if source is None else str(source),
        "campaign_dir": None if camp is None else str(camp),
        "campaign_dir_relative": None if camp is None else os.path.relpath(camp, out.resolve()),
        "n_traces": n,
        "read_options": json.loads(json.dumps(read_options or {}, sort_keys=True, default=str)),
    }


def _check_out_dir(out: Path, resume: bool, force: bool) -> None:
    if resume and force:
        raise InputError("--force and --resume exclude each other: --force refits everything, "
                         "--resume keeps finished traces")
    if out.exists() and not out.is_dir():
        raise OutputExistsError(f"{out} exists and is not a folder; choose another output folder")
    for parent in out.absolute().parents:  # nearest existing ancestor must be a folder
        if parent.exists():
            if not parent.is_dir():
                raise InputError(f"cannot create output folder {out}: {parent} is a file, not a "
                                 "folder; choose another --out")
            break
    if out.is_dir() and any(out.iterdir()) and not (resume or force):
        raise OutputExistsError(
            f"output folder {out} is not empty; use --force to refit and replace its results, "
            "or --resume to keep finished traces and fit the rest")


def _clear_outputs(out: Path) -> None:
    """Remove a previous run's results (only files palpbayes writes)."""
    for name in OUTPUT_FILES:
        (out / name).unlink(missing_ok=True)
    for sub, pattern in ((POSTERIOR_DIR, "*.nc"), (PARTIAL_DIR, "*.json")):
        for f in (out / sub).glob(pattern):
            f.unlink()


# ----------------------------------------------------------------------------- one trace


def _jsonable(v):
    if isinstance(v, np.generic):
        v = v.item()
    if v is None or isinstance(v, bool | int | str):
        return v
    if isinstance(v, float):
        return v
    return str(v)


def _failed_rows(trace: IndentationTrace, methods: list[str], exc: Exception) -> list[dict]:
    return [{
        "trace_id": trace.trace_id, "method": m, "tip": trace.tip.kind,
        "converged": False, "flags": f"fit failed: {exc}", "material": trace.material,
        "specimen": trace.specimen, "repetition": trace.repetition,
        "rest_time_s": trace.rest_time,
    } for m in methods]


def _methods(options: FitOptions) -> list[str]:
    return ["bayes", "lsq"] if options.method == "both" else [options.method]


def trace_fingerprint(trace: IndentationTrace) -> str:
    """SHA-256 of what a fit of ``trace`` depends on: the time, z and force arrays, the tip,
    the thickness and a manifest's per-row nu.  ``--resume`` refits a trace whose fingerprint
    changed (an edited file) instead of reusing its recorded rows."""
    h = hashlib.sha256()
    for a in (trace.time, trace.z, trace.force):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    h.update(repr((trace.tip, trace.thickness, trace.metadata.get("nu"))).encode("utf-8"))
    return h.hexdigest()


def _fit_one(trace: IndentationTrace, options: FitOptions, out: str) -> dict:
    """Fit one trace, write its posterior and partial JSON; never raises PalpbayesErrors.

    Returns ``{"rows": [...]}`` or, for bad input, ``{"error": (class name, message)}`` (custom
    exception classes do not all survive pickling between processes).
    """
    post_dir = Path(out) / POSTERIOR_DIR
    try:
        try:
            rows = fit_trace(trace, options, post_dir).rows
        except FitError as exc:
            rows = None
            if options.method == "both":
                try:
                    rows = fit_trace(trace, replace(options, method="lsq")).rows
                    rows += _failed_rows(trace, ["bayes"], exc)
                except FitError:
                    rows = None
            if rows is None:
                rows = _failed_rows(trace, _methods(options), exc)
    except InputError as exc:
        msg = str(exc)
        if trace.trace_id not in msg:
            msg = f"trace {trace.trace_id!r}: {msg}"
        return {"error": (type(exc).__name__, msg)}
    rows = [{k: _jsonable(v) for k, v in r.items()} for r in rows]
    record = {"trace_id": trace.trace_id, "options": options_record(options)["repr"],
              "data_sha256": trace_fingerprint(trace), "rows": rows}
    write_text_atomic(json.dumps(record, indent=1),
                      layout.partial_path(out, trace.trace_id))
    return {"rows": rows}


def _raise_input(error: tuple[str, str]) -> None:
    name, msg = error
    cls = getattr(_errors, name, InputError)
    if not (isinstance(cls, type) and issubclass(cls, InputError)):
        cls = InputError
    if cls is _errors.DataFileError:
        raise _errors.DataFileError(None, msg)
    raise cls(msg)


def _read_partial(out: Path, trace: IndentationTrace, options: FitOptions) -> list[dict] | None:
    """The recorded rows of a finished trace, or None when it must be (re)fitted."""
    path = layout.partial_path(out, trace.trace_id)
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
    if sorted(r.get("method") for r in rows) != sorted(_methods(options)):
        return None
    for r in rows:
        ok = r.get("E_pa") is not None and not (isinstance(r["E_pa"], float)
                                                and math.isnan(r["E_pa"]))
        if r["method"] == "bayes" and ok and \
                not layout.posterior_path(out, trace.trace_id).is_file():
            return None
    return rows


# ----------------------------------------------------------------------------- campaign


def _progress_bar(total: int, initial: int, progress: bool | None):
    from tqdm.auto import tqdm

    show = sys.stderr.isatty() if progress is None else bool(progress)
    return tqdm(total=total, initial=initial, disable=not show, desc="fitting", unit="trace",
                file=sys.stderr, dynamic_ncols=True)


def _mp_context():
    """Process start method: fork where it is safe and fast (Linux, Python < 3.12: the workers
    inherit the imported modules), else forkserver/spawn (fork of a multi-threaded process is
    deprecated from Python 3.12)."""
    import multiprocessing as mp

    methods = mp.get_all_start_methods()
    if "fork" in methods and sys.platform.startswith("linux") and sys.version_info < (3, 12):
        return mp.get_context("fork")
    return mp.get_context("forkserver" if "forkserver" in methods else "spawn")


def _run(todo: list[IndentationTrace], options: FitOptions, out: Path, workers: int,
         on_done: Callable[[], None]) -> None:
    if workers <= 1 or len(todo) <= 1:
        for t in todo:
            res = _fit_one(t, options, str(out))
            if "error" in res:
                _raise_input(res["error"])
            on_done()
        return
    pool = cf.ProcessPoolExecutor(max_workers=min(workers, len(todo)), mp_context=_mp_context())
    try:
        futures = [pool.submit(_fit_one, t, options, str(out)) for t in todo]
        for fut in cf.as_completed(futures):
            res = fut.result()
            if "error" in res:
                _raise_input(res["error"])
            on_done()
    finally:  # on an error or Ctrl-C, drop the traces not started yet
        pool.shutdown(wait=True, cancel_futures=True)


def fit_campaign(
    source: str | os.PathLike | Sequence[IndentationTrace],
    out_dir: str | os.PathLike,
    options: FitOptions | None = None,
    *,
    workers: int | None = None,
    resume: bool = False,
    force: bool = False,
    progress: bool | None = None,
    read_options: dict | None = None,
) -> pd.DataFrame:
    """Fit every trace of a campaign and write the results folder (module docstring).

    Nothing is written, and with ``force`` nothing is removed, until every trace has been read
    and has passed :func:`palpbayes.fitjob.check_fittable` (geometry, units, contact, fit
    window, the contact model over every depth a fit evaluates) and the output folder can be
    created.

    Parameters
    ----------
    source
        Campaign manifest (:mod:`palpbayes.io.manifest`) or a sequence of traces with tips.
    out_dir
        Results folder; created if needed.
    options
        Fit options shared by every trace (default :class:`~palpbayes.fitjob.FitOptions`).
    workers
        Worker processes (default ``os.cpu_count()``); 1 fits in this process.
    resume
        Keep traces already recorded in ``out_dir/.partial`` with the same options and fit the
        rest (an interrupted run picks up where it stopped).
    force
        Replace the results of a previous run in a non-empty ``out_dir``.
    progress
        Progress bar over traces on stderr; None: only when stderr is a terminal.
    read_options
        Reader options for every trace file of a manifest (``columns``, ``units``,
        ``force_sign``, ``z_sign``; see :func:`load_source`); recorded in ``settings.json``,
        and resuming with other read options is refused.

    Returns
    -------
    pandas.DataFrame
        The summary table, as written to ``summary.csv`` (rows sorted by trace_id, method).

    Raises
    ------
    OutputExistsError
        ``out_dir`` is not empty and neither ``force`` nor ``resume`` is set.
    InputError
        Bad source or a trace with bad input (the message names the trace); resuming a folder
        fitted with other options.
    FitError
        Only with ``options.strict``: some traces failed (after ``summary.csv`` is written).
    """
    options = options or FitOptions()
    out = Path(out_dir)
    _check_out_dir(out, resume, force)
    traces, src = load_source(source, read_options)
    if workers is None:
        workers = os.cpu_count() or 1
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"workers {workers!r} must be a positive integer")
    options = options.with_progress(False)  # one bar over traces, none per fit

    settings = _settings(options, src, out, len(traces), read_options)
    old = read_settings(out) if resume else {}
    if resume and old and old.get("options") != settings["options"]:
        raise InputError(
            f"cannot resume {out}: it was fitted with other options ({old.get('options')}); "
            "use --force to refit everything with the new options")
    if resume and old and old.get("read_options", {}) != settings["read_options"]:
        raise InputError(
            f"cannot resume {out}: its traces were read with other column/unit/sign options "
            f"({old.get('read_options', {})}); use --force to refit everything with the new ones")
    for t in traces:  # bad input (geometry, nu, no contact) fails before anything is written
        try:
            check_fittable(t, options)
        except InputError as exc:
            if t.trace_id in str(exc):
                raise
            exc.args = (f"trace {t.trace_id!r}: {exc}",)  # keep the class, name the trace
            raise
    # every check passed: only now create the folder and (with force) remove the old results
    try:
        out.mkdir(parents=True, exist_ok=True)
        (out / PARTIAL_DIR).mkdir(exist_ok=True)
        (out / POSTERIOR_DIR).mkdir(exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot create output folder {out} ({exc.strerror or exc}); choose "
                         "another --out") from None
    if force:
        _clear_outputs(out)
    write_text_atomic(json.dumps(settings, indent=2) + "\n", out / layout.SETTINGS)
    write_csv_atomic(pd.DataFrame([_geometry_row(t) for t in traces],
                                  columns=MANIFEST_COLUMNS), out / layout.TRACES,
                     float_format="%.10g")

    done = {t.trace_id for t in traces if resume and _read_partial(out, t, options) is not None}
    todo = [t for t in traces if t.trace_id not in done]
    with _progress_bar(len(traces), len(done), progress) as bar:
        _run(todo, options, out, workers, lambda: bar.update(1))

    rows = []
    for t in traces:
        recorded = _read_partial(out, t, options)
        if recorded is None:  # pragma: no cover - written just above
            raise FitError(f"trace {t.trace_id!r}: its results were not recorded")
        rows += recorded
    summary = pd.DataFrame(rows, columns=SUMMARY_COLUMNS)
    summary = summary.sort_values(["trace_id", "method"], kind="stable").reset_index(drop=True)
    write_csv_atomic(summary, out / layout.SUMMARY)
    if options.strict:
        failed = sorted({r["trace_id"] for r in rows
                         if str(r.get("flags") or "").startswith("fit failed")})
        if failed:
            raise FitError(f"{len(failed)} trace(s) failed in strict mode: {', '.join(failed)} "
                           f"(see {out / layout.SUMMARY})")
    return summary
