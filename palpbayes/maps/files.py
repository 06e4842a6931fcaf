"""The files of a map folder (``palpbayes map MANIFEST --out DIR``)::

    DIR/
      points.csv      one row per trace: its own posterior of E and the naive least squares
      map.csv         one row per lattice node: posterior mean, sd, 90 % interval of E,
                      P(E > k × background), the points' own values
      lump.csv        the lump: centre, radius, depth, stiffness ratio, apparent peak ratio
                      and FWHM, background, nugget (mean, sd, median, 90 % interval)
      hyper.csv       the field's hyperparameters (sigma_f, range, nugget) over their grid
      map.nc          arviz InferenceData: posterior draws of log E on the lattice (chain,
                      draw, y, x; coordinates in metres), the background and the
                      hyperparameters; observed_data the per-point summaries
      lump.nc         arviz InferenceData of the lump sampler (walkers as chains)
      settings.json   options, versions, flags, detection score
      map.png         heat map, uncertainty, probability, profile (palpbayes.reporting.map_pages)
      map-report.pdf  the report pages

The files are written into a staging folder beside ``DIR`` and moved into it only when the
whole run succeeded (:func:`prepare_out_dir`, :func:`publish`); the csv files open in pandas
(``pd.read_csv``), the netCDF files in arviz (``az.from_netcdf``).
"""

from __future__ import annotations

import json
import os
import platform
import shutil
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from .. import __version__
from ..bayes.diagnostics import import_arviz
from ..errors import OutputExistsError
from ..io.atomic import write_csv_atomic, write_netcdf_atomic, write_text_atomic
from .run import MapResult

__all__ = ["POINTS", "MAP", "LUMP", "HYPER", "MAP_NC", "LUMP_NC", "SETTINGS", "FIGURE",
           "REPORT", "MAP_OUTPUTS", "check_out_dir", "prepare_out_dir", "publish", "discard",
           "write_map"]

POINTS = "points.csv"
MAP = "map.csv"
LUMP = "lump.csv"
HYPER = "hyper.csv"
MAP_NC = "map.nc"
LUMP_NC = "lump.nc"
SETTINGS = "settings.json"
FIGURE = "map.png"
REPORT = "map-report.pdf"
#: Every file a map run writes (``--force`` removes them first).
MAP_OUTPUTS = (POINTS, MAP, LUMP, HYPER, MAP_NC, LUMP_NC, SETTINGS, FIGURE, REPORT)


def prepare_out_dir(out: str | os.PathLike, force: bool) -> Path:
    """Check that ``out`` can take a map (:func:`check_out_dir`) and return a new, empty
    staging folder beside it.  Write everything there, then :func:`publish` it: a run that
    fails leaves ``out`` as it was (the old map, if any, stays until the new one is
    complete)."""
    out = check_out_dir(out, force)
    return Path(tempfile.mkdtemp(prefix=f".{out.name}-partial-", dir=out.parent))


def check_out_dir(out: str | os.PathLike, force: bool) -> Path:
    """``out`` as a Path, once it is known to take a map: not a file, no map files in it
    unless ``force``, its parent made.  ``palpbayes map`` calls it before the fits."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise OutputExistsError(f"{out} exists and is not a folder; choose another --out")
    present = [n for n in MAP_OUTPUTS if (out / n).exists()]
    if present and not force:
        raise OutputExistsError(f"{out} already holds a map ({', '.join(present)}); use --force "
                                "(force=True from Python) to replace it or choose another "
                                "--out")
    out.parent.mkdir(parents=True, exist_ok=True)
    return out


def publish(stage: Path, out: str | os.PathLike) -> Path:
    """Replace the map files in ``out`` by those of the staging folder ``stage``; remove it."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    for n in MAP_OUTPUTS:
        if (out / n).exists() and not (stage / n).exists():
            (out / n).unlink()  # e.g. an old lump.csv when this map has no lump model
    for f in stage.iterdir():
        os.replace(f, out / f.name)
    stage.rmdir()
    return out


