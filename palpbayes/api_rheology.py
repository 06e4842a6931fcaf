"""The viscoelastic fit's front door: one builder of its options that
:func:`palpbayes.fit_rheology` and ``palpbayes fit --rheology`` both call, and the result of
a run over a file or a manifest (as :mod:`palpbayes.api` is the elastic fit's).

:func:`rheology_options` checks what a user chose into a :class:`RheologyOptions`;
:func:`run_rheology` fits every trace (:func:`palpbayes.rheology.results.fit_traces`) and pools
a manifest's power laws over speeds (:class:`palpbayes.rheology.campaign.SpeedPools`).
:func:`fit_rheology` takes a trace (one :class:`~palpbayes.rheology.fit.RheologyFit`), a
recording or a manifest (a :class:`RheologyRun`: ``summary()`` is ``rheology.csv``,
``save(DIR)`` writes what ``palpbayes fit --rheology ... --out DIR`` writes).

>>> import palpbayes as pb
>>> run = pb.fit_rheology("campaign/manifest.csv", "power-law")   # doctest: +SKIP
>>> run.summary(); run.save("visco-results")                       # doctest: +SKIP
"""

from __future__ import annotations

import os
import shutil
import tempfile
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from .contact import Tip
from .errors import InputError
from .outputs import RHEOLOGY_DIR, RHEOLOGY_TABLE
from .rheology.results import RheologyOptions, rheology_options
from .trace import IndentationTrace

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .rheology.fit import RheologyFit
    from .rheology.store import StoredRheologyFit

__all__ = ["RheologyOptions", "RheologyRun", "rheology_options", "run_rheology",
           "fit_rheology", "manifest_traces"]


def run_rheology(traces: list, options: RheologyOptions, out: str | os.PathLike, *,
                 manifest: pd.DataFrame | None = None, progress: bool | None = None
                 ) -> tuple[pd.DataFrame, pd.DataFrame | None]:
    """Fit ``traces`` (traces, or a manifest's (trace_id, file, load) triples) into ``out``:
    ``rheology.csv`` and the stored fits; with a ``manifest`` and the power law (read as
    recorded, not as a peer), each specimen x tip's traces at several speeds pooled into
    ``rheology_pooled.csv``.  Returns (table, pooled table or None)."""
    from .rheology.campaign import SpeedPools
    from .rheology.results import fit_traces

    o = options
    pools = (SpeedPools(manifest, seed=o.seed) if manifest is not None
             and "power-law" in o.rheology and o.peer is None else None)
    table = fit_traces(traces, o, out, progress=progress, total=len(traces),
                       on_fit=None if pools is None else pools.add)
    return table, (None if pools is None else pools.finish(out))


def manifest_traces(path: str | os.PathLike, read_options: dict | None = None
                    ) -> tuple[pd.DataFrame, list[tuple[str, str, Callable]]]:
    """A manifest and its rows as (trace_id, file, load) triples, each trace read when
    fitted (a file that cannot be read keeps its row in the table)."""
    from .io.manifest import load_trace, read_manifest

    opts = read_options or {}
    manifest = read_manifest(path)
    rows = [r for _, r in manifest.iterrows()]
    return manifest, [(str(r["trace_id"]), str(r["file"]), lambda r=r: load_trace(r, **opts))
                      for r in rows]


