"""Per-point fits of a stiffness map: each palpation's posterior of log E, on Dask.

Every trace of a map manifest (rows with ``x_m``, ``y_m``) is fitted with the exact engine
(:mod:`palpbayes.bayes.exact`: E*, F0 and the noise integrated out in closed form, the surface
on an adaptive grid) and summarised by the mean and sd of log E over 2,000 posterior draws —
the Gaussian summary the spatial model (:mod:`palpbayes.maps.gmrf`) combines.  The paper's
least squares is fitted beside it: the naive per-point map the Bayesian map is compared with.

The per-point E excludes the uncertainty budget's systematic terms (tip radius, Poisson ratio,
sensor calibration): they are common to every point of a map and cancel in the ratios to the
background that the map reports.

The fits run on ``dask.distributed``: a :class:`~dask.distributed.LocalCluster` with one
single-threaded worker process per core by default, or the scheduler at ``scheduler``
(``tcp://host:8786``), whose workers must see the trace files under the same paths.  Traces
go out in chunks and at most a few chunks per worker are in flight, so memory stays bounded
whatever the map size; only the small result rows come back.  ``scheduler="synchronous"``
runs in this process (debugging, tests).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from itertools import islice

import numpy as np
import pandas as pd

from ..bayes.exact import exact_posterior, sampled_coordinates
from ..bayes.flags import bound_flags
from ..bayes.noisemodels import EXACT_NOISE_MODELS
from ..campaign.fitjob import FitOptions, check_fittable, force_scale_flag
from ..cluster import close_client, dask_client
from ..errors import FitError, InputError, PalpbayesError
from ..flagcodes import flag_columns
from ..intervals import LEVEL, central
from ..io.manifest import tip_from_row
from ..lsq import fit_lsq_data
from ..progress import progress_bar
from ..trace import IndentationTrace
from .afm_source import is_afm_row, load_point_trace, read_afm_rows

__all__ = ["PointOptions", "POINT_COLUMNS", "check_positions", "fit_point", "fit_points"]

#: Columns of the per-point table (``points.csv``), in order.
POINT_COLUMNS = [
    "trace_id", "x_m", "y_m", "logE_mean", "logE_sd", "E_median_pa", "E_lo_pa", "E_hi_pa",
    "E_lsq_pa", "z_surf_m", "depth_m", "n_nodes", "nu", "notes", "flag_codes", "flag_level",
    "error",
]


#: Traces per Dask task by default (a task then takes ~1 s: the scheduler's ~ms per task is
#: lost in it, and the in-flight queue of a few tasks per worker stays small).
CHUNK = 25


@dataclass(frozen=True)
class PointOptions:
    """How each point is fitted (picklable: it travels to the Dask workers).

    Parameters
    ----------
    fit
        The trace preparation (Poisson ratio, fit window, tare, thickness correction); its
        ``noise`` must be ``"gaussian"`` or ``"ar1"`` (the exact engine's noise models).
    draws
        Posterior draws per point for the log-E summary.
    seed
        Base seed; each point's draws use (seed, row number).
    read_options
        Passed to the trace reader (columns, units, signs) for every file.
    """

    fit: FitOptions = field(default_factory=lambda: FitOptions(layer="off"))
    draws: int = 2000
    seed: int = 0
    read_options: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.fit.noise not in EXACT_NOISE_MODELS:
            raise InputError(f"map fits use the exact engine: noise "
                             f"{' or '.join(map(repr, EXACT_NOISE_MODELS))}, not "
                             f"{self.fit.noise!r}")
        if self.fit.layer != "off":
            raise InputError("map fits take each point as a half-space (FitOptions.layer "
                             "'off'): the lump model carries the block's thickness")
        if int(self.draws) < 100:
            raise InputError(f"draws per point {self.draws!r} must be at least 100")


def _empty_row(row: pd.Series) -> dict:
    out = {c: np.nan for c in POINT_COLUMNS}
    out.update(trace_id=str(row["trace_id"]), x_m=float(row["x_m"]), y_m=float(row["y_m"]),
               notes="", flag_codes="", flag_level="", error="")
    return out


def fit_point(row: pd.Series, options: PointOptions, index: int = 0,
              trace: IndentationTrace | None = None) -> dict:
    """Fit one manifest row; return its :data:`POINT_COLUMNS` record.

    A row that is a hole (its ``error`` set: a grid node of an AFM map without a curve) or
    a trace that cannot be fitted (no contact, bad geometry, unreadable file or curve, a
    numerical failure) gives a record with the reason in ``error`` and NaN estimates: the map
    leaves its node without data instead of stopping.

    Parameters
    ----------
    row
        A validated manifest row (:func:`palpbayes.io.manifest.read_manifest`) with ``x_m``
        and ``y_m`` [m].
    options
        :class:`PointOptions`.
    index
        Row number (seeds the draws).
    trace
        The row's trace when already read (:func:`_fit_chunk` reads the curves of one AFM
        file together); None reads it here (:func:`~.afm_source.load_point_trace`).
    """
    out = _empty_row(row)
    if _is_hole(row):
        out["error"] = row["error"]
        return out
    try:
        if trace is None:
            trace = load_point_trace(row, **options.read_options)
        data = check_fittable(trace, options.fit)
        prior = options.fit.priors.for_trace(data, options.fit.noise, options.fit.baseline)
        post = exact_posterior(data, prior)
        rng = np.random.default_rng([int(options.seed), int(index)])
        d = post.draws(rng, int(options.draws))
    except PalpbayesError as exc:
        out["error"] = str(exc)
        return out
    except (ValueError, ArithmeticError, OSError) as exc:  # one odd trace must not stop a map
        out["error"] = f"{type(exc).__name__}: {exc}"
        return out
    E = data.model.to_E(d["E_star"])
    logE = np.log(E)
    lo, hi = central(E, LEVEL)
    scale = force_scale_flag(data, options.fit)
    flags = ([] if scale is None else [scale]) + bound_flags(
        sampled_coordinates(d, list(prior.bounds)), prior)
    if not post.complete:
        flags.append("surface grid stopped at its node cap: the posterior may be incomplete")
    try:
        e_lsq = float(fit_lsq_data(data, trace_id=trace.trace_id).E)
    except FitError:
        e_lsq = np.nan
    out.update(logE_mean=float(logE.mean()), logE_sd=float(logE.std(ddof=1)),
               E_median_pa=float(np.median(E)), E_lo_pa=float(lo), E_hi_pa=float(hi),
               E_lsq_pa=e_lsq, z_surf_m=float(np.median(d["z_surf"])),
               depth_m=float(np.median(d["z_surf"])) - data.z_min,
               n_nodes=post.n_nodes, nu=float(data.model.nu), **flag_columns("; ".join(flags)))
    return out


def _fit_chunk(rows: list[tuple[int, dict]], options: PointOptions) -> list[dict]:
    """Worker task: fit a chunk of (row number, manifest row as dict)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        series = [pd.Series(r) for _, r in rows]
        traces = _read_afm_curves(series, options.read_options)
        return [fit_point(r, options, i, traces.get(k))
                for k, ((i, _), r) in enumerate(zip(rows, series, strict=True))]


