"""Viscoelastic fits kept in a results folder and read back, so that the report draws them
without fitting anything.

:func:`save_rheology_fit` writes one netCDF file per trace and relaxation model,
``DIR/rheology/<trace_id>_<rheology>.nc`` (:func:`~palpbayes.outputs.rheology_fit_path`),
atomically (a temporary file renamed), with h5netcdf through xarray: a plain dataset that
``xarray.open_dataset(path, engine="h5netcdf")`` opens; nothing is pickled.  It holds

* dimension ``draw``: :data:`STORED_DRAWS` posterior draws, evenly spread over the fit's, of
  every parameter of ``fit.draws`` (moduli E* [Pa], ``alpha`` [-] or ``tau`` [s], ``z_surf``
  [m], ``offset`` [N], ``sigma`` [N], ``phi`` [-], ``drag`` [N·s/m] with a drag term), each
  with its ``units``;
* dimension ``point``: the fitted block means ``time`` [s] (from the first fitted sample),
  ``z`` [m], ``force`` [N] and ``segment`` (code into :data:`~palpbayes.trace.SEGMENTS`);
* dimension ``point``: the median and central 90 % band (``force_median``, ``force_lo``,
  ``force_hi`` [N]) of the model force at the block means over :data:`BAND_CURVES` draws
  (:meth:`RheologyFit.force_curves <palpbayes.rheology.RheologyFit.force_curves>`), and
  (dimensions ``curve`` × ``point``) :data:`STORED_CURVES` of those curves, ``model_force`` [N]
  in single precision (a file stays small: 50 curves of 800 points are 160 kB);
* dimension ``relax_time``: E*(t) [Pa], median and central 90 % band (``E_star_pa``,
  ``E_star_lo_pa``, ``E_star_hi_pa``) at the times ``relax_time_s`` [s] (:func:`relaxation_grid`:
  log-spaced from the shortest step between block means to the fitted span);
* dimension ``sample``: the recorded cycle, every segment (also those not fitted: the
  retract's hysteresis), as block means of at most :data:`RECORD_POINTS` points (``record_time``
  [s], ``record_z`` [m], ``record_force`` [N], ``record_segment``);
* attributes: ``rheology``, ``t0_s``, ``nu`` (NaN when not given), ``trace_id``, ``source``,
  ``segments``, ``tip_kind``, ``tip`` (its description) and its size (``tip_radius_m``, ...),
  ``model_ok``, ``flags`` (JSON list of strings), ``units`` (JSON), ``level``, ``z_surf_m`` (the
  median of all draws), ``ess``, ``n_draws_fit``, ``block``, ``palpbayes_version``.

:func:`load_rheology_fit` reads one back as a :class:`StoredRheologyFit` (what the report's
pages and :mod:`palpbayes.plots.rheology` need); :func:`clear_rheology_outputs` removes a
previous run's table and stored fits (``fit --rheology --force``).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from .. import __version__, outputs
from ..errors import DataFileError, InputError
from ..intervals import LEVEL, central_band
from ..io.atomic import write_with
from ..trace import IndentationTrace

if TYPE_CHECKING:
    from .fit import RheologyFit

__all__ = ["StoredRheologyFit", "StoredCycle", "StoredRecord", "save_rheology_fit",
           "load_rheology_fit",
           "clear_rheology_outputs", "relaxation_grid", "STORED_DRAWS", "STORED_CURVES",
           "BAND_CURVES", "RELAXATION_POINTS", "RECORD_POINTS"]

#: Posterior draws kept per stored fit (evenly spread over the fit's draws).
STORED_DRAWS = 1000
#: Model force curves behind the stored band of force against time.
BAND_CURVES = 200
#: Model force curves kept in the file (evenly spread over the band's).
STORED_CURVES = 50
#: Times of the stored E*(t) band.
RELAXATION_POINTS = 60
#: Most points of the stored record (the hysteresis figure).
RECORD_POINTS = 2000
#: Version of the file's layout (attribute ``format_version``).
FORMAT_VERSION = 1


def relaxation_grid(data) -> np.ndarray:
    """[s] :data:`RELAXATION_POINTS` log-spaced times from the shortest step between block means
    to the fitted span of ``data`` (a :class:`~palpbayes.rheology.CycleData` or
    :class:`StoredCycle`)."""
    return np.geomspace(data.dt_min, data.span, RELAXATION_POINTS)


@dataclass(frozen=True)
class StoredCycle:
    """The fitted block means of a stored fit, as in :class:`~palpbayes.rheology.CycleData`:
    ``time`` [s], ``z`` [m], ``force`` [N], ``segment`` (codes into
    :data:`~palpbayes.trace.SEGMENTS`) and the fitted ``segments``' names."""

    time: np.ndarray
    z: np.ndarray
    force: np.ndarray
    segment: np.ndarray
    segments: tuple[str, ...]

    @property
    def n_points(self) -> int:
        return int(self.time.size)

    @property
    def dt_min(self) -> float:
        """[s] Shortest step between block means."""
        return float(np.diff(self.time).min())

    @property
    def span(self) -> float:
        """[s] Duration of the fitted record."""
        return float(self.time[-1] - self.time[0])