def discard(stage: Path) -> None:
    """Remove a staging folder after a failed run."""
    shutil.rmtree(stage, ignore_errors=True)


def _field_idata(res: MapResult):
    az = import_arviz()
    n = res.draws.shape[0]
    chains = 4 if n % 4 == 0 else 1
    shape = (chains, n // chains)
    lat = res.field.lattice
    hyper = res.hyper_draws
    post = {"log_E": res.draws.reshape(*shape, lat.ny, lat.nx),
            "background_E": np.exp(res.background).reshape(shape)}
    post.update({k: np.asarray(v).reshape(shape) for k, v in hyper.items()})
    ok = res.points["error"].fillna("") == ""
    pts = res.points[ok]
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="More chains", category=UserWarning)
        idata = az.from_dict(
            posterior=post,
            observed_data={"logE_mean": pts["logE_mean"].to_numpy(),
                           "logE_sd": pts["logE_sd"].to_numpy()},
            constant_data={"point_x_m": pts["x_m"].to_numpy(),
                           "point_y_m": pts["y_m"].to_numpy()},
            coords={"x": lat.xs, "y": lat.ys},
            dims={"log_E": ["y", "x"], "logE_mean": ["point"], "logE_sd": ["point"],
                  "point_x_m": ["point"], "point_y_m": ["point"]},
        )
    idata.posterior.attrs.update({"units": "log_E: natural log of E/Pa; background_E: Pa; "
                                           "x, y: palpation position [m]",
                                  "threshold_k": res.options.threshold,
                                  "palpbayes_version": __version__})
    return idata


def _lump_idata(res: MapResult):
    az = import_arviz()
    from .lump import LUMP_PARAMS

    ch = res.lump.chains
    post = {name: ch[..., i] for i, name in enumerate(LUMP_PARAMS)}
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="More chains", category=UserWarning)
        return az.from_dict(posterior=post, sample_stats={"lp": res.lump.log_prob})


def _settings(res: MapResult, extra: dict) -> dict:
    import dask
    import scipy

    return {"palpbayes": __version__, "python": platform.python_version(),
            "numpy": np.__version__, "scipy": scipy.__version__, "dask": dask.__version__,
            **res.settings, "detection": res.detection, "p_lump": res.p_lump,
            "lump_found": res.lump_found, "flags": res.flags,
            "contact_radius_m": res.contact_radius, "thickness_m": res.thickness,
            "lattice": {"x0_m": res.field.lattice.x0, "y0_m": res.field.lattice.y0,
                        "step_m": res.field.lattice.step, "nx": res.field.lattice.nx,
                        "ny": res.field.lattice.ny}, **extra}


def write_map(res: MapResult, out: str | os.PathLike, *, extra: dict | None = None) -> list[Path]:
    """Write the tables, netCDF files and settings of a map into ``out`` (figures and the
    report: :func:`palpbayes.reporting.map_pages.write_map_report`); return the paths."""
    out = Path(out)
    paths = [write_csv_atomic(res.points, out / POINTS, index=False),
             write_csv_atomic(res.nodes, out / MAP, index=False),
             write_csv_atomic(res.field.hyper, out / HYPER, index=False)]
    if res.lump is not None:
        paths.append(write_csv_atomic(res.lump.summary(), out / LUMP, index=False))
    write_netcdf_atomic(_field_idata(res), out / MAP_NC)
    paths.append(out / MAP_NC)
    if res.lump is not None:
        write_netcdf_atomic(_lump_idata(res), out / LUMP_NC)
        paths.append(out / LUMP_NC)
    text = json.dumps(_settings(res, extra or {}), indent=2, default=_jsonable)
    paths.append(write_text_atomic(text + "\n", out / SETTINGS))
    return paths


def _jsonable(v):
    if isinstance(v, (np.integer, np.floating)):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, pd.DataFrame):
        return v.to_dict("records")
    return str(v)