@dataclass
class RheologyRun:
    """Viscoelastic fits of a recording's or a manifest's traces.

    Attributes
    ----------
    table
        One row per trace and model: ``rheology.csv``
        (:mod:`palpbayes.rheology.results`).
    pooled
        A manifest's power laws pooled over speeds (``rheology_pooled.csv``; empty when no
        group has two traces), None for a recording or models without the power law.
    options
        The checked options of the run.
    source
        The recording or manifest.
    folder
        Where the run's files wait until :meth:`save` (a temporary folder, removed with the
        object).
    """

    table: pd.DataFrame
    pooled: pd.DataFrame | None
    options: RheologyOptions
    source: Path
    folder: Path

    def __repr__(self) -> str:
        n = self.table["trace_id"].nunique() if "trace_id" in self.table else 0
        ok = int(self.table.get("model_ok", pd.Series(dtype=bool)).fillna(False).sum())
        pooled = 0 if self.pooled is None else len(self.pooled)
        return (f"RheologyRun({self.source.name!r}: {n} trace(s), "
                f"{'/'.join(self.options.rheology)}, {ok} of {len(self.table)} fit(s) pass "
                f"their model check, {pooled} pooled group(s))")

    def summary(self) -> pd.DataFrame:
        """One row per trace and model: the table ``palpbayes fit --rheology`` writes as
        ``rheology.csv`` (a copy)."""
        return self.table.copy()

    def fit(self, trace_id: str, rheology: str | None = None) -> StoredRheologyFit:
        """The stored fit of one trace (its draws and force bands:
        :func:`palpbayes.rheology.store.load_rheology_fit`); ``rheology`` picks the model
        when several were fitted."""
        from .outputs import rheology_fit_path
        from .rheology.store import load_rheology_fit

        models = self.options.rheology
        name = rheology or models[0]
        if rheology is None and len(models) > 1:
            raise InputError(f"{len(models)} models were fitted: pick one with rheology= "
                             f"({', '.join(models)})")
        path = rheology_fit_path(self.folder, trace_id, name)
        if not path.is_file():
            ids = ", ".join(map(str, self.table["trace_id"].unique()))
            raise InputError(f"no stored {name} fit of {trace_id!r} (traces: {ids}; a trace "
                             "that failed has its reason in the table's error column)")
        return load_rheology_fit(path)

    def plot(self) -> Figure:
        """Each fitted trace's relaxation modulus E*(t) with its 90 % band
        (:func:`palpbayes.plots.rheology.plot_relaxation`): a Figure."""
        from .plots.rheology import plot_relaxation

        error = self.table.get("error", pd.Series("", index=self.table.index))
        ok = self.table[error.fillna("").eq("")]
        many = len(self.options.rheology) > 1
        fits = {(f"{r['trace_id']} ({r['rheology']})" if many else str(r["trace_id"])):
                self.fit(r["trace_id"], r["rheology"]) for _, r in ok.iterrows()}
        if not fits:
            raise InputError(f"{self.source}: no trace was fitted (see the table's error "
                             "column)")
        return plot_relaxation(fits)

    def save(self, out: str | os.PathLike, *, force: bool = False) -> Path:
        """Write what ``palpbayes fit --rheology ... --out DIR`` writes: ``rheology.csv``,
        ``rheology_pooled.csv`` (when a group pooled) and the stored fits ``rheology/*.nc``;
        the table last, so a folder with a table holds its fits.  ``force`` replaces an
        earlier run's.  Returns the folder."""
        from .io.atomic import write_with
        from .rheology.store import clear_rheology_outputs

        out = Path(out)
        if out.exists() and not out.is_dir():
            raise InputError(f"{out} exists and is not a folder")
        if (out / RHEOLOGY_TABLE).exists() and not force:
            raise InputError(f"{out / RHEOLOGY_TABLE} exists; pass force=True to overwrite it")
        (out / RHEOLOGY_DIR).mkdir(parents=True, exist_ok=True)
        clear_rheology_outputs(out)
        names = [p.relative_to(self.folder) for p in sorted(self.folder.rglob("*"))
                 if p.is_file() and p.name != RHEOLOGY_TABLE]
        for rel in [*names, Path(RHEOLOGY_TABLE)]:
            write_with(lambda tmp, rel=rel: shutil.copyfile(self.folder / rel, tmp),
                       out / rel, suffix=rel.suffix)
        return out


def _traces_of(source, tip: Tip | None, thickness, read_options: dict, segments: str):
    """(manifest or None, the traces to fit) of a path."""
    from .io.manifest import is_manifest
    from .io.recording import read_recording, recording_kind

    path = Path(source)
    if path.is_file() and is_manifest(path):
        if tip is not None or thickness is not None:
            raise InputError(f"{path} is a manifest: it gives each row's tip and thickness "
                             "in its columns (leave tip= and thickness= out)")
        return manifest_traces(path, read_options)
    from .api import _thickness

    opts = dict(read_options)
    if recording_kind(path) == "afm":  # the fitted segments, as the command line reads them
        opts.setdefault("segments", segments)
    return None, read_recording(path, tip=tip, thickness=_thickness(thickness), **opts)


