"""A rigid frictionless tip pressed into the hyperelastic twin: force against depth at finite
strain.

The specimen is the linear twin's (:mod:`palpbayes.twin.palpation`): a cylinder of radius
``radius`` and height ``height`` (a block's equal-area cylinder,
:class:`~palpbayes.specimen.Specimen`) on a rigid plate, bonded (u = 0) or lying on it
without friction (u_z = 0), its side free, at finite strain (:class:`~.hyper.HyperSolid`, any
registered law).  The tip presses the top face's centre without friction, by a penalty on
the signed distance to its true surface (:mod:`.hyper_contact`), k = ``penalty``·E0/a with a
the half-space contact radius of the step's depth (the punch's radius for a flat punch), and
an augmented Lagrangian's updates where the penetration still exceeds ``tolerance`` (5e-4)
of the depth (a flat punch's edge, a cone's apex); every curve reports its largest.

The depth is stepped up to each asked depth, the step halved when Newton's method fails
(:func:`~.hyper.newton`) and grown by half after an easy step; the predictor extrapolates the
last two solutions.  The mesh is the linear twin's graded grid (:mod:`.mesh`) at the
resolutions of :data:`HYPER_RESOLUTIONS`: cells growing with the distance from the axis up to
:attr:`HyperResolution.reach` times the deepest half-space contact radius, a flat punch's grid
graded towards its edge.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..contact import Tip, get_law
from ..errors import GeometryError
from ..material import MaterialLaw, material_law
from .hyper import HyperSolid
from .hyper_contact import PenaltyContact, tip_surface
from .hyper_newton import march
from .mesh import Resolution, contact_grid, depth_grid, punch_grid
from .palpation import TWIN_BASES

__all__ = ["HyperResolution", "HYPER_RESOLUTIONS", "HyperCurve", "solve_hyper_palpation",
           "PENALTY", "TOLERANCE", "fixed_dofs"]

#: Penalty factor: k = PENALTY·E0/a.
PENALTY = 2000.0
#: The largest penetration a converged step keeps, as a fraction of its depth.
TOLERANCE = 5e-4


@dataclass(frozen=True)
class HyperResolution:
    """How fine the hyperelastic twin's mesh is (the linear twin's grid parameters,
    :class:`~palpbayes.twin.mesh.Resolution`, with the reach of its fine zone).

    Attributes
    ----------
    grid
        The grid's parameters.
    reach
        The fine zone spans this many times the deepest half-space contact radius (the
        contact at finite strain is wider than the half-space's: pile-in, curvature).
    """

    grid: Resolution
    reach: float = 1.6


#: ``coarse`` for the default tests, ``default`` for tables, ``fine`` for convergence.
HYPER_RESOLUTIONS = {
    "coarse": HyperResolution(Resolution(core=4.0, first=0.04, outer=1.5, vertical=1.4,
                                         punch_first=2e-2, punch_growth=1.5)),
    "default": HyperResolution(Resolution(core=6.5, first=0.02, outer=1.35, vertical=1.25,
                                          punch_first=8e-3, punch_growth=1.35)),
    "fine": HyperResolution(Resolution(core=10.0, first=0.01, outer=1.25, vertical=1.15,
                                       punch_first=4e-3, punch_growth=1.25)),
}


@dataclass(frozen=True)
class HyperCurve:
    """Force of a tip in the hyperelastic twin at each depth.

    Attributes
    ----------
    depth
        Depths [L] (the caller's length unit L).
    force
        The tip's force [E·L²] (E the unit of the law's parameters).
    contact_radius
        [L] Radius of the outermost surface point in contact, deformed configuration.
    penetration
        [L] The largest penetration of the tip at each depth.
    steps, iterations
        Load steps and Newton iterations taken in all.
    dofs
        Unknowns of the finite-element model.
    seconds
        Wall time of the solve.
    """

    depth: np.ndarray
    force: np.ndarray
    contact_radius: np.ndarray
    penetration: np.ndarray
    steps: int
    iterations: int
    dofs: int
    seconds: float
    notes: tuple[str, ...] = field(default=())


def _resolution(resolution) -> HyperResolution:
    if isinstance(resolution, HyperResolution):
        return resolution
    try:
        return HYPER_RESOLUTIONS[resolution]
    except KeyError:
        raise GeometryError(f"unknown resolution {resolution!r}; use one of "
                            f"{', '.join(HYPER_RESOLUTIONS)}") from None


def _contact_scale(tip: Tip, depths: np.ndarray) -> np.ndarray:
    """The length of the penalty, k = PENALTY·E0/scale [L]: the half-space contact radius at
    ``depths``; a tenth of a flat punch's radius (its pressure is singular at the edge, where
    the penetration would otherwise exceed the tolerance and take many updates)."""
    law = get_law(tip)
    if math.isinf(law.profile_exponent(tip)):
        return np.full(depths.shape, 0.1 * float(tip.radius))
    return np.asarray(law.contact_radius(depths, tip), dtype=float)


def fixed_dofs(solid: HyperSolid, base: str) -> np.ndarray:
    """The supported displacements: the axis's u_r, the base's u_z (and u_r, bonded)."""
    if base not in TWIN_BASES:
        raise GeometryError(f"unknown base {base!r}; use one of {', '.join(TWIN_BASES)}")
    fixed = [solid.dofs("r", solid.on_axis), solid.dofs("z", solid.on_bottom)]
    if base == "bonded":
        fixed.append(solid.dofs("r", solid.on_bottom))
    return np.unique(np.concatenate(fixed))


def _mesh(radius, height, tip, depths, res: HyperResolution):
    law = get_law(tip)
    g = res.grid
    if math.isinf(law.profile_exponent(tip)):
        a = float(tip.radius)
        if a >= radius:
            raise GeometryError(f"a flat punch of radius {a:.4g} does not fit on a specimen "
                                f"of radius {radius:.4g}")
        return punch_grid(a, radius, g), depth_grid(height, g.punch_first * a * 4, g)
    a_top = res.reach * float(_contact_scale(tip, np.array([depths.max()]))[0])
    if a_top * 1.2 >= radius:
        raise GeometryError(f"a contact radius of about {a_top:.4g} does not fit well inside "
                            f"the specimen's radius {radius:.4g} (a shallower depth, a wider "
                            "specimen)")
    return contact_grid(a_top / 1.3, radius, g), depth_grid(height, g.first * a_top, g)


# Many parameters: one finite-strain solve: the block, tip, law with its parameters, base, depths
# and the solver's controls.
def solve_hyper_palpation(radius: float, height: float, tip: Tip, law: str | MaterialLaw,
                          params: dict, nu: float, base: str, depths: np.ndarray,
                          resolution: str | HyperResolution = "default",
                          penalty: float = PENALTY, max_cuts: int = 10,
                          tolerance: float = TOLERANCE) -> HyperCurve:
    """Force of ``tip`` pressed ``depths`` into the hyperelastic twin (module docstring).

    Parameters
    ----------
    radius, height
        The cylinder's radius and height [L] (any length unit L, the tip's too).
    tip
        A tip whose law has a profile (every registered kind).
    law, params
        A registered material law and its natural parameters (stresses in any unit E).
    nu
        The small-strain Poisson ratio of a law that is not a foam (0.5 incompressible).
    base
        ``"bonded"`` or ``"free"``.
    depths
        Increasing positive depths [L].
    resolution
        A name of :data:`HYPER_RESOLUTIONS` or a :class:`HyperResolution`.
    penalty
        k = ``penalty``·E0/a (module docstring).
    max_cuts
        Halvings of a load step before giving up.
    tolerance
        The largest penetration allowed, as a fraction of the depth (the augmented
        Lagrangian's updates stop below it).

    Raises
    ------
    GeometryError
        A tip without a profile, a contact that does not fit the specimen, bad depths.
    FitError
        The load steps cannot be made to converge (a law unstable at these strains, a mesh
        too coarse for the depth): the message names the depth reached.
    """
    t0 = time.perf_counter()
    res = _resolution(resolution)
    law = material_law(law)
    depths = np.asarray(depths, dtype=float)
    if not (depths.size and np.all(np.isfinite(depths)) and np.all(depths > 0)
            and np.all(np.diff(depths) > 0)):
        raise GeometryError("depths must be positive, finite and increasing")
    if depths[-1] >= height:
        raise GeometryError(f"depth {depths[-1]:.4g} is not less than the height {height:.4g}")
    surface = tip_surface(tip)
    r_nodes, z_nodes = _mesh(radius, height, tip, depths, res)
    solid = HyperSolid(r_nodes, z_nodes, law, params, nu)
    contact = PenaltyContact(solid, surface)
    fixed = fixed_dofs(solid, base)
    e0 = law.E0(solid.params, solid.nu)
    scale = _contact_scale(tip, depths)
    values = np.zeros(fixed.size)
    out = np.empty((4, depths.size))

    def load(d):
        k = penalty * e0 / float(_contact_scale(tip, np.array([d]))[0])

        def extra(x, it):
            return contact.forces(x, height - d, k, curvature=it > 0)
        return values, extra

    def record(i, x, sol):
        out[:, i] = (depths[i], *contact.measure(x, height - depths[i],
                                                 penalty * e0 / scale[i]))

    class _Augmented:
        """The contact's multipliers for :func:`~.hyper.march`."""

        @property
        def multiplier(self):
            return contact.multiplier

        @multiplier.setter
        def multiplier(self, value):
            contact.multiplier = value

        def augment(self, x, d):
            k = penalty * e0 / float(_contact_scale(tip, np.array([d]))[0])
            return contact.augment(x, height - d, k, tolerance * d)

    steps, iters = march(solid, depths, fixed, load, record,
                         f"the hyperelastic twin ({law.title}, {tip.describe()})", max_cuts,
                         contact=_Augmented(), first_fraction=4.0)
    return HyperCurve(out[0], out[1], out[2], out[3], steps, iters, solid.size,
                      time.perf_counter() - t0)
