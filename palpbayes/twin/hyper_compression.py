"""The compression test of the hyperelastic twin: the block between platens to large strain.

The half of the specimen's equal-area cylinder above its mid-plane (u_z = 0 there, u_r free:
symmetry) at finite strain (:class:`~.hyper.HyperSolid`, any registered law), the platen
pushing its top face down by the compressive engineering strain eps (u_z = −eps·H/2),
frictionless (``"lubricated"``: u_r free) or ``"bonded"`` (u_r = 0 on the platen).  The
nominal stress is the platen's force over the undeformed area.  Between lubricated platens
the block is in homogeneous uniaxial stress and the nominal stress is the closed form of
:func:`palpbayes.material.compression_stress` exactly (the P2 displacement holds the linear
field; ``tests/unit/test_hyper.py`` checks every law to 1e-6); bonded platens stiffen the
block as the linear twin's (:mod:`.compression`) do.  The mesh is the linear twin's, graded
towards the platen's edge.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..errors import GeometryError
from ..material import MaterialLaw, material_law
from .hyper import HyperSolid
from .hyper_newton import march
from .hyper_palpation import HyperResolution, _resolution
from .mesh import compression_grid

__all__ = ["HyperCompression", "solve_hyper_compression"]


@dataclass(frozen=True)
class HyperCompression:
    """Nominal stress of the block between platens at each compressive strain.

    Attributes
    ----------
    strain
        Compressive engineering strains [-].
    stress
        Compressive nominal stress [E] (force over the undeformed footprint).
    bulge
        [-] The free side's largest radial displacement over the radius.
    steps, iterations, dofs, seconds
        Load steps, Newton iterations, unknowns, wall time.
    """

    strain: np.ndarray
    stress: np.ndarray
    bulge: np.ndarray
    steps: int
    iterations: int
    dofs: int
    seconds: float


def solve_hyper_compression(radius: float, height: float, law: str | MaterialLaw,
                            params: dict, nu: float, platens: str, strains: np.ndarray,
                            resolution: str | HyperResolution = "coarse",
                            max_cuts: int = 10) -> HyperCompression:
    """The compression test of the hyperelastic twin (module docstring).

    Parameters
    ----------
    radius, height
        The cylinder's radius and height [L].
    law, params, nu
        A registered law, its natural parameters, the small-strain Poisson ratio (not a
        foam's).
    platens
        ``"lubricated"`` (frictionless) or ``"bonded"``.
    strains
        Increasing compressive engineering strains in (0, 0.95).

    Raises
    ------
    GeometryError
        Unknown platens, bad strains or sizes.
    FitError
        The load steps do not converge (the message names the strain reached).
    """
    t0 = time.perf_counter()
    if platens not in ("lubricated", "bonded"):
        raise GeometryError(f"platens {platens!r}: use 'lubricated' or 'bonded'")
    strains = np.asarray(strains, dtype=float)
    if not (strains.size and np.all(strains > 0) and np.all(strains < 0.95)
            and np.all(np.diff(strains) > 0)):
        raise GeometryError("compressive strains must increase within (0, 0.95)")
    if not (radius > 0 and height > 0):
        raise GeometryError("the block's radius and height must be positive")
    res = _resolution(resolution)
    law = material_law(law)
    half = 0.5 * height
    r_nodes, z_nodes = compression_grid(radius, half, res.grid)
    solid = HyperSolid(r_nodes, z_nodes, law, params, nu)
    platen = solid.dofs("z", solid.on_top)
    parts = [solid.dofs("r", solid.on_axis), solid.dofs("z", solid.on_bottom), platen]
    if platens == "bonded":
        parts.append(solid.dofs("r", solid.on_top))
    fixed = np.unique(np.concatenate(parts))
    on_platen = np.isin(fixed, platen)
    side = solid.dofs("r", solid.on_side)
    out = np.empty((2, strains.size))

    def load(eps):
        values = np.zeros(fixed.size)
        values[on_platen] = -eps * half
        return values, None

    def record(i, x, sol):
        force = -2.0 * math.pi * sol.residual[platen].sum()
        out[:, i] = force / (math.pi * radius * radius), x[side].max() / radius

    steps, iters = march(solid, strains, fixed, load, record,
                         f"the compression of the hyperelastic twin ({law.title})", max_cuts)
    return HyperCompression(strains, out[0], out[1], steps, iters, solid.size,
                            time.perf_counter() - t0)
