"""Synthetic campaigns: a folder of palpation traces, Instron exports and the truth behind them.

:func:`simulate` writes the layout of docs/design.md §5::

    OUT_DIR/
      manifest.csv                 one row per trace (palpbayes.io.manifest columns, the
                                   blocks' footprint length_m, width_m among them)
      traces/<trace_id>.csv        time_s, z_m, force_n   (trace ids like White_flat_r01)
      groundtruth/manifest.csv     file, specimen, material, area_m2, height_m
      groundtruth/<Material>_S<k>.csv   Instron-like compression exports
      truth.csv                    the true parameters of every trace
      truth_groundtruth.csv        the true modulus of every compression specimen
      truth_materials.csv          material, E_pa, E_sd_pa, thickness_m, nu, width_m, length_m

The defaults reproduce the paper's campaign (:mod:`palpbayes.paper`).  Every trace and block
has its own random stream (:func:`child_seed`).
"""

from __future__ import annotations

import os
import re
import zlib
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from ..arguments import check_seed
from ..contact import DEFAULT_NU, Tip, check_nu
from ..errors import InputError, OutputExistsError
from ..io.atomic import write_csv_atomic
from ..io.manifest import tip_columns, write_manifest
from ..io.trace_csv import write_trace
from ..paper import PAPER_MATERIALS, PAPER_TIPS, Material
from ..sensor_noise import PAPER_NOISE_PP
from ..trace import IndentationTrace
from ..twin import Specimen, compression_factor
from ..units import format_pressure
from .compression import simulate_compression_test, write_compression_export
from .trace import simulate_trace

__all__ = ["simulate", "child_seed", "check_seed", "check_count", "check_file_name",
           "prepare_out_dir", "manifest_row"]

_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]*$")

#: simulate_trace options a campaign passes through (the others it sets itself).
_PASS_THROUGH = frozenset({
    "approach", "speed", "rate", "hold", "retract", "drift", "position_noise", "repeatability",
    "compliance", "base", "stiffening", "depth",
})


def child_seed(seed: int, *keys: str | int) -> np.random.SeedSequence:
    """The child of ``SeedSequence(seed)`` addressed by ``keys`` in its spawn tree.

    ``SeedSequence(seed).spawn(n)[i]`` is ``SeedSequence(seed, spawn_key=(i,))``; here the spawn
    key is built from the labels (CRC32 of strings, integers as they are), so a trace's stream
    depends only on (seed, material, tip, repetition): adding repetitions, materials or tips
    leaves every other trace's noise unchanged, and streams stay statistically independent.
    """
    key = tuple(zlib.crc32(k.encode()) if isinstance(k, str) else int(k) for k in keys)
    return np.random.SeedSequence(seed, spawn_key=key)


def check_count(value, what: str, minimum: int) -> int:
    """``value`` as an int; :class:`InputError` (naming ``what``) unless it is an integer
    >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise InputError(f"{what} {value!r} must be an integer >= {minimum}")
    return int(value)


def check_file_name(name: str, what: str) -> str:
    """``name`` as a string; :class:`InputError` unless it is usable in a file name (letters,
    digits, '_' and '-', not starting with either of the last two)."""
    if not _NAME.match(str(name)):
        raise InputError(f"{what} name {name!r} is not usable in a file name; use letters, "
                         "digits, '_' and '-'")
    return str(name)


def prepare_out_dir(out: Path, overwrite: bool) -> None:
    """Refuse a non-empty folder unless ``overwrite``; then drop a previous campaign's files."""
    if out.exists() and not out.is_dir():
        raise OutputExistsError(f"{out} exists and is not a folder; choose another OUT_DIR")
    if out.is_dir() and any(out.iterdir()):
        if not overwrite:
            raise OutputExistsError(
                f"output folder {out} is not empty; use --force (overwrite=True) to write "
                "into it, or choose an empty folder")
        if (out / "truth.csv").is_file():  # a previous simulated campaign: remove its traces
            for sub in ("traces", "groundtruth"):
                for f in sorted((out / sub).glob("*.csv")):
                    f.unlink()


