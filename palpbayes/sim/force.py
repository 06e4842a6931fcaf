"""The simulator's noise-free contact force, with its physics misspecification knobs.

One job: the force the tip really feels at a given depth.  Conventions (docs/design.md §1, §5):
SI units, depth d = z_surf - z (positive in contact), force positive when pressing::

    F_true = E*·s(delta)·xi(delta),        E* = E/(1 - nu²)
    delta  = d_cmd - C·F_true              (series compliance C, :func:`solve_series_compliance`)
    F_on   = gradual onset before the surface (:func:`onset_force_profile`)

with s(d) the tip's shape function (:func:`palpbayes.contact.shape`, optionally on a layer of
thickness h over a rigid base: :func:`layer_factor`) and xi the strain-stiffening factor
(:func:`stiffening_factor`).  Every knob is off by default, and then :func:`true_force` is
exactly :func:`palpbayes.contact.force`.
A hyperelastic block (:class:`palpbayes.material.Solid` in place of E) is pressed by the
finite-strain twin instead (:func:`solid_force`).  Noise, offsets and drift are added by
:func:`palpbayes.sim.trace.simulate_trace`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from ..contact import Tip, effective_modulus, shape, thickness_factor
from ..errors import GeometryError, InputError
from ..material import Solid
from ..twin import Specimen, solid_table, twin_factor
from ..twin.hyper_shape import table_depth

__all__ = [
    "SIM_BASES",
    "SIM_RESOLUTION",
    "layer_factor",
    "STIFFENING_STRAIN0",
    "stiffening_factor",
    "true_force",
    "onset_force_profile",
    "solve_series_compliance",
    "blunted_paraboloid_shape",
    "solid_force",
    "SOLID_DEPTH_POINTS",
]

#: Depths of the finite-strain curve the simulator interpolates: a fit's table's
#: (:data:`palpbayes.twin.hyper_table.DEPTH_POINTS` up to
#: :func:`palpbayes.twin.hyper_shape.table_depth` of the depth), so that on the fit's own mesh
#: the data are drawn from the very curve that fits them (a test of the statistics alone); on
#: another mesh (the simulator's default, ``fine``) they are not.  The twin's flat punch at
#: finite strain depends on its load steps: in a softening foam (hyperfoam nu 0.1, alpha 8,
#: 2 mm into 20 mm) two solves of one mesh with other depths differ by up to 2.8 %.
SOLID_DEPTH_POINTS = 12

#: Nominal strain d/h below which the stiffening law is inactive.
STIFFENING_STRAIN0 = 0.05


def stiffening_factor(depth: ArrayLike, thickness: float | None, stiffening: float) -> np.ndarray:
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


#: Base conditions the simulator knows by name (a number in [0, 1] is a partial bond).
SIM_BASES = ("bonded", "free")
#: Mesh of the simulator's specimen twin (finer than the fits', :data:`palpbayes.twin.mesh.
#: RESOLUTIONS`).
SIM_RESOLUTION = "fine"


def layer_factor(depth: ArrayLike, tip: Tip, thickness: float | None, nu: float,
                 base: str | float | None, block: Specimen | None = None,
                 twin_resolution: str = SIM_RESOLUTION) -> np.ndarray:
    """The bottom effect of the simulated specimen: F_layer/F_half-space [-].

    Parameters
    ----------
    depth
        [m] Indentation depth.
    tip
        The indenter.
    thickness
        [m] Specimen thickness h.
    nu
        Poisson ratio [-].
    base
        None: a half-space (factor 1); ``"bonded"`` or ``"free"``: a layer on a rigid base,
        bonded to it or lying on it without friction (:func:`palpbayes.contact.
        thickness_factor`, the exact layer solution); a number w in [0, 1]: a *partial* bond,
        (1 − w)·f_free + w·f_bonded — a misspecification knob for a block lying on a plate with
        friction, which the fit's two-component model (bonded or free) does not contain.
    block
        The specimen as tested (:class:`~palpbayes.twin.Specimen`, its height the
        ``thickness``): the factor is its finite-element twin's on the ``fine`` mesh
        (:func:`palpbayes.twin.twin_factor`; the fits use the ``default`` one, so data are not
        drawn from the very model that fits them); None: a layer of infinite width.
    """
    d = np.asarray(depth, dtype=float)
    if base is None:
        return np.ones_like(d)
    if thickness is None:
        raise GeometryError("a layer (base=...) needs the specimen thickness (give thickness=)")

    def factor(b: str) -> np.ndarray:
        if block is None:
            return thickness_factor(d, tip, thickness, nu, b)
        return twin_factor(d, tip, block, nu, b, resolution=twin_resolution)

    if isinstance(base, str):
        if base not in SIM_BASES:
            raise InputError(f"unknown base {base!r}; use one of {', '.join(SIM_BASES)}, a "
                             "number in [0, 1] (partial bond) or None (half-space)")
        return factor(base)
    w = float(base)
    if not 0.0 <= w <= 1.0:
        raise InputError(f"partial bond {base!r} must lie in [0, 1] (0 free, 1 bonded)")
    return (1.0 - w) * factor("free") + w * factor("bonded")


def blunted_paraboloid_shape(depth: ArrayLike, radius: float, flat_radius: float
                             ) -> np.ndarray:
    """Shape function s(d) = F/E* [m²] of a paraboloid whose apex is worn flat.

    The profile f(r) = max(0, r² − b²)/(2R) (a paraboloid of apex radius R with a flat of
    radius b, the apex removed down to b²/2R) maps by the MDR (Popov & Hess 2015, ch. 3) to
    g(x) = x·sqrt(x² − b²)/R for x > b (0 inside), so the contact radius a solves
    a²(a² − b²) = (dR)² and

        F = 2E*·[d·a − (a² − b²)^(3/2)/(3R)],   a² = (b² + sqrt(b⁴ + 4d²R²))/2.

    b = 0 gives Hertz's (4/3)·E*·R^(1/2)·d^(3/2); at d ≪ b²/R it is the flat punch 2E*·b·d.
    A misspecification knob of the simulator (a worn or badly printed tip fitted with the
    paraboloid law), not a registered contact law.

    Parameters
    ----------
    depth
        [m] Indentation depth d (0 for d <= 0).
    radius
        [m] Apex radius R of the paraboloid.
    flat_radius
        [m] Radius b of the flat, >= 0.

    Returns
    -------
    numpy.ndarray
        [m²] s(d), F = E*·s(d).
    """
    d = np.clip(np.asarray(depth, dtype=float), 0.0, None)
    R, b = float(radius), float(flat_radius)
    a2 = 0.5 * (b * b + np.sqrt(b**4 + 4.0 * (d * R) ** 2))
    return 2.0 * (d * np.sqrt(a2) - np.clip(a2 - b * b, 0.0, None) ** 1.5 / (3.0 * R))


# Many parameters: the contact law's inputs (depth, E, nu, tip) and each physics knob of the
# simulator (layer, base, stiffening, blunt apex, block's twin).
def true_force(
    depth: ArrayLike,
    E: float,
    nu: float,
    tip: Tip,
    *,
    thickness: float | None = None,
    base: str | float | None = None,
    stiffening: float = 0.0,
    apex_flat_radius: float = 0.0,
    block: Specimen | None = None,
    twin_resolution: str = SIM_RESOLUTION,
) -> np.ndarray:
    """The simulator's noise-free force F = E*·s(d)·f(d)·xi(d) [N] (0 for d <= 0).

    s is :func:`palpbayes.contact.shape` on a half-space (or, with ``apex_flat_radius`` b > 0
    on a paraboloid tip, :func:`blunted_paraboloid_shape`: an apex worn flat), f the
    specimen's bottom effect (:func:`layer_factor`: off with ``base=None``; the layer factor
    is that of the sharp tip; with a ``block`` its finite-element twin's), xi
    :func:`stiffening_factor`.  With every knob off this is
    exactly :func:`palpbayes.contact.force`.
    """
    d = np.asarray(depth, dtype=float)
    if apex_flat_radius:
        if tip.kind != "paraboloid":
            raise GeometryError(f"a blunted apex (apex_flat_radius={apex_flat_radius!r} m) "
                                f"is a paraboloid tip's knob; got tip {tip.kind!r}")
        if apex_flat_radius < 0:
            raise GeometryError(f"apex flat radius {apex_flat_radius!r} m must be >= 0")
        s = blunted_paraboloid_shape(d, tip.radius, apex_flat_radius)
    else:
        s = shape(d, tip)
    if base is not None:
        s = s * layer_factor(d, tip, thickness, nu, base, block, twin_resolution)
    f = effective_modulus(E, nu) * s
    if stiffening != 0:
        f = f * stiffening_factor(d, thickness, stiffening)
    return f


def onset_force_profile(depth: ArrayLike, onset_force: float, onset_length: float) -> np.ndarray:
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


def solve_series_compliance(
    d_cmd: ArrayLike,
    force_of_depth: Callable[[np.ndarray], np.ndarray],
    compliance: float,
    iterations: int = 64,
) -> tuple[np.ndarray, np.ndarray]:
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


def solid_force(depth: ArrayLike, solid: Solid, tip: Tip, block: Specimen,
                base: str | float, max_depth: float, resolution: str = SIM_RESOLUTION
                ) -> np.ndarray:
    """The force [N] of ``tip`` pressed ``depth`` [m] into a hyperelastic ``block`` of
    ``solid`` (0 for d <= 0): its finite-strain twin's curve to the table depth of
    ``max_depth`` [m] at :data:`SOLID_DEPTH_POINTS` depths (:func:`palpbayes.twin.
    solid_table`, cached on disk), interpolated monotonically in ln d.

    Parameters
    ----------
    base
        ``"free"``, ``"bonded"`` or a partial bond w in [0, 1]: (1 − w)·F_free + w·F_bonded.
    resolution
        The twin's mesh (default ``fine``: the fits use ``default`` or ``coarse``).
    """
    d = np.asarray(depth, dtype=float)
    top = table_depth(max_depth)

    def curve(b: str) -> np.ndarray:
        table = solid_table(solid, block, tip, b, top, resolution, SOLID_DEPTH_POINTS)
        return table.force(d, solid.E0)

    if isinstance(base, str):
        if base not in SIM_BASES:
            raise InputError(f"unknown base {base!r}; use one of {', '.join(SIM_BASES)} or a "
                             "number in [0, 1] (partial bond)")
        return curve(base)
    w = float(base)
    if not 0.0 <= w <= 1.0:
        raise InputError(f"partial bond {base!r} must lie in [0, 1] (0 free, 1 bonded)")
    return (1.0 - w) * curve("free") + w * curve("bonded")
