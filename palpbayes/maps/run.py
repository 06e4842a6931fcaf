"""A stiffness map from a map manifest: per-point fits, the spatial field, the lump.

Three stages:

1. every trace's posterior of log E by the exact engine, on Dask (:mod:`~.pertrace`);
2. the one-inclusion model (:mod:`~.lump`) fitted to those points, started at the largest
   excess of the smoothed points: centre, radius, depth, stiffness ratio and apparent peak
   ratio with their intervals, and P(apparent peak ratio > k).  It comes first because a
   stationary field prior alone shrinks a small lump on a large map to nothing (measured: a
   +22 % lump on a 100 × 100 map came out +7 %);
3. the log-modulus field over the palpation lattice, a sparse SPDE/GMRF prior with its
   hyperparameters integrated out (:mod:`~.gmrf`), fitted to what the lump's posterior-mean
   profile leaves; each field draw plus one lump draw is a draw of the map: posterior mean,
   sd and interval of E at every node, and P(E > k × background), the background being the
   median of the map per draw.

Computation only: files are written by :mod:`~.files`, figures by :mod:`palpbayes.plots.maps`.
"""

# Long module: one job, the map pipeline (per-point fits, field, lump) and its manifest check.

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..contact import Tip
from ..errors import InputError
from ..flagcodes import scoped
from ..inclusion import contact_radius as tip_contact_radius
from ..intervals import LEVEL, central, central_band
from ..io.manifest import check_trace_headers, tip_from_row
from .afm_source import NO_CURVE, is_afm_row
from .gmrf import FieldPosterior, FieldPrior, fit_field, robust_spread
from .lattice import lattice_from_positions
from .lump import LumpPosterior, fit_lump
from .pertrace import PointOptions, check_positions, fit_points

#: sd of log E given to a point without a fit: no information, but its node stays on the map.
_NO_DATA_SD = 1e3

__all__ = ["MapOptions", "MapResult", "NODE_COLUMNS", "check_map_manifest", "make_map",
           "map_from_points", "nu_used"]

#: Columns of the node table (``map.csv``), one row per lattice node.
NODE_COLUMNS = [
    "ix", "iy", "x_m", "y_m", "n_traces", "logE_mean", "logE_sd", "E_mean_pa", "E_sd_pa",
    "E_rel_sd", "E_lo_pa", "E_hi_pa", "p_stiffer", "E_point_pa", "E_point_lo_pa",
    "E_point_hi_pa", "E_lsq_pa",
]


@dataclass(frozen=True)
class MapOptions:
    """Settings of the spatial and lump stages.

    Parameters
    ----------
    threshold
        k of P(E > k × background) (> 1).
    detect
        Report a lump when P(apparent peak ratio > k) >= this (0: always).
    field_draws
        Joint posterior draws of the field.
    lump_max_steps
        Cap on the emcee steps per walker of the lump model (it stops earlier once converged).
    seed
        Seed of the field draws and the lump sampler.
    lump
        Fit the lump model at all.
    min_points
        Fewest fitted points a map takes (>= 4; below 10 a flag says the field's
        hyperparameters come from their priors: an AFM map of 2 × 2 curves).
    line
        Accept palpations on one row or column (an AFM line of QI curves): the 2-D field
        observed along a line, a flag saying so.
    """

    threshold: float = 1.1
    detect: float = 0.5
    field_draws: int = 1000
    lump_max_steps: int = 20000
    seed: int = 0
    lump: bool = True
    min_points: int = 10
    line: bool = False

    def __post_init__(self) -> None:
        if not (isinstance(self.min_points, int) and self.min_points >= 4):
            raise InputError(f"min_points = {self.min_points!r} must be a whole number of at "
                             "least 4")
        if not (self.threshold > 1 and math.isfinite(self.threshold)):
            raise InputError(f"threshold k = {self.threshold!r} must be a number above 1 (E > k "
                             "× background), e.g. 1.1")
        if not 0 <= self.detect <= 1:
            raise InputError(f"detect = {self.detect!r} must be a probability in [0, 1]")
        if self.field_draws < 100:
            raise InputError(f"field_draws = {self.field_draws!r} must be at least 100")