def _is_hole(row: pd.Series) -> bool:
    """A grid node of an AFM map without a curve (its ``error`` says why)."""
    return isinstance(row.get("error"), str) and bool(row["error"])


def _read_afm_curves(rows: list[pd.Series], read_options: dict) -> dict[int, IndentationTrace]:
    """The traces of a chunk's AFM rows, each file opened once for all its curves in the
    chunk (reading curve by curve re-parses the file's headers per curve: ~15 ms of the ~25 ms
    a 4,000-sample JPK curve took); {} entries are read one by one by :func:`fit_point`.

    A file that fails as a whole (one unreadable or implausible curve among them) is left to
    the one-by-one reads, which put each curve's own error in its row."""
    by_file: dict[tuple[str, object], list[int]] = {}
    for k, row in enumerate(rows):
        if is_afm_row(row) and not _is_hole(row):
            by_file.setdefault((str(row["file"]), tip_from_row(row)), []).append(k)
    out: dict[int, IndentationTrace] = {}
    for ks in by_file.values():
        if len(ks) < 2:
            continue
        try:
            traces = read_afm_rows([rows[k] for k in ks], **read_options)
        except (PalpbayesError, ValueError, ArithmeticError, OSError):
            continue
        out.update(zip(ks, traces, strict=True))
    return out


