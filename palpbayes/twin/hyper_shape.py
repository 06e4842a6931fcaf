"""A hyperelastic law in a fit's contact model: its shape function F/E* from the finite-strain
twin's table (issue 56, item 4).

At fixed shape parameters and Poisson ratio the force of every registered law is linear in the
small-strain modulus, F = E0·Phi(d; shape, nu) (:mod:`.hyper_table`), so a fit with a law is
the paper's model with another shape function: with E* = E0/(1 − nu²),

    s(d) = F/E* = Phi(d; shape, nu)·(1 − nu²),

and E = E*·(1 − nu²) is E0.  :class:`LawModel` says which law, which shape parameters are fixed
and which are a grid of finite-element nodes (a fit then mixes over them:
:mod:`palpbayes.bayes.lawmix`), how deep its table reaches and on which mesh;
:func:`law_shape` evaluates s(d) of a concrete one on the geometry of the fit:

=====================  ======================================================================
the fit's geometry     the twin the law is solved on
=====================  ======================================================================
the specimen as        its equal-area cylinder (:class:`~.specimen.Specimen`), on the fit's
tested (--specimen)    base, as the linear twin
a known thickness h    a wide cylinder of height h: radius max(:data:`WIDE_CONTACT` × the
                       half-space contact radius at the table's deepest depth,
                       :data:`WIDE_HEIGHT` × h); measured with the linear twin against the
                       infinitely wide layer (:mod:`palpbayes.contact.layer`): within 0.2 %
                       (sphere, paraboloid, flat punch on 20-30 mm, both bases; the free base
                       reads 0.75 % low at a radius of 1.7 h, 0.16 % at 3.5 h)
neither (a half-space) a bonded cylinder :data:`PROXY_DEPTH` contact radii deep and
                       :data:`WIDE_HEIGHT` times as wide, whose bottom effect is divided out by
                       the infinite layer's (:func:`palpbayes.contact.thickness_factor` at
                       chi = 1/PROXY_DEPTH: 1.5-2.5 % at the deepest depth); what is left is
                       the cross term of finite strain and the bottom effect: against a proxy
                       twice as deep, neo-Hookean sphere at a/R 0.8, 0.17 % at nu 0 and
                       0.04 % at nu 0.3 (coarse mesh; 0.5 % for a proxy half as deep);
                       against Hertz and Sneddon at small depth (d/L 0.0025-0.01, extrapolated
                       to d = 0, default mesh, nu 0.3 and 0.45): -0.16 to -0.11 % (sphere,
                       paraboloid), +0.18 to +0.21 % (flat punch): ``benchmarks/bench_law_fit.py
                       --proxy``
=====================  ======================================================================

Depths: a table reaches :data:`DEPTH_MARGIN` times the fitted indentation rounded up to a power
of 2^(1/4) (:func:`table_depth`), so that traces of one experiment share their tables (each
curve is cached on disk, :mod:`.cache`); deeper, the table continues its last power law, which
only trial surfaces above the data's onset ask for.

``mode="correction"`` is the model form's cheap neo-Hookean reading of a linear fit
(:mod:`.hyper_correction`): the linear model's own shape times the neo-Hookean half-space's
F/F_linear, shipped as a table, no finite elements at fit time.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np

from ..contact import Tip, get_law, thickness_factor, youngs_factor
from ..errors import GeometryError, InputError
from ..material import MaterialLaw, material_law
from ..specimen import Specimen

__all__ = ["LawModel", "law_shape", "law_table", "law_block", "table_depth", "DEPTH_MARGIN",
           "WIDE_CONTACT", "WIDE_HEIGHT", "PROXY_DEPTH", "LAW_MODES", "LAW_MESHES", "nu_of",
           "INSTRON_STRAIN"]

#: The twin's meshes a law may be solved on: the keys of
#: :data:`~.hyper_palpation.HYPER_RESOLUTIONS`, written out so that a model with a law does
#: not load the finite elements until it is evaluated (a test holds them equal).
LAW_MESHES = ("coarse", "default", "fine")

#: The table's deepest depth over the fitted indentation (before rounding up).
DEPTH_MARGIN = 1.25
#: Depths are rounded up to a power of this factor (traces of one experiment share a table).
_LADDER = 2.0 ** 0.25
#: A known thickness's wide cylinder: its radius is at least this many half-space contact
#: radii at the table's deepest depth ...
WIDE_CONTACT = 10.0
#: ... and at least this many times its height (the half-space proxy: its width over height).
WIDE_HEIGHT = 4.0
#: The half-space proxy's height in half-space contact radii at the table's deepest depth.
PROXY_DEPTH = 40.0
#: The paper's Instron test, nominally: 5 mm of compression on 20-30 mm blocks.
INSTRON_STRAIN = 0.2
#: How a law's shape is computed: on the fit's own geometry (``twin``) or as the linear model
#: times the shipped neo-Hookean half-space correction (``correction``, the model form's).
LAW_MODES = ("twin", "correction")


def table_depth(depth: float) -> float:
    """[m] The deepest depth of a law's table for a fitted indentation ``depth`` [m]:
    :data:`DEPTH_MARGIN` times it, rounded up to a power of 2^(1/4)."""
    d = DEPTH_MARGIN * float(depth)
    if not (math.isfinite(d) and d > 0):
        raise InputError(f"indentation depth {depth!r} m must be positive to tabulate a "
                         "material law")
    top = _LADDER ** math.ceil(math.log(d, _LADDER))
    while top < d * (1 - 1e-12):
        top *= _LADDER
    return float(top)


@dataclass(frozen=True)
class LawModel:
    """A registered hyperelastic law in a fit's contact model (module docstring).

    Attributes
    ----------
    name
        The law's registry name (:func:`palpbayes.material.law_names`, not ``linear``).
    nodes
        (name, nodes) of every shape parameter: one node when it is fixed, the finite-element
        nodes of its grid when the fit mixes over it (its uniform prior spans the first to the
        last node).  A foam's ``nu`` is left out when fixed (the model's own nu is then it).
    point
        (name, value) of the free parameters (more than one node) at which the model is
        concrete; None: not concrete (a mixture over them).
    depth
        [m] The table's deepest depth (:func:`table_depth`).
    resolution
        The twin's mesh (:data:`~.hyper_palpation.HYPER_RESOLUTIONS`).
    mode
        ``"twin"`` or ``"correction"`` (:data:`LAW_MODES`).
    instron_strain
        [-] The nominal compressive strain of the Instron-equivalent chord modulus a fit
        reports (``E_instron_law_pa``, :mod:`palpbayes.bayes.lawfit`; not part of the
        shape).
    """

    name: str
    nodes: tuple[tuple[str, tuple[float, ...]], ...] = ()
    point: tuple[tuple[str, float], ...] | None = ()
    depth: float = math.nan
    resolution: str = "default"
    mode: str = "twin"
    instron_strain: float = INSTRON_STRAIN

    def __post_init__(self) -> None:
        law = material_law(self.name)
        object.__setattr__(self, "name", law.name)
        if self.resolution not in LAW_MESHES:
            raise InputError(f"unknown law mesh {self.resolution!r}; use one of "
                             f"{', '.join(LAW_MESHES)}")
        if not 0.0 < float(self.instron_strain) < 0.95:
            raise InputError(f"--instron-strain {self.instron_strain!r} must be a compressive "
                             "strain in (0, 0.95), e.g. 0.2 for 5 mm of a 25 mm block")
        if self.mode not in LAW_MODES:
            raise InputError(f"unknown law mode {self.mode!r}; use one of {', '.join(LAW_MODES)}")
        known = {s.name for s in law.shape}
        nodes = tuple((str(n), tuple(float(v) for v in grid)) for n, grid in self.nodes)
        for n, grid in nodes:
            if n not in known:
                raise InputError(f"the {law.title} law has no shape parameter {n!r}; it has "
                                 f"{', '.join(sorted(known)) or 'none'}")
            if not grid or not all(math.isfinite(v) for v in grid) or any(
                    b <= a for a, b in zip(grid, grid[1:], strict=False)):
                raise InputError(f"the nodes of {n} must be finite and increasing")
        object.__setattr__(self, "nodes", nodes)
        if self.point is not None:
            point = tuple((str(n), float(v)) for n, v in self.point)
            grids = dict(nodes)
            if sorted(n for n, _ in point) != sorted(self.free):
                raise InputError(f"a concrete {law.title} model gives a value to each free "
                                 f"shape parameter ({', '.join(self.free) or 'none'})")
            for n, v in point:
                if not grids[n][0] <= v <= grids[n][-1]:
                    raise InputError(f"{n} = {v:g} lies outside its nodes "
                                     f"[{grids[n][0]:g}, {grids[n][-1]:g}]")
            object.__setattr__(self, "point", point)

    @property
    def law(self) -> MaterialLaw:
        """The registry entry."""
        return material_law(self.name)

    @property
    def free(self) -> tuple[str, ...]:
        """The shape parameters the fit mixes over (more than one node)."""
        return tuple(n for n, grid in self.nodes if len(grid) > 1)

    @property
    def is_concrete(self) -> bool:
        """True when every free shape parameter has its value (one shape function)."""
        return self.point is not None

    def at(self, point: Mapping[str, float]) -> LawModel:
        """The concrete model at the free parameters' values ``point``."""
        return replace(self, point=tuple((n, float(point[n])) for n in self.free))

    def values(self) -> dict[str, float]:
        """Every shape parameter's value of a concrete model (fixed ones and the point)."""
        if self.point is None:
            raise InputError(f"the {self.law.title} model mixes over "
                             f"{', '.join(self.free)}: take a concrete one (LawModel.at)")
        out = {n: grid[0] for n, grid in self.nodes}
        out.update(dict(self.point))
        return out

    def foam_nu(self) -> float | None:
        """A foam's Poisson ratio when it is a parameter of this model with a value (fixed
        or the point's), else None (not a foam, or nu the model's own)."""
        name = self.law.nu_parameter
        if name is None or name not in dict(self.nodes):
            return None
        if name in self.free:
            return None if self.point is None else dict(self.point)[name]
        return dict(self.nodes)[name][0]

    def describe(self) -> str:
        """The law and its shape in words: ``'neo-Hookean'``, ``'hyperfoam (1 term),
        alpha_1 in [4, 12], nu 0.1'``."""
        parts = []
        point = dict(self.point or ())
        for n, grid in self.nodes:
            if len(grid) == 1:
                parts.append(f"{n} {grid[0]:g}")
            elif n in point:
                parts.append(f"{n} {point[n]:.4g}")
            else:
                parts.append(f"{n} in [{grid[0]:g}, {grid[-1]:g}]")
        text = ", ".join([self.law.title] + parts)
        return text + (" (half-space correction)" if self.mode == "correction" else "")


