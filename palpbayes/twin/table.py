"""The twin's force–depth law, tabulated once per geometry × tip × nu × base.

A fit evaluates the contact law millions of times; the finite elements
(:func:`~palpbayes.twin.palpation.solve_palpation`) run once per specimen, tip, Poisson ratio
and base, and the law is kept as a factor over the half-space law, F = E*·s_hs(d)·f(chi),
with chi = a_hs(d)/H (the half-space contact radius over the specimen's height, the variable
of the layer tables in :mod:`palpbayes.contact.layer`).  The factor is written as the exact
infinite layer's factor times the finite width's: f = f_layer·w, w solved by the twin at 24
depths whose half-space contact radius runs from a tenth of the deepest one's to it (the
twin's cells are sized for those), w = 1 at chi = 0 (a vanishing contact does not see the
specimen's sides); between, w is interpolated monotonically (PCHIP).  Beyond the deepest solved
depth w is held at its last value.  A flat punch's factor is one number (its contact does not
grow).

Everything is solved in units of the specimen's height: the table's key (the tip's and the
footprint's sizes over H, nu, base, the mesh's parameters, the depths' rule and the solver's
version) is dimensionless, so a table serves any specimen of the same proportions.  The disk
cache (:mod:`palpbayes.twin.cache`) keeps the finite elements' points and the lookup table
made from them (the infinite layer's factor, the grid) under a stamp of the code that makes it
(:func:`derived_stamp`): read with the same stamp, a table is used as stored (a new process
solves no infinite-layer table for each nu and base); with another, it is rebuilt from the
points, so a change of :mod:`palpbayes.contact.layer` never meets a stale table.

A block L × W is modelled as the cylinder of equal footprint area.  Against the block itself
in 3-D (``benchmarks/bench_twin_3d.py``, the sphere and flat punch of the paper at 10 % depth,
free base, nu 0.3) the width effect of that cylinder is within 0.2-0.4 % for a square, 0.4-1.0 %
at 1.5:1, 0.9-2.5 % at 2:1 and 2.1-6.4 % at 3:1 (the cylinder too stiff); footprints longer
than :data:`MAX_ASPECT` are refused, those beyond 1.5:1 carry a note.
"""

from __future__ import annotations

import functools
import math
import sys
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import PchipInterpolator

from ..contact import Tip, get_law
from ..contact import layer as layer_solution
from ..errors import GeometryError
from ..specimen import Specimen
from ..units import format_length
from .cache import code_stamp, key_text, load_arrays, save_arrays
from .mesh import RESOLUTIONS
from .palpation import TWIN_BASES, solve_palpation

__all__ = ["TwinTable", "twin_table", "twin_shape", "twin_factor", "prepare_tables",
           "table_key", "TWIN_SOLVER_VERSION", "twin_depth_limit", "twin_depth_limit_reason",
           "clear_memory", "MAX_ASPECT", "derived_stamp"]

#: Changes whenever the solver, the mesh or the table's construction does (part of the key).
TWIN_SOLVER_VERSION = 1
#: Depths the twin solves per table.
_POINTS = 24
#: Smallest solved contact radius, as a fraction of the deepest's.
_A_MIN = 0.1
#: Uniform grid of the lookup table.
_GRID = 2049
#: Arrays of a table on disk: the finite elements' output (what the key stands for) ...
_POINT_ARRAYS = {"punch", "points_chi", "points_factor", "dofs"}
#: ... and the lookup table made from them, valid for the code of its stamp (module docstring).
_DERIVED_ARRAYS = {"derived_stamp", "chi", "log_factor", "tail_slope", "chi_top",
                   "points_layer"}
#: Longest footprint (length/width) the equal-area cylinder stands for (module docstring).
MAX_ASPECT = 3.0