@dataclass
class MapResult:
    """Everything a map run computed (files: :func:`palpbayes.maps.files.write_map`)."""

    points: pd.DataFrame
    nodes: pd.DataFrame
    field: FieldPosterior
    draws: np.ndarray  # (n, ny, nx) log E of the data lattice
    background: np.ndarray  # (n,) log of the per-draw median
    hyper_draws: dict  # (n,) draws of sigma_f, range_m, tau, beta with the field's
    lump: LumpPosterior | None
    detection: float  # largest P(E > k × background) over the nodes
    flags: list[str]  # "info: ..." is information, any other flag a warning
    contact_radius: float
    thickness: float | None
    options: MapOptions
    settings: dict = field(default_factory=dict)
    p_lump: float = float("nan")  # P(apparent peak ratio > k) of the lump model

    @property
    def lump_found(self) -> bool:
        """The lump model ran and P(apparent peak ratio > k) >= ``options.detect``."""
        return self.lump is not None and not self.p_lump < self.options.detect

    @property
    def lump_summary(self) -> pd.DataFrame | None:
        return None if self.lump is None else self.lump.summary()

    def background_interval(self, level: float = LEVEL) -> tuple[float, float, float]:
        """[Pa] Median and central interval of the background (median of the field)."""
        b = np.exp(self.background)
        lo, hi = central(b, level)
        return float(np.median(b)), lo, hi

    def lump_centre(self) -> dict[str, tuple[float, float, float]] | None:
        """``{"x_m": (median, lo, hi), "y_m": (...)}`` of a found lump's centre, or None."""
        if not self.lump_found:
            return None
        d = self.lump.draws
        return {k: (float(np.median(d[k])), *central(d[k].to_numpy())) for k in ("x_m", "y_m")}


def _node_table(fp: FieldPosterior, node: np.ndarray, points: pd.DataFrame, ok: np.ndarray,
                draws: np.ndarray, bg: np.ndarray, threshold: float) -> pd.DataFrame:
    lat = fp.lattice
    n = draws.shape[0]
    flat = draws.reshape(n, -1)
    E = np.exp(flat)
    lo, _, hi = central_band(E, LEVEL, axis=0)
    ix, iy = np.meshgrid(np.arange(lat.nx), np.arange(lat.ny))
    nodes = pd.DataFrame({
        "ix": ix.ravel(), "iy": iy.ravel(), "x_m": lat.node_x.ravel(), "y_m": lat.node_y.ravel(),
        "logE_mean": flat.mean(axis=0), "logE_sd": flat.std(axis=0, ddof=1),
        "E_mean_pa": E.mean(axis=0), "E_sd_pa": E.std(axis=0, ddof=1),
        "E_lo_pa": lo, "E_hi_pa": hi,
        "p_stiffer": (flat - bg[:, None] > math.log(threshold)).mean(axis=0),
    })
    nodes["E_rel_sd"] = nodes["E_sd_pa"] / nodes["E_mean_pa"]
    per = pd.DataFrame({"node": node[ok],
                        "E_point_pa": points.loc[ok, "E_median_pa"].to_numpy(),
                        "E_point_lo_pa": points.loc[ok, "E_lo_pa"].to_numpy(),
                        "E_point_hi_pa": points.loc[ok, "E_hi_pa"].to_numpy(),
                        "E_lsq_pa": points.loc[ok, "E_lsq_pa"].to_numpy()})
    agg = per.groupby("node").agg(n_traces=("E_point_pa", "size"),
                                  E_point_pa=("E_point_pa", "median"),
                                  E_point_lo_pa=("E_point_lo_pa", "median"),
                                  E_point_hi_pa=("E_point_hi_pa", "median"),
                                  E_lsq_pa=("E_lsq_pa", "median"))
    nodes = nodes.join(agg, how="left")
    nodes["n_traces"] = nodes["n_traces"].fillna(0).astype(int)
    return nodes[NODE_COLUMNS]