def fit_rheology(source, rheology: str | Sequence[str] = "power-law", *,
                 tip: str | Tip | None = None, radius: float | None = None,
                 thickness: float | None = None, seed: int | None = None,
                 progress: bool | None = None, read_options: dict | None = None,
                 **options: Any) -> RheologyFit | RheologyRun:
    """Relaxation moduli from a ramp, a hold and a retract, as ``palpbayes fit --rheology``
    fits them.

    Parameters
    ----------
    source
        An :class:`~palpbayes.trace.IndentationTrace` (one fit, returned as a
        :class:`~palpbayes.rheology.fit.RheologyFit`: ``options`` are those of
        :func:`palpbayes.rheology.fit.fit_rheology`), or a recording (trace CSV, bag, AFM
        file: every curve) or a manifest CSV (each row's trace; a specimen x tip at several
        speeds pooled), returned as a :class:`RheologyRun`.
    rheology
        ``"power-law"``, ``"sls"``, ``"elastic"``, or several (compared by PSIS-LOO; a
        recording or manifest only).
    tip, radius
        The indenter of a recording (``tip="sphere", radius=...`` or a :class:`Tip`); a
        manifest names it per row.
    thickness
        [m] The specimen's thickness (a recording; with ``nu`` the table gains the modulus a
        compression test would read).
    seed
        Seed of the draws (default 0, as the command line's).
    progress
        A progress bar over the traces (None: on a terminal).
    read_options
        Columns, units, signs of a trace CSV (as ``palpbayes fit`` reads them).
    **options
        :func:`rheology_options` for a recording or manifest (``segments``, ``t0``, ``nu``,
        ``drag``, ``baseline``, ``engine``, ``adhesion``, ``peer``,
        ``compression_speed_mm_min``).

    Returns
    -------
    RheologyFit or RheologyRun
        One fit of a trace; a run of a file or manifest (``.summary()`` is ``rheology.csv``,
        ``.pooled`` ``rheology_pooled.csv``, ``.save(DIR)``, ``.plot()``, ``.fit(trace_id)``).
    """
    from .api import make_tip

    tip_obj = make_tip(tip, radius=radius) if (tip is not None or radius is not None) else None
    if isinstance(source, IndentationTrace):
        from .rheology.fit import fit_rheology as fit_one

        if read_options or thickness is not None:
            raise InputError("read_options and thickness apply to a file, not to a trace")
        if not isinstance(rheology, str):
            raise InputError("a trace is fitted one model at a time (compare them with "
                             "pb.compare_rheology), or give a file to fit several")
        if seed is not None:
            options["seed"] = seed
        return fit_one(source, rheology, tip=tip_obj, **options)
    if not isinstance(source, str | os.PathLike):
        raise InputError(f"fit_rheology takes a path or an IndentationTrace, not "
                         f"{type(source).__name__}")
    allowed = {f.name for f in fields(RheologyOptions)} - {"rheology", "seed"}
    unknown = sorted(set(options) - allowed)
    if unknown:
        raise InputError(f"fit_rheology: unknown option(s) {', '.join(unknown)} for a file; "
                         f"use {', '.join(sorted(allowed))}")
    opts = rheology_options(rheology, seed=0 if seed is None else seed, **options)
    path = Path(source)
    if not path.exists():
        raise InputError(f"{path}: file not found (a trace CSV, ROS 2 bag, AFM file or "
                         "manifest)")
    manifest, traces = _traces_of(path, tip_obj, thickness, read_options or {}, opts.segments)
    folder = Path(tempfile.mkdtemp(prefix="palpbayes-rheology-"))
    try:
        table, pooled = run_rheology(traces, opts, folder, manifest=manifest,
                                     progress=progress)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    run = RheologyRun(table, pooled, opts, path, folder)
    weakref.finalize(run, shutil.rmtree, folder, ignore_errors=True)
    return run
