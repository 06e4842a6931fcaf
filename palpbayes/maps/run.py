"""A stiffness map from a map manifest: per-point fits, the spatial field, the lump.

Three stages (docs/design.md, "Stiffness maps"):

1. every trace's posterior of log E by the exact engine, on Dask (:mod:`~.pertrace`);
2. the log-modulus field over the palpation lattice, a sparse SPDE/GMRF prior with its
   hyperparameters integrated out (:mod:`~.gmrf`): posterior mean, sd and interval of E at
   every node, and P(E > k × background) with the background the median of the field over
   the map, per posterior draw;
3. if some node has P >= ``detect``, the one-inclusion model (:mod:`~.lump`): centre, radius,
   depth, stiffness ratio and apparent peak ratio with their intervals.

Computation only: files are written by :mod:`~.files`, figures by :mod:`palpbayes.plots.maps`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np
import pandas as pd

from ..contact import Tip
from ..errors import InputError
from ..intervals import LEVEL, central, central_band
from ..io.manifest import tip_from_row
from ..sim.inclusion import contact_radius as tip_contact_radius
from .gmrf import FieldPosterior, fit_field
from .lump import LumpPosterior, fit_lump
from .pertrace import PointOptions, fit_points

__all__ = ["MapOptions", "MapResult", "NODE_COLUMNS", "check_map_manifest", "make_map",
           "map_from_points"]

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
        Run the lump model when some node has P(E > k × background) >= this (0: always).
    field_draws
        Joint posterior draws of the field.
    lump_max_steps
        Cap on the emcee steps per walker of the lump model (it stops earlier once converged).
    seed
        Seed of the field draws and the lump sampler.
    lump
        Fit the lump model at all.
    """

    threshold: float = 1.1
    detect: float = 0.5
    field_draws: int = 1000
    lump_max_steps: int = 20000
    seed: int = 0
    lump: bool = True

    def __post_init__(self) -> None:
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
    detection: float
    flags: list[str]
    contact_radius: float
    thickness: float | None
    options: MapOptions
    settings: dict = field(default_factory=dict)

    @property
    def lump_summary(self) -> pd.DataFrame | None:
        return None if self.lump is None else self.lump.summary()

    def background_interval(self, level: float = LEVEL) -> tuple[float, float, float]:
        """[Pa] Median and central interval of the background (median of the field)."""
        b = np.exp(self.background)
        lo, hi = central(b, level)
        return float(np.median(b)), lo, hi

    def lump_centre(self) -> dict[str, tuple[float, float, float]] | None:
        """``{"x_m": (median, lo, hi), "y_m": (...)}`` of the lump centre, or None."""
        if self.lump is None:
            return None
        d = self.lump.draws
        return {k: (float(np.median(d[k])), *central(d[k].to_numpy())) for k in ("x_m", "y_m")}