def nu_of(law: LawModel, nu: float) -> float:
    """[-] The small-strain Poisson ratio of a concrete law model whose fit states ``nu``: a
    foam's own when it is a parameter, else ``nu``."""
    own = law.foam_nu()
    return float(nu) if own is None else own


def _contact_radius(tip: Tip, depth: float) -> float:
    law = get_law(tip)
    if law.contact_radius is None:
        raise GeometryError(f"the {tip.kind} tip has no contact radius: a material law needs "
                            "a tip with a profile")
    return float(law.contact_radius(np.array([depth]), tip)[0])


def law_block(tip: Tip, depth: float, thickness: float | None,
              specimen: Specimen | None) -> tuple[Specimen, bool]:
    """(the cylinder the twin solves, True for the half-space proxy) of a fit's geometry
    (module docstring) for a table reaching ``depth`` [m]."""
    if specimen is not None:
        return specimen, False
    a = _contact_radius(tip, depth)
    if thickness is not None:
        h = float(thickness)
        return Specimen(h, diameter=2.0 * max(WIDE_CONTACT * a, WIDE_HEIGHT * h)), False
    h = PROXY_DEPTH * a
    return Specimen(h, diameter=2.0 * WIDE_HEIGHT * h), True


@functools.lru_cache(maxsize=64)
def _table(law: LawModel, tip: Tip, nu: float, block: Specimen, base: str):
    from .hyper_table import prepare_hyper_table  # the finite elements, when first needed

    nodes = {n: list(grid) for n, grid in law.nodes}
    return prepare_hyper_table(law.law, block, tip, float(nu), base, nodes,
                               max_depth=law.depth, resolution=law.resolution)