@dataclass(frozen=True)
class TwinTable:
    """F/E* of a tip in the twin of a specimen over the half-space's, as a function of chi.

    Attributes
    ----------
    punch
        True for a flat punch: the factor is the constant ``points_factor[0]``.
    chi, log_factor
        Uniform grid of chi = a_hs(d)/H [-] and ln f on it.
    tail_slope
        d ln f / d ln chi beyond the grid.
    chi_top
        Largest chi the finite elements solved (beyond, w is held).
    points_chi, points_factor, points_layer
        The solved points: chi, the twin's factor f and the infinite layer's f_layer there.
    dofs
        Unknowns of the finite-element model.
    """

    punch: bool
    chi: np.ndarray
    log_factor: np.ndarray
    tail_slope: float
    chi_top: float
    points_chi: np.ndarray
    points_factor: np.ndarray
    points_layer: np.ndarray
    dofs: int

    @classmethod
    def from_points(cls, punch: bool, points_chi: np.ndarray, points_factor: np.ndarray,
                    dofs: int, n: float, nu: float, base: str) -> TwinTable:
        """The table of the finite elements' points (chi, f = F_twin/F_hs) of a profile of
        exponent ``n`` (module docstring: f = f_layer·w, w interpolated, held beyond)."""
        chi = np.asarray(points_chi, dtype=float)
        f = np.asarray(points_factor, dtype=float)
        if punch:
            f_layer = np.array([layer_solution.flat_punch_factor(float(chi[0]), nu, base)])
            return cls(True, chi, np.log(f), 0.0, float(chi[0]), chi, f, f_layer, int(dofs))
        f_layer = layer_solution.profile_factor(chi, n, nu, base)
        w = PchipInterpolator(np.r_[0.0, chi], np.r_[1.0, f / f_layer])
        grid = np.linspace(0.0, 2.0 * chi[-1], _GRID)
        logf = (np.log(layer_solution.profile_factor(grid, n, nu, base))
                + np.log(w(np.minimum(grid, chi[-1]))))
        slope = float((logf[-1] - logf[-9]) / math.log(grid[-1] / grid[-9]))
        return cls(False, grid, logf, slope, float(chi[-1]), chi, f, f_layer, int(dofs))

    def factor(self, chi: np.ndarray) -> np.ndarray:
        """f(chi) [-] (1 at chi <= 0; a flat punch's constant at chi > 0).

        Linear interpolation of ln f on the uniform grid by index arithmetic (the grid's
        values to 1 ulp of :func:`numpy.interp`'s, four times as fast: a binary search over
        a grid that the fitted depths span widely is the slow part of a fit's shape
        function); NaN gives NaN."""
        chi = np.asarray(chi, dtype=float)
        if self.punch:
            return np.where(chi > 0, self.points_factor[0], 1.0)[()]
        c = np.maximum(chi.ravel(), 0.0)  # NaN stays NaN
        lf_grid, slope, step = self.log_factor, self._slopes, self.chi[1]
        q = c * (1.0 / step)
        i = np.minimum(np.where(q > 0, q, 0.0), lf_grid.size - 2).astype(np.intp)
        lf = lf_grid[i] + (c - i * step) * slope[i]
        beyond = c > self.chi[-1]
        if beyond.any():
            lf[beyond] = self.log_factor[-1] + self.tail_slope * np.log(c[beyond] / self.chi[-1])
        return np.exp(lf, out=lf).reshape(chi.shape)[()]

    @functools.cached_property
    def _slopes(self) -> np.ndarray:
        """d ln f / d chi on each interval of the grid."""
        return np.diff(self.log_factor) / np.diff(self.chi)

    def arrays(self) -> dict[str, np.ndarray]:
        """The table as the disk cache keeps it: the points and the lookup table with the
        stamp of the code that made it (:func:`derived_stamp`)."""
        return {"punch": np.array(self.punch), "points_chi": self.points_chi,
                "points_factor": self.points_factor, "dofs": np.array(self.dofs),
                "derived_stamp": np.array(derived_stamp()), "chi": self.chi,
                "log_factor": self.log_factor, "tail_slope": np.array(self.tail_slope),
                "chi_top": np.array(self.chi_top), "points_layer": self.points_layer}

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray]) -> TwinTable | None:
        """The table stored by :meth:`arrays`, or None when its lookup table is missing or
        was made by other code (another stamp): then rebuild it with :meth:`from_points`."""
        if not _DERIVED_ARRAYS <= set(arrays) or str(arrays["derived_stamp"]) != derived_stamp():
            return None
        return cls(bool(arrays["punch"]), arrays["chi"], arrays["log_factor"],
                   float(arrays["tail_slope"]), float(arrays["chi_top"]),
                   arrays["points_chi"], arrays["points_factor"], arrays["points_layer"],
                   int(arrays["dofs"]))