def _guess(lat, node: np.ndarray, mean: np.ndarray, a: float, tau: float) -> dict:
    """Starting values of the lump model: the largest excess of the per-point log E smoothed
    over about a contact radius (a stationary field would shrink a small lump on a large map,
    so the raw points are used), its half-maximum area and its height."""
    from scipy import ndimage

    grid = np.full(lat.n_nodes, np.nan)
    sums = np.bincount(node, weights=mean, minlength=lat.n_nodes)
    counts = np.bincount(node, minlength=lat.n_nodes)
    grid[counts > 0] = sums[counts > 0] / counts[counts > 0]
    bg = float(np.nanmedian(grid))
    grid = np.where(np.isfinite(grid), grid, bg).reshape(lat.ny, lat.nx) - bg
    smooth = ndimage.gaussian_filter(grid, sigma=max(1.0, 0.5 * a / lat.step), mode="nearest")
    iy, ix = np.unravel_index(int(np.argmax(smooth)), smooth.shape)
    peak = float(smooth[iy, ix])
    labels, _ = ndimage.label(smooth >= 0.5 * peak)
    blob = labels == labels[iy, ix]
    w = np.where(blob, smooth, 0.0)
    yy, xx = np.mgrid[0:lat.ny, 0:lat.nx]
    return {"apparent": float(np.exp(max(grid[iy, ix], peak, 1e-3))),
            "x": lat.x0 + lat.step * float(np.sum(w * xx) / w.sum()),
            "y": lat.y0 + lat.step * float(np.sum(w * yy) / w.sum()),
            "radius": max(math.sqrt(blob.sum() / math.pi) * lat.step, 0.6 * lat.step),
            "log_eb": bg, "tau": tau}


