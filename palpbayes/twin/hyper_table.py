"""The hyperelastic twin's force curves, tabulated for a fit: F(d; E0, shape) by interpolation.

At fixed shape parameters and nu every stress of a law scales with E0 (its natural parameters
are E0 × a function of the shape: :meth:`~palpbayes.material.MaterialLaw.natural`), so the
force does too: F = E0·L²·y(d/L; shape), with L the tip's radius (a tip without one: the
specimen's height H).  A cone has no length: its y is kept as F/(E0·d²) against d/H, nearly
constant (exactly so on a half-space: the cone's contact is self-similar), which interpolates
best.  A table holds y on a grid of depths × a tensor grid over the law's shape parameters
(none for the neo-Hookean solid, one or two for most laws), one finite-element curve per node
of the grid (:func:`~.hyper_palpation.solve_hyper_palpation`), per law × nu × tip ×
geometry (H/L, the footprint's equal-area radius/L) × base.

**Evaluation** (:meth:`HyperTable.force`): ln y is interpolated multilinearly over the shape
grid at the table's depths (positive weights: each node's curve increases with depth, so the
blend does), then monotonically in ln d (PCHIP, Fritsch & Carlson 1980), continued below the
shallowest depth by the first interval's power law (Hertz's exponent) and beyond the deepest
by the last's.  A node whose finite elements did not converge (a law unstable at those
strains) is NaN and so is every force interpolated from it: a fit's likelihood reads -inf
there.

**Cache**: each curve is stored once (:mod:`.cache`: ``.npz``, no pickle, under a key of all
its inputs: the law, the node's natural parameters per unit E0, nu, the tip and geometry in
units of L, base, depths, mesh and solver version), so a table grows and resumes node by node;
:func:`prepare_hyper_table` solves the missing ones behind a progress bar.
"""

from __future__ import annotations

import itertools
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import PchipInterpolator

from ..contact import Tip, get_law
from ..errors import FitError, GeometryError, InputError
from ..material import MaterialLaw, material_law
from ..specimen import Specimen
from .cache import load_arrays, save_arrays
from .hyper_palpation import HYPER_RESOLUTIONS, PENALTY, solve_hyper_palpation
from .palpation import TWIN_BASES

__all__ = ["HyperTable", "hyper_table", "prepare_hyper_table", "hyper_curve", "curve_key",
           "table_depths", "solid_table", "HYPER_TABLE_VERSION", "DEPTH_POINTS"]

#: Changes whenever the solver, the mesh or the table's construction does (part of the key).
HYPER_TABLE_VERSION = 1
#: Depths solved per curve.
DEPTH_POINTS = 12
#: The shallowest depth solved, as a fraction of the deepest (the contact needs cells).
_D_MIN = 0.03


def _unit(tip: Tip, specimen: Specimen) -> tuple[float, bool]:
    """(L [m], per_depth): the tip's radius, else the height; a cone keeps F/(E0 d²)."""
    radius = tip.radius if "radius" in get_law(tip).parameters else None
    return (float(radius) if radius else specimen.height), tip.kind == "cone"


def table_depths(d_max: float, points: int = DEPTH_POINTS) -> np.ndarray:
    """The solved depths [any unit]: geometric from ``_D_MIN``·d_max to ``d_max``."""
    return d_max * np.geomspace(_D_MIN, 1.0, points)


def curve_key(law: MaterialLaw, natural: Mapping[str, float], nu: float, tip: Tip,
              radius: float, height: float, base: str, depths: np.ndarray,
              resolution: str) -> dict:
    """The key of one cached curve, every length in units of L and stresses per unit E0."""
    sizes = {f"tip_{name}": float(getattr(tip, name)) for name in get_law(tip).parameters}
    return {"kind": "hyper-curve", "version": HYPER_TABLE_VERSION, "law": law.name,
            **{f"p_{k}": float(v) for k, v in sorted(natural.items())},
            "nu": round(float(nu), 6), "tip": tip.kind, **sizes, "radius": float(radius),
            "height": float(height), "base": base, "depths": ",".join(f"{d:.9g}" for d in depths),
            "resolution": resolution, "mesh": repr(HYPER_RESOLUTIONS[resolution]),
            "penalty": PENALTY}


def hyper_curve(law: MaterialLaw, natural: Mapping[str, float], nu: float, tip: Tip,
                radius: float, height: float, base: str, depths: np.ndarray,
                resolution: str = "default") -> tuple[np.ndarray, str]:
    """(F/(E0·L²) at ``depths`` [L], a note): one curve in units of L (E0 = 1 in
    ``natural``), from the disk cache or solved and stored; NaN with the error's text when the
    finite elements do not converge."""
    key = curve_key(law, natural, nu, tip, radius, height, base, depths, resolution)
    stored = load_arrays(key)
    if stored is not None and "force" in stored:
        return stored["force"], str(stored.get("note", ""))
    try:
        curve = solve_hyper_palpation(radius, height, tip, law, dict(natural), nu, base,
                                      depths, resolution)
        force, note = curve.force, ""
    except FitError as err:
        force, note = np.full(depths.shape, np.nan), str(err)
    save_arrays(key, {"force": force, "note": np.array(note)})
    return force, note


