"""A simulated Instron compression test (the ground truth) and its Instron-like export file.

:func:`simulate_compression_test` compresses a foam block between flat platens at constant
crosshead speed (linear elastic or viscoelastic, with a smooth toe,
:func:`~palpbayes.compression.toe_compression`, re-exported here);
:func:`write_compression_export` writes the table in the layout that
:func:`palpbayes.io.instron.read_compression_test` reads, so the ground-truth path of the
pipeline can be tested end to end on a known modulus.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pandas as pd

from ..arguments import nonneg, positive
from ..compression.window import toe_compression
from ..contact import check_nu
from ..errors import InputError
from ..io.atomic import write_text_atomic
from ..material import Solid
from ..twin import Specimen, compression_factor

__all__ = ["toe_compression", "simulate_compression_test", "write_compression_export"]


# Many parameters: one compression test's block, platens, cross-head motion and load-cell noise:
# each a physical setting with its unit.
def simulate_compression_test(
    E: float | None = None,
    *,
    kernel=None,
    width: float = 0.05,
    length: float = 0.05,
    height: float,
    speed: float = 50 / 60e3,
    rate: float = 25.0,
    max_compression: float = 5e-3,
    toe: float = 0.2e-3,
    noise_n: float = 0.02,
    rng: np.random.Generator | int | None = None,
    specimen: str = "",
    material: str = "",
    platens: str = "lubricated",
    nu: float | None = None,
) -> pd.DataFrame:
    """Simulate an unconfined uniaxial compression test (Instron 4502 style).

    The crosshead moves down at ``speed`` from first touch (x = 0) to ``max_compression``,
    sampled at ``rate`` at t_k = k/rate, k = 0..N.  Load (linear elastic, frictionless
    platens)::

        F(x) = c·E·A/h·u(x) + noise,   A = width·length,   u = toe_compression(x, toe)

    so beyond x = 2·toe the curve is a line of slope c·E·A/h [N/m] through (toe, 0); c = 1
    between lubricated platens, c(nu, block) > 1 between bonded ones, whose friction holds
    the faces' lateral expansion (the block's finite-element twin,
    :func:`palpbayes.twin.compression_factor`): what an Instron reports as E is then c·E.  A
    viscoelastic block (``kernel``, its uniaxial relaxation modulus E(t)) carries the load of
    the same strain history through the hereditary integral (Boltzmann),

        F(t) = A·∫_0^t E(t − s)·dε(s),   ε = u(x(s))/h,

    evaluated on the sample times (:func:`~palpbayes.contact.viscoelastic.hereditary_force`
    with C = 1, m = 1): its apparent modulus depends on the crosshead speed.

    Parameters
    ----------
    E
        [Pa] Young's modulus of an elastic block, or a hyperelastic
        :class:`~palpbayes.material.Solid` (its nominal stress at finite strain between
        lubricated platens, :meth:`~palpbayes.material.Solid.compression_stress`; ``E_true_pa``
        is then its E0); give either ``E`` or ``kernel``.
    kernel
        Uniaxial relaxation modulus E(t) [Pa] of a viscoelastic block: a
        :class:`~palpbayes.contact.PowerLawKernel` or
        :class:`~palpbayes.contact.PronyKernel` (E(t) = (1 − nu²)·E*(t) of a palpation fit).
    width, length, height
        [m] Block dimensions (height is the loading direction).
    speed
        [m/s] Crosshead speed (default 50 mm/min).
    rate
        [Hz] Sample rate (default 25 Hz).
    max_compression
        [m] Final crosshead travel.
    toe
        [m] Slack before full contact (quadratic toe of length 2·toe).
    noise_n
        [N] Load-cell noise sd (white Gaussian).
    rng
        numpy Generator or seed.
    specimen, material
        Labels, stored in ``df.attrs``.
    platens
        ``"lubricated"`` (frictionless: the block in uniaxial stress) or ``"bonded"`` (the
        faces cannot slide; needs ``nu``; an elastic block only).
    nu
        Poisson ratio [-] of the block (bonded platens).

    Returns
    -------
    pandas.DataFrame
        Columns ``time_s``, ``compression_m``, ``force_n`` (both positive in compression);
        ``attrs`` holds the truth (``E_true_pa``, NaN for a ``kernel``, then ``kernel``
        its repr; ``area_m2``, ``height_m``, ``width_m``,
        ``length_m``, ``stiffness_n_per_m``, ``toe_m``, ``noise_n``, ``speed_m_per_s``,
        ``specimen``, ``material``, ``platens``, ``nu``, ``platen_factor`` (c) and
        ``E_apparent_pa``, c·E: what the test reads).
    """
    solid = None
    if (E is None) == (kernel is None):
        raise InputError("give the block's Young's modulus E [Pa] or its relaxation modulus "
                         "kernel=, one of the two")
    if kernel is not None:
        from ..contact.viscoelastic import PowerLawKernel, PronyKernel
        if not isinstance(kernel, PowerLawKernel | PronyKernel):
            raise InputError(f"kernel {kernel!r} is neither a PowerLawKernel nor a PronyKernel")
    elif isinstance(E, Solid):
        solid, E = E, E.E0
        if platens != "lubricated":
            raise InputError("a hyperelastic block is compressed between lubricated platens "
                             "only (bonded platens at finite strain need its twin)")
    else:
        E = positive(E, "Young's modulus E [Pa]")
    width = positive(width, "block width [m]")
    length = positive(length, "block length [m]")
    height = positive(height, "block height [m]")
    speed = positive(speed, "crosshead speed [m/s]")
    rate = positive(rate, "sample rate [Hz]")
    max_compression = positive(max_compression, "maximum compression [m]")
    if max_compression >= height:
        raise InputError(f"maximum compression {max_compression} m must be below the block "
                         f"height {height} m")
    toe = nonneg(toe, "toe length [m]")
    if platens not in ("lubricated", "bonded"):
        raise InputError(f"platens {platens!r}: use 'lubricated' or 'bonded'")
    c = 1.0
    if platens == "bonded":
        if kernel is not None:
            raise InputError("bonded platens are simulated for an elastic block (E=) only")
        if nu is None:
            raise InputError("bonded platens need the block's Poisson ratio (nu=)")
        c = compression_factor(Specimen(height, length=length, width=width), check_nu(nu),
                               "bonded")
    noise_n = nonneg(noise_n, "load-cell noise sd [N]")
    gen = np.random.default_rng(rng)
    n = math.ceil(max_compression / speed * rate - 1e-6)
    t = np.arange(n + 1) / rate
    x = np.minimum(speed * t, max_compression)
    area = width * length
    if solid is not None:
        k = E * area / height
        load = area * solid.compression_stress(toe_compression(x, toe) / height)
    elif kernel is None:
        k = c * E * area / height
        load = k * toe_compression(x, toe)
    else:
        from ..contact.viscoelastic import hereditary_force
        E, k = math.nan, math.nan
        load = area * hereditary_force(t, toe_compression(x, toe) / height, 1.0, 1.0, kernel)
    f = load + noise_n * gen.standard_normal(t.size)
    df = pd.DataFrame({"time_s": t, "compression_m": x, "force_n": f})
    if kernel is not None:
        df.attrs["kernel"] = repr(kernel)
    if solid is not None:
        df.attrs["solid"] = solid.describe()
    df.attrs.update({
        "E_true_pa": E, "area_m2": area, "height_m": height, "width_m": width,
        "length_m": length, "stiffness_n_per_m": k, "toe_m": toe, "noise_n": noise_n,
        "speed_m_per_s": speed, "specimen": specimen, "material": material,
        "platens": platens, "nu": math.nan if nu is None else float(nu), "platen_factor": c,
        "E_apparent_pa": c * E,
    })
    return df


def _mm(x: float) -> str:
    return f"{x * 1e3:.6g}"


def write_compression_export(
    df: pd.DataFrame,
    path: str | os.PathLike,
    *,
    width: float | None = None,
    length: float | None = None,
    height: float | None = None,
    speed: float | None = None,
    sample_name: str | None = None,
) -> Path:
    """Write an Instron-like export of a compression test (atomic); return the path.

    Layout (the style of the Instron exports in ``shared/data/phantom-compression``)::

        <sample_name>
        Compression test;
        Block Width: 50mm;
        Block Length: 50mm;
        Block Height: 30mm;
        Speed (mm/min): 50;
        Machine: INSTRON 4502 (simulated);
        Load cell: 1kN;
        Time (s),Extension (mm),Load (kN)
        0.000000,0.000000,-0.00001234
        ...

    Extension and load are **negative in compression** (Instron convention).  Extension is
    written to 1 nm (6 decimals in mm), load to 1e-8 kN = 10 uN, time to 1 us.

    Parameters
    ----------
    df
        From :func:`simulate_compression_test` (columns ``time_s``, ``compression_m``,
        ``force_n``, positive in compression).
    path
        Output file.
    width, length, height
        [m] Block dimensions; default from ``df.attrs``.
    speed
        [m/s] Crosshead speed; default from ``df.attrs``.
    sample_name
        First header line; default ``df.attrs['specimen']``.
    """
    missing = [c for c in ("time_s", "compression_m", "force_n") if c not in df.columns]
    if missing:
        raise InputError(f"compression table lacks column(s) {', '.join(missing)}")
    attrs = df.attrs
    vals = {}
    for key, given, attr in (("width", width, "width_m"), ("length", length, "length_m"),
                             ("height", height, "height_m"), ("speed", speed, "speed_m_per_s")):
        v = given if given is not None else attrs.get(attr)
        if v is None:
            raise InputError(f"give the block {key} for the export header")
        vals[key] = positive(v, f"block {key}")
    name = sample_name if sample_name is not None else attrs.get("specimen") or "sample"
    header = [
        str(name),
        "Compression test;",
        f"Block Width: {_mm(vals['width'])}mm;",
        f"Block Length: {_mm(vals['length'])}mm;",
        f"Block Height: {_mm(vals['height'])}mm;",
        f"Speed (mm/min): {vals['speed'] * 60e3:.6g};",
        "Machine: INSTRON 4502 (simulated);",
        "Load cell: 1kN;",
        "Time (s),Extension (mm),Load (kN)",
    ]
    ext = -df["compression_m"].to_numpy(dtype=float) * 1e3 + 0.0  # + 0.0 turns -0.0 into 0.0
    load = -df["force_n"].to_numpy(dtype=float) * 1e-3 + 0.0
    rows = [f"{t:.6f},{e:.6f},{f:.8f}"
            for t, e, f in zip(df["time_s"].to_numpy(dtype=float), ext, load, strict=True)]
    return write_text_atomic("\n".join(header + rows) + "\n", path)
