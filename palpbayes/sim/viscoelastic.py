"""Palpations of a linear viscoelastic specimen: a ramp–hold–retract from a known relaxation
kernel, with the truth in the trace's metadata.

The motion (:func:`ramp_hold_motion`) is sampled at t_k = k/rate, k = 0..N-1, from rest: the
tip starts ``approach`` above the surface, moves down at ``speed`` to ``depth`` below it, holds
and (optionally) moves back up at the same speed to where it started.  The force is that of a
rigid tip with the elastic law F = E*·g·d^m (the tip's own law, :func:`palpbayes.contact.exponent`
and :func:`~palpbayes.contact.prefactor`) on a viscoelastic half-space whose relaxation modulus
is the kernel, Lee–Radok while the contact grows and Ting when it shrinks
(:func:`palpbayes.contact.hereditary_force`, ``../shared/DESIGN.md`` §9)::

    F_rec(t) = F0 + g·∫_0^t E*(t - s)·d/ds[d(s)^m] ds + e(t)     (Ting's upper limit on retract)
    z_rec(t) = z(t) + eta(t)
    e(t)     = phi·e(t-1) + sqrt(1 - phi²)·sigma·w(t),  e(0) = sigma·w(0)

Two additions to a simulated trace, each a new trace with its truth in the metadata:
:func:`adhesive_pull_off` (the sample holding the tip after Ting's contact has ended,
−A·(s/L)·exp(1 − s/L) over the height s travelled up since, the dip real AFM retracts show)
and :func:`add_baseline_terms` (a viscous drag on the probe b·(−dz/dt) and a baseline that
tilts with the height F1·(z − z_ref), as :mod:`palpbayes.rheology.posterior` models them).

The kernel's moduli are **reduced** moduli E* (palpbayes works in E*; E = E*·(1 - nu²)).  The
noise model is :mod:`palpbayes.sim.trace`'s; the default sigma is the paper's 48 mN peak-to-peak
read as ±3 sigma (8 mN).  A paper-scale foam is E* ~ 50–150 kPa under the paper's tips
(:data:`palpbayes.paper.PAPER_TIPS`: the paraboloid and the flat punch; the exact sphere has no
power law, use its Hertz paraboloid), a few mm deep at 50 mm/min, 800 Hz.

>>> from palpbayes.contact import PowerLawKernel
>>> from palpbayes.paper import PAPER_TIPS
>>> tr = simulate_viscoelastic(PowerLawKernel(100e3, 0.1), PAPER_TIPS["paraboloid"],
...                            depth=3e-3, speed=50 / 60e3, hold_time=2.0, rng=1)
>>> tr.segment_names, tr.metadata["kernel"]
(('approach', 'hold', 'retract'), 'power-law')
"""

# Long module: one job, simulating a viscoelastic palpation; the motion, the kernel's truth,
#   adhesion and baseline terms are parts of one trace.

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..arguments import ar1_phi, finite, nonneg, positive
from ..contact import PowerLawKernel, PronyKernel, Tip, exponent, get_law, hereditary_force
from ..contact import prefactor as tip_prefactor
from ..errors import GeometryError, InputError
from ..sensor_noise import PAPER_NOISE_PP, ar1_noise, pp_from_sigma, sigma_from_pp
from ..trace import IndentationTrace

__all__ = ["ramp_hold_motion", "simulate_viscoelastic", "multi_speed", "adhesive_pull_off",
           "add_baseline_terms", "noise_free_force", "VISCO_BASELINE_TIME"]

#: [s] Default pre-contact baseline: the default approach is ``speed`` times this.
VISCO_BASELINE_TIME = 0.5
#: Sample periods by which a duration may exceed a whole number of them and still round down.
_SLACK = 1e-6


def _steps(duration: float, rate: float) -> int:
    """Whole sample periods covering ``duration`` [s] at ``rate`` [Hz] (rounded up, but a
    duration within :data:`_SLACK` of a period above a whole number rounds down)."""
    return max(0, math.ceil(duration * rate - _SLACK))