def derived_stamp() -> str:
    """The stamp of the code a table's lookup grid is made with from its points
    (:func:`palpbayes.twin.cache.code_stamp` of :mod:`palpbayes.contact.layer`, the infinite
    layer's factor, and of this module)."""
    return code_stamp((layer_solution.__name__, __name__), f"grid {_GRID}")


def _check(specimen: Specimen, tip: Tip, nu: float, base: str) -> None:
    """The twin's domain, in the user's units (metres)."""
    if base not in TWIN_BASES:
        raise GeometryError(f"unknown base {base!r}; use one of {', '.join(TWIN_BASES)}")
    law = get_law(tip)
    if law.profile is None or law.contact_radius is None:
        raise GeometryError(f"tip '{tip.kind}' has no profile: it cannot be pressed into the "
                            "specimen twin")
    if not 0.0 <= nu <= 0.5:
        raise GeometryError(f"Poisson ratio {nu!r} outside [0, 0.5]")
    if specimen.aspect > MAX_ASPECT:
        raise GeometryError(
            f"the {specimen.describe()} is {specimen.aspect:.1f} times as long as wide: the "
            "twin models a block as the cylinder of equal footprint area, measured within 1 % "
            "of the block itself up to 1.5:1, 0.9-2.5 % at 2:1 and 2-6 % at 3:1 "
            f"(benchmarks/bench_twin_3d.py); beyond {MAX_ASPECT:g}:1 it is not a model of "
            "the block. Fit it as a layer instead (--thickness H without --specimen)")
    if math.isinf(law.profile_exponent(tip)) and tip.radius >= specimen.half_width:
        raise GeometryError(
            f"a flat punch of radius {format_length(tip.radius)} does not fit on the "
            f"{specimen.describe()} (half its narrowest side is "
            f"{format_length(specimen.half_width)})")


def _unit_tip(tip: Tip, height: float) -> Tip:
    """``tip`` in units of the specimen's height."""
    return tip.scaled(1.0 / height) if tip.has_length_scale else tip


def table_key(specimen: Specimen, tip: Tip, nu: float, base: str,
              resolution: str = "default") -> dict:
    """The dimensionless key of a table (module docstring): everything the finite elements'
    points depend on, the mesh's parameters and the depths' rule among them."""
    unit = _unit_tip(tip, specimen.height)
    sizes = {name: float(getattr(unit, name)) for name in get_law(tip).parameters}
    mesh = RESOLUTIONS[resolution]
    return {"kind": "palpation", "version": TWIN_SOLVER_VERSION, "tip": tip.kind, **sizes,
            "radius_over_height": specimen.radius / specimen.height,
            "half_width_over_height": specimen.half_width / specimen.height,
            "nu": round(float(nu), 6), "base": base, "resolution": resolution,
            "mesh": repr(mesh), "points": _POINTS, "a_min": _A_MIN}