def manifest_row(trace_id: str, file: str, specimen: str, material: str, tip: Tip,
                 thickness: float, repetition: int, rest_time: float | None,
                 block: Specimen | None = None) -> dict:
    """One row of a simulated campaign's ``manifest.csv`` (tip geometry columns included; a
    block's footprint when given)."""
    footprint = {} if block is None else {"length_m": block.length, "width_m": block.width}
    return {
        "trace_id": trace_id,
        "file": file,
        "specimen": specimen,
        "material": material,
        "tip": tip.kind,
        **tip_columns(tip),
        "thickness_m": thickness,
        "repetition": repetition,
        "rest_time_s": np.nan if rest_time is None else rest_time,
        **footprint,
    }


def _truth_row(trace: IndentationTrace, tip_name: str, block: Specimen | None,
               platens: str) -> dict:
    m = trace.metadata
    c = 1.0 if block is None or platens == "lubricated" else compression_factor(
        block, m["nu_true"], platens)
    return {
        "trace_id": trace.trace_id,
        "material": trace.material,
        "tip": trace.tip.kind,
        "tip_name": tip_name,
        "specimen": trace.specimen,
        "repetition": trace.repetition,
        "E_true_pa": m["E_true"],
        "nu": m["nu_true"],
        "Estar_true_pa": m["Estar_true"],
        "z_surf_true_m": m["z_surf_true"],
        "z_offset_true_m": m["z_offset_true"],
        "sigma_true_n": m["sigma_true"],
        "noise_pp_n": m["noise_pp"],
        "phi_true": m["phi_true"],
        "force_offset_true_n": m["force_offset_true"],
        "drift_true_n_per_s": m["drift_true"],
        "position_noise_true_m": m["position_noise_true"],
        "repeatability_m": m["repeatability"],
        "compliance_true_m_per_n": m["compliance_true"],
        "base": "" if m["base"] is None else m["base"],
        "stiffening": m["stiffening"],
        "thickness_m": trace.thickness,
        "depth_m": m["depth_true"],
        "max_force_true_n": m["max_force_true"],
        "n_points": trace.n_points,
        # what a compression test of this location's block would read (the fits' E_instron)
        "platens": platens if block is not None else "",
        "E_instron_true_pa": m["E_true"] * c if block is not None else np.nan,
    }


def _draw_modulus(gen: np.random.Generator, mat: Material) -> float:
    E = mat.E_pa + mat.E_sd_pa * gen.standard_normal()
    if E <= 0:
        raise InputError(f"material {mat.name}: drew a non-positive modulus "
                         f"{format_pressure(E, 6)}; the sd {format_pressure(mat.E_sd_pa, 6)} is "
                         f"too large for the mean {format_pressure(mat.E_pa, 6)}")
    return float(E)


