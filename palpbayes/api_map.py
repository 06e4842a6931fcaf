"""The map's front door: one builder of a map run that :func:`palpbayes.fit_map` and
``palpbayes map`` both call, and the files a run writes (as :mod:`palpbayes.api` is the trace
fit's).

A map is a manifest (rows with ``x_m``, ``y_m``) or an AFM force map (positions from the file,
the tip given).  :class:`MapRequest` holds what a user chooses; :func:`prepare_map` reads and
checks the source (every trace file's header too, before a cluster starts) into a
:class:`MapJob`; :func:`run_map` fits it into a :class:`MapFit`, whose ``save`` writes the folder
(:mod:`palpbayes.maps.files`) with its figure and report, all or nothing.

>>> import palpbayes as pb
>>> m = pb.fit_map("phantom/manifest.csv", seed=0)          # doctest: +SKIP
>>> m.summary().head(); m.save("phantom-map")                # doctest: +SKIP
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from .campaign.options import FitOptions
from .contact import Tip, check_nu
from .errors import InputError
from .io.afm import is_afm_file
from .io.manifest import read_manifest
from .maps import run as map_run
from .maps.pertrace import PointOptions
from .maps.run import MapOptions, MapResult, check_map_manifest

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["MapRequest", "MapJob", "MapFit", "prepare_map", "run_map", "fit_map"]


@dataclass(frozen=True)
class MapRequest:
    """What a map run is asked to do (the options of ``palpbayes map``).

    Parameters
    ----------
    tip, thickness
        An AFM force map's tip and the specimen's thickness [m] (no AFM file records them); a
        manifest gives both in its columns.
    nu, noise, tare, f_unc
        The per-point fits (the exact engine, each point a half-space): Poisson's ratio
        (None: the manifest's column, else 0.3), the noise model, subtract the pre-contact
        level, the contact threshold [N].
    seed
        Random seed of the fits, the field and the lump model.
    threshold, detect, lump, lump_max_steps
        :class:`~palpbayes.maps.run.MapOptions` (``lump`` None: on for a manifest, off for an
        AFM map).
    read_options
        Columns, units and signs of the trace files (as ``palpbayes fit`` reads them).
    afm_meta
        An AFM map's metadata the file lacks (spring constant, sensitivity, sample rate).
    """

    tip: Tip | None = None
    thickness: float | None = None
    nu: float | None = None
    noise: str = "gaussian"
    tare: bool = False
    f_unc: float | None = None
    seed: int = 0
    threshold: float = 1.1
    detect: float = 0.5
    lump: bool | None = None
    lump_max_steps: int = 20000
    read_options: dict = field(default_factory=dict)
    afm_meta: dict = field(default_factory=dict)


@dataclass(frozen=True)
class MapJob:
    """A checked map run: its source, rows and options."""

    source: Path
    afm: bool
    manifest: pd.DataFrame
    point_options: PointOptions
    options: MapOptions
    checked: tuple  # (Tip, thickness [m] or None): check_map_manifest's answer


def _afm_rows(source: Path, req: MapRequest) -> pd.DataFrame:
    """The map rows of an AFM force map (:func:`palpbayes.maps.afm_source.afm_map_rows`),
    with the request's thickness."""
    from .maps.afm_source import afm_map_rows

    if req.tip is None:
        raise InputError(f"{source} is an AFM force map: give the tip (e.g. tip=Tip.sphere"
                         "(5e-6), or --tip sphere --radius 5e-6); no AFM file records it")
    rows = afm_map_rows(source, req.tip, **({"meta_override": req.afm_meta}
                                              if req.afm_meta else {}))
    if req.thickness is not None:
        if not req.thickness > 0:
            raise InputError(f"thickness {req.thickness!r} must be a positive length [m]")
        rows["thickness_m"] = float(req.thickness)
    return rows


def prepare_map(source: str | os.PathLike, request: MapRequest | None = None, *,
                scheduler: str | None = None) -> MapJob:
    """Read and check a map's source (a manifest CSV or an AFM force map) for ``request``.

    Raises
    ------
    InputError
        The source, a trace file's header or an option is not usable: the message names it
        and what to do.
    """
    label = str(source)  # as the user wrote it, for the messages
    source = Path(source)
    req = request or MapRequest()
    nu = None if req.nu is None else check_nu(req.nu)
    # each point a half-space: the lump's forward model (palpbayes.inclusion) reads the
    # block's thickness itself, and the map's per-point fits compare points with each other;
    # built first, so that its own checks (seed, f_unc, noise) come before any file is read
    fit = FitOptions(nu=nu, noise=req.noise, tare=req.tare, f_unc=req.f_unc, engine="exact",
                     seed=req.seed, layer="off")
    if req.tip is not None and not isinstance(req.tip, Tip):
        raise InputError(f"tip {req.tip!r} must be a palpbayes.Tip (e.g. Tip.sphere(5e-6))")
    if req.lump_max_steps < 1000:
        raise InputError(f"lump_max_steps {req.lump_max_steps} is too few; use at least 1000")
    afm = is_afm_file(source)
    if not afm and (req.tip is not None or req.thickness is not None or req.afm_meta):
        given = [n for n, v in (("tip", req.tip), ("thickness", req.thickness))
                 if v is not None] + (["AFM metadata"] if req.afm_meta else [])
        raise InputError(f"{', '.join(given)}: for an AFM force map; a manifest gives the tip "
                         "and the thickness in its columns (tip, radius_m ..., thickness_m)")
    lump = (not afm) if req.lump is None else bool(req.lump)
    # a map is one block: a manifest's material label is optional (it pools nothing here)
    manifest = _afm_rows(source, req) if afm else read_manifest(source, default_material="")
    point_opts = PointOptions(
        fit=fit, seed=req.seed,
        read_options={**({"meta_override": req.afm_meta} if afm and req.afm_meta else {}),
                      **req.read_options})
    # an AFM line of curves (QI data) maps as a line; a manifest's grid must be 2-D
    map_opts = MapOptions(threshold=req.threshold, detect=req.detect, seed=req.seed,
                          lump=lump, lump_max_steps=req.lump_max_steps,
                          min_points=4 if afm else 10, line=afm)
    try:  # every trace file's header too: a bad column is reported before a cluster starts
        checked = check_map_manifest(
            manifest, lump=lump, min_points=map_opts.min_points, line=map_opts.line,
            read_options=point_opts.read_options, source=label,
            remote=scheduler not in (None, "local"))
    except InputError as exc:
        if not afm:
            raise
        raise InputError(f"{label}: {exc}; a field needs at least 4 curves (on a grid or a "
                         "line); fit the curves one by one with palpbayes fit "
                         f"{label} --tip ...") from None
    return MapJob(source, afm, manifest, point_opts, map_opts, checked)


def run_map(job: MapJob, *, scheduler: str | None = None, workers: int | None = None,
            progress: bool | None = None) -> MapFit:
    """Fit a prepared map (:func:`palpbayes.maps.run.make_map`)."""
    t0 = time.perf_counter()
    # through the module, so that a test's patch of maps.run.make_map reaches it
    res = map_run.make_map(job.manifest, point_options=job.point_options,
                           options=job.options, scheduler=scheduler, workers=workers,
                           progress=progress, checked=job.checked)
    return MapFit(res, job.source, job.afm, time.perf_counter() - t0)


def _truth(folder: Path) -> dict | None:
    """The simulator's lump truth next to the manifest (for the figures), if any."""
    try:
        from .sim.map import read_map_truth

        return read_map_truth(folder)
    except (ImportError, OSError, ValueError, KeyError, InputError):
        return None


@dataclass
class MapFit:
    """A map run: its :class:`~palpbayes.maps.run.MapResult` (``result``: the points, the
    field, the lump), where it came from and how long it took [s]."""

    result: MapResult
    source: Path
    afm: bool
    elapsed_s: float

    def summary(self) -> pd.DataFrame:
        """The map per lattice node: the table ``palpbayes map`` writes as ``map.csv``."""
        return self.result.nodes.copy()

    @property
    def truth(self) -> dict | None:
        """The simulator's lump truth beside a simulated phantom's manifest, else None."""
        return None if self.afm else _truth(self.source.parent)

    def plot(self) -> Figure:
        """The four panels of ``map.png`` (:func:`palpbayes.plots.maps.plot_map`): a Figure."""
        from .reporting.map_pages import map_figure

        return map_figure(self.result, truth=self.truth)

    def save(self, out: str | os.PathLike, *, force: bool = False,
             report: bool = True) -> Path:
        """Write the folder ``palpbayes map`` writes: tables, netCDF, settings and
        (``report``) ``map.png`` and ``map-report.pdf``; all or nothing (a staging folder
        published at the end).  ``force`` replaces the map files of an existing folder.
        Returns the folder."""
        from .maps.files import FIGURE, REPORT, discard, prepare_out_dir, publish, write_map

        res = self.result
        stage = prepare_out_dir(out, force)
        try:
            write_map(res, stage, extra={("afm_file" if self.afm else "manifest"):
                                         str(self.source.resolve()),
                                         "elapsed_s": self.elapsed_s})
            if report:
                from .reporting.map_pages import write_map_figure, write_map_report

                truth = self.truth
                write_map_figure(res, stage / FIGURE, truth=truth)
                write_map_report(res, stage / REPORT, truth=truth,
                                 name=self.source.name if self.afm else self.source.parent.name)
        except BaseException:
            discard(stage)
            raise
        return publish(stage, out)


def fit_map(source: str | os.PathLike, *, seed: int = 0, scheduler: str | None = None,
            workers: int | None = None, progress: bool | None = None,
            **request) -> MapFit:
    """A stiffness map of a manifest or an AFM force map, as ``palpbayes map`` makes it.

    Parameters
    ----------
    source
        Manifest CSV (``x_m``, ``y_m`` per row) or AFM force map file.
    seed
        Random seed (default 0, as the command line's).
    scheduler, workers, progress
        Dask scheduler address (None: a LocalCluster), its worker processes, progress bars.
    **request
        Any field of :class:`MapRequest` (``tip=``, ``nu=``, ``lump=``, ``threshold=`` ...).

    Returns
    -------
    MapFit
        ``.summary()`` is ``map.csv``, ``.save(DIR)`` writes the folder ``palpbayes map``
        writes, ``.plot()`` draws ``map.png``'s figure, ``.result`` holds the rest.
    """
    unknown = sorted(set(request) - set(MapRequest.__dataclass_fields__))
    if unknown:
        raise InputError(f"fit_map: unknown option(s) {', '.join(unknown)}; use "
                         f"{', '.join(MapRequest.__dataclass_fields__)}")
    req = replace(MapRequest(**request), seed=seed)
    job = prepare_map(source, req, scheduler=scheduler)
    return run_map(job, scheduler=scheduler, workers=workers, progress=progress)