def ramp_hold_motion(*, depth: float, speed: float, hold_time: float, retract: bool = True,
                     rate: float = 800.0, approach: float | None = None, z_surf: float = 0.0
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Time, tip height and segment codes of one ramp–hold–retract, sampled at ``rate``.

    The samples are t_k = k/rate, k = 0..N-1, the first at the start height.  The descent is a
    whole number n of sample periods: the start height is z_surf + approach', with approach'
    the requested ``approach`` raised to the next multiple of speed/rate above depth (by less
    than one sample's travel), so that the deepest point z_surf - depth is sampled exactly at
    k = n and the speed is exact.  The hold is ``hold_time`` rounded up to whole sample periods
    (h samples at the bottom, 0 for no hold); the retract (if any) takes n more samples back up
    to the start height.  N = n + 1 + h (+ n).

    Parameters
    ----------
    depth
        [m] Depth below the surface at the bottom (> 0).
    speed
        [m/s] Tip speed down and up (> 0; the paper's 50 mm/min is 8.33e-4 m/s).
    hold_time
        [s] Hold at the bottom (>= 0).
    retract
        Move back up to the start height after the hold.
    rate
        [Hz] Sample rate (> 0).
    approach
        [m] Height above the surface where the motion starts (>= 0); default
        :data:`VISCO_BASELINE_TIME` · speed (a 0.5 s pre-contact baseline).
    z_surf
        [m] Surface height (z up, depth d = z_surf - z).

    Returns
    -------
    (time [s], z [m], segment)
        ``segment`` codes into :data:`palpbayes.trace.SEGMENTS`: 0 while descending (the bottom
        sample included), 1 on the hold, 2 on the retract.

    Raises
    ------
    InputError
        A non-positive depth, speed or rate, a negative hold time or approach, a non-finite
        z_surf, or a motion of fewer than 3 samples.
    """
    depth = positive(depth, "indentation depth [m]")
    speed = positive(speed, "speed [m/s]")
    hold_time = nonneg(hold_time, "hold time [s]")
    rate = positive(rate, "sample rate [Hz]")
    z_surf = finite(z_surf, "surface height z_surf [m]")
    approach = VISCO_BASELINE_TIME * speed if approach is None else nonneg(
        approach, "approach distance [m]")
    n_down = max(1, _steps((approach + depth) / speed, rate))
    n_hold = _steps(hold_time, rate)
    n_up = n_down if retract else 0
    if n_down + 1 + n_hold + n_up < 3:
        raise InputError(f"the motion has only {n_down + 1 + n_hold + n_up} samples at "
                         f"{rate:g} Hz (a trace needs 3): raise the rate, the approach "
                         "distance [m] or the hold time [s]")
    # sample periods of travel above the bottom: n..0 down, 0 on the hold, 1..n up
    above = np.concatenate([np.arange(n_down, -1, -1), np.zeros(n_hold),
                            np.arange(1, n_up + 1)])
    bottom = z_surf - depth
    z = bottom + above * (speed / rate)
    z[0] = max(z[0], z_surf)  # out of contact at rest even when approach' rounds to 0
    if retract:
        z[-1] = z[0]
    segment = np.repeat(np.array([0, 1, 2], dtype=np.int8), [n_down + 1, n_hold, n_up])
    return np.arange(above.size) / rate, z, segment


def _kernel_truth(kernel) -> dict:
    """The kernel's kind and parameters as metadata entries."""
    if isinstance(kernel, PowerLawKernel):
        return {"kernel": "power-law", "E0_true": kernel.E0, "alpha_true": kernel.alpha,
                "t0_true": kernel.t0}
    if len(kernel.E) == 1:
        return {"kernel": "sls", "E_inf_true": kernel.E_inf, "E1_true": kernel.E[0],
                "tau_true": kernel.tau[0]}
    return {"kernel": "prony", "E_inf_true": kernel.E_inf, "E_prony_true": tuple(kernel.E),
            "tau_prony_true": tuple(kernel.tau)}


def _power_law_tip(tip) -> tuple[float, float]:
    """(g, m) of the tip's law F = E*·g·d^m, else InputError/GeometryError."""
    if not isinstance(tip, Tip):
        raise InputError(f"tip must be a palpbayes.contact.Tip, got {type(tip).__name__}")
    g, m = tip_prefactor(tip), exponent(tip)
    if g is None or m is None:
        law = get_law(tip)
        hint = ""
        if law.hertz_approximation is not None:
            hint = f"; use tip '{law.hertz_approximation(tip).kind}' (its Hertz approximation)"
        raise GeometryError(f"tip '{tip.kind}' has no power-law form F = E*·g·d^m, which the "
                            f"viscoelastic simulator needs{hint}")
    return float(g), float(m)


# Many parameters: the relaxation kernel, tip and the ramp-hold-retract motion with its sensor
# noise: each a physical setting with its unit, by the simulator's names.
def simulate_viscoelastic(
    kernel: PowerLawKernel | PronyKernel,
    tip: Tip,
    *,
    depth: float,
    speed: float,
    hold_time: float,
    retract: bool = True,
    rate: float = 800.0,
    z_surf: float = 0.0,
    noise_sd: float = sigma_from_pp(PAPER_NOISE_PP),
    phi: float = 0.0,
    offset: float = 0.0,
    position_noise_sd: float = 0.0,
    approach: float | None = None,
    rng: np.random.Generator | np.random.SeedSequence | int | None = None,
    trace_id: str = "visco",
) -> IndentationTrace:
    """One ramp–hold–retract palpation of a viscoelastic half-space (module docstring).

    Parameters
    ----------
    kernel
        Relaxation modulus of the reduced modulus E*(t): a
        :class:`~palpbayes.contact.PowerLawKernel` or a
        :class:`~palpbayes.contact.PronyKernel` (e.g.
        :func:`~palpbayes.contact.standard_linear_solid`).
    tip
        A power-law tip (paraboloid, flat punch, cone, power); F = E*·g·d^m when elastic.
    depth, speed, hold_time, retract, rate, approach, z_surf
        The motion: :func:`ramp_hold_motion`.
    noise_sd
        [N] Marginal sd sigma of the force noise (default 8 mN: the paper's 48 mN p-p / 6).
    phi
        Lag-one correlation of the AR(1) force noise, |phi| < 1 (0: white).
    offset
        [N] Constant force offset F0 (tare error).
    position_noise_sd
        [m] White noise sd added to the recorded z.
    rng
        numpy Generator, SeedSequence or seed.  Two draws of N standard normals, force then
        z, whatever the options (the same seed gives the same noise across settings).
    trace_id
        The trace's identifier.

    Returns
    -------
    IndentationTrace
        Recorded z (up positive), force positive when pressing, ``segment`` codes.
        ``metadata`` holds the truth: ``kernel`` ("power-law" with ``E0_true`` [Pa],
        ``alpha_true``, ``t0_true`` [s]; "sls" with ``E_inf_true``, ``E1_true`` [Pa],
        ``tau_true`` [s]; "prony" with ``E_inf_true``, ``E_prony_true``, ``tau_prony_true``),
        ``z_surf_true``, ``sigma_true``, ``noise_pp``, ``phi_true``, ``force_offset_true``,
        ``position_noise_true``, ``depth_true``, ``max_force_true`` (noise-free), the tip's law
        ``m_true`` and ``g_true``, the motion (``speed``, ``rate``, ``hold`` [s] as sampled,
        ``hold_requested``, ``approach`` [m] as sampled, ``retract``), ``simulated`` and
        ``seed`` when ``rng`` was an int.

    Raises
    ------
    InputError, GeometryError
        An unknown kernel, a tip without a power law (the exact sphere), a bad motion
        (:func:`ramp_hold_motion`), negative noise, |phi| >= 1, a non-finite offset.
    """
    if not isinstance(kernel, PowerLawKernel | PronyKernel):
        raise InputError(f"kernel {kernel!r} is neither a PowerLawKernel nor a PronyKernel "
                         "(palpbayes.contact)")
    g, m = _power_law_tip(tip)
    sigma = nonneg(noise_sd, "force noise sd noise_sd [N]")
    phi = ar1_phi(phi)
    offset = finite(offset, "force offset [N]")
    position_noise_sd = nonneg(position_noise_sd, "position noise sd position_noise_sd [m]")
    t, z, segment = ramp_hold_motion(depth=depth, speed=speed, hold_time=hold_time,
                                     retract=retract, rate=rate, approach=approach,
                                     z_surf=z_surf)
    z_surf, speed, rate = float(z_surf), float(speed), float(rate)

    gen = np.random.default_rng(rng)
    n = t.size
    w_force = gen.standard_normal(n)
    w_z = gen.standard_normal(n)
    f_true = hereditary_force(t, z_surf - z, g, m, kernel)
    force = offset + f_true + ar1_noise(n, sigma, phi, w_force)
    z_rec = z + position_noise_sd * w_z

    metadata = {
        "simulated": True,
        **_kernel_truth(kernel),
        "z_surf_true": z_surf,
        "sigma_true": sigma,
        "noise_pp": pp_from_sigma(sigma),
        "phi_true": phi,
        "force_offset_true": offset,
        "position_noise_true": position_noise_sd,
        "depth_true": float(depth),
        "max_force_true": float(f_true.max()),
        "m_true": m,
        "g_true": g,
        "approach": float(z[0] - z_surf),
        "speed": speed,
        "rate": rate,
        "hold": int(np.count_nonzero(segment == 1)) / rate,
        "hold_requested": float(hold_time),
        "retract": bool(retract),
    }
    if isinstance(rng, int | np.integer):
        metadata["seed"] = int(rng)
    return IndentationTrace(time=t, z=z_rec, force=force, tip=tip, trace_id=trace_id,
                            source=f"simulated viscoelastic trace {trace_id!r}",
                            metadata=metadata, segment=segment)


def multi_speed(kernel: PowerLawKernel | PronyKernel, tip: Tip, speeds, **kwargs
                ) -> list[IndentationTrace]:
    """One :func:`simulate_viscoelastic` trace per speed in ``speeds`` [m/s], in that order.

    The noise of the traces is independent: ``rng`` (a seed, SeedSequence or Generator in
    ``kwargs``) is spawned into one child per trace (:meth:`numpy.random.SeedSequence.spawn`),
    so the same seed gives the same list.  Trace ids are ``f"{trace_id}-{v:.4g}mm-min"`` with v
    the speed in mm/min (``-{i}`` appended to every id when two speeds print alike);
    ``metadata`` adds ``speed_index`` i and, for an int seed, ``seed``.

    Raises
    ------
    InputError
        No speeds, a speed that is not a positive number, ``speed`` among ``kwargs``, or any
        error of :func:`simulate_viscoelastic`.
    """
    if "speed" in kwargs:
        raise InputError("multi_speed takes the speeds as its third argument, not speed=")
    try:
        v = np.asarray(speeds, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"speeds {speeds!r} [m/s] are not numbers") from None
    if v.ndim != 1 or v.size == 0:
        raise InputError(f"speeds must be a non-empty list of speeds [m/s], got {speeds!r}")
    v = [positive(x, f"speeds[{i}] [m/s]") for i, x in enumerate(v)]
    rng = kwargs.pop("rng", None)
    base = kwargs.pop("trace_id", "visco")
    if isinstance(rng, np.random.Generator):
        children = rng.spawn(len(v))
    else:
        seq = rng if isinstance(rng, np.random.SeedSequence) else np.random.SeedSequence(rng)
        children = seq.spawn(len(v))
    ids = [f"{base}-{x * 60e3:.4g}mm-min" for x in v]
    if len(set(ids)) < len(ids):
        ids = [f"{name}-{i}" for i, name in enumerate(ids)]
    out = []
    for i, (x, child, name) in enumerate(zip(v, children, ids, strict=True)):
        tr = simulate_viscoelastic(kernel, tip, speed=x, rng=child, trace_id=name, **kwargs)
        meta = dict(tr.metadata, speed_index=i)
        if isinstance(rng, int | np.integer):
            meta["seed"] = int(rng)
        out.append(replace(tr, metadata=meta))
    return out


def _kernel_of(meta: dict) -> PowerLawKernel | PronyKernel:
    """The relaxation kernel recorded in a simulated trace's metadata (:func:`_kernel_truth`)."""
    kind = meta.get("kernel")
    if kind == "power-law":
        return PowerLawKernel(meta["E0_true"], meta["alpha_true"], meta["t0_true"])
    if kind == "sls":
        return PronyKernel(meta["E_inf_true"], (meta["E1_true"],), (meta["tau_true"],))
    if kind == "prony":
        return PronyKernel(meta["E_inf_true"], tuple(meta["E_prony_true"]),
                           tuple(meta["tau_prony_true"]))
    raise InputError("the trace's metadata names no relaxation kernel: give a trace of "
                     "simulate_viscoelastic")


def _motion(trace: IndentationTrace) -> tuple[np.ndarray, dict]:
    """The noise-free tip height [m] of a whole :func:`simulate_viscoelastic` trace, rebuilt
    from its metadata (:func:`ramp_hold_motion`), and the metadata; InputError otherwise."""
    meta = trace.metadata or {}
    need = ("simulated", "kernel", "z_surf_true", "depth_true", "speed", "rate",
            "hold_requested", "retract", "approach", "m_true", "g_true")
    missing = [k for k in need if k not in meta]
    if missing:
        raise InputError(f"{trace.trace_id}: not a trace of simulate_viscoelastic (its metadata "
                         f"lack {missing[0]!r}); the noise-free force is rebuilt from that "
                         "truth")
    t, z, _ = ramp_hold_motion(depth=meta["depth_true"], speed=meta["speed"],
                               hold_time=meta["hold_requested"], retract=meta["retract"],
                               rate=meta["rate"], approach=meta["approach"],
                               z_surf=meta["z_surf_true"])
    if t.size != trace.n_points or not np.allclose(t, trace.time, rtol=0, atol=1e-9):
        raise InputError(f"{trace.trace_id}: its {trace.n_points} samples are not the "
                         f"{t.size} of its simulated motion (cut or resampled?); use the "
                         "whole simulated trace")
    return z, meta


def noise_free_force(trace: IndentationTrace) -> np.ndarray:
    """[N] The contact force of a :func:`simulate_viscoelastic` trace without its noise and
    offset (nor anything added since): the hereditary force of its kernel and tip on its
    motion, rebuilt from the metadata (:func:`ramp_hold_motion`; the recorded z may be noisy).

    Raises
    ------
    InputError
        A trace that is not one of :func:`simulate_viscoelastic` whole (its metadata lack the
        truth, or its samples are not those of the motion).
    """
    z, meta = _motion(trace)
    return hereditary_force(trace.time, meta["z_surf_true"] - z, meta["g_true"],
                            meta["m_true"], _kernel_of(meta))


def adhesive_pull_off(trace: IndentationTrace, force: float, length: float
                      ) -> IndentationTrace:
    """``trace`` (one of :func:`simulate_viscoelastic`, with a retract) with an adhesive
    pull-off on its retract: from the first retract sample where the noise-free Ting force
    has come back to zero (the contact ends, t_off), the force gains

        F_adh = −A·(s/L)·exp(1 − s/L),   s = z(t) − z(t_off) >= 0 the height travelled up,

    zero at t_off, a pull of A at s = L, then a decay (a sample holding the tip as it lets
    go, which Ting's rule does not model).  The heights are the motion's, without position
    noise.

    Parameters
    ----------
    trace
        A whole :func:`simulate_viscoelastic` trace with a retract (other additions, e.g.
        :func:`add_baseline_terms`, may come before or after).
    force
        [N] A >= 0, the largest pull.
    length
        [m] L > 0, the height above t_off where the pull is largest.

    Returns
    -------
    IndentationTrace
        The new trace; ``metadata`` adds ``adhesion_force_true`` [N],
        ``adhesion_length_true`` [m] and ``adhesion_start_true`` (t_off [s]).

    Raises
    ------
    InputError
        A negative force or non-positive length, a trace without a retract, not a whole
        simulated trace (:func:`noise_free_force`), or a contact that never ends on the
        retract.
    """
    A = nonneg(force, "adhesive force A [N]")
    L = positive(length, "adhesion length L [m]")
    if trace.segment is None or not np.any(trace.segment == 2):
        raise InputError(f"{trace.trace_id}: no retract to add the pull-off to "
                         "(simulate with retract=True)")
    z, meta = _motion(trace)
    free = noise_free_force(trace)
    ret = np.flatnonzero(trace.segment == 2)
    off = ret[free[ret] <= 0.0]
    if off.size == 0:
        raise InputError(f"{trace.trace_id}: the contact does not end on the retract, so "
                         "there is no pull-off to add")
    i0 = int(off[0])
    s = np.zeros(trace.n_points)
    s[i0:] = np.clip(z[i0:] - z[i0], 0.0, None)
    adh = -A * (s / L) * np.exp(1.0 - s / L)
    return trace.replace(force=trace.force + adh,
                         metadata=dict(meta, adhesion_force_true=A, adhesion_length_true=L,
                                       adhesion_start_true=float(trace.time[i0])))


def add_baseline_terms(trace: IndentationTrace, *, drag: float = 0.0, tilt: float = 0.0,
                       z_ref: float | None = None) -> IndentationTrace:
    """``trace`` with a viscous drag on the probe and a tilted baseline added to its force:

        F += b·(−dz/dt) + F1·(z − z_ref),

    dz/dt from the recorded z (:func:`numpy.gradient`; simulate without position noise to
    keep the drag's column exact), so the drag pushes down (+) on the way down and pulls on
    the way up, as :mod:`palpbayes.rheology.posterior` models it.

    Parameters
    ----------
    trace
        Any trace.
    drag
        [N·s/m] b (>= 0).
    tilt
        [N/m] F1 (any sign).
    z_ref
        [m] Height where the tilt is zero (default the first sample's).

    Returns
    -------
    IndentationTrace
        The new trace; ``metadata`` adds ``drag_true`` [N·s/m], ``tilt_true`` [N/m] and
        ``tilt_z_ref`` [m] (added to any earlier ones).
    """
    b = nonneg(drag, "viscous drag b [N·s/m]")
    f1 = finite(tilt, "baseline tilt F1 [N/m]")
    ref = float(trace.z[0]) if z_ref is None else finite(z_ref, "tilt reference z_ref [m]")
    meta = dict(trace.metadata or {})
    if meta.get("tilt_true", 0.0) and meta.get("tilt_z_ref", ref) != ref:
        raise InputError("a tilt is already added about another z_ref; give the same z_ref")
    force = trace.force - b * np.gradient(trace.z, trace.time) + f1 * (trace.z - ref)
    meta.update(drag_true=meta.get("drag_true", 0.0) + b,
                tilt_true=meta.get("tilt_true", 0.0) + f1, tilt_z_ref=ref)
    return trace.replace(force=force, metadata=meta)