def _bracket(nodes, point: dict[str, float]) -> tuple:
    """Each free parameter's nodes cut to the one or two around its value in ``point``."""
    out = []
    for n, grid in nodes:
        if n in point and len(grid) > 1:
            g = np.asarray(grid)
            i = int(np.searchsorted(g, point[n]))
            if i < g.size and np.isclose(g[i], point[n], rtol=0, atol=1e-12):
                grid = (grid[i],)
            else:
                i = int(np.clip(i - 1, 0, g.size - 2))
                grid = (grid[i], grid[i + 1])
        out.append((n, tuple(grid)))
    return tuple(out)


def law_table(law: LawModel, tip: Tip, nu: float, thickness: float | None,
              specimen: Specimen | None, base: str) -> tuple:
    """The :class:`~.hyper_table.HyperTable` of ``law`` (every node of its grid; at a
    concrete point of a grid the nodes around it, all its interpolation needs) on the fit's
    geometry, its cylinder and whether that is the half-space proxy (:func:`law_block`);
    built once per process (and solved once per disk cache, a progress bar on stderr while
    curves are solved on a terminal).  ``nu`` is the model's (a foam's fixed nu)."""
    block, proxy = law_block(tip, law.depth, thickness, specimen)
    key = replace(law, point=None if law.free else (), instron_strain=INSTRON_STRAIN)
    if law.free and law.point is not None:  # a concrete point: the nodes around it suffice
        key = replace(key, nodes=_bracket(law.nodes, dict(law.point)))
    name = law.law.nu_parameter
    if name is not None:  # a foam's solid takes its nu from its parameters
        if name not in dict(law.nodes):
            key = replace(key, nodes=key.nodes + ((name, (float(nu),)),))
        nu = 0.0
    return _table(key, tip, round(float(nu), 9), block, "bonded" if proxy else base), block, proxy


def law_shape(depth, tip: Tip, nu: float, law: LawModel, thickness: float | None = None,
              specimen: Specimen | None = None, base: str = "bonded") -> np.ndarray:
    """F/E* [m²] at ``depth`` [m] of a concrete law model in ``mode`` ``"twin"`` (module
    docstring): Phi(d; shape, nu)·(1 − nu²) on the fit's geometry, 0 at depth <= 0; NaN
    where a node of the table did not converge."""
    d = np.asarray(depth, dtype=float)
    table, block, proxy = law_table(law, tip, nu, thickness, specimen, base)
    nu0 = nu_of(law, nu)
    values = law.values()
    if law.law.nu_parameter is not None:
        values.setdefault(law.law.nu_parameter, nu0)
    out = table.force(d, 1.0, values) * youngs_factor(nu0)
    if proxy:
        pos = d > 0
        out[pos] = out[pos] / thickness_factor(d[pos], tip, block.height, nu0, "bonded")
    return out