@dataclass(frozen=True)
class StoredRecord:
    """The recorded cycle of a stored fit, every segment, as block means: ``time`` [s],
    ``z`` [m], ``force`` [N], ``segment`` (codes), ``trace_id``."""

    time: np.ndarray
    z: np.ndarray
    force: np.ndarray
    segment: np.ndarray
    trace_id: str


@dataclass(frozen=True)
class StoredRheologyFit:
    """A viscoelastic fit as stored in a results folder (module docstring): what the report
    draws, read back without fitting.

    It offers what :mod:`palpbayes.plots.rheology` takes from a
    :class:`~palpbayes.rheology.RheologyFit` (``rheology``, ``model_ok``, ``t0``, ``flags``,
    ``data``, ``draws``, :meth:`force_curves`, :meth:`relaxation`), from the stored numbers
    only, and the stored band itself (:meth:`band`).

    Attributes
    ----------
    path, trace_id, source
        The netCDF file; the trace and the file it was read from.
    rheology, t0, nu
        ``"power-law"`` or ``"sls"``; [s] the power law's reference time; Poisson's ratio or
        None.
    tip_kind, tip
        The tip's kind and its description (``'paraboloid R=11.7 mm'``).
    model_ok, flags
        The fit's model check passed (and phi is not at its bound); its flags in words.
    units, level
        Parameter -> unit; the central probability of the stored bands.
    z_surf
        [m] Posterior median of the surface (all draws).
    draws, data
        Parameter -> thinned posterior draws; the fitted block means.
    curves
        [N] (curves, points) some model force curves at the block means.
    force_band
        [N] (lo, median, hi) of the model force at ``level`` over :data:`BAND_CURVES` curves.
    relax
        E*(t): ``time_s``, ``E_star_pa``, ``E_star_lo_pa``, ``E_star_hi_pa`` at ``level``.
    record
        The recorded cycle (every segment).
    """

    path: Path
    trace_id: str
    source: str
    rheology: str
    t0: float
    nu: float | None
    tip_kind: str
    tip: str
    model_ok: bool
    flags: tuple[str, ...]
    units: dict[str, str]
    level: float
    z_surf: float
    draws: dict[str, np.ndarray]
    data: StoredCycle
    curves: np.ndarray
    force_band: tuple[np.ndarray, np.ndarray, np.ndarray]
    relax: pd.DataFrame
    record: StoredRecord

    def force_curves(self, n: int | None = None) -> np.ndarray:
        """[N] The stored model force curves at the block means: ``n`` of them evenly spread
        (all by default, and at most all)."""
        k = self.curves.shape[0]
        return self.curves if n is None or n >= k else self.curves[_thin(k, max(int(n), 1))]

    def band(self, level: float = LEVEL) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """[N] Lower bound, median and upper bound of the model force at the block means: the
        stored band at its ``level``; at another level, the band of the stored curves (fewer
        draws: rougher)."""
        if math.isclose(level, self.level, abs_tol=1e-12):
            return self.force_band
        return central_band(self.curves, level, axis=0)

    def relaxation(self, times=None, level: float = LEVEL) -> pd.DataFrame:
        """E*(t) [Pa]: the stored median and band (``times`` None or the stored times), else
        interpolated linearly in log E* against log t between the stored times (NaN outside
        them).

        Raises
        ------
        InputError
            ``level`` is not the stored band's.
        """
        if not math.isclose(level, self.level, abs_tol=1e-12):
            raise InputError(f"{self.path}: the stored E*(t) band is the central "
                             f"{100 * self.level:g} %; {100 * level:g} % needs the fit itself")
        grid = self.relax["time_s"].to_numpy()
        if times is None:
            return self.relax.copy()
        t = np.atleast_1d(np.asarray(times, dtype=float))
        if t.shape == grid.shape and np.allclose(t, grid, rtol=1e-10, atol=0.0):
            return self.relax.copy()
        out = {"time_s": t}
        with np.errstate(divide="ignore", invalid="ignore"):
            lt = np.log(t)
            for col in ("E_star_pa", "E_star_lo_pa", "E_star_hi_pa"):
                y = np.interp(lt, np.log(grid), np.log(self.relax[col].to_numpy()),
                              left=np.nan, right=np.nan)
                out[col] = np.exp(y)
        return pd.DataFrame(out)