def _chunks(manifest: pd.DataFrame, size: int) -> Iterator[list[tuple[int, dict]]]:
    records = manifest.to_dict("records")
    for start in range(0, len(records), size):
        yield [(start + k, r) for k, r in enumerate(records[start:start + size])]


def check_positions(manifest: pd.DataFrame) -> None:
    """Raise :class:`InputError` unless every row has its palpation position ``x_m``, ``y_m``."""
    for col in ("x_m", "y_m"):
        if col not in manifest.columns or manifest[col].isna().any():
            raise InputError(f"a map needs the palpation position of every trace: manifest "
                             f"column {col!r} (metres) is missing or has empty cells")


def fit_points(manifest: pd.DataFrame, options: PointOptions | None = None, *,
               scheduler: str | None = None, workers: int | None = None,
               chunk: int | None = None,
               progress: bool | None = None,
               on_done: Callable[[int], None] | None = None) -> pd.DataFrame:
    """Fit every row of a map manifest; return the per-point table (:data:`POINT_COLUMNS`).

    Parameters
    ----------
    manifest
        Validated manifest with ``x_m`` and ``y_m`` (:func:`palpbayes.io.manifest.read_manifest`).
    options
        :class:`PointOptions`.
    scheduler
        ``None``/``"local"`` (a LocalCluster), ``"synchronous"`` (this process) or a Dask
        scheduler address.
    workers
        Worker processes of the LocalCluster (default: one per core).
    chunk
        Traces per task; None: :data:`CHUNK`, fewer on a small map so that every worker
        gets at least two tasks (a 4 × 4 AFM map in one task of 25 would leave a worker idle).
    progress
        Progress bar on stderr (None: when stderr is a terminal).
    on_done
        Called with the number of traces finished after every chunk.

    Returns
    -------
    pandas.DataFrame
        One row per trace, in manifest order.
    """
    options = options or PointOptions()
    check_positions(manifest)
    if scheduler == "synchronous" and workers is not None:
        raise InputError("workers applies to the local cluster, not to scheduler='synchronous'")
    if chunk is not None and chunk < 1:
        raise InputError(f"chunk {chunk!r} must be at least 1")
    bar = progress_bar(len(manifest), progress, desc="fitting points")
    results: list[dict] = []

    def done(part: list[dict]) -> None:
        results.extend(part)
        bar.update(len(part))
        if on_done is not None:
            on_done(len(results))

    try:
        if scheduler == "synchronous":
            for rows in _chunks(manifest, chunk or CHUNK):
                done(_fit_chunk(rows, options))
        else:
            _run_dask(manifest, options, scheduler, workers, chunk, done)
    finally:
        bar.close()
    table = pd.DataFrame(results, columns=POINT_COLUMNS)
    order = {t: i for i, t in enumerate(manifest["trace_id"].astype(str))}
    return table.sort_values("trace_id", key=lambda s: s.map(order)).reset_index(drop=True)


def auto_chunk(n_rows: int, n_workers: int) -> int:
    """Traces per task: :data:`CHUNK`, or fewer so that each of ``n_workers`` workers gets at
    least two of the ``n_rows`` rows' tasks."""
    return max(1, min(CHUNK, math.ceil(n_rows / (2 * max(1, n_workers)))))


def _run_dask(manifest: pd.DataFrame, options: PointOptions, scheduler: str | None,
              workers: int | None, chunk: int | None,
              done: Callable[[list[dict]], None]) -> None:
    from dask.distributed import as_completed

    client = dask_client(scheduler, workers)
    try:
        n_workers = max(1, len(client.scheduler_info().get("workers", {})) or 1)
        in_flight = 3 * n_workers  # bounded queue: memory does not grow with the map
        chunk = chunk or auto_chunk(len(manifest), n_workers)
        chunks = _chunks(manifest, chunk)
        opts = client.scatter(options, broadcast=True)
        pending = as_completed()
        for rows in islice(chunks, in_flight):
            pending.add(client.submit(_fit_chunk, rows, opts, pure=False))
        for fut in pending:
            done(fut.result())
            fut.release()
            for rows in islice(chunks, 1):
                pending.add(client.submit(_fit_chunk, rows, opts, pure=False))
    finally:
        close_client(client)