def map_from_points(points: pd.DataFrame, *, tip: Tip, thickness: float | None,
                    options: MapOptions | None = None, progress: bool = False) -> MapResult:
    """Stages 2 and 3 from a per-point table (:data:`palpbayes.maps.pertrace.POINT_COLUMNS`).

    Parameters
    ----------
    points
        Per-point fits: ``x_m``, ``y_m``, ``logE_mean``, ``logE_sd``, ``error`` (rows with an
        error have no data), ``depth_m``.
    tip
        The tip of every trace (for the contact radius of the lump model).
    thickness
        [m] Block thickness (None: no lump model; a flag says so).
    """
    options = options or MapOptions()
    ok = ((points["error"].fillna("") == "") & np.isfinite(points["logE_mean"])
          & np.isfinite(points["logE_sd"])).to_numpy()
    good = points[ok]
    flags: list[str] = []
    if len(good) < options.min_points:
        errors = points.loc[~ok, "error"].fillna("").astype(str)
        errors = errors[errors != ""]
        why = f"; the first error: {errors.iloc[0]}" if len(errors) else ""
        raise InputError(f"a map needs at least {options.min_points} fitted points, got "
                         f"{len(good)} of {len(points)}{why}")
    holes = int(points["error"].fillna("").str.startswith(NO_CURVE).sum())
    if int((~ok).sum()) > holes:
        flags.append(f"{int((~ok).sum()) - holes} of {len(points)} traces could not be fitted "
                     "(see points.csv, column error); their nodes have no data")
    if holes:
        flags.append(f"info: {holes} of {len(points)} grid nodes have no curve in the file "
                     "(holes without data; see points.csv, column error)")
    codes = good.get("flag_codes", pd.Series("", index=good.index)).fillna("").astype(str)
    scaled = codes.str.split(";").map(lambda c: "force_scale" in c)
    if scaled.any():  # the first flag: every E of the map is off by the factor it names
        head = str(good.loc[scaled, "notes"].iloc[0])
        head = head[:head.find(" (")] if " (" in head else head
        flags.insert(0, f"{head} (on {int(scaled.sum())} of {len(good)} fitted points; see "
                        "points.csv, column notes)")
    notes = good.get("notes", good.get("flags"))  # "flags": a points.csv written before
    n_flag = 0 if notes is None else int(notes.map(lambda v: isinstance(v, str) and v != "")
                                         .sum())
    if n_flag:
        levels = good.get("flag_level", pd.Series(["warning"] * len(good), index=good.index))
        n_warn = int((levels.fillna("") == "warning").sum())
        flags.append(("" if n_warn else "info: ")
                     + f"{n_flag} fitted points carry a flag ({n_warn} a warning; see "
                     "points.csv, columns notes, flag_codes and flag_level)")
    if len(good) < 10:
        flags.append(f"only {len(good)} fitted points: the field's sd and range come from "
                     "their priors, not the data; read the per-point E (points.csv) as the "
                     "measurement and the field between points as the prior's guess")
    # the lattice of every palpation, fitted or not: a point without a fit enters with an sd
    # of 1000 in log E (no information), so a failed edge row keeps its place on the map
    x, y = points["x_m"].to_numpy(float), points["y_m"].to_numpy(float)
    lat, node = lattice_from_positions(x, y, line=options.line)
    if min(lat.nx, lat.ny) == 1:
        flags.append(f"info: the palpations lie on one line ({lat.nx} × {lat.ny} nodes): the "
                     "field is read along it, and its range across the line is the prior's")
    mean = np.where(ok, points["logE_mean"], float(good["logE_mean"].median()))
    sd = np.where(ok, points["logE_sd"], _NO_DATA_SD)
    depth = float(np.nanmedian(good["depth_m"]))
    a, lump, k = float("nan"), None, options.threshold
    if not options.lump:
        flags.append("info: lump model off (--no-lump; the default for an AFM map)")
    elif thickness is None:
        flags.append("info: lump model skipped: it needs the block thickness (manifest column "
                     "thickness_m, metres)")
    else:  # the lump first: a local bump a stationary field alone would shrink away
        a = tip_contact_radius(tip, depth)
        spread = robust_spread(good["logE_mean"].to_numpy())
        guess = _guess(lat, node[ok], good["logE_mean"].to_numpy(), a, max(spread, 1e-3))
        lump = fit_lump(good["x_m"].to_numpy(), good["y_m"].to_numpy(),
                        good["logE_mean"].to_numpy(), good["logE_sd"].to_numpy(),
                        contact_radius=a, thickness=thickness, step=lat.step, guess=guess,
                        seed=options.seed, max_steps=options.lump_max_steps,
                        min_steps=min(2000, options.lump_max_steps), progress=progress)
        flags += [scoped("lump", f) for f in lump.flags]
        # the field is fitted to what the lump leaves (its posterior-mean log excess)
        mean = mean - lump.excess(x, y).mean(axis=0)
    prior = FieldPrior().resolved(lat.step, mean[ok])
    fp = fit_field(x, y, mean, sd, prior=prior, step=lat.step, progress=progress,
                   line=options.line)
    flags += [scoped("field", f) for f in fp.flags]
    rng = np.random.default_rng(options.seed)
    joint = fp.draws(rng, options.field_draws)
    draws = joint["field"]
    hyper_draws = {k_: np.asarray(v) for k_, v in joint.items() if k_ != "field"}
    if lump is not None:  # each field draw plus one lump draw: both uncertainties
        pick = rng.choice(len(lump.draws), size=draws.shape[0], replace=True)
        ex = lump.excess(lat.node_x, lat.node_y)[pick]
        draws = draws + ex.reshape(draws.shape)
    bg = np.median(draws.reshape(draws.shape[0], -1), axis=1)
    nodes = _node_table(fp, node, points, ok, draws, bg, k)
    detection = float(nodes["p_stiffer"].max())
    p_lump = float("nan")
    if lump is not None:
        p_lump = lump.p_apparent_above(k)
        if options.detect > 0 and p_lump < options.detect:
            flags.append(f"info: no lump: P(apparent peak ratio > {k:g}) = {p_lump:.2f} is below "
                         f"{options.detect:g}; the lump model's numbers describe the largest "
                         "bump the data allow, not a detected lump")
    return MapResult(points=points, nodes=nodes, field=fp, draws=draws, background=bg,
                     hyper_draws=hyper_draws, lump=lump, detection=detection, flags=flags,
                     contact_radius=a, thickness=thickness, options=options,
                     settings={"map": asdict(options), "tip": tip.kind, "depth_m": depth},
                     p_lump=p_lump)


