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
footprint's sizes over H, nu, base, the mesh resolution and the solver's version) is
dimensionless, so a table serves any specimen of the same proportions, and is cached on disk
(:mod:`palpbayes.twin.cache`).
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
from .cache import key_text, load_arrays, save_arrays
from .palpation import TWIN_BASES, solve_palpation
from .specimen import Specimen

__all__ = ["TwinTable", "twin_table", "twin_shape", "twin_factor", "prepare_tables",
           "table_key", "TWIN_SOLVER_VERSION", "twin_depth_limit", "clear_memory"]

#: Changes whenever the solver, the mesh or the table's construction does (part of the key).
TWIN_SOLVER_VERSION = 1
#: Depths the twin solves per table.
_POINTS = 24
#: Smallest solved contact radius, as a fraction of the deepest's.
_A_MIN = 0.1
#: Uniform grid of the lookup table.
_GRID = 2049


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

    def width_effect(self) -> np.ndarray:
        """w = f/f_layer [-] at the solved points: what the finite width changes."""
        return self.points_factor / self.points_layer

    def to_arrays(self) -> dict[str, np.ndarray]:
        return {"punch": np.array(self.punch), "chi": self.chi, "log_factor": self.log_factor,
                "tail_slope": np.array(self.tail_slope), "chi_top": np.array(self.chi_top),
                "points_chi": self.points_chi, "points_factor": self.points_factor,
                "points_layer": self.points_layer, "dofs": np.array(self.dofs)}

    @classmethod
    def from_arrays(cls, a: dict[str, np.ndarray]) -> TwinTable:
        return cls(punch=bool(a["punch"]), chi=a["chi"], log_factor=a["log_factor"],
                   tail_slope=float(a["tail_slope"]), chi_top=float(a["chi_top"]),
                   points_chi=a["points_chi"], points_factor=a["points_factor"],
                   points_layer=a["points_layer"], dofs=int(a["dofs"]))


def _check(specimen: Specimen, tip: Tip, nu: float, base: str) -> None:
    if base not in TWIN_BASES:
        raise GeometryError(f"unknown base {base!r}; use one of {', '.join(TWIN_BASES)}")
    law = get_law(tip)
    if law.profile is None or law.contact_radius is None:
        raise GeometryError(f"tip '{tip.kind}' has no profile: it cannot be pressed into the "
                            "specimen twin")
    if not 0.0 <= nu <= 0.5:
        raise GeometryError(f"Poisson ratio {nu!r} outside [0, 0.5]")


def _unit_tip(tip: Tip, height: float) -> Tip:
    """``tip`` in units of the specimen's height."""
    return tip.scaled(1.0 / height) if tip.has_length_scale else tip


def table_key(specimen: Specimen, tip: Tip, nu: float, base: str,
              resolution: str = "default") -> dict:
    """The dimensionless key of a table (module docstring)."""
    unit = _unit_tip(tip, specimen.height)
    sizes = {name: float(getattr(unit, name)) for name in get_law(tip).parameters}
    return {"kind": "palpation", "version": TWIN_SOLVER_VERSION, "tip": tip.kind, **sizes,
            "radius_over_height": specimen.radius / specimen.height,
            "nu": round(float(nu), 6), "base": base, "resolution": resolution}


def twin_depth_limit(specimen: Specimen, tip: Tip) -> float:
    """[m] The deepest depth the twin's table solves: half the specimen's height, half the
    tip's depth limit (a sphere's radius), and a half-space contact radius at most half the
    footprint's equal-area radius, whichever is least (deeper, the table is continued)."""
    law = get_law(tip)
    h = specimen.height
    limit = 0.5 * h
    if law.max_depth is not None:
        limit = min(limit, 0.5 * law.max_depth(tip))
    if math.isinf(law.profile_exponent(tip)):
        return limit
    a_max = 0.5 * specimen.radius
    d = np.geomspace(limit * 1e-6, limit, 2000)
    a = law.contact_radius(d, tip)
    if a[-1] > a_max:
        limit = float(np.interp(a_max, a, d))
    return limit


def _depths_for_radii(tip: Tip, radii: np.ndarray, d_top: float) -> np.ndarray:
    law = get_law(tip)
    d = np.geomspace(d_top * 1e-8, d_top, 4000)
    return np.interp(radii, law.contact_radius(d, tip), d)


def _solve_table(specimen: Specimen, tip: Tip, nu: float, base: str, resolution: str
                 ) -> TwinTable:
    h = specimen.height
    unit = _unit_tip(tip, h)
    radius = specimen.radius / h
    law = get_law(tip)
    n = law.profile_exponent(tip)
    if math.isinf(n):
        curve = solve_palpation(radius, 1.0, unit, nu, base, np.array([1.0]), resolution)
        a = float(unit.radius)
        f = float(curve.shape[0] / (2.0 * a))
        f_layer = float(layer_solution.flat_punch_factor(a, nu, base))
        one = np.array([a])
        return TwinTable(True, one, np.log([f]), 0.0, a, one, np.array([f]),
                         np.array([f_layer]), curve.dofs)
    d_top = twin_depth_limit(specimen, tip) / h
    a_top = float(law.contact_radius(np.array([d_top]), unit)[0])
    radii = a_top * np.geomspace(_A_MIN, 1.0, _POINTS)
    depths = _depths_for_radii(unit, radii, d_top)
    depths[-1] = d_top
    curve = solve_palpation(radius, 1.0, unit, nu, base, depths, resolution)
    chi = law.contact_radius(depths, unit)
    half = law.shape(depths, unit)
    f_layer = layer_solution.profile_factor(chi, n, nu, base)
    f = curve.shape / half
    w = PchipInterpolator(np.r_[0.0, chi], np.r_[1.0, f / f_layer])
    grid = np.linspace(0.0, 2.0 * chi[-1], _GRID)
    logf = (np.log(layer_solution.profile_factor(grid, n, nu, base))
            + np.log(w(np.minimum(grid, chi[-1]))))
    slope = float((logf[-1] - logf[-9]) / math.log(grid[-1] / grid[-9]))
    return TwinTable(False, grid, logf, slope, float(chi[-1]), chi, f, f_layer, curve.dofs)


#: Tables of this process, by the text of their key.
_MEMORY: dict[str, TwinTable] = {}


def _table(key: dict, specimen: Specimen, tip: Tip, nu: float, base: str,
           resolution: str) -> TwinTable:
    text = key_text(key)
    table = _MEMORY.get(text)
    if table is None:
        stored = load_arrays(key)
        if stored is not None:
            table = TwinTable.from_arrays(stored)
        else:
            table = _solve_table(specimen, tip, nu, base, resolution)
            save_arrays(key, table.to_arrays())
        _MEMORY[text] = table
    return table


def _normalized(specimen: Specimen, tip: Tip, nu: float, base: str, resolution: str):
    """The key and the arguments of the table at unit height (the table is dimensionless,
    so equal keys give one table)."""
    h = specimen.height
    key = table_key(specimen, tip, nu, base, resolution)
    unit_specimen = Specimen(1.0, diameter=2.0 * specimen.radius / h)
    return key, unit_specimen, _unit_tip(tip, h), key["nu"], base


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


def _available(specimen: Specimen, tip: Tip, nu: float, base: str, resolution: str) -> bool:
    """True when the table is in memory or on disk (no finite elements to run)."""
    key = table_key(specimen, tip, nu, base, resolution)
    return key_text(key) in _MEMORY or load_arrays(key) is not None


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
    missing = [(nu, b) for nu, b in todo if not _available(specimen, tip, nu, b, resolution)]
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