def twin_depth_limit(specimen: Specimen, tip: Tip) -> float:
    """[m] The deepest depth the twin's table solves: half the specimen's height, half the
    tip's depth limit (a sphere's radius), and a half-space contact radius at most half the
    footprint's narrowest half-width (and its equal-area radius), whichever is least
    (deeper, the table is continued)."""
    law = get_law(tip)
    h = specimen.height
    limit = 0.5 * h
    if law.max_depth is not None:
        limit = min(limit, 0.5 * law.max_depth(tip))
    if math.isinf(law.profile_exponent(tip)):
        return limit
    a_max = 0.5 * min(specimen.radius, specimen.half_width)
    d = np.geomspace(limit * 1e-6, limit, 2000)
    a = law.contact_radius(d, tip)
    if a[-1] > a_max:
        limit = float(np.interp(a_max, a, d))
    return limit


def twin_depth_limit_reason(specimen: Specimen, tip: Tip) -> str:
    """Which of :func:`twin_depth_limit`'s bounds binds, in words."""
    law = get_law(tip)
    limit = twin_depth_limit(specimen, tip)
    if math.isclose(limit, 0.5 * specimen.height):
        return "half its height"
    if law.max_depth is not None and math.isclose(limit, 0.5 * law.max_depth(tip)):
        return f"half the {law.max_depth_name}"
    return "a contact radius at most half the footprint's narrowest half-width"


def _depths_for_radii(tip: Tip, radii: np.ndarray, d_top: float) -> np.ndarray:
    law = get_law(tip)
    d = np.geomspace(d_top * 1e-8, d_top, 4000)
    return np.interp(radii, law.contact_radius(d, tip), d)


def _solve_points(specimen: Specimen, tip: Tip, nu: float, base: str, resolution: str
                  ) -> dict[str, np.ndarray]:
    """The finite elements' points of a table (``specimen`` and ``tip`` at unit height): what
    the disk cache keeps."""
    radius = specimen.radius
    law = get_law(tip)
    if math.isinf(law.profile_exponent(tip)):
        curve = solve_palpation(radius, 1.0, tip, nu, base, np.array([1.0]), resolution)
        a = float(tip.radius)
        return {"punch": np.array(True), "points_chi": np.array([a]),
                "points_factor": np.array([curve.shape[0] / (2.0 * a)]),
                "dofs": np.array(curve.dofs)}
    d_top = twin_depth_limit(specimen, tip)
    a_top = float(law.contact_radius(np.array([d_top]), tip)[0])
    radii = a_top * np.geomspace(_A_MIN, 1.0, _POINTS)
    depths = _depths_for_radii(tip, radii, d_top)
    depths[-1] = d_top
    curve = solve_palpation(radius, 1.0, tip, nu, base, depths, resolution)
    return {"punch": np.array(False), "points_chi": law.contact_radius(depths, tip),
            "points_factor": curve.shape / law.shape(depths, tip),
            "dofs": np.array(curve.dofs)}


#: Tables of this process, by the text of their key.
_MEMORY: dict[str, TwinTable] = {}


def _table(key: dict, specimen: Specimen, tip: Tip, nu: float, base: str,
           resolution: str, stored: dict[str, np.ndarray] | None = None) -> TwinTable:
    """The table of ``key``: from memory, the disk (``stored``: read already) or solved; a
    table read or solved here is stored on disk with its lookup table when that is new."""
    text = key_text(key)
    table = _MEMORY.get(text)
    if table is None:
        points = load_arrays(key) if stored is None else stored
        if points is None or not _POINT_ARRAYS <= set(points):
            points = _solve_points(specimen, tip, nu, base, resolution)
        table = TwinTable.from_arrays(points)
        if table is None:
            table = TwinTable.from_points(bool(points["punch"]), points["points_chi"],
                                          points["points_factor"], int(points["dofs"]),
                                          get_law(tip).profile_exponent(tip), nu, base)
            save_arrays(key, table.arrays())
        _MEMORY[text] = table
    return table


def _normalized(specimen: Specimen, tip: Tip, nu: float, base: str, resolution: str):
    """The key and the arguments of the table at unit height (the table is dimensionless,
    so equal keys give one table)."""
    h = specimen.height
    key = table_key(specimen, tip, nu, base, resolution)
    return key, specimen.scaled(1.0 / h), _unit_tip(tip, h), key["nu"], base


