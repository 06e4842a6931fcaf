"""Synthetic palpation traces and Instron compression curves, with misspecification knobs.

The public face is :mod:`palpbayes.simulate`, which re-exports this module and
:mod:`palpbayes.simulate_campaign` (this lower module imports neither).

The simulator draws data from a *known* truth so that every estimator in palpbayes can be checked
against it (bias, interval coverage, simulation-based calibration).  Conventions
(docs/design.md §1, §5): SI units; z is up, the tip moves down into the specimen, depth
d = z_surf - z; the force is the compressive normal force, positive when pressing.

Force model of one trace (every term optional except the contact law)::

    F_rec(t) = F_true(t) + F_on(delta) + F0 + drift·t + e(t)
    F_true   = E*·s(delta)·xi(delta),          E* = E/(1 - nu²)
    F_on     = gradual onset (:func:`onset_force_profile`, off by default)
    delta    = z_surf - z_cmd(t) - C·F_true     (series compliance C, solved implicitly)
    z_rec(t) = z_cmd(t) + b + eta(t)            (registration offset b, encoder noise eta)
    e(t)     = phi·e(t-1) + sqrt(1 - phi²)·sigma·w(t),  w ~ N(0, 1),  e(0) = sigma·w(0)

with s(d) the tip's shape function (:func:`palpbayes.contact.shape`, optionally with the bonded
finite-thickness factor), xi the strain-stiffening factor (:func:`stiffening_factor`) and
sigma = noise_pp / :data:`PP_TO_SIGMA`.  The drift is **per second** (``drift`` [N/s], t the
sample time from the start of the trace, t_k = k/rate), so on the loading segment it is also a
linear function of z with slope -drift/speed [N/m].

**Peak-to-peak to sigma.**  A sensor's "peak-to-peak noise" is read as ±3 sigma, the band that
holds 99.7 % of Gaussian samples, so sigma = pp/6: the paper's 48 mN gives sigma = 8 mN (the
value docs/design.md §3 uses).  Note that the *observed* range of N samples grows with N (about 6.4
sigma for N = 800 and 7.2 sigma for N = 3840), so a range measured over a long record overstates
the ±3 sigma convention; ``tests/unit/test_simulate.py`` checks both facts.

Paper numbers (:data:`PAPER_MATERIALS`, :data:`PAPER_TIPS`, :data:`PAPER_ROBOT_ESTIMATES`) are
those of docs/design.md §2 (UR3e robotic palpation of polyethylene foam, Instron 4502 ground truth).
Campaign folders are written by :func:`~palpbayes.simulate_campaign.simulate_campaign`.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.signal import lfilter

from ..contact import Tip, check_nu, effective_modulus, shape
from ..errors import GeometryError, InputError
from ..io.atomic import write_text_atomic
from ..noise import PAPER_NOISE_PP, PP_TO_SIGMA, sigma_from_pp
from ..paper import (  # re-exported: the simulator reproduces the paper's campaign
    PAPER_MATERIALS,
    PAPER_ROBOT_ESTIMATES,
    PAPER_SURFACE_ERROR_M,
    PAPER_TIPS,
    Material,
    RobotEstimate,
    paper_robot_estimates_frame,
)
from ..trace import IndentationTrace

__all__ = [
    "PP_TO_SIGMA",
    "sigma_from_pp",
    "Material",
    "RobotEstimate",
    "PAPER_MATERIALS",
    "PAPER_TIPS",
    "PAPER_ROBOT_ESTIMATES",
    "PAPER_SURFACE_ERROR_M",
    "paper_robot_estimates_frame",
    "STIFFENING_STRAIN0",
    "stiffening_factor",
    "true_force",
    "onset_force_profile",
    "solve_series_compliance",
    "ar1_noise",
    "simulate_trace",
    "toe_compression",
    "simulate_compression_test",
    "write_compression_export",
]

# ----------------------------------------------------------------------------- validation


def _finite(value, what: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{what} {value!r} is not a number") from None
    if not math.isfinite(v):
        raise InputError(f"{what} must be finite, got {value!r}")
    return v


def _positive(value, what: str) -> float:
    v = _finite(value, what)
    if v <= 0:
        raise InputError(f"{what} must be positive, got {value!r}")
    return v


def _nonneg(value, what: str) -> float:
    v = _finite(value, what)
    if v < 0:
        raise InputError(f"{what} must be non-negative, got {value!r}")
    return v


def _phi(value) -> float:
    v = _finite(value, "AR(1) coefficient phi")
    if not -1.0 < v < 1.0:
        raise InputError(f"AR(1) coefficient phi = {value!r} must lie in (-1, 1)")
    return v


# ----------------------------------------------------------------------------- force model

#: Nominal strain d/h below which the stiffening law is inactive.
STIFFENING_STRAIN0 = 0.05


def stiffening_factor(depth, thickness: float | None, stiffening: float) -> np.ndarray:
    """Strain-stiffening factor xi(d) = exp(beta·max(0, d/h - 0.05)) [-].

    A phenomenological misspecification knob (secant modulus E_eff = E·xi): linear up to the
    nominal strain d/h = :data:`STIFFENING_STRAIN0`, exponentially stiffer beyond.  beta = 5 at
    the paper's depth d/h = 0.1 gives xi = exp(0.25) = 1.28.  It is monotone in d, so the force
    stays monotone and the compliance solve keeps its bracket.

    Parameters
    ----------
    depth
        [m] Indentation depth d.
    thickness
        [m] Specimen thickness h (needed when ``stiffening`` != 0).
    stiffening
        beta [-], >= 0; 0 switches the law off (factor exactly 1).
    """
    d = np.asarray(depth, dtype=float)
    if stiffening == 0:
        return np.ones_like(d)
    if thickness is None:
        raise GeometryError("strain stiffening needs the specimen thickness (give thickness=)")
    return np.exp(stiffening * np.maximum(0.0, d / thickness - STIFFENING_STRAIN0))


def true_force(
    depth,
    E: float,
    nu: float,
    tip: Tip,
    *,
    thickness: float | None = None,
    finite_thickness: bool = False,
    bonded: bool = True,
    stiffening: float = 0.0,
) -> np.ndarray:
    """The simulator's noise-free force F = E*·s(d)·xi(d) [N] (0 for d <= 0).

    s is :func:`palpbayes.contact.shape`, with the bonded Dimitriadis/Hayes finite-thickness
    factor when ``finite_thickness``; xi is :func:`stiffening_factor`.  With both off this is
    exactly :func:`palpbayes.contact.force`.
    """
    d = np.asarray(depth, dtype=float)
    h = thickness if finite_thickness else None
    if finite_thickness and thickness is None:
        raise GeometryError("finite_thickness=True needs the specimen thickness (give thickness=)")
    s = shape(d, tip, thickness_m=h, nu=nu, bonded=bonded)
    f = effective_modulus(E, nu) * s
    if stiffening != 0:
        f = f * stiffening_factor(d, thickness, stiffening)
    return f


def onset_force_profile(depth, onset_force: float, onset_length: float) -> np.ndarray:
    """Gradual-onset force F_on(d) [N]: a smooth force that starts before the true surface.

    Real curves rarely switch on sharply at the surface: a soft skin or coating, surface
    roughness, long-range repulsion (electrostatic double layer, steric brushes in AFM) or,
    with a negative ``onset_force``, attraction/adhesion, make the force change over a length
    L = ``onset_length`` *before* the contact law starts.  The simulator models it as::

        F_on(d) = F_a·exp(d/L)              for d <  0   (pre-contact, decays to 0 far above)
        F_on(d) = F_a·(2 - exp(-d/L))       for d >= 0   (in contact, saturates at 2·F_a)

    with F_a = ``onset_force``.  The in-contact branch is the point reflection of the
    pre-contact one about (0, F_a), so F_on is continuous with a continuous slope F_a/L at the
    surface (C¹), monotone, and bounded by 2·F_a: a layer of thickness ~L that is squeezed flat
    within a few L and then carries a constant extra load (it does not change the contact
    law's stiffness at depth).  Far above the surface it vanishes, so a fit's constant
    baseline sees the untouched sensor; a fit that ignores the onset puts its surface into
    the exponential tail and leaves a structured residual near contact (what
    :func:`palpbayes.checks.residual_structure_check` detects).

    Parameters
    ----------
    depth
        [m] Depth d = z_surf - z (negative above the surface).
    onset_force
        F_a [N], the onset force at the surface (> 0 repulsive/soft skin, < 0 attractive).
    onset_length
        L [m] > 0, the decay length of the pre-contact force.

    Returns
    -------
    numpy.ndarray
        [N] F_on(d), same shape as ``depth``.
    """
    d = np.asarray(depth, dtype=float)
    if onset_length <= 0:
        raise InputError(f"onset length {onset_length!r} m must be positive")
    x = d / onset_length
    # exp of a non-positive argument only: no overflow deep in contact or far above
    e = np.exp(-np.abs(x))
    return onset_force * np.where(x < 0, e, 2.0 - e)


def solve_series_compliance(d_cmd, force_of_depth, compliance: float,
                            iterations: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """Solve F = g(d_cmd - C·F) for the actual depth and force with series compliance C.

    The tip sits C·F above its commanded position, so the actual depth delta solves
    r(delta) = delta + C·g(delta) - d_cmd = 0.  r is strictly increasing for any non-decreasing
    force law g with g(0) = 0, and r(0) = -d_cmd <= 0 <= r(d_cmd) = C·g(d_cmd): the root is
    bracketed in [0, d_cmd].  Vectorised bisection with ``iterations`` = 64 halvings reaches the
    floating-point resolution of delta (width d_cmd·2^-64); it cannot fail or overshoot.

    Parameters
    ----------
    d_cmd
        [m] Commanded depth z_surf - z_cmd (array).
    force_of_depth
        g(d) [N], vectorised, non-decreasing, 0 for d <= 0.
    compliance
        C [m/N] >= 0; 0 returns (d_cmd, g(d_cmd)) without iterating.

    Returns
    -------
    delta, force
        [m], [N] Actual depth and contact force F = g(delta).
    """
    d_cmd = np.asarray(d_cmd, dtype=float)
    if compliance == 0:
        return d_cmd, force_of_depth(d_cmd)
    delta = np.minimum(d_cmd, 0.0)  # out of contact: the tip is where it was sent
    pos = d_cmd > 0
    dc = d_cmd[pos]
    lo, hi = np.zeros_like(dc), dc.copy()
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        r = mid + compliance * force_of_depth(mid) - dc
        above = r > 0
        hi = np.where(above, mid, hi)
        lo = np.where(above, lo, mid)
    delta[pos] = 0.5 * (lo + hi)
    return delta, force_of_depth(delta)


def ar1_noise(n: int, sigma: float, phi: float, w: np.ndarray) -> np.ndarray:
    """Stationary Gaussian AR(1) noise from standard normal draws ``w`` (length n).

    e(0) = sigma·w(0), e(t) = phi·e(t-1) + sqrt(1 - phi²)·sigma·w(t), so every e(t) has sd sigma
    whatever phi, and corr(e(t), e(t-k)) = phi^k.
    """
    w = np.asarray(w, dtype=float)[:n]
    if phi == 0:
        return sigma * w
    e = np.empty(n)
    e[0] = sigma * w[0]
    e[1:], _ = lfilter([math.sqrt(1.0 - phi * phi) * sigma], [1.0, -phi], w[1:],
                       zi=[phi * e[0]])
    return e


# ----------------------------------------------------------------------------- motion


def _motion(travel: float, speed: float, rate: float, hold: float,
            retract: bool) -> tuple[np.ndarray, np.ndarray]:
    """Sample times t_k = k/rate (k = 1..N) and distance moved down s(t_k) [m].

    Down at ``speed`` for travel/speed, hold, then (optionally) back up at ``speed``.  N =
    ceil(T·rate) for the programme's duration T, so the last sample falls at or after the end;
    samples past the end stay at the final position.
    """
    t_down = travel / speed
    t_end = t_down + hold + (t_down if retract else 0.0)
    n = max(3, math.ceil(t_end * rate - 1e-6))
    t = np.arange(1, n + 1) / rate
    s = np.minimum(speed * t, travel)
    s[np.isclose(s, travel, rtol=1e-12, atol=0.0)] = travel
    if retract:
        up = np.clip(speed * (t - t_down - hold), 0.0, travel)
        up[np.isclose(up, travel, rtol=1e-12, atol=0.0)] = travel
        s = s - up
    return t, s


# ----------------------------------------------------------------------------- traces


def simulate_trace(
    E: float,
    tip: Tip,
    *,
    nu: float = 0.3,
    z_surf: float = 0.1,
    thickness: float | None = None,
    depth: float | None = None,
    approach: float = 1e-3,
    speed: float = 50 / 60e3,
    rate: float = 800.0,
    hold: float = 0.0,
    retract: bool = False,
    noise_pp: float = PAPER_NOISE_PP,
    noise_ar1: float = 0.0,
    force_offset: float = 0.0,
    drift: float = 0.0,
    onset_force: float = 0.0,
    onset_length: float = 0.0,
    position_noise: float = 0.0,
    repeatability: float = 0.0,
    compliance: float = 0.0,
    finite_thickness: bool = False,
    bonded: bool = True,
    stiffening: float = 0.0,
    rng: np.random.Generator | int | None = None,
    trace_id: str = "sim",
    specimen: str = "",
    material: str = "",
    repetition: int | None = None,
    rest_time: float | None = None,
) -> IndentationTrace:
    """Simulate one palpation: a tip driven down into an elastic specimen at constant speed.

    The tip starts ``approach`` above the surface, moves down at ``speed`` to the depth
    ``depth`` below it, optionally holds and retracts at the same speed, and is sampled at
    ``rate`` at t_k = k/rate, k = 1..N (a sample at the end of each sampling period, so the
    deepest point is recorded).  With the defaults on a 30 mm specimen (depth 3 mm, approach
    1 mm, 50 mm/min, 800 Hz) the trace has exactly 4 mm / (0.8333 mm/s) · 800 Hz = **3840
    samples**, the benchmark trace size.  The model is given in the module docstring.

    Parameters
    ----------
    E
        [Pa] Young's modulus.
    tip
        The indenter (tip ``sphere`` is the exact Sneddon law).
    nu
        Poisson ratio [-].
    z_surf
        [m] Surface height in the robot's commanded frame.
    thickness
        [m] Specimen thickness h (for the default depth, ``finite_thickness``, ``stiffening``).
    depth
        [m] Commanded maximum depth; default 10 % of ``thickness`` (required without it).
    approach
        [m] Height above the surface where the motion starts.
    speed
        [m/s] Tip speed (default 50 mm/min).
    rate
        [Hz] Sample rate.
    hold
        [s] Hold at the deepest point.
    retract
        Move back up to the start after the hold.
    noise_pp
        [N] Peak-to-peak force noise; sigma = noise_pp/6 (:func:`sigma_from_pp`).
    noise_ar1
        AR(1) coefficient phi of the force noise, |phi| < 1 (marginal sd stays sigma).
    force_offset
        [N] Constant force offset F0 (sensor tare error).
    drift
        [N/s] Linear force drift **per second**, F += drift·t with t the sample time
        (t_k = k/rate, so the first sample already carries drift/rate).  On the loading
        segment this equals a linear baseline in z of slope -drift/speed [N/m].
    onset_force, onset_length
        [N], [m] Gradual onset (:func:`onset_force_profile`): F += F_on(delta) with
        F_on = onset_force·exp(delta/onset_length) above the surface (delta < 0) and its C¹
        saturating continuation onset_force·(2 - exp(-delta/onset_length)) in contact.  Off
        when ``onset_force`` is 0 (the default; then the output is bit-for-bit what it was
        without the knob); ``onset_length`` must be positive when it is on.  The onset force
        is evaluated at the actual depth and does not feed the compliance solve (its own
        deflection C·F_on is neglected).
    position_noise
        [m] White noise sd on the recorded z (encoder/kinematic jitter).
    repeatability
        [m] Half-range of a uniform per-trace offset b of the recorded z (robot repeatability,
        e.g. 3e-5 for the UR3e); it shifts the surface seen in the recorded frame to z_surf + b.
    compliance
        [m/N] Series compliance C of robot and sensor: the tip sits C·F above the recorded
        position; solved by :func:`solve_series_compliance`.
    finite_thickness, bonded
        Apply the finite-thickness correction (Dimitriadis 2002 / Hayes 1972, bonded by
        default) to the truth; needs ``thickness``.
    stiffening
        beta of :func:`stiffening_factor` (0 = linear elastic); needs ``thickness``.
    rng
        numpy Generator or seed.  The draws are made in a fixed order whatever the options
        (one uniform for b, N normals for the force, N normals for z), so the same seed gives
        the same noise across misspecification settings (common random numbers).
    trace_id, specimen, material, repetition, rest_time
        Labels stored in the trace.

    Returns
    -------
    IndentationTrace
        z recorded (up positive), force positive when pressing.  ``metadata`` holds the truth:
        ``E_true``, ``Estar_true``, ``nu``, ``z_surf_true`` (surface in the *recorded* frame,
        z_surf + b, what a perfect fit recovers), ``z_surf_commanded``, ``z_offset_true`` (b),
        ``sigma_true``, ``noise_pp``, ``phi_true``, ``force_offset_true``, ``drift_true``,
        ``onset_force_true``, ``onset_length_true``,
        ``position_noise_true``, ``repeatability``, ``compliance_true``, ``finite_thickness``,
        ``bonded``, ``stiffening``, ``depth_true``, ``max_force_true``, motion settings, and
        ``seed`` when ``rng`` was an int.

    Raises
    ------
    InputError, GeometryError
        Non-positive E, speed or rate, missing depth and thickness, |phi| >= 1, negative noise,
        an invalid nu, a finite-thickness request for a tip without a correction, or a
        non-zero ``onset_force`` without a positive ``onset_length``.
    """
    if not isinstance(tip, Tip):
        raise InputError(f"tip must be a palpbayes.contact.Tip, got {type(tip).__name__}")
    E = _positive(E, "Young's modulus E [Pa]")
    nu = check_nu(nu)
    z_surf = _finite(z_surf, "surface height z_surf [m]")
    if thickness is not None:
        thickness = _positive(thickness, "specimen thickness [m]")
    if depth is None:
        if thickness is None:
            raise InputError("give the indentation depth (depth=) or the specimen thickness "
                             "(thickness=, depth defaults to 10 % of it)")
        depth = 0.1 * thickness
    depth = _positive(depth, "indentation depth [m]")
    approach = _nonneg(approach, "approach distance [m]")
    speed = _positive(speed, "speed [m/s]")
    rate = _positive(rate, "sample rate [Hz]")
    hold = _nonneg(hold, "hold time [s]")
    sigma = sigma_from_pp(noise_pp)
    phi = _phi(noise_ar1)
    force_offset = _finite(force_offset, "force offset [N]")
    drift = _finite(drift, "force drift [N/s]")
    onset_force = _finite(onset_force, "onset force [N]")
    onset_length = _nonneg(onset_length, "onset length [m]")
    if onset_force != 0 and onset_length == 0:
        raise InputError("a gradual onset (onset_force != 0) needs a positive onset_length [m]")
    position_noise = _nonneg(position_noise, "position noise [m]")
    repeatability = _nonneg(repeatability, "repeatability [m]")
    compliance = _nonneg(compliance, "compliance [m/N]")
    stiffening = _nonneg(stiffening, "stiffening beta")
    law = {"nu": nu, "tip": tip, "thickness": thickness, "finite_thickness": finite_thickness,
           "bonded": bool(bonded), "stiffening": stiffening}
    true_force(np.array([depth]), E, **law)  # validate geometry before drawing anything

    gen = np.random.default_rng(rng)
    t, s = _motion(approach + depth, speed, rate, hold, retract)
    n = t.size
    u = gen.uniform(-1.0, 1.0)
    w_force = gen.standard_normal(n)
    w_z = gen.standard_normal(n)

    z_cmd = (z_surf + approach) - s
    d_cmd = z_surf - z_cmd
    delta, f_true = solve_series_compliance(
        d_cmd, lambda d: true_force(d, E, **law), compliance)
    b = repeatability * u + 0.0  # + 0.0: no negative zero in the truth tables
    z_rec = z_cmd + b + position_noise * w_z
    if onset_force != 0:  # skipped when off, so default outputs stay bit-for-bit identical
        f_true_rec = f_true + onset_force_profile(delta, onset_force, onset_length)
    else:
        f_true_rec = f_true
    f_rec = f_true_rec + force_offset + drift * t + ar1_noise(n, sigma, phi, w_force)

    metadata = {
        "simulated": True,
        "E_true": E,
        "Estar_true": float(effective_modulus(E, nu)),
        "nu_true": nu,
        "z_surf_true": z_surf + b,
        "z_surf_commanded": z_surf,
        "z_offset_true": b,
        "sigma_true": sigma,
        "noise_pp": float(noise_pp),
        "phi_true": phi,
        "force_offset_true": force_offset,
        "drift_true": drift,
        "onset_force_true": onset_force,
        "onset_length_true": onset_length,
        "position_noise_true": position_noise,
        "repeatability": repeatability,
        "compliance_true": compliance,
        "finite_thickness": bool(finite_thickness),
        "bonded": bool(bonded),
        "stiffening": stiffening,
        "depth_true": depth,
        "max_depth_actual": float(delta.max()),
        "max_force_true": float(f_true.max()),
        "approach": approach,
        "speed": speed,
        "rate": rate,
        "hold": hold,
        "retract": bool(retract),
    }
    if isinstance(rng, int | np.integer):
        metadata["seed"] = int(rng)
    return IndentationTrace(
        time=t, z=z_rec, force=f_rec, tip=tip, trace_id=trace_id, specimen=specimen,
        material=material, thickness=thickness, repetition=repetition, rest_time=rest_time,
        source=f"simulated trace {trace_id!r}", metadata=metadata,
    )


# ----------------------------------------------------------------------------- compression


def toe_compression(x, toe: float) -> np.ndarray:
    """Effective compression [m] of a block with ``toe`` [m] of slack, smooth (C¹) toe.

    u(x) = x²/(4·toe) for 0 <= x < 2·toe, and x - toe beyond; u and du/dx are continuous at
    x = 2·toe, and the linear part extrapolates to zero at x = toe.  toe = 0 gives u = x.
    """
    x = np.clip(np.asarray(x, dtype=float), 0.0, None)
    if toe == 0:
        return x
    return np.where(x < 2.0 * toe, x * x / (4.0 * toe), x - toe)


def simulate_compression_test(
    E: float,
    *,
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
) -> pd.DataFrame:
    """Simulate an unconfined uniaxial compression test (Instron 4502 style).

    The crosshead moves down at ``speed`` from first touch (x = 0) to ``max_compression``,
    sampled at ``rate`` at t_k = k/rate, k = 0..N.  Load (linear elastic, frictionless
    platens)::

        F(x) = E·A/h·u(x) + noise,   A = width·length,   u = toe_compression(x, toe)

    so beyond x = 2·toe the curve is a line of slope E·A/h [N/m] through (toe, 0).

    Parameters
    ----------
    E
        [Pa] Young's modulus of the block.
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

    Returns
    -------
    pandas.DataFrame
        Columns ``time_s``, ``compression_m``, ``force_n`` (both positive in compression);
        ``attrs`` holds the truth (``E_true_pa``, ``area_m2``, ``height_m``, ``width_m``,
        ``length_m``, ``stiffness_n_per_m``, ``toe_m``, ``noise_n``, ``speed_m_per_s``,
        ``specimen``, ``material``).
    """
    E = _positive(E, "Young's modulus E [Pa]")
    width = _positive(width, "block width [m]")
    length = _positive(length, "block length [m]")
    height = _positive(height, "block height [m]")
    speed = _positive(speed, "crosshead speed [m/s]")
    rate = _positive(rate, "sample rate [Hz]")
    max_compression = _positive(max_compression, "maximum compression [m]")
    if max_compression >= height:
        raise InputError(f"maximum compression {max_compression} m must be below the block "
                         f"height {height} m")
    toe = _nonneg(toe, "toe length [m]")
    noise_n = _nonneg(noise_n, "load-cell noise sd [N]")
    gen = np.random.default_rng(rng)
    n = math.ceil(max_compression / speed * rate - 1e-6)
    t = np.arange(n + 1) / rate
    x = np.minimum(speed * t, max_compression)
    area = width * length
    k = E * area / height
    f = k * toe_compression(x, toe) + noise_n * gen.standard_normal(t.size)
    df = pd.DataFrame({"time_s": t, "compression_m": x, "force_n": f})
    df.attrs.update({
        "E_true_pa": E, "area_m2": area, "height_m": height, "width_m": width,
        "length_m": length, "stiffness_n_per_m": k, "toe_m": toe, "noise_n": noise_n,
        "speed_m_per_s": speed, "specimen": specimen, "material": material,
    })
    return df


def _mm(x: float) -> str:
    return f"{x * 1e3:.6g}"


def write_compression_export(
    df: pd.DataFrame,
    path,
    *,
    width: float | None = None,
    length: float | None = None,
    height: float | None = None,
    speed: float | None = None,
    sample_name: str | None = None,
):
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
        vals[key] = _positive(v, f"block {key}")
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
