"""Graded grids for the twin's tensor meshes: fine where the contact is, coarse far from it.

A contact's stresses vary over the contact radius a; so near the axis the cells grow in
proportion to the distance from it (every contact radius a then sees about the same number of
cells, ~1/(growth − 1)), and beyond the contact they grow geometrically to the specimen's edge.
Under the surface the cells grow geometrically with depth.  A flat punch's edge is singular: its
grid is graded towards r = a from both sides, the smallest cell 1e-3·a (docs/design.md, the
specimen twin).  The compression test's bonded corner is graded likewise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Resolution", "RESOLUTIONS", "graded", "towards", "contact_grid", "punch_grid",
           "depth_grid", "compression_grid"]


@dataclass(frozen=True)
class Resolution:
    """How fine a twin's mesh is.

    Parameters
    ----------
    core
        Cells per unit of the distance from the axis near the contact (the growth of a cell
        to the next is 1 + 1/core).
    first
        Smallest cell at the axis and under the surface, as a fraction of the largest contact
        radius of the table.
    outer
        Growth of a cell to the next beyond the contact.
    vertical
        Growth of a cell to the next with depth under the surface.
    punch_first
        Smallest cell at a flat punch's edge (and a bonded corner), as a fraction of its
        radius (of the specimen's height).
    punch_growth
        Growth of the cells away from a punch's edge or a corner.
    """

    core: float = 12.5
    first: float = 0.01
    outer: float = 1.3
    vertical: float = 1.15
    punch_first: float = 1e-3
    punch_growth: float = 1.25


#: Named resolutions: ``default`` for fits (about 0.05 % from the closed forms it is checked
#: against), ``fine`` for the simulator (a finer mesh than the fit's: data are not drawn from
#: the model that fits them), ``coarse`` for quick checks.
RESOLUTIONS = {
    "coarse": Resolution(core=8.0, first=0.02, outer=1.4, vertical=1.25, punch_first=3e-3,
                         punch_growth=1.35),
    "default": Resolution(),
    "fine": Resolution(core=20.0, first=0.005, outer=1.2, vertical=1.1, punch_first=5e-4,
                       punch_growth=1.18),
}


def graded(start: float, stop: float, first: float, growth: float) -> np.ndarray:
    """Nodes from ``start`` to ``stop``, the first cell ``first`` long and each next one
    ``growth`` times the last (the last cell merged into its neighbour when it would be
    shorter than a third of it)."""
    if stop <= start:
        return np.array([start])
    x, h = [start], first
    while x[-1] < stop:
        x.append(x[-1] + h)
        h *= growth
    nodes = np.array(x)
    nodes[-1] = stop
    if nodes.size > 2 and nodes[-1] - nodes[-2] < (nodes[-2] - nodes[-3]) / 3:
        nodes = np.delete(nodes, -2)
    return nodes


def towards(point: float, lo: float, hi: float, first: float, growth: float) -> np.ndarray:
    """Nodes on [lo, hi] graded towards ``point`` from both sides."""
    left = point - graded(0.0, point - lo, first, growth)[::-1]
    right = point + graded(0.0, hi - point, first, growth)
    return np.unique(np.r_[left, right])


def contact_grid(a_top: float, radius: float, res: Resolution) -> np.ndarray:
    """Radial nodes on [0, radius] for contacts up to radius ``a_top``: cells ~ r/core near
    the contact (down to ``first``·a_top at the axis), geometric growth beyond 1.3·a_top."""
    h0 = res.first * a_top
    reach = min(1.3 * a_top, radius)
    core = [0.0, h0]
    while core[-1] < reach:
        core.append(core[-1] + max(h0, core[-1] / res.core))
    core = np.array(core)
    if core[-1] >= radius:
        core = np.r_[core[core < radius], radius]
        return core
    return np.unique(np.r_[core, graded(core[-1], radius, core[-1] - core[-2], res.outer)])


def punch_grid(a: float, radius: float, res: Resolution) -> np.ndarray:
    """Radial nodes on [0, radius] graded towards a flat punch's edge r = a."""
    return towards(a, 0.0, radius, res.punch_first * a, res.punch_growth)


def depth_grid(height: float, first: float, res: Resolution) -> np.ndarray:
    """Vertical nodes on [0, height] (the top surface at ``height``), cells from ``first`` at
    the top growing by ``res.vertical`` downwards."""
    z = height - graded(0.0, height, first, res.vertical)[::-1]
    z[0] = 0.0
    return z


def compression_grid(radius: float, half_height: float, res: Resolution
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Nodes of the compression test's half (the mid-plane at z = 0, the platen at
    ``half_height``): graded towards the platen's edge, the singular corner."""
    h = 2.0 * half_height
    first = res.punch_first * min(radius, h)
    r = radius - graded(0.0, radius, first, res.punch_growth)[::-1]
    r[0] = 0.0
    z = half_height - graded(0.0, half_height, first, res.punch_growth)[::-1]
    z[0] = 0.0
    return r, z
