"""Stiffness-map phantoms: a grid of palpations over a block that hides a stiff sphere.

:func:`simulate_map` writes::

    OUT_DIR/
      manifest.csv      one row per trace (palpbayes.io.manifest columns, nu, x_m, y_m)
      traces/<id>.csv   time_s, z_m, force_n; id ``p<j>_<i>`` for row j (y) and column i (x)
      truth.csv         per trace: position, V, the smooth E_app, the E it was simulated with,
                        surface height, force offset, ...
      truth_lump.json   one record: the lump, the grid, the tip, the apparent peak and width

The palpation at column i, row j sits at x_i = i·step, y_j = j·step (origin at the first
palpation).  The smooth field E_app(x, y) is :func:`~palpbayes.inclusion.apparent_modulus`
(a Reuss average over the Boussinesq stress under the tip; its limits are listed in
:mod:`palpbayes.inclusion`).  On top of it each point has its own material modulus,
ln E_point = ln E_app + heterogeneity·N(0, 1) (the median is E_app; for small values the
heterogeneity is the coefficient of variation), and each trace is simulated as a homogeneous
block of modulus E_point by :func:`~palpbayes.sim.trace.simulate_trace`.  Every point has its
own random stream, :func:`~palpbayes.sim.campaign.child_seed` (seed, "map", j, i): the same
seed gives byte-identical files whatever ``workers``.
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import math
import multiprocessing as mp
import os
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.optimize import brentq

from ..arguments import finite, nonneg, positive
from ..contact import DEFAULT_NU, Tip, check_nu
from ..errors import DataFileError, InputError
from ..inclusion import Inclusion, apparent_ratio, contact_radius, sensitivity
from ..io.atomic import write_csv_atomic, write_text_atomic
from ..io.manifest import tip_columns, write_manifest
from ..io.trace_csv import write_trace
from ..paper import PAPER_TIPS
from ..procs import lifeline
from ..sensor_noise import PAPER_NOISE_PP, sigma_from_pp
from ..trace import IndentationTrace
from .campaign import check_count, check_seed, child_seed, prepare_out_dir
from .trace import simulate_trace

__all__ = ["simulate_map", "read_map_truth", "default_inclusion", "lump_summary", "press_trace"]

#: File with the lump's truth in a map folder.
LUMP_FILE = "truth_lump.json"


def default_inclusion(nx: int, ny: int, step: float, *, depth: float = 7e-3,
                      radius: float = 6e-3, ratio: float = 10.0) -> Inclusion:
    """The default lump: near the grid's centre but off the nodes (+0.3 step in x, +0.2 in y).

    Centre ((nx − 1)/2 + 0.3)·step, ((ny − 1)/2 + 0.2)·step; ``depth`` of the centre, ``radius``
    [m] and modulus ``ratio`` to the background.
    """
    return Inclusion(x=((nx - 1) / 2 + 0.3) * step, y=((ny - 1) / 2 + 0.2) * step,
                     depth=depth, radius=radius, ratio=ratio)


def lump_summary(inclusion: Inclusion | None, *, contact_radius: float,
                 thickness: float) -> dict[str, float]:
    """Peak apparent ratio E_app(centre)/E_b and the FWHM diameter [m] of its excess.

    ``apparent_fwhm_diameter_m`` is 2·s where E_app(s)/E_b − 1 falls to half its value at
    s = 0 (NaN without a lump or with ratio 1).
    """
    if inclusion is None or inclusion.ratio == 1.0:
        return {"peak_apparent_ratio": 1.0, "apparent_fwhm_diameter_m": math.nan}
    geo = {"radius": inclusion.radius, "depth": inclusion.depth,
           "contact_radius": contact_radius, "thickness": thickness}

    def excess(s: float) -> float:
        return float(apparent_ratio(sensitivity(np.array([s]), **geo), inclusion.ratio)[0]) - 1

    peak = excess(0.0)
    if peak == 0.0:
        return {"peak_apparent_ratio": 1.0, "apparent_fwhm_diameter_m": math.nan}
    hi = inclusion.radius + inclusion.depth + contact_radius
    while excess(hi) / peak > 0.5:
        hi *= 2
    half = brentq(lambda s: excess(s) / peak - 0.5, 0.0, hi, xtol=1e-9)
    return {"peak_apparent_ratio": 1.0 + peak, "apparent_fwhm_diameter_m": 2.0 * half}


def press_trace(E_app: float, gen: np.random.Generator, tip: Tip, options: dict,
                trace_id: str) -> IndentationTrace:
    """One press of a map phantom where the smooth field is ``E_app`` [Pa], drawing from
    ``gen`` the point's heterogeneity, surface height, force offset, then the trace's noise.

    ``options``: ``nu``, ``z_surf``, ``z_surf_halfwidth``, ``force_offset_sd``,
    ``heterogeneity``, ``thickness``, ``depth``, ``approach``, ``noise_pp`` (SI units).
    """
    o = options
    e = gen.standard_normal()
    zs = o["z_surf"] + o["z_surf_halfwidth"] * gen.uniform(-1.0, 1.0)
    f0 = o["force_offset_sd"] * gen.standard_normal()
    E = float(E_app * math.exp(o["heterogeneity"] * e))
    return simulate_trace(
        E, tip, nu=o["nu"], z_surf=zs, thickness=o["thickness"], depth=o["depth"],
        approach=o["approach"], noise_pp=o["noise_pp"], force_offset=f0, rng=gen,
        trace_id=trace_id, specimen="phantom", material="phantom", repetition=1,
        base=None)  # a half-space at E_app: the map's model (palpbayes.maps)


def _write_rows(job: dict) -> list[dict]:
    """Simulate and write the traces of some grid rows; return their truth rows (in order)."""
    out, tip, o = Path(job["out"]), job["tip"], job["options"]
    rows = []
    for j, E_row in zip(job["rows"], job["E_app"], strict=True):
        for i, E_app in enumerate(E_row):
            gen = np.random.default_rng(child_seed(job["seed"], "map", j, i))
            tid = job["ids"][j][i]
            trace = press_trace(float(E_app), gen, tip, o, tid)
            if not job["dry_run"]:
                write_trace(trace, out / "traces" / f"{tid}.csv", float_format=o["float_format"])
            m = trace.metadata
            rows.append({"trace_id": tid, "E_true_pa": m["E_true"],
                         "z_surf_true_m": m["z_surf_true"],
                         "force_offset_true_n": m["force_offset_true"],
                         "sigma_true_n": m["sigma_true"], "depth_m": m["depth_true"],
                         "max_force_true_n": m["max_force_true"], "n_points": trace.n_points})
            if job["dry_run"]:
                return rows
    return rows


# Many parameters: one `palpbayes simulate --map` option each (the phantom's grid, lump,
# heterogeneity and sensor), by the command's names.
def simulate_map(
    out_dir: str | os.PathLike,
    *,
    seed: int = 0,
    nx: int = 15,
    ny: int = 15,
    step: float = 3e-3,
    E_background: float = 50e3,
    nu: float = DEFAULT_NU,
    tip: Tip = PAPER_TIPS["paraboloid"],
    thickness: float = 0.02,
    depth: float | None = None,
    inclusion: Inclusion | None | str = "default",
    heterogeneity: float = 0.03,
    noise_pp: float = PAPER_NOISE_PP,
    force_offset_sd: float = 5e-3,
    z_surf: float = 0.1,
    z_surf_halfwidth: float = 1e-3,
    approach: float = 5e-4,
    overwrite: bool = False,
    float_format: str = "%.8g",
    workers: int = 1,
) -> Path:
    """Write a stiffness-map phantom folder (layout and model in the module docstring).

    Parameters
    ----------
    out_dir
        Output folder (created; must be empty unless ``overwrite``).
    seed
        Non-negative integer.
    nx, ny
        Palpations along x and y (1..10000 each).
    step
        [m] Grid spacing.
    E_background
        [Pa] Background modulus E_b of the block.
    nu
        Poisson ratio [-] (written to the manifest's ``nu`` column).
    tip
        The indenter, any :class:`~palpbayes.contact.Tip` whose law has a contact radius (default
        the paper's paraboloid).
    thickness
        [m] Block thickness H.
    depth
        [m] Commanded indentation depth; default 10 % of ``thickness`` (the paper's protocol).
    inclusion
        The lump; ``"default"`` is :func:`default_inclusion` (centre depth 7 mm, radius 6 mm,
        ratio 10, near the middle of the grid but off its nodes); None for a homogeneous block.
        It must lie inside the block (depth + radius <= thickness).
    heterogeneity
        sd of ln E between points (about the coefficient of variation), >= 0.
    noise_pp
        [N] Peak-to-peak force noise (sigma = pp/6).
    force_offset_sd
        [N] sd of the per-trace force offset.
    z_surf, z_surf_halfwidth
        [m] Centre and half-width of the uniform surface height of each trace.
    approach
        [m] Height above the surface where each trace starts.
    overwrite
        Write into a non-empty folder (a previous campaign's or map's traces are removed).
    float_format
        Number format of the trace CSVs ("%.8g": z to 1e-9 m at 0.1 m).
    workers
        Processes that simulate and write the traces (rows split in chunks); 1 = in-process.

    Returns
    -------
    Path
        ``out_dir``.

    Raises
    ------
    InputError
        A bad option (the message names it); checked before anything is written.
    OutputExistsError
        ``out_dir`` is not empty and ``overwrite`` is False.
    """
    seed = check_seed(seed)
    nx, ny = (check_count(n, what, 1) for n, what in ((nx, "nx"), (ny, "ny")))
    if nx > 10000 or ny > 10000:
        raise InputError(f"grid {nx}x{ny} is too large; use at most 10000 points per side")
    workers = check_count(workers, "workers", 1)
    step = positive(step, "grid step [m]")
    E_b = positive(E_background, "background modulus E_background [Pa]")
    nu = check_nu(nu)
    thickness = positive(thickness, "block thickness [m]")
    depth = positive(0.1 * thickness if depth is None else depth, "indentation depth [m]")
    if isinstance(inclusion, str):
        if inclusion != "default":
            raise InputError(f"inclusion {inclusion!r} must be an Inclusion, None or 'default'")
        inclusion = default_inclusion(nx, ny, step)
    if inclusion is not None:
        if not isinstance(inclusion, Inclusion):
            raise InputError(f"inclusion must be an Inclusion or None, got "
                             f"{type(inclusion).__name__}")
        if inclusion.depth + inclusion.radius > thickness:
            raise InputError(
                f"the lump (centre depth {inclusion.depth:g} m + radius {inclusion.radius:g} m) "
                f"reaches below the block's thickness {thickness:g} m; give a shallower or "
                "smaller lump, or a thicker block")
    a = contact_radius(tip, depth)  # checks the tip kind and the depth
    options = {
        "nu": nu, "thickness": thickness, "depth": depth, "float_format": str(float_format),
        "heterogeneity": nonneg(heterogeneity, "heterogeneity (sd of ln E)"),
        "noise_pp": noise_pp, "z_surf": finite(z_surf, "z_surf [m]"),
        "force_offset_sd": nonneg(force_offset_sd, "force_offset_sd [N]"),
        "z_surf_halfwidth": nonneg(z_surf_halfwidth, "z_surf_halfwidth [m]"),
        "approach": nonneg(approach, "approach distance [m]"),
    }
    sigma_from_pp(noise_pp)  # checks noise_pp
    try:
        float_format % 1.0
    except (TypeError, ValueError):
        raise InputError(f"float_format {float_format!r} is not a %-format such as "
                         "'%.8g'") from None

    x, y = np.arange(nx) * step, np.arange(ny) * step
    X, Y = np.meshgrid(x, y)  # [j, i]
    if inclusion is None:
        V = np.zeros(X.shape)
        E_app = np.full(X.shape, E_b)
    else:
        s = np.hypot(X - inclusion.x, Y - inclusion.y)
        V = sensitivity(s, radius=inclusion.radius, depth=inclusion.depth, contact_radius=a,
                        thickness=thickness)
        E_app = E_b * apparent_ratio(V, inclusion.ratio)
    width = max(3, len(str(max(nx, ny) - 1)))
    ids = [[f"p{j:0{width}d}_{i:0{width}d}" for i in range(nx)] for j in range(ny)]
    job = {"out": str(out_dir), "tip": tip, "options": options, "seed": seed, "ids": ids}
    _write_rows({**job, "rows": [0], "E_app": E_app[:1], "dry_run": True})  # validate

    out = Path(out_dir)
    prepare_out_dir(out, overwrite)
    size = max(1, min(8, ny // (4 * workers)))  # rows per job: several jobs per worker
    chunks = [list(range(j, min(ny, j + size))) for j in range(0, ny, size)]
    jobs = [{**job, "rows": c, "E_app": E_app[c], "dry_run": False} for c in chunks]
    truth: list[dict] = []
    if workers == 1 or len(jobs) == 1:
        for jb in jobs:
            truth += _write_rows(jb)
    else:
        methods = mp.get_all_start_methods()
        ctx = mp.get_context("forkserver" if "forkserver" in methods else "spawn")
        with cf.ProcessPoolExecutor(min(workers, len(jobs)), mp_context=ctx,
                                    **lifeline(ctx)) as pool:
            for rows in pool.map(_write_rows, jobs):
                truth += rows

    flat = {"x_m": X.ravel(), "y_m": Y.ravel()}
    manifest = pd.DataFrame({
        "trace_id": [t for row in ids for t in row],
        "file": [f"traces/{t}.csv" for row in ids for t in row],
        "specimen": "phantom", "material": "phantom", "tip": tip.kind, **tip_columns(tip),
        "thickness_m": thickness, "repetition": 1, "rest_time_s": np.nan, "nu": nu, **flat,
    })
    write_manifest(manifest, out / "manifest.csv")
    truth_df = pd.DataFrame(truth)
    truth_df.insert(1, "x_m", flat["x_m"])
    truth_df.insert(2, "y_m", flat["y_m"])
    truth_df.insert(3, "V", V.ravel())
    truth_df.insert(4, "E_apparent_pa", E_app.ravel())
    write_csv_atomic(truth_df, out / "truth.csv")
    write_text_atomic(json.dumps(_lump_record(E_b, inclusion, a, tip, options, nx, ny, step),
                                 indent=2, allow_nan=False) + "\n", out / LUMP_FILE)
    return out


def _lump_record(E_b: float, inclusion: Inclusion | None, a: float, tip: Tip, options: dict,
                 nx: int, ny: int, step: float) -> dict:
    """The one-record truth of a map (None for what does not apply, never NaN)."""
    summary = lump_summary(inclusion, contact_radius=a, thickness=options["thickness"])
    lump = {k: None if inclusion is None else getattr(inclusion, k)
            for k in ("x", "y", "depth", "radius", "ratio")}
    rec = {
        "E_background_pa": E_b, "has_lump": inclusion is not None,
        "x_m": lump["x"], "y_m": lump["y"], "depth_m": lump["depth"],
        "radius_m": lump["radius"], "ratio": lump["ratio"],
        "contact_radius_m": a, "thickness_m": options["thickness"],
        "indentation_depth_m": options["depth"], "nu": options["nu"],
        "heterogeneity": options["heterogeneity"], **summary,
        "nx": nx, "ny": ny, "step_m": step, "tip": tip.kind,
        **{f"tip_{k}": v for k, v in tip_columns(tip).items()},
    }
    return {k: None if isinstance(v, float) and math.isnan(v) else v for k, v in rec.items()}


def read_map_truth(folder: str | os.PathLike) -> dict:
    """The lump's truth of a map folder (its ``truth_lump.json``) as a dict.

    Absent values (no lump, tip sizes a tip does not have) are None.

    Raises
    ------
    DataFileError
        The folder has no readable ``truth_lump.json``.
    """
    path = Path(folder) / LUMP_FILE
    if not path.is_file():
        raise DataFileError(path, "not found", "is this a folder written by simulate_map?")
    try:
        rec = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise DataFileError(path, f"not readable JSON ({exc})") from None
    if not isinstance(rec, dict) or "E_background_pa" not in rec:
        raise DataFileError(path, "is not a map truth record (no E_background_pa)")
    return rec