def _thin(n_total: int, n: int) -> np.ndarray:
    return np.linspace(0, n_total - 1, min(n, n_total)).round().astype(int)


def _record_blocks(trace: IndentationTrace, limit: int) -> dict[str, np.ndarray]:
    """Block means of every segment of ``trace`` (no block straddles two segments), at most
    about ``limit`` points in all."""
    from ..io.motion_segments import cycle_segments

    seg = cycle_segments(trace)
    k = max(1, math.ceil(seg.size / limit))
    out: dict[str, list] = {"time": [], "z": [], "force": [], "segment": []}
    bounds = np.flatnonzero(np.diff(seg)) + 1
    for idx in np.split(np.arange(seg.size), bounds):
        n = idx.size // k * k or idx.size  # a segment shorter than a block: one mean
        rows = idx[:n].reshape(-1, k) if idx.size >= k else idx[None, :]
        for name, arr in (("time", trace.time), ("z", trace.z), ("force", trace.force)):
            out[name].append(np.asarray(arr, dtype=float)[rows].mean(axis=1))
        out["segment"].append(np.full(rows.shape[0], seg[idx[0]], dtype=np.int8))
    return {key: np.concatenate(v) for key, v in out.items()}


def _tip_attrs(tip) -> dict:
    if tip is None:
        return {"tip_kind": "", "tip": ""}
    from ..contact import get_law

    attrs = {"tip_kind": tip.kind, "tip": tip.describe()}
    units = {"radius": "m", "half_angle": "rad", "c": "", "n": ""}
    for name in get_law(tip).parameters:
        value = getattr(tip, name, None)
        if value is not None:
            attrs["_".join(p for p in ("tip", name, units.get(name, "")) if p)] = float(value)
    return attrs


def save_rheology_fit(fit: RheologyFit, path: str | os.PathLike, *,
                      trace: IndentationTrace | None = None, n_draws: int = STORED_DRAWS,
                      n_band: int = BAND_CURVES, n_curves: int = STORED_CURVES,
                      level: float = LEVEL) -> Path:
    """Write ``fit`` to the netCDF file ``path`` atomically (module docstring); return it.

    Parameters
    ----------
    fit
        A :func:`~palpbayes.rheology.fit_rheology` result.
    path
        The file (folders created), usually :func:`~palpbayes.outputs.
        rheology_fit_path`.
    trace
        The whole recording, for the hysteresis of every segment; default the fitted
        segments' samples (``fit.data.trace``).
    n_draws
        Posterior draws kept.
    n_band, n_curves
        Model force curves behind the band, and kept in the file.
    level
        Central probability of the stored bands.
    """
    import xarray as xr

    data, draws = fit.data, fit.draws
    n_total = len(draws["z_surf"])
    keep = _thin(n_total, n_draws)
    units = {}
    for _, r in fit.table().iterrows():
        units.setdefault(str(r["parameter"]).rstrip("*"), str(r["unit"]))
    params = [p for p in units if p in draws]
    curves = fit.force_curves(n_band)
    f_lo, f_med, f_hi = central_band(curves, level, axis=0)
    curves = curves[_thin(curves.shape[0], n_curves)].astype(np.float32)
    times = relaxation_grid(data)
    relax = fit.relaxation(times, level)
    rec = _record_blocks(trace if trace is not None else data.trace, RECORD_POINTS)
    src = trace if trace is not None else data.trace
    variables = {p: ("draw", np.asarray(draws[p], dtype=float)[keep], {"units": units[p]})
                 for p in params}
    variables.update(
        time=("point", data.time, {"units": "s"}), z=("point", data.z, {"units": "m"}),
        force=("point", data.force, {"units": "N"}),
        segment=("point", np.asarray(data.segment, dtype=np.int8), {}),
        model_force=(("curve", "point"), curves, {"units": "N"}),
        force_lo=("point", f_lo, {"units": "N"}), force_median=("point", f_med, {"units": "N"}),
        force_hi=("point", f_hi, {"units": "N"}),
        relax_time_s=("relax_time", times, {"units": "s"}),
        **{c: ("relax_time", relax[c].to_numpy(), {"units": "Pa"})
           for c in ("E_star_pa", "E_star_lo_pa", "E_star_hi_pa")},
        record_time=("sample", rec["time"], {"units": "s"}),
        record_z=("sample", rec["z"], {"units": "m"}),
        record_force=("sample", rec["force"], {"units": "N"}),
        record_segment=("sample", rec["segment"], {}))
    attrs = {"format_version": FORMAT_VERSION, "palpbayes_version": __version__,
             "rheology": fit.rheology, "t0_s": float(fit.t0),
             "nu": float("nan") if fit.nu is None else float(fit.nu),
             "trace_id": str(getattr(src, "trace_id", "")), "source": str(src.source or ""),
             "segments": ",".join(data.segments), **_tip_attrs(src.tip),
             "model_ok": int(fit.model_ok), "flags": json.dumps(list(fit.flags)),
             "units": json.dumps(units), "parameters": ",".join(params), "level": float(level),
             "z_surf_m": float(np.median(draws["z_surf"])),
             "ess": float(draws.get("ess", np.nan)), "n_draws_fit": int(n_total),
             "block": int(getattr(data, "block", 1))}
    ds = xr.Dataset({k: xr.Variable(dims, np.asarray(v), attrs=a)
                     for k, (dims, v, a) in variables.items()}, attrs=attrs)
    encoding = {"model_force": {"zlib": True, "complevel": 4}}
    return write_with(lambda tmp: ds.to_netcdf(str(tmp), engine="h5netcdf", encoding=encoding),
                      path, suffix=".nc")


