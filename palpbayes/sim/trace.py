"""One simulated palpation trace from a known truth, with its misspecification knobs.

The simulator draws data from a *known* truth so that every estimator in palpbayes can be checked
against it (bias, interval coverage, simulation-based calibration).  Conventions
(docs/design.md §1, §5): SI units; z is up, the tip moves down into the specimen, depth
d = z_surf - z; the force is the compressive normal force, positive when pressing.

Model of one trace (every term optional except the contact law)::

    F_rec(t) = F_true(t) + F_on(delta) + F0 + drift·t + e(t)
    z_rec(t) = z_cmd(t) + b + eta(t)            (registration offset b, encoder noise eta)
    e(t)     = phi·e(t-1) + sqrt(1 - phi²)·sigma·w(t),  w ~ N(0, 1),  e(0) = sigma·w(0)

F_true, F_on and the actual depth delta under series compliance are those of
:mod:`palpbayes.sim.force`; sigma = noise_pp / :data:`palpbayes.sensor_noise.PP_TO_SIGMA`.  The
drift is **per second** (``drift`` [N/s], t the sample time from the start of the trace,
t_k = k/rate), so on the loading segment it is also a linear function of z with slope
-drift/speed [N/m].

**Peak-to-peak to sigma.**  A sensor's "peak-to-peak noise" is read as ±3 sigma
(:func:`palpbayes.sensor_noise.sigma_from_pp`): the paper's 48 mN gives sigma = 8 mN.  Note that the
*observed* range of N samples grows with N (about 6.4 sigma for N = 800 and 7.2 sigma for
N = 3840), so a range measured over a long record overstates the ±3 sigma convention;
``tests/unit/test_sim.py`` checks both facts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

import numpy as np

from ..arguments import ar1_phi, finite, nonneg, positive
from ..contact import DEFAULT_NU, Tip, check_nu, effective_modulus
from ..errors import InputError
from ..material import Solid
from ..sensor_noise import PAPER_NOISE_PP, ar1_noise, sigma_from_pp
from ..trace import IndentationTrace
from ..twin import FOOTPRINT_COLUMNS, Specimen
from .force import onset_force_profile, solid_force, solve_series_compliance, true_force

__all__ = ["ar1_noise", "TraceSpec", "trace_spec", "simulate_trace"]


#: Sample periods by which the motion may end after the last sample (rounding in T·rate).
_SLACK = 1e-6


def _motion(travel: float, speed: float, rate: float, hold: float,
            retract: bool) -> tuple[np.ndarray, np.ndarray]:
    """Sample times t_k = k/rate (k = 1..N) and distance moved down s(t_k) [m].

    Down at ``speed`` for travel/speed, hold, then (optionally) back up at ``speed``.  N =
    ceil(T·rate) for the programme's duration T, so the last sample falls at or after the end;
    samples past the end stay at the final position.  A programme that ends less than
    ``_SLACK`` of a sample period after a sample ends *at* that sample (no extra sample for
    rounding in T·rate): such a sample is at the end position, the bottom or the start.
    """
    t_down = travel / speed
    t_end = t_down + hold + (t_down if retract else 0.0)
    n = max(3, math.ceil(t_end * rate - _SLACK))
    k = np.arange(1, n + 1)
    t = k / rate
    s = np.minimum(speed * t, travel)
    s[np.isclose(s, travel, rtol=1e-12, atol=0.0)] = travel
    s[k >= t_down * rate - _SLACK] = travel  # the bottom, also when N rounded T·rate down
    if retract:
        up = np.clip(speed * (t - t_down - hold), 0.0, travel)
        up[np.isclose(up, travel, rtol=1e-12, atol=0.0)] = travel
        up[k >= t_end * rate - _SLACK] = travel  # back at the start
        s = s - up
    return t, s


@dataclass(frozen=True)
class TraceSpec:
    """Everything one simulated palpation is but its modulus, its tip and its random draws:
    the specimen, the motion, the sensor's errors and the labels (:func:`simulate_trace`).

    A spec is checked when a trace is simulated from it; ``dataclasses.replace(spec, ...)``
    (or ``simulate_trace(E, tip, spec, field=value)``) changes a field.

    Attributes
    ----------
    nu
        Poisson ratio [-].
    z_surf
        [m] Surface height in the robot's commanded frame.
    thickness
        [m] Specimen thickness h (for the default depth, ``base``, ``stiffening``).
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
        [N] Peak-to-peak force noise; sigma = noise_pp/6
        (:func:`~palpbayes.sensor_noise.sigma_from_pp`).
    noise_ar1
        AR(1) coefficient phi of the force noise, |phi| < 1 (marginal sd stays sigma).
    force_offset
        [N] Constant force offset F0 (sensor tare error).
    drift
        [N/s] Linear force drift **per second**, F += drift·t with t the sample time
        (t_k = k/rate, so the first sample already carries drift/rate).  On the loading
        segment this equals a linear baseline in z of slope -drift/speed [N/m].
    onset_force, onset_length
        [N], [m] Gradual onset (:func:`~palpbayes.sim.force.onset_force_profile`):
        F += F_on(delta) with F_on = onset_force·exp(delta/onset_length) above the surface
        (delta < 0) and its C¹ saturating continuation onset_force·(2 - exp(-delta/onset_length))
        in contact.  Off when ``onset_force`` is 0 (the default; then the output is bit-for-bit
        what it was without the knob); ``onset_length`` must be positive when it is on.  The
        onset force is evaluated at the actual depth and does not feed the compliance solve
        (its own deflection C·F_on is neglected).
    position_noise
        [m] White noise sd on the recorded z (encoder/kinematic jitter).
    repeatability
        [m] Half-range of a uniform per-trace offset b of the recorded z (robot repeatability,
        e.g. 3e-5 for the UR3e); it shifts the surface seen in the recorded frame to z_surf + b.
    compliance
        [m/N] Series compliance C of robot and sensor: the tip sits C·F above the recorded
        position; solved by :func:`~palpbayes.sim.force.solve_series_compliance`.
    base
        A specimen of known ``thickness`` is a layer on a rigid base
        (:func:`~palpbayes.sim.force.layer_factor`): ``"free"`` (default: lying on it without
        friction), ``"bonded"`` or a number in [0, 1] (a partial bond); None: a half-space (the
        paper's model) whatever the thickness.  Without ``thickness`` the specimen is a
        half-space.
    stiffening
        beta of :func:`~palpbayes.sim.force.stiffening_factor` (0 = linear elastic); needs
        ``thickness``.
    apex_flat_radius
        [m] Radius b of a flat worn into a paraboloid tip's apex
        (:func:`~palpbayes.sim.force.blunted_paraboloid_shape`); 0 (default) is the sharp
        paraboloid.
    block
        The specimen as tested, a block or cylinder of known footprint
        (:class:`~palpbayes.twin.Specimen`): the force is its finite-element twin's on the
        simulator's finer mesh (:func:`~palpbayes.sim.force.layer_factor`), on the ``base``
        (a half-space with ``base=None`` is refused); its height is the ``thickness`` (given
        or not), and the trace's metadata carry its footprint (``length_m``, ``width_m`` or
        ``diameter_m``), so that a fit of the trace uses the twin too.
    twin_resolution
        The block's twin's mesh (default ``fine``, finer than the fits'; ``default`` for a
        quick prediction whose fit is no twin, e.g. :mod:`palpbayes.gap`).
    trace_id, specimen, material, repetition, rest_time
        Labels stored in the trace.

    """

    nu: float = DEFAULT_NU
    z_surf: float = 0.1
    thickness: float | None = None
    depth: float | None = None
    approach: float = 1e-3
    speed: float = 50 / 60e3
    rate: float = 800.0
    hold: float = 0.0
    retract: bool = False
    noise_pp: float = PAPER_NOISE_PP
    noise_ar1: float = 0.0
    force_offset: float = 0.0
    drift: float = 0.0
    onset_force: float = 0.0
    onset_length: float = 0.0
    position_noise: float = 0.0
    repeatability: float = 0.0
    compliance: float = 0.0
    base: str | float | None = "free"
    stiffening: float = 0.0
    apex_flat_radius: float = 0.0
    block: Specimen | None = None
    twin_resolution: str = "fine"
    trace_id: str = "sim"
    specimen: str = ""
    material: str = ""
    repetition: int | None = None
    rest_time: float | None = None


#: The fields of :class:`TraceSpec`, in order.
SPEC_FIELDS = tuple(f.name for f in fields(TraceSpec))


def trace_spec(spec: TraceSpec | None = None, **changes) -> TraceSpec:
    """``spec`` (default :class:`TraceSpec`) with ``changes``; an unknown field is an
    :class:`~palpbayes.errors.InputError` naming it and the fields there are."""
    unknown = sorted(set(changes) - set(SPEC_FIELDS))
    if unknown:
        raise InputError(f"simulate_trace: unknown option(s) {', '.join(unknown)}; the "
                         f"options are {', '.join(SPEC_FIELDS)} and rng")
    if spec is None:
        return TraceSpec(**changes)
    if not isinstance(spec, TraceSpec):
        raise InputError(f"spec must be a palpbayes.sim.TraceSpec, got {type(spec).__name__}")
    return replace(spec, **changes) if changes else spec


def simulate_trace(E: float | Solid, tip: Tip, spec: TraceSpec | None = None, *,
                   rng: np.random.Generator | int | None = None,
                   **changes) -> IndentationTrace:
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
        [Pa] Young's modulus, or a hyperelastic solid (:class:`~palpbayes.material.Solid`:
        a registered law, its natural parameters and its Poisson ratio, ``nu`` then unused)
        pressed at finite strain in its ``block`` (required): the force is the finite-strain
        twin's (:func:`~palpbayes.sim.force.solid_force`, on the ``twin_resolution`` mesh),
        the truth's ``E_true`` its small-strain modulus E0; ``stiffening`` and
        ``apex_flat_radius`` are linear knobs and refused with it.
    tip
        The indenter (tip ``sphere`` is the exact Sneddon law).
    spec
        The specimen, motion, sensor and labels (:class:`TraceSpec`; default its defaults).
    rng
        numpy Generator or seed.  The draws are made in a fixed order whatever the options
        (one uniform for b, N normals for the force, N normals for z), so the same seed gives
        the same noise across misspecification settings (common random numbers).
    **changes
        Fields of :class:`TraceSpec` that replace the spec's (``nu=0.45, thickness=0.02``).

    Returns
    -------
    IndentationTrace
        z recorded (up positive), force positive when pressing.  ``metadata`` holds the truth:
        ``E_true``, ``Estar_true``, ``nu``, ``z_surf_true`` (surface in the *recorded* frame,
        z_surf + b, what a perfect fit recovers), ``z_surf_commanded``, ``z_offset_true`` (b),
        ``sigma_true``, ``noise_pp``, ``phi_true``, ``force_offset_true``, ``drift_true``,
        ``onset_force_true``, ``onset_length_true``,
        ``position_noise_true``, ``repeatability``, ``compliance_true``, ``base`` (None, a
        name or a number), ``stiffening``, ``apex_flat_radius_true``, ``depth_true``,
        ``max_force_true``, motion settings, and
        ``seed`` when ``rng`` was an int.

    Raises
    ------
    InputError, GeometryError
        Non-positive E, speed or rate, missing depth and thickness, |phi| >= 1, negative noise,
        an invalid nu, a finite-thickness request for a tip without a correction, or a
        non-zero ``onset_force`` without a positive ``onset_length``, a blunted apex
        (``apex_flat_radius`` > 0) on a tip other than a paraboloid.
    """
    p = trace_spec(spec, **changes)
    nu, z_surf, thickness, depth, base, block = (p.nu, p.z_surf, p.thickness, p.depth, p.base,
                                                 p.block)
    stiffening, apex_flat_radius, twin_resolution = (p.stiffening, p.apex_flat_radius,
                                                     p.twin_resolution)
    if not isinstance(tip, Tip):
        raise InputError(f"tip must be a palpbayes.contact.Tip, got {type(tip).__name__}")
    solid = E if isinstance(E, Solid) else None
    if solid is not None:
        if block is None:
            raise InputError(f"a hyperelastic solid ({solid.describe()}) is pressed in its "
                             "block: give block=Specimen(...)")
        if stiffening or apex_flat_radius:
            raise InputError("stiffening and apex_flat_radius are knobs of the linear law; a "
                             "hyperelastic solid has its own finite strain")
        nu = solid.nu0
        E = solid.E0
    E = positive(E, "Young's modulus E [Pa]")
    nu = check_nu(nu)
    z_surf = finite(z_surf, "surface height z_surf [m]")
    if block is not None:
        if not isinstance(block, Specimen):
            raise InputError(f"block must be a palpbayes.twin.Specimen, got "
                             f"{type(block).__name__}")
        if thickness is not None and not np.isclose(thickness, block.height, rtol=1e-9):
            raise InputError(f"thickness {thickness!r} m differs from the block's height "
                             f"{block.height!r} m: give one of the two")
        if base is None:
            raise InputError("a block (block=...) lies on a plate: give base='free', "
                             "'bonded' or a partial bond, not None")
        thickness = block.height
    if thickness is not None:
        thickness = positive(thickness, "specimen thickness [m]")
    if depth is None:
        if thickness is None:
            raise InputError("give the indentation depth (depth=) or the specimen thickness "
                             "(thickness=, depth defaults to 10 % of it)")
        depth = 0.1 * thickness
    depth = positive(depth, "indentation depth [m]")
    approach = nonneg(p.approach, "approach distance [m]")
    speed = positive(p.speed, "speed [m/s]")
    rate = positive(p.rate, "sample rate [Hz]")
    hold = nonneg(p.hold, "hold time [s]")
    noise_pp = p.noise_pp
    sigma = sigma_from_pp(noise_pp)
    phi = ar1_phi(p.noise_ar1)
    force_offset = finite(p.force_offset, "force offset [N]")
    drift = finite(p.drift, "force drift [N/s]")
    onset_force = finite(p.onset_force, "onset force [N]")
    onset_length = nonneg(p.onset_length, "onset length [m]")
    if onset_force != 0 and onset_length == 0:
        raise InputError("a gradual onset (onset_force != 0) needs a positive onset_length [m]")
    position_noise = nonneg(p.position_noise, "position noise [m]")
    repeatability = nonneg(p.repeatability, "repeatability [m]")
    compliance = nonneg(p.compliance, "compliance [m/N]")
    stiffening = nonneg(stiffening, "stiffening beta")
    apex_flat_radius = nonneg(apex_flat_radius, "apex flat radius [m]")
    if thickness is None:
        base = None
    law = {"nu": nu, "tip": tip, "thickness": thickness, "base": base,
           "stiffening": stiffening, "apex_flat_radius": apex_flat_radius, "block": block,
           "twin_resolution": twin_resolution}

    def force_of_depth(d: np.ndarray) -> np.ndarray:
        if solid is not None:
            return solid_force(d, solid, tip, block, base, depth, twin_resolution)
        return true_force(d, E, **law)

    force_of_depth(np.array([depth]))  # validate geometry before drawing anything

    gen = np.random.default_rng(rng)
    t, s = _motion(approach + depth, speed, rate, hold, p.retract)
    n = t.size
    u = gen.uniform(-1.0, 1.0)
    w_force = gen.standard_normal(n)
    w_z = gen.standard_normal(n)

    z_cmd = (z_surf + approach) - s
    d_cmd = z_surf - z_cmd
    delta, f_true = solve_series_compliance(d_cmd, force_of_depth, compliance)
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
        "base": base,
        "stiffening": stiffening,
        "apex_flat_radius_true": apex_flat_radius,
        "depth_true": depth,
        "max_depth_actual": float(delta.max()),
        "max_force_true": float(f_true.max()),
        "approach": approach,
        "speed": speed,
        "rate": rate,
        "hold": hold,
        "retract": bool(p.retract),
    }
    if isinstance(rng, int | np.integer):
        metadata["seed"] = int(rng)
    if solid is not None:  # the law's truth: E_true is its small-strain modulus E0
        metadata.update({"law_true": solid.law, "law_params_true": dict(solid.params),
                         "twin_resolution": twin_resolution})
    if block is not None:  # the footprint, as a manifest row gives it (FOOTPRINT_COLUMNS)
        metadata.update({c: getattr(block, c[:-2]) for c in FOOTPRINT_COLUMNS
                         if getattr(block, c[:-2]) is not None})
    return IndentationTrace(
        time=t, z=z_rec, force=f_rec, tip=tip, trace_id=p.trace_id, specimen=p.specimen,
        material=p.material, thickness=thickness, repetition=p.repetition,
        rest_time=p.rest_time, source=f"simulated trace {p.trace_id!r}", metadata=metadata,
    )