# Many parameters: one `palpbayes simulate` option each (the campaign's design: materials, tips,
# repetitions, compression tests, knobs), by the command's names.
def simulate(
    out_dir: str | os.PathLike,
    *,
    seed: int = 0,
    repetitions: int = 3,
    materials: Mapping[str, Material] = PAPER_MATERIALS,
    tips: Mapping[str, Tip] = PAPER_TIPS,
    nu: float = DEFAULT_NU,
    gt_specimens: int = 5,
    noise_pp: float = PAPER_NOISE_PP,
    noise_ar1: float = 0.0,
    force_offset_sd: float = 5e-3,
    z_surf: float = 0.1,
    z_surf_halfwidth: float = 1e-3,
    rest_time: float | None = 60.0,
    blocks: bool = True,
    platens: str = "bonded",
    overwrite: bool = False,
    float_format: str = "%.10g",
    **trace_options,
) -> Path:
    """Write a synthetic palpation campaign folder (layout in the module docstring).

    For every material m, tip and repetition r = 1..``repetitions`` one trace is simulated at a
    new specimen location with its own modulus E_i ~ Normal(E_m, sd_m), surface height
    z_surf_i ~ Uniform(z_surf ± z_surf_halfwidth) and force offset F0_i ~ Normal(0,
    force_offset_sd); depth 10 % of the thickness, approach 1 mm, 50 mm/min, 800 Hz, Gaussian
    noise ``noise_pp`` p-p (sigma = pp/6), each specimen the material's block (its footprint
    and thickness, the force its finite-element twin's, :mod:`palpbayes.twin`) lying free on a
    rigid plate (``base="free"``; ``blocks=False``: a layer of infinite width; ``base=None``:
    half-spaces, the paper's model).  The manifest gives each block's footprint, so the
    package's default model (the block's twin, base unknown) is well specified.
    ``gt_specimens`` compression blocks per material are drawn from the same Normal(E_m,
    sd_m) and tested between ``platens`` (default bonded: the Instron reads c·E, c > 1).

    Each trace and block has its own random stream, :func:`child_seed` (seed, kind, material,
    tip, repetition): the same seed gives byte-identical files (no timestamps), and changing
    ``repetitions`` leaves the other traces unchanged.  Files are written atomically.

    Parameters
    ----------
    out_dir
        Output folder (created; must be empty unless ``overwrite``).
    seed
        Non-negative integer.
    repetitions
        Traces per (material, tip), >= 1.
    materials, tips
        Name -> :class:`~palpbayes.paper.Material` / :class:`~palpbayes.contact.Tip`.
    nu
        True Poisson ratio [-].
    gt_specimens
        Compression tests per material (0 for none).
    noise_pp, noise_ar1
        [N] Peak-to-peak force noise and its AR(1) coefficient.
    force_offset_sd
        [N] sd of the per-trace force offset.
    z_surf, z_surf_halfwidth
        [m] Centre and half-width of the uniform surface height.
    rest_time
        [s] Rest time recorded before every trace (manifest ``rest_time_s``).
    blocks
        The specimens as tested: each material's block of ``width_m`` × ``length_m`` ×
        ``thickness_m`` (its twin's force, its footprint in the manifest); False: layers of
        infinite width, no footprint.
    platens
        The compression tests' platens, ``"bonded"`` (default: a foam on dry steel does not
        slide) or ``"lubricated"``; truth.csv's ``E_instron_true_pa`` is what such a test of
        each palpated location's block would read.
    overwrite
        Write into a non-empty folder (a previous campaign's traces are removed first).
    float_format
        Number format of the trace CSVs; "%.10g" keeps z to 1e-10 m and force to 10
        significant digits.
    **trace_options
        Passed to :func:`~palpbayes.sim.trace.simulate_trace`: approach, speed, rate, hold,
        retract, depth, drift, position_noise, repeatability, compliance, base (the
        specimens as layers on a rigid base: "bonded", "free" or a partial bond in [0, 1];
        None: half-spaces), stiffening.

    Returns
    -------
    Path
        ``out_dir``.

    Raises
    ------
    OutputExistsError
        ``out_dir`` is not empty and ``overwrite`` is False.
    InputError
        Bad seed, counts, names or options.
    """
    seed = check_seed(seed)
    repetitions = check_count(repetitions, "repetitions", 1)
    gt_specimens = check_count(gt_specimens, "gt_specimens", 0)
    nu = check_nu(nu)
    unknown = set(trace_options) - _PASS_THROUGH
    if unknown:
        raise InputError(f"unknown trace option(s) {', '.join(sorted(unknown))}; allowed: "
                         f"{', '.join(sorted(_PASS_THROUGH))}")
    if not materials or not tips:
        raise InputError("a campaign needs at least one material and one tip")
    for name in materials:
        check_file_name(name, "material")
    for name in tips:
        check_file_name(name, "tip")
    if force_offset_sd < 0 or z_surf_halfwidth < 0:
        raise InputError("force_offset_sd and z_surf_halfwidth must be non-negative")
    if platens not in ("lubricated", "bonded"):
        raise InputError(f"platens {platens!r}: use 'lubricated' or 'bonded'")
    layered = trace_options.get("base", "free") is not None

    out = Path(out_dir)
    traces, manifest, truth = [], [], []  # simulate first: bad options fail before any write
    for mname, mat in materials.items():
        for tname, tip in tips.items():
            for rep in range(1, repetitions + 1):
                gen = np.random.default_rng(child_seed(seed, "trace", mname, tname, rep))
                E_i = _draw_modulus(gen, mat)
                zs = z_surf + z_surf_halfwidth * gen.uniform(-1.0, 1.0)
                f0 = force_offset_sd * gen.standard_normal()
                tid = f"{mname}_{tname}_r{rep:02d}"
                block = (Specimen(mat.thickness_m, length=mat.length_m, width=mat.width_m)
                         if blocks and layered else None)
                trace = simulate_trace(
                    E_i, tip, nu=nu, z_surf=zs, thickness=mat.thickness_m, noise_pp=noise_pp,
                    noise_ar1=noise_ar1, force_offset=f0, rng=gen, trace_id=tid,
                    specimen=mname, material=mname, repetition=rep, rest_time=rest_time,
                    block=block, **trace_options)
                traces.append(trace)
                manifest.append(manifest_row(tid, f"traces/{tid}.csv", mname, mname, tip,
                                              mat.thickness_m, rep, rest_time, block))
                truth.append(_truth_row(trace, tname, block, platens))
    tests = _simulate_groundtruth(seed, materials, gt_specimens, platens, nu)
    prepare_out_dir(out, overwrite)
    for trace in traces:
        write_trace(trace, out / "traces" / f"{trace.trace_id}.csv", float_format=float_format)
    write_manifest(pd.DataFrame(manifest), out / "manifest.csv")
    write_csv_atomic(pd.DataFrame(truth), out / "truth.csv")
    _write_groundtruth(out, tests)
    mats = pd.DataFrame([{"material": k, "E_pa": m.E_pa,
                          "E_sd_pa": m.E_sd_pa, "thickness_m": m.thickness_m, "nu": nu,
                          "width_m": m.width_m, "length_m": m.length_m}
                         for k, m in materials.items()])
    write_csv_atomic(mats, out / "truth_materials.csv")
    return out