@dataclass(frozen=True)
class HyperTable:
    """F(d; E0, shape) of a tip in the hyperelastic twin, for a fit (module docstring).

    Attributes
    ----------
    law
        The law's registry name.
    nu, base
        The Poisson ratio (the foam's comes from its shape) and the base.
    length
        L [m]: the tip's radius, or the specimen's height for a tip without one.
    per_depth
        True for a cone: ``values`` are F/(E0·d²), else F/(E0·L²).
    names, nodes
        The shape parameters' names and their grid nodes.
    depth
        The solved depths d/L [-].
    values
        (len(nodes[0]), ..., len(depth)) the dimensionless force at each node and depth.
    notes
        Why a node failed (empty when all converged).
    """

    law: str
    nu: float
    base: str
    length: float
    per_depth: bool
    names: tuple[str, ...]
    nodes: tuple[np.ndarray, ...]
    depth: np.ndarray
    values: np.ndarray
    notes: tuple[str, ...] = ()

    def _blend(self, shape: Mapping[str, float]) -> np.ndarray:
        """ln of the dimensionless force at the table's depths for ``shape``."""
        logv = np.log(self.values)
        for name, grid in zip(self.names, self.nodes, strict=True):
            s = float(shape[name])
            if not grid[0] <= s <= grid[-1]:
                return np.full(self.depth.shape, np.nan)
            if grid.size == 1:
                logv = logv[0]
                continue
            i = int(np.clip(np.searchsorted(grid, s) - 1, 0, grid.size - 2))
            t = (s - grid[i]) / (grid[i + 1] - grid[i])
            logv = (1.0 - t) * logv[i] + t * logv[i + 1]
        return logv

    def force(self, depth, E0: float, shape: Mapping[str, float] | None = None) -> np.ndarray:
        """F [N] at ``depth`` [m] for the small-strain modulus ``E0`` [Pa] and the shape
        parameters ``shape`` (a dict by name; NaN outside the grid); 0 at depth <= 0."""
        d = np.asarray(depth, dtype=float) / self.length
        logv = self._blend(shape or {})
        out = np.zeros(d.shape)
        pos = d > 0
        if not np.all(np.isfinite(logv)):
            out[pos] = np.nan
            return out
        x = np.log(self.depth)
        interp = PchipInterpolator(x, logv, extrapolate=False)
        lx = np.log(d[pos])
        lv = interp(lx)
        lo, hi = lx < x[0], lx > x[-1]
        lv[lo] = logv[0] + (lx[lo] - x[0]) * (logv[1] - logv[0]) / (x[1] - x[0])
        lv[hi] = logv[-1] + (lx[hi] - x[-1]) * (logv[-1] - logv[-2]) / (x[-1] - x[-2])
        y = np.exp(lv)
        scale = (d[pos] * self.length) ** 2 if self.per_depth else self.length ** 2
        out[pos] = E0 * y * scale
        return out


def _grid(law: MaterialLaw, shape_nodes: Mapping[str, Sequence[float]] | None):
    names = tuple(s.name for s in law.shape)
    given = dict(shape_nodes or {})
    unknown = set(given) - set(names)
    if unknown:
        raise InputError(f"the {law.title} law has no shape parameter(s) "
                         f"{', '.join(sorted(unknown))}; it has {', '.join(names) or 'none'}")
    nodes = []
    for s in law.shape:
        grid = np.asarray(given.get(s.name, [s.default]), dtype=float)
        if grid.ndim != 1 or grid.size == 0 or np.any(np.diff(grid) <= 0):
            raise InputError(f"the nodes of {s.name} must increase")
        nodes.append(grid)
    return names, tuple(nodes)


def _plan(law, specimen, tip, nu, base, shape_nodes, max_depth, resolution):
    law = material_law(law)
    if base not in TWIN_BASES:
        raise GeometryError(f"unknown base {base!r}; use one of {', '.join(TWIN_BASES)}")
    if resolution not in HYPER_RESOLUTIONS:
        raise GeometryError(f"unknown resolution {resolution!r}")
    length, per_depth = _unit(tip, specimen)
    unit_tip = tip.scaled(1.0 / length) if tip.has_length_scale else tip
    if max_depth is None:
        max_depth = 0.15 * specimen.height
        if get_law(tip).max_depth is not None:
            max_depth = min(max_depth, 0.5 * get_law(tip).max_depth(tip))
    depths = table_depths(max_depth / length)
    names, nodes = _grid(law, shape_nodes)
    points = []
    for combo in itertools.product(*nodes):
        shape = dict(zip(names, combo, strict=True))
        points.append((combo, law.natural(1.0, shape, nu)))
    geometry = (specimen.radius / length, specimen.height / length)
    return law, length, per_depth, unit_tip, depths, names, nodes, points, geometry