def check_map_manifest(manifest: pd.DataFrame, *, lump: bool = True, min_points: int = 10,
                       line: bool = False, read_options: dict | None = None,
                       source: str | None = None,
                       remote: bool = False) -> tuple[Tip, float | None]:
    """The map's one tip and its block thickness (None if the manifest has none).

    Everything that can be checked before the fits (and before a Dask cluster starts) is:
    positions on a regular lattice (:func:`palpbayes.maps.lattice.lattice_from_positions`; on
    one line only with ``line``), at least ``min_points`` rows, one tip, one thickness, a tip
    kind whose contact radius the lump model knows (``lump``), and every trace file's header:
    its time, z and force columns found with ``read_options``
    (:func:`palpbayes.io.manifest.check_trace_headers`; rows of an AFM map and holes are not
    trace files).

    Parameters
    ----------
    manifest
        Validated map manifest with ``x_m``, ``y_m`` [m], or the rows of an AFM map.
    lump, min_points, line
        As :class:`MapOptions`.
    read_options
        The trace reader's options (``columns``, ``units``, ``force_sign``, ``z_sign``):
        :attr:`PointOptions.read_options <palpbayes.maps.pertrace.PointOptions.read_options>`.
    source
        The manifest's path, named in a header error.
    remote
        The fits run on a remote Dask cluster (``--scheduler ADDRESS``), whose workers may see
        files this machine does not: only the headers of files present here are checked.

    Raises
    ------
    InputError
        Naming what is wrong and what to do (:class:`~palpbayes.errors.DataFileError` for a
        trace file, naming the file, its row and the missing column).
    """
    check_positions(manifest)
    n = int((manifest["error"].fillna("") == "").sum()) if "error" in manifest else len(manifest)
    if n < min_points:
        raise InputError(f"a map needs at least {min_points} palpations, the input has {n}")
    lattice_from_positions(manifest["x_m"].to_numpy(float), manifest["y_m"].to_numpy(float),
                           line=line)
    tips = {tip_from_row(r) for _, r in manifest.iterrows()}
    if len(tips) != 1:
        raise InputError(f"a map takes traces of one tip; the manifest has {len(tips)}: "
                         f"{', '.join(sorted(t.kind for t in tips))}; split it by tip")
    tip = tips.pop()
    th = manifest["thickness_m"].dropna().unique() if "thickness_m" in manifest else []
    if len(th) > 1:
        raise InputError(f"a map is one block: thickness_m has {len(th)} values "
                         f"({', '.join(f'{v:g}' for v in sorted(th)[:4])} m); give one thickness")
    if lump:
        try:
            tip_contact_radius(tip, 1e-3)
        except InputError as exc:
            raise InputError(f"the lump model: {exc}; map with --no-lump") from None
    files = [not is_afm_row(r) and not (isinstance(r.get("error"), str) and r["error"])
             and not (remote and not Path(str(r["file"])).is_file())
             for _, r in manifest.iterrows()]
    if any(files):
        check_trace_headers(manifest[files], source=source, **(read_options or {}))
    return tip, (float(th[0]) if len(th) else None)


def nu_used(points: pd.DataFrame, given: float | None) -> float | list[float] | None:
    """The Poisson ratio the points were fitted with (``points``' ``nu``: ``--nu``, else each
    manifest row's, else :data:`~palpbayes.contact.DEFAULT_NU`): one number, or the sorted
    values when the rows differ; ``given`` when no point was fitted."""
    if "nu" in points:
        used = sorted({float(v) for v in points["nu"].dropna()})
        if used:
            return used[0] if len(used) == 1 else used
    return given


def make_map(manifest: pd.DataFrame, *, point_options: PointOptions | None = None,
             options: MapOptions | None = None, scheduler: str | None = None,
             workers: int | None = None, progress: bool | None = None,
             checked: tuple[Tip, float | None] | None = None) -> MapResult:
    """The whole map of a validated manifest (:func:`palpbayes.io.manifest.read_manifest`)
    whose rows carry ``x_m`` and ``y_m``: per-point fits on Dask, then
    :func:`map_from_points`.  Every trace must use the same tip.

    ``checked`` is what :func:`check_map_manifest` returned for this manifest and these
    options, when the caller has run it already (``palpbayes map`` does, before it makes the
    output folder): the manifest and every trace file's header are then not checked again."""
    point_options = point_options or PointOptions()
    options = options or MapOptions()
    tip, thickness = checked if checked is not None else check_map_manifest(
        manifest, lump=options.lump, min_points=options.min_points, line=options.line,
        read_options=point_options.read_options, remote=scheduler not in (None, "local"))
    points = fit_points(manifest, point_options, scheduler=scheduler, workers=workers,
                        progress=progress)
    result = map_from_points(points, tip=tip, thickness=thickness, options=options,
                             progress=bool(progress))
    result.settings["points"] = {"noise": point_options.fit.noise,
                                 "nu": nu_used(points, point_options.fit.nu),
                                 "draws": point_options.draws, "seed": point_options.seed,
                                 "scheduler": scheduler or "local", "workers": workers}
    return result