def _simulate_groundtruth(seed: int, materials: Mapping[str, Material], n: int,
                          platens: str, nu: float) -> list[tuple[str, pd.DataFrame, float]]:
    """(specimen name, compression table, true E) for ``n`` blocks per material, tested
    between ``platens``."""
    tests = []
    for mname, mat in materials.items():
        for k in range(1, n + 1):
            gen = np.random.default_rng(child_seed(seed, "groundtruth", mname, k))
            E = _draw_modulus(gen, mat)
            name = f"{mname}_S{k}"
            df = simulate_compression_test(E, width=mat.width_m, length=mat.length_m,
                                           height=mat.thickness_m, rng=gen, specimen=name,
                                           material=mname, platens=platens, nu=nu)
            tests.append((name, df, E))
    return tests


def _write_groundtruth(out: Path, tests: list[tuple[str, pd.DataFrame, float]]) -> None:
    if not tests:
        return
    rows, truth = [], []
    for name, df, E in tests:
        a = df.attrs
        write_compression_export(df, out / "groundtruth" / f"{name}.csv", sample_name=name)
        rows.append({"file": f"{name}.csv", "specimen": name, "material": a["material"],
                     "area_m2": a["area_m2"], "height_m": a["height_m"]})
        truth.append({"file": f"groundtruth/{name}.csv", "specimen": name,
                      "material": a["material"], "E_true_pa": E, "toe_m": a["toe_m"],
                      "noise_n": a["noise_n"], "platens": a["platens"],
                      "platen_factor": a["platen_factor"],
                      "E_apparent_pa": a["E_apparent_pa"]})
    write_csv_atomic(pd.DataFrame(rows), out / "groundtruth" / "manifest.csv",
                     float_format="%.10g")
    write_csv_atomic(pd.DataFrame(truth), out / "truth_groundtruth.csv")