def prepare_hyper_table(law: str | MaterialLaw, specimen: Specimen, tip: Tip, nu: float,
                        base: str, shape_nodes: Mapping[str, Sequence[float]] | None = None,
                        max_depth: float | None = None, resolution: str = "default",
                        progress: bool | None = None) -> HyperTable:
    """Build (or read from the disk cache) the :class:`HyperTable` of ``law`` on ``specimen``
    pressed by ``tip``, with a progress bar on stderr while curves are solved.

    Parameters
    ----------
    law
        A registered law or its name.
    specimen, tip
        The block as tested and the tip, in metres (the table is dimensionless: any specimen
        of the same proportions shares it).
    nu
        The small-strain Poisson ratio (a foam takes its own from ``shape_nodes``' ``nu``).
    base
        ``"bonded"`` or ``"free"``.
    shape_nodes
        The grid's nodes per shape parameter (a parameter left out: its default alone).
    max_depth
        [m] The deepest depth solved (default: 15 % of the height, at most half a sphere's
        radius); the shallowest is 3 % of it.
    progress
        Show the bar (None: when stderr is a terminal).
    """
    from tqdm.auto import tqdm

    law, length, per_depth, unit_tip, depths, names, nodes, points, (radius, height) = _plan(
        law, specimen, tip, nu, base, shape_nodes, max_depth, resolution)
    show = sys.stderr.isatty() if progress is None else progress
    values = np.empty((len(points), depths.size))
    notes = []
    missing = [i for i, (_, nat) in enumerate(points)
               if load_arrays(curve_key(law, nat, nu, unit_tip, radius, height, base, depths,
                                        resolution)) is None]
    bar = tqdm(total=len(missing), disable=not (show and missing), unit="curve", file=sys.stderr,
               desc=f"hyperelastic twin of the {specimen.describe()}, {tip.describe()}, "
                    f"{law.title}")
    with bar:
        for i, (combo, nat) in enumerate(points):
            if i in missing:
                bar.set_postfix_str(", ".join(f"{n} {v:g}" for n, v in zip(names, combo,
                                                                            strict=True)))
            force, note = hyper_curve(law, nat, nu, unit_tip, radius, height, base, depths,
                                      resolution)
            if note:
                notes.append(f"{dict(zip(names, combo, strict=True))}: {note}")
            values[i] = force / (depths ** 2) if per_depth else force
            if i in missing:
                bar.update()
    shape = tuple(n.size for n in nodes) + (depths.size,)
    return HyperTable(law.name, float(nu), base, float(length), per_depth, names, nodes,
                      depths, values.reshape(shape), tuple(notes))


def hyper_table(law: str | MaterialLaw, specimen: Specimen, tip: Tip, nu: float, base: str,
                shape_nodes: Mapping[str, Sequence[float]] | None = None,
                max_depth: float | None = None, resolution: str = "default") -> HyperTable:
    """:func:`prepare_hyper_table` without a progress bar."""
    return prepare_hyper_table(law, specimen, tip, nu, base, shape_nodes, max_depth,
                               resolution, progress=False)



def solid_table(solid, specimen: Specimen, tip: Tip, base: str, max_depth: float,
                resolution: str = "default", points: int = DEPTH_POINTS) -> HyperTable:
    """The one-node :class:`HyperTable` of a :class:`~palpbayes.material.Solid` (a law with
    its natural parameters) on ``specimen`` pressed by ``tip`` to ``max_depth`` [m] at
    ``points`` depths (:func:`table_depths`), cached on disk as every curve: what the
    simulator presses (:mod:`palpbayes.sim.force`); ``table.force(d, solid.E0)`` is F [N].

    Raises
    ------
    FitError
        The finite elements did not converge (the message names the depth reached).
    """
    law = solid.spec
    e0 = solid.E0
    units = dict(law.parameters)
    natural = {k: v / e0 if units.get(k) == "Pa" else v for k, v in solid.params.items()}
    nu = solid.nu0
    length, per_depth = _unit(tip, specimen)
    unit_tip = tip.scaled(1.0 / length) if tip.has_length_scale else tip
    if base not in TWIN_BASES:
        raise GeometryError(f"unknown base {base!r}; use one of {', '.join(TWIN_BASES)}")
    depths = table_depths(float(max_depth) / length, points)
    force, note = hyper_curve(law, natural, nu, unit_tip, specimen.radius / length,
                              specimen.height / length, base, depths, resolution)
    if note:
        raise FitError(f"the hyperelastic twin of {solid.describe()} pressed by "
                       f"{tip.describe()}: {note}")
    values = force / depths ** 2 if per_depth else force
    return HyperTable(law.name, float(nu), base, float(length), per_depth, (), (), depths,
                      values)