def _node_table(fp: FieldPosterior, node: np.ndarray, points: pd.DataFrame, draws: np.ndarray,
                bg: np.ndarray, threshold: float) -> pd.DataFrame:
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
    ok = points["error"].fillna("") == ""
    per = pd.DataFrame({"node": node[ok.to_numpy()],
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


def _guess(nodes: pd.DataFrame, bg: float, tau: float, step: float) -> dict:
    """Starting values of the lump model from the map's posterior mean."""
    excess = nodes["logE_mean"].to_numpy() - bg
    k = int(np.argmax(excess))
    x0, y0 = nodes["x_m"].iloc[k], nodes["y_m"].iloc[k]
    d = np.hypot(nodes["x_m"] - x0, nodes["y_m"] - y0).to_numpy()
    half = (excess >= 0.5 * excess[k]) & (d < 10 * step + d.min())
    w = excess[half]
    radius = max(math.sqrt(half.sum() * step * step / math.pi), 0.6 * step)
    return {"apparent": float(math.exp(excess[k])),
            "x": float(np.sum(w * nodes["x_m"].to_numpy()[half]) / w.sum()),
            "y": float(np.sum(w * nodes["y_m"].to_numpy()[half]) / w.sum()),
            "radius": radius, "log_eb": bg, "tau": tau}


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
    ok = (points["error"].fillna("") == "") & np.isfinite(points["logE_mean"])
    good = points[ok]
    flags: list[str] = []
    if (~ok).any():
        flags.append(f"{int((~ok).sum())} of {len(points)} traces could not be fitted (see "
                     "points.csv, column error); their nodes have no data")
    n_flag = int((good["flags"].fillna("") != "").sum())
    if n_flag:
        flags.append(f"{n_flag} fitted points carry a flag (see points.csv, column flags)")
    if len(good) < 10:
        raise InputError(f"a map needs at least 10 fitted points, got {len(good)}")
    fp = fit_field(good["x_m"].to_numpy(), good["y_m"].to_numpy(),
                   good["logE_mean"].to_numpy(), good["logE_sd"].to_numpy(), progress=progress)
    flags += [f"field: {f}" for f in fp.flags]
    # every point's node, the unfitted ones too (their node simply has no data)
    lat = fp.lattice
    ix = np.rint((points["x_m"].to_numpy() - lat.x0) / lat.step).astype(int)
    iy = np.rint((points["y_m"].to_numpy() - lat.y0) / lat.step).astype(int)
    node = iy * lat.nx + ix
    rng = np.random.default_rng(options.seed)
    joint = fp.draws(rng, options.field_draws)
    draws = joint["field"]
    hyper_draws = {k: np.asarray(v) for k, v in joint.items() if k != "field"}
    bg = np.median(draws.reshape(draws.shape[0], -1), axis=1)
    nodes = _node_table(fp, node, points, draws, bg, options.threshold)
    detection = float(nodes["p_stiffer"].max())
    depth = float(np.nanmedian(good["depth_m"]))
    a = tip_contact_radius(tip, depth)
    lump = None
    if not options.lump:
        pass
    elif options.detect > 0 and detection < options.detect:
        flags.append(f"no lump: no node has P(E > {options.threshold:g} × background) >= "
                     f"{options.detect:g} (largest {detection:.2f})")
    elif thickness is None:
        flags.append("lump model skipped: it needs the block thickness (manifest column "
                     "thickness_m, metres)")
    else:
        tau = float(fp.hyper_summary().set_index("parameter").loc["tau", "mean"])
        guess = _guess(nodes, float(np.median(bg)), tau, lat.step)
        lump = fit_lump(good["x_m"].to_numpy(), good["y_m"].to_numpy(),
                        good["logE_mean"].to_numpy(), good["logE_sd"].to_numpy(),
                        contact_radius=a, thickness=thickness, step=lat.step, guess=guess,
                        seed=options.seed, max_steps=options.lump_max_steps,
                        min_steps=min(2000, options.lump_max_steps), progress=progress)
        flags += [f"lump: {f}" for f in lump.flags]
    return MapResult(points=points, nodes=nodes, field=fp, draws=draws, background=bg,
                     hyper_draws=hyper_draws, lump=lump, detection=detection, flags=flags,
                     contact_radius=a, thickness=thickness, options=options,
                     settings={"map": asdict(options), "tip": tip.kind, "depth_m": depth})


def check_map_manifest(manifest: pd.DataFrame) -> tuple[Tip, float | None]:
    """The map's one tip and its block thickness (None if the manifest has none); raises
    :class:`InputError` for a manifest a map cannot use (no positions, several tips)."""
    for col in ("x_m", "y_m"):
        if col not in manifest.columns or manifest[col].isna().any():
            raise InputError(f"a map needs the palpation position of every trace: manifest "
                             f"column {col!r} (metres) is missing or has empty cells")
    tips = {tip_from_row(r) for _, r in manifest.iterrows()}
    if len(tips) != 1:
        raise InputError(f"a map takes traces of one tip; the manifest has {len(tips)}: "
                         f"{', '.join(sorted(t.kind for t in tips))}; split it by tip")
    th = manifest["thickness_m"].dropna().unique() if "thickness_m" in manifest else []
    return tips.pop(), (float(np.median(th)) if len(th) else None)


def make_map(manifest: pd.DataFrame, *, point_options: PointOptions | None = None,
             options: MapOptions | None = None, scheduler: str | None = None,
             workers: int | None = None, progress: bool | None = None) -> MapResult:
    """The whole map of a validated manifest (:func:`palpbayes.io.manifest.read_manifest`)
    whose rows carry ``x_m`` and ``y_m``: per-point fits on Dask, then
    :func:`map_from_points`.  Every trace must use the same tip."""
    point_options = point_options or PointOptions()
    tip, thickness = check_map_manifest(manifest)
    points = fit_points(manifest, point_options, scheduler=scheduler, workers=workers,
                        progress=progress)
    result = map_from_points(points, tip=tip, thickness=thickness, options=options,
                             progress=bool(progress))
    result.settings["points"] = {"noise": point_options.fit.noise, "nu": point_options.fit.nu,
                                 "draws": point_options.draws, "seed": point_options.seed,
                                 "scheduler": scheduler or "local", "workers": workers}
    return result