@functools.lru_cache(maxsize=1024)
def _lookup(specimen: Specimen, tip: Tip, nu: float, base: str, resolution: str) -> TwinTable:
    """:func:`twin_table` without its key's cost on the second call (a fit asks for its table
    at every evaluation of the shape)."""
    _check(specimen, tip, nu, base)
    return _table(*_normalized(specimen, tip, nu, base, resolution), resolution)


def clear_memory() -> None:
    """Forget the tables of this process (the disk cache stays): the next call reads them
    from disk or solves them again."""
    _MEMORY.clear()
    _lookup.cache_clear()


def twin_table(specimen: Specimen, tip: Tip, nu: float, base: str,
               resolution: str = "default") -> TwinTable:
    """The :class:`TwinTable` of ``tip`` on ``specimen`` (cached in memory and on disk;
    about a second of finite elements when new).

    Raises
    ------
    GeometryError
        An unknown base, a tip without a profile, nu outside [0, 0.5], or a contact that does
        not fit the specimen.
    """
    return _lookup(specimen, tip, float(nu), base, resolution)


def twin_factor(depth: np.ndarray, tip: Tip, specimen: Specimen, nu: float, base: str,
                resolution: str = "default") -> np.ndarray:
    """F_twin/F_half-space [-] at ``depth`` [m]."""
    a = get_law(tip).contact_radius(np.asarray(depth, dtype=float), tip)
    return twin_table(specimen, tip, nu, base, resolution).factor(a / specimen.height)


def twin_shape(depth: np.ndarray, tip: Tip, specimen: Specimen, nu: float, base: str,
               resolution: str = "default") -> np.ndarray:
    """F/E* [m²] of ``tip`` pressed ``depth`` [m] into the twin of ``specimen`` (0 out of
    contact)."""
    law = get_law(tip)
    table = twin_table(specimen, tip, nu, base, resolution)
    d = np.asarray(depth, dtype=float)
    if law.shape_and_radius is not None:
        s, a = law.shape_and_radius(d, tip)
    else:
        s, a = law.shape(d, tip), law.contact_radius(d, tip)
    return s * table.factor(a / specimen.height)


def _load(specimen: Specimen, tip: Tip, nu: float, base: str, resolution: str) -> bool:
    """Put the table in memory when it is on disk (read once, no finite elements to run);
    True when it is in memory then."""
    key, *args = _normalized(specimen, tip, nu, base, resolution)
    if key_text(key) in _MEMORY:
        return True
    stored = load_arrays(key)
    if stored is None or not _POINT_ARRAYS <= set(stored):
        return False
    _table(key, *args, resolution, stored=stored)
    return True


def prepare_tables(specimen: Specimen, tip: Tip, nus: Iterable[float], bases: Iterable[str],
                   resolution: str = "default", progress: bool | None = None) -> int:
    """Build (or load) every table of ``nus`` × ``bases``, with a progress bar on stderr
    while new ones are solved; the number of tables solved.

    ``progress`` None shows the bar when stderr is a terminal.
    """
    from tqdm.auto import tqdm

    todo = [(float(nu), b) for nu in sorted({round(float(v), 6) for v in nus})
            for b in dict.fromkeys(bases)]
    for nu, b in todo:
        _check(specimen, tip, nu, b)
    missing = [(nu, b) for nu, b in todo if not _load(specimen, tip, nu, b, resolution)]
    show = sys.stderr.isatty() if progress is None else progress
    bar = tqdm(total=len(missing), disable=not (show and missing), unit="table",
               desc=f"twin of the {specimen.describe()}, {tip.describe()}", file=sys.stderr)
    with bar:
        for nu, b in todo:
            new = (nu, b) in missing
            if new:
                bar.set_postfix_str(f"nu {nu:g}, {b}")
            twin_table(specimen, tip, nu, b, resolution)
            if new:
                bar.update()
    return len(missing)
