"""Viscoelastic campaigns: ramp–hold–retract palpations of specimens at several speeds.

:func:`simulate_visco_campaign` writes the folder ``palpbayes fit OUT/manifest.csv --rheology
power-law|sls`` reads::

    OUT_DIR/
      manifest.csv           one row per trace (palpbayes.io.manifest columns, with nu)
      traces/<trace_id>.csv  time_s, z_m, force_n, segment (approach, hold, retract)
      truth.csv              the true parameters of every trace
      truth_materials.csv    one row per specimen: its relaxation modulus, thickness, nu

For every material, tip, speed and repetition one trace is simulated
(:func:`~palpbayes.sim.viscoelastic.simulate_viscoelastic`): trace ids like
``Medium_paraboloid_v50_r01`` (the speed in mm/min, a decimal point written ``p``).  Each
material is one specimen with one relaxation modulus (reduced, E*): its palpations at several
speeds share it, which is what :func:`palpbayes.rheology.pool.pool_rheology` pools.  Each
trace has its own surface height z_surf ~ Uniform(z_surf ± z_surf_halfwidth), force offset
F0 ~ Normal(0, force_offset_sd) and noise stream, :func:`~palpbayes.sim.campaign.child_seed`
(seed, "visco", material, tip, speed label, repetition): the same seed gives byte-identical
files, and adding speeds, tips or repetitions leaves the other traces unchanged.

The specimens are half-spaces (the hereditary force has no finite-thickness correction); the
manifest's ``thickness_m`` is the height of the compression test the fit's
``E_compression_pa`` is read for, and truth.csv's ``E_compression_true_pa`` is what that
test reads for the true kernel (:func:`~palpbayes.rheology.compression.compression_moduli`,
the ground truth's rule).  Keep the depth below 5 % of it, or the fit flags the half-space
it assumes.  No compression exports are written.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import numpy as np
import pandas as pd

from ..arguments import ar1_phi, finite, nonneg, positive
from ..contact import (
    DEFAULT_NU,
    PowerLawKernel,
    PronyKernel,
    Tip,
    check_nu,
    standard_linear_solid,
)
from ..errors import InputError
from ..io.atomic import write_csv_atomic
from ..io.manifest import write_manifest
from ..io.trace_csv import write_trace
from ..paper import PAPER_TIPS
from ..rheology.compression import PAPER_COMPRESSION_SPEED, compression_moduli
from ..sensor_noise import PAPER_NOISE_PP, sigma_from_pp
from ..trace import IndentationTrace
from .campaign import (
    check_count,
    check_file_name,
    check_seed,
    child_seed,
    manifest_row,
    prepare_out_dir,
)
from .viscoelastic import simulate_viscoelastic

__all__ = ["ViscoMaterial", "POWER_LAW_FOAMS", "SLS_FOAMS", "VISCO_TIPS", "DEFAULT_SPEEDS",
           "speed_label", "simulate_visco_campaign"]


@dataclass(frozen=True)
class ViscoMaterial:
    """A viscoelastic specimen of a simulated campaign.

    Attributes
    ----------
    name
        Label (used in file names).
    kernel
        Relaxation modulus of the reduced modulus E*(t) [Pa]: a
        :class:`~palpbayes.contact.PowerLawKernel` or a one-term
        :class:`~palpbayes.contact.PronyKernel` (the SLS,
        :func:`~palpbayes.contact.standard_linear_solid`).
    thickness_m
        [m] Specimen height (manifest ``thickness_m``: the compression test's height).
    """

    name: str
    kernel: PowerLawKernel | PronyKernel
    thickness_m: float = 0.05


#: Three power-law foams, soft and strongly rate-dependent to firm and nearly elastic.
POWER_LAW_FOAMS: Mapping[str, ViscoMaterial] = MappingProxyType({
    "Soft": ViscoMaterial("Soft", PowerLawKernel(35e3, 0.25)),
    "Medium": ViscoMaterial("Medium", PowerLawKernel(80e3, 0.15)),
    "Firm": ViscoMaterial("Firm", PowerLawKernel(140e3, 0.07)),
})
#: Three standard linear solids E*(t) = E_inf* + E1*·exp(−t/tau), tau within a 5 s hold.
SLS_FOAMS: Mapping[str, ViscoMaterial] = MappingProxyType({
    "Soft": ViscoMaterial("Soft", standard_linear_solid(25e3, 20e3, 0.5)),
    "Medium": ViscoMaterial("Medium", standard_linear_solid(60e3, 30e3, 1.0)),
    "Firm": ViscoMaterial("Firm", standard_linear_solid(110e3, 40e3, 2.0)),
})
#: The paper's tips with a power law F = E*·g·d^m (the exact sphere has none).
VISCO_TIPS: Mapping[str, Tip] = MappingProxyType(
    {k: PAPER_TIPS[k] for k in ("flat", "paraboloid")})
#: [m/s] Default speeds: 5, 50 (the paper's) and 500 mm/min.
DEFAULT_SPEEDS = (5 / 6e4, 50 / 6e4, 500 / 6e4)


def speed_label(speed: float) -> str:
    """The speed [m/s] in mm/min as it appears in a trace id: ``50``, ``0p5``, ``12p5``."""
    return f"{speed * 6e4:.6g}".replace(".", "p").replace("+", "")


def _kernel_columns(kernel: PowerLawKernel | PronyKernel) -> dict:
    if isinstance(kernel, PowerLawKernel):
        return {"rheology": "power-law", "E0_star_pa": kernel.E0, "alpha": kernel.alpha,
                "t0_s": kernel.t0}
    return {"rheology": "sls", "E_inf_star_pa": kernel.E_inf, "E1_star_pa": kernel.E[0],
            "tau_s": kernel.tau[0]}


def _check_material(name: str, mat) -> ViscoMaterial:
    check_file_name(name, "material")
    if not isinstance(mat, ViscoMaterial):
        raise InputError(f"material {name!r} must be a palpbayes.sim.ViscoMaterial, got "
                         f"{type(mat).__name__}")
    k = mat.kernel
    if not (isinstance(k, PowerLawKernel) or (isinstance(k, PronyKernel) and len(k.E) == 1)):
        raise InputError(f"material {name!r}: the kernel must be a PowerLawKernel or a "
                         "one-term PronyKernel (the SLS); truth.csv has columns for those")
    positive(mat.thickness_m, f"material {name!r} thickness [m]")
    return mat


def _speeds(speeds: Sequence[float]) -> list[float]:
    try:
        v = [float(s) for s in speeds]
    except (TypeError, ValueError):
        raise InputError(f"speeds {speeds!r} [m/s] are not numbers") from None
    if not v:
        raise InputError("a campaign needs at least one speed [m/s]")
    v = [positive(s, f"speed {s!r} [m/s]") for s in v]
    labels = [speed_label(s) for s in v]
    if len(set(labels)) < len(labels):
        raise InputError(f"speeds {', '.join(f'{s * 6e4:g}' for s in v)} mm/min repeat "
                         "(give every speed once; --repetitions repeats them)")
    return v


def _truth_row(trace: IndentationTrace, mat: ViscoMaterial, tip_name: str, nu: float,
               e_compression: float, compression_speed: float) -> dict:
    m = trace.metadata
    return {
        "trace_id": trace.trace_id, "material": trace.material, "specimen": trace.specimen,
        "tip": trace.tip.kind, "tip_name": tip_name, "repetition": trace.repetition,
        "speed_m_s": m["speed"], "speed_mm_min": m["speed"] * 6e4,
        **_kernel_columns(mat.kernel),
        "nu": nu, "thickness_m": mat.thickness_m,
        "E_compression_true_pa": e_compression,
        "compression_speed_mm_min": compression_speed * 6e4,
        "z_surf_true_m": m["z_surf_true"], "sigma_true_n": m["sigma_true"],
        "noise_pp_n": m["noise_pp"], "phi_true": m["phi_true"],
        "force_offset_true_n": m["force_offset_true"], "depth_m": m["depth_true"],
        "approach_m": m["approach"], "hold_s": m["hold"], "retract": m["retract"],
        "rate_hz": m["rate"], "max_force_true_n": m["max_force_true"],
        "n_points": trace.n_points,
    }


# Many parameters: one `palpbayes simulate --rheology` option each (materials, tips, speeds,
# motion, sensor), by the command's names.
def simulate_visco_campaign(
    out_dir: str | os.PathLike,
    *,
    rheology: str = "power-law",
    materials: Mapping[str, ViscoMaterial] | None = None,
    tips: Mapping[str, Tip] = VISCO_TIPS,
    speeds: Sequence[float] = DEFAULT_SPEEDS,
    repetitions: int = 1,
    seed: int = 0,
    depth: float = 2e-3,
    hold: float = 5.0,
    rate: float = 800.0,
    retract: bool = True,
    nu: float = DEFAULT_NU,
    noise_pp: float = PAPER_NOISE_PP,
    noise_ar1: float = 0.0,
    force_offset_sd: float = 5e-3,
    z_surf: float = 0.1,
    z_surf_halfwidth: float = 1e-3,
    compression_speed: float = PAPER_COMPRESSION_SPEED,
    overwrite: bool = False,
    float_format: str = "%.10g",
) -> Path:
    """Write a viscoelastic palpation campaign folder (layout in the module docstring).

    Parameters
    ----------
    out_dir
        Output folder (created; must be empty unless ``overwrite``).
    rheology
        ``"power-law"`` or ``"sls"``: which default specimens (:data:`POWER_LAW_FOAMS`,
        :data:`SLS_FOAMS`) when ``materials`` is None.
    materials
        Name -> :class:`ViscoMaterial` (power law or SLS, mixed if need be).
    tips
        Name -> :class:`~palpbayes.contact.Tip` with a power law (not the exact sphere).
    speeds
        [m/s] Tip speeds down and up, each palpated ``repetitions`` times.
    repetitions
        Traces per (material, tip, speed), >= 1.
    seed
        Non-negative integer.
    depth, hold, rate, retract
        [m], [s], [Hz] The motion (:func:`~palpbayes.sim.viscoelastic.ramp_hold_motion`:
        a pre-contact approach of 0.5 s at each speed).
    nu
        Poisson's ratio [-] written to the manifest (the fit's Young's moduli and
        ``E_compression_pa``).
    noise_pp, noise_ar1
        [N] Peak-to-peak force noise (sigma = pp/6) and its AR(1) coefficient.
    force_offset_sd
        [N] sd of the per-trace force offset.
    z_surf, z_surf_halfwidth
        [m] Centre and half-width of the uniform surface height.
    compression_speed
        [m/s] Cross-head speed of the compression test ``E_compression_true_pa`` is read for.
    overwrite
        Write into a non-empty folder (a previous campaign's traces are removed first).
    float_format
        Number format of the trace CSVs.

    Returns
    -------
    Path
        ``out_dir``.

    Raises
    ------
    OutputExistsError
        ``out_dir`` is not empty and ``overwrite`` is False.
    InputError, GeometryError
        Bad seed, counts, names, speeds, motion or noise; a tip without a power law.
    """
    seed = check_seed(seed)
    repetitions = check_count(repetitions, "repetitions", 1)
    nu = check_nu(nu)
    if materials is None:
        defaults = {"power-law": POWER_LAW_FOAMS, "sls": SLS_FOAMS}
        if rheology not in defaults:
            raise InputError(f"rheology {rheology!r}: use power-law or sls")
        materials = defaults[rheology]
    if not materials or not tips:
        raise InputError("a campaign needs at least one material and one tip")
    materials = {k: _check_material(k, m) for k, m in materials.items()}
    for name in tips:
        check_file_name(name, "tip")
    speeds = _speeds(speeds)
    sigma = sigma_from_pp(nonneg(noise_pp, "peak-to-peak noise noise_pp [N]"))
    noise_ar1 = ar1_phi(noise_ar1)
    force_offset_sd = nonneg(force_offset_sd, "force offset sd [N]")
    z_surf_halfwidth = nonneg(z_surf_halfwidth, "surface half-width [m]")
    z_surf = finite(z_surf, "surface height z_surf [m]")
    compression_speed = positive(compression_speed, "compression speed [m/s]")

    out = Path(out_dir)
    traces, manifest, truth, mats = [], [], [], []  # simulate first: bad options fail early
    for mname, mat in materials.items():
        e_comp = float(compression_moduli([mat.kernel], nu, compression_speed,
                                          mat.thickness_m)[0])
        mats.append({"material": mname, **_kernel_columns(mat.kernel),
                     "thickness_m": mat.thickness_m, "nu": nu, "E_compression_true_pa": e_comp,
                     "compression_speed_mm_min": compression_speed * 6e4})
        for tname, tip in tips.items():
            for v in speeds:
                label = speed_label(v)
                for rep in range(1, repetitions + 1):
                    gen = np.random.default_rng(child_seed(seed, "visco", mname, tname, label,
                                                           rep))
                    zs = z_surf + z_surf_halfwidth * gen.uniform(-1.0, 1.0)
                    f0 = force_offset_sd * gen.standard_normal()
                    tid = f"{mname}_{tname}_v{label}_r{rep:02d}"
                    tr = simulate_viscoelastic(
                        mat.kernel, tip, depth=depth, speed=v, hold_time=hold, retract=retract,
                        rate=rate, z_surf=zs, noise_sd=sigma, phi=noise_ar1, offset=f0,
                        rng=gen, trace_id=tid)
                    tr = tr.replace(specimen=mname, material=mname, repetition=rep,
                                    thickness=mat.thickness_m)
                    traces.append(tr)
                    manifest.append({**manifest_row(tid, f"traces/{tid}.csv", mname, mname,
                                                     tip, mat.thickness_m, rep, None),
                                     "nu": nu})
                    truth.append(_truth_row(tr, mat, tname, nu, e_comp, compression_speed))
    prepare_out_dir(out, overwrite)
    (out / "truth_groundtruth.csv").unlink(missing_ok=True)  # an elastic campaign's, if any
    for tr in traces:
        write_trace(tr, out / "traces" / f"{tr.trace_id}.csv", float_format=float_format)
    write_manifest(pd.DataFrame(manifest), out / "manifest.csv")
    write_csv_atomic(pd.DataFrame(truth), out / "truth.csv")
    write_csv_atomic(pd.DataFrame(mats), out / "truth_materials.csv")
    return out