def _frozen(a) -> np.ndarray:
    out = np.array(a)
    out.setflags(write=False)
    return out


def load_rheology_fit(path: str | os.PathLike) -> StoredRheologyFit:
    """The fit :func:`save_rheology_fit` stored in ``path``.

    Raises
    ------
    InputError
        No such file (rerun ``palpbayes fit --rheology ... --force``).
    DataFileError
        The file is not a stored viscoelastic fit, or cannot be read.
    """
    import xarray as xr

    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no stored viscoelastic fit (written by 'palpbayes fit "
                         "--rheology'; rerun it with --force)")
    try:
        with xr.open_dataset(path, engine="h5netcdf") as opened:
            ds = opened.load()
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise DataFileError(path, f"cannot be read as netCDF ({type(exc).__name__}: {exc})",
                            "rerun 'palpbayes fit --rheology ... --force'") from None
    try:
        a = ds.attrs
        if int(a.get("format_version", 0)) != FORMAT_VERSION:
            raise KeyError("format_version")
        params = [p for p in str(a["parameters"]).split(",") if p]
        nu = float(a["nu"])
        segments = tuple(s for s in str(a["segments"]).split(",") if s)
        level = float(a["level"])
        relax = pd.DataFrame({"time_s": ds["relax_time_s"].values,
                              **{c: ds[c].values for c in ("E_star_pa", "E_star_lo_pa",
                                                           "E_star_hi_pa")}})
        data = StoredCycle(*(_frozen(ds[k].values) for k in ("time", "z", "force", "segment")),
                           segments=segments)
        record = StoredRecord(*(_frozen(ds[f"record_{k}"].values)
                                for k in ("time", "z", "force", "segment")),
                              trace_id=str(a["trace_id"]))
        return StoredRheologyFit(
            path=path, trace_id=str(a["trace_id"]), source=str(a.get("source", "")),
            rheology=str(a["rheology"]), t0=float(a["t0_s"]),
            nu=None if math.isnan(nu) else nu, tip_kind=str(a.get("tip_kind", "")),
            tip=str(a.get("tip", "")), model_ok=bool(int(a["model_ok"])),
            flags=tuple(str(f) for f in json.loads(str(a["flags"]))),
            units=dict(json.loads(str(a["units"]))), level=level, z_surf=float(a["z_surf_m"]),
            draws={p: _frozen(ds[p].values) for p in params}, data=data,
            curves=_frozen(ds["model_force"].values),
            force_band=tuple(_frozen(ds[k].values) for k in ("force_lo", "force_median",
                                                              "force_hi")),
            relax=relax, record=record)
    except (KeyError, ValueError, TypeError, json.JSONDecodeError) as exc:
        raise DataFileError(path, f"is not a stored viscoelastic fit (missing or bad {exc})",
                            "rerun 'palpbayes fit --rheology ... --force'") from None


def clear_rheology_outputs(results_dir: str | os.PathLike) -> None:
    """Remove a previous viscoelastic run's files from a results folder
    (:data:`~palpbayes.outputs.RHEOLOGY_OUTPUTS` and the stored fits
    ``rheology/*.nc``); other files are kept."""
    out = Path(results_dir)
    for name in outputs.RHEOLOGY_OUTPUTS:
        (out / name).unlink(missing_ok=True)
    for f in (out / outputs.RHEOLOGY_DIR).glob("*.nc"):
        f.unlink()
