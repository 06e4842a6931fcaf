"""Meshes of the 3-D yardstick (:mod:`.solid3d`): the quarter footprint's O-grid around the
tip's axis extruded over the block's height, the compression test's eighth block, their named
resolutions, and a nested-dissection order of their nodes for the direct solver.

The footprint's curved cells are isoparametric (:class:`skfem.MeshHex2`): rings on exact
circles out to the contact zone's edge (a flat punch's edge r = a is one of them), then rings
blending from the circles into the rectangle's edges.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree
from skfem import MeshHex, MeshHex2

from ..errors import GeometryError
from .mesh import graded

__all__ = ["Resolution3D", "RESOLUTIONS_3D", "resolution_3d", "footprint_mesh",
           "compression_mesh", "towards_top", "nested_dissection"]


@dataclass(frozen=True)
class Resolution3D:
    """How fine a 3-D mesh is.

    Parameters
    ----------
    per_radius
        Rings per contact radius in a curved tip's contact zone.
    angular
        Cells per 45° around the axis.
    core
        Radius of the core block around the axis, as a fraction of a curved tip's contact
        radius (a flat punch's core is half its radius).
    outer
        Growth of a ring to the next beyond the contact zone.
    top
        First cell under the top face, as a fraction of the contact radius (curved tips).
    vertical
        Growth of a cell to the next with depth (curved tips; under a flat punch
        ``punch_growth``).
    punch_first
        Smallest cell at a flat punch's edge (radially and under the face), as a fraction
        of its radius.
    punch_growth
        Growth of the cells away from the punch's edge.
    platen_first
        Compression: smallest cell at the platen's edges, as a fraction of the height.
    platen_growth
        Compression: growth of the cells away from the platen's edges.
    """

    per_radius: float = 12.0
    angular: int = 4
    core: float = 0.4
    outer: float = 1.6
    top: float = 0.15
    vertical: float = 1.5
    punch_first: float = 0.02
    punch_growth: float = 1.6
    platen_first: float = 0.01
    platen_growth: float = 1.4


#: Named resolutions (``benchmarks/bench_twin_3d.py`` measures their cost and accuracy):
#: ``default`` for the measurements, ``fine`` finer where the results move (the contact
#: zone's rings, the punch's edge, the platen's edges; halving the angular, vertical and
#: outer cells moved a block's width effect by less than 0.03 %), ``coarse`` for quick
#: checks.
RESOLUTIONS_3D = {
    "coarse": Resolution3D(per_radius=8.0, angular=3, outer=1.8, top=0.2, vertical=1.6,
                           punch_first=0.03, punch_growth=1.7, platen_first=0.03,
                           platen_growth=1.6),
    "default": Resolution3D(),
    "fine": Resolution3D(per_radius=18.0, punch_first=0.01, punch_growth=1.45,
                         platen_first=0.005, platen_growth=1.3),
}


def resolution_3d(resolution: str | Resolution3D) -> Resolution3D:
    if isinstance(resolution, Resolution3D):
        return resolution
    try:
        return RESOLUTIONS_3D[resolution]
    except KeyError:
        raise GeometryError(f"unknown 3-D resolution {resolution!r}; use one of "
                            f"{', '.join(RESOLUTIONS_3D)} or a Resolution3D") from None



def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[0] * v[1] - u[1] * v[0]


class _Footprint:
    """The quarter footprint's O-grid (module docstring): a continuous map of each block's
    logical coordinates, so that the quadratic nodes of every cell lie on the same curves."""

    def __init__(self, half_length: float, half_width: float, circles: np.ndarray,
                 outer: np.ndarray, angular: int) -> None:
        self.x_max, self.y_max = float(half_length), float(half_width)
        self.circles = np.asarray(circles, dtype=float)  # r_0 = core radius b < ... < R_c
        self.outer = np.asarray(outer, dtype=float)  # fractions (0, 1] from R_c to the edge
        b = self.circles[0]
        self.theta_c = math.atan2(self.y_max, self.x_max)
        self.n_a = max(2, round(angular * self.theta_c / (math.pi / 4)))
        self.n_b = max(2, round(angular * (math.pi / 2 - self.theta_c) / (math.pi / 4)))
        self.p1 = np.array([b, 0.0])
        self.p2 = np.array([0.0, b])
        self.pc = 0.8 * math.sqrt(2.0) * b * np.array([math.cos(self.theta_c),
                                                       math.sin(self.theta_c)])
        # parameters of the inner edges' nodes (rays at uniform angles)
        th = np.linspace(0.0, self.theta_c, self.n_a + 1)
        u = np.array([np.cos(th), np.sin(th)])
        self.eta = -_cross(u, self.p1[:, None]) / _cross(u, (self.pc - self.p1)[:, None])
        th = np.linspace(self.theta_c, math.pi / 2, self.n_b + 1)
        u = np.array([np.cos(th), np.sin(th)])
        self.zeta = -_cross(u, self.pc[:, None]) / _cross(u, (self.p2 - self.pc)[:, None])
        self.eta[[0, -1]] = 0.0, 1.0
        self.zeta[[0, -1]] = 0.0, 1.0
        self.blend = 2.0 * b  # circles are exact from here on
        self.n_levels = self.circles.size + self.outer.size

    def _levels(self, q: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Points at the (fractional) radial level ``s`` on the rays through the inner-edge
        points ``q`` (2, n)."""
        rho_in = np.hypot(q[0], q[1])
        theta = np.arctan2(q[1], q[0])
        b, rc = self.circles[0], self.circles[-1]
        with np.errstate(divide="ignore"):
            rho_out = np.minimum(self.x_max / np.cos(theta), self.y_max / np.sin(theta))
        w = np.clip(1.0 - (self.circles - b) / (self.blend - b), 0.0, 1.0)
        inner = self.circles[:, None] + (rho_in - b)[None, :] * w[:, None]
        inner[0] = rho_in
        outer = rc + self.outer[:, None] * (rho_out - rc)[None, :]
        levels = np.vstack([inner, outer])  # (n_levels, n)
        lo = np.clip(np.floor(s).astype(int), 0, self.n_levels - 2)
        f = s - lo
        cols = np.arange(s.size)
        rho = (1.0 - f) * levels[lo, cols] + f * levels[lo + 1, cols]
        return rho * np.array([np.cos(theta), np.sin(theta)])

    @staticmethod
    def _param(j: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        return np.interp(j, np.arange(nodes.size, dtype=float), nodes)

    def map_a(self, lp: np.ndarray) -> np.ndarray:
        eta = self._param(lp[1], self.eta)
        q = self.p1[:, None] + eta[None, :] * (self.pc - self.p1)[:, None]
        return self._levels(q, lp[0])

    def map_b(self, lp: np.ndarray) -> np.ndarray:
        zeta = self._param(lp[1], self.zeta)
        q = self.pc[:, None] + zeta[None, :] * (self.p2 - self.pc)[:, None]
        return self._levels(q, lp[0])

    def map_core(self, lp: np.ndarray) -> np.ndarray:
        xi = self._param(lp[0], 1.0 - self.zeta[::-1])
        eta = self._param(lp[1], self.eta)
        return (np.outer(self.p1, xi * (1 - eta)) + np.outer(self.pc, xi * eta)
                + np.outer(self.p2, (1 - xi) * eta))

    def blocks(self) -> list[tuple[np.ndarray, np.ndarray, Callable]]:
        """(logical x nodes, logical y nodes, map) of the core and the two ring blocks."""
        levels = np.arange(self.n_levels, dtype=float)
        return [(np.arange(self.n_b + 1.0), np.arange(self.n_a + 1.0), self.map_core),
                (levels, np.arange(self.n_a + 1.0), self.map_a),
                (levels, np.arange(self.n_b + 1.0), self.map_b)]


def _merge_points(points: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """(index of one representative, label) of every cluster of ``points`` (d, n) closer
    than ``tol``."""
    pairs = cKDTree(points.T).query_pairs(tol, output_type="ndarray")
    n = points.shape[1]
    graph = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    first = np.full(label.max() + 1, n)
    np.minimum.at(first, label, np.arange(n))
    return first, label


def footprint_mesh(half_length: float, half_width: float, circles: np.ndarray,
                   outer: np.ndarray, z_nodes: np.ndarray, angular: int) -> MeshHex2:
    """The quarter block [0, ``half_length``] × [0, ``half_width``] × [z_0, z_n] [L] as an
    O-grid (module docstring) with quadratic geometry.

    Parameters
    ----------
    half_length, half_width
        Half the block's footprint [L] (any length unit L).
    circles
        Radii [L] of the rings, increasing: the first is the core block's radius, the last
        (below both half sizes) the edge of the zone of exact circles.
    outer
        Fractions (0, 1], increasing to 1, of the way from the last circle to the block's
        edge at which the outer rings lie.
    z_nodes
        Increasing heights [L] of the layers.
    angular
        Cells per 45° around the axis.
    """
    fp = _Footprint(half_length, half_width, circles, outer, angular)
    z_nodes = np.asarray(z_nodes, dtype=float)
    scale = max(half_length, half_width, z_nodes[-1] - z_nodes[0])
    verts, ts, straight, exact = [], [], [], []
    offset = 0
    for lx, ly, fmap in fp.blocks():
        logical = MeshHex.init_tensor(lx, ly, z_nodes)
        p = logical.p.copy()
        p[:2] = fmap(p[:2])
        phys = MeshHex(p, logical.t)
        q = MeshHex2.from_mesh(logical).doflocs.copy()
        q[:2] = fmap(q[:2])
        verts.append(p)
        ts.append(logical.t + offset)
        offset += p.shape[1]
        straight.append(MeshHex2.from_mesh(phys).doflocs)
        exact.append(q)
    first, label = _merge_points(np.hstack(verts), 1e-9 * scale)
    merged = MeshHex(np.ascontiguousarray(np.hstack(verts)[:, first]),
                     np.ascontiguousarray(label[np.hstack(ts)]))
    quad = MeshHex2.from_mesh(merged)
    dist, idx = cKDTree(np.hstack(straight).T).query(quad.doflocs.T)
    if dist.max() > 1e-9 * scale:
        raise RuntimeError("footprint mesh: quadratic nodes do not match their blocks'")
    return MeshHex2(np.ascontiguousarray(np.hstack(exact)[:, idx]), quad.t)


def compression_mesh(half_length: float, half_width: float, half_height: float,
                     res: Resolution3D) -> MeshHex:
    """The eighth block [0, ``half_length``] × [0, ``half_width``] × [0, ``half_height``]
    [L], graded towards the platen's edges x = half_length, y = half_width, z = half_height."""
    first = res.platen_first * 2.0 * half_height

    def towards_end(stop: float) -> np.ndarray:
        nodes = stop - graded(0.0, stop, first, res.platen_growth)[::-1]
        nodes[0] = 0.0
        return nodes

    return MeshHex.init_tensor(towards_end(half_length), towards_end(half_width),
                               towards_end(half_height))


def towards_top(height: float, first: float, growth: float) -> np.ndarray:
    z = height - graded(0.0, height, first, growth)[::-1]
    z[0] = 0.0
    return z


def nested_dissection(element_nodes: np.ndarray, centroids: np.ndarray, n_nodes: int,
                       leaf: int = 16) -> np.ndarray:
    """A nested-dissection order of the nodes: the elements split across one axis near their
    median centroid (the axis and quantile of the smallest separator), the nodes both halves
    share (the separator) numbered after them, recursively."""
    in_l = np.zeros(n_nodes, dtype=bool)
    in_r = np.zeros(n_nodes, dtype=bool)

    def split(elements: np.ndarray, nodes: np.ndarray) -> list | None:
        best = None
        for key in centroids[:, elements]:
            for q in (0.35, 0.425, 0.5, 0.575, 0.65):
                left = key < np.quantile(key, q)
                if left.all() or not left.any():
                    continue
                el, er = elements[left], elements[~left]
                in_l[element_nodes[:, el].ravel()] = True
                in_r[element_nodes[:, er].ravel()] = True
                a, b = in_l[nodes], in_r[nodes]
                in_l[element_nodes[:, el].ravel()] = False
                in_r[element_nodes[:, er].ravel()] = False
                sep = nodes[a & b]
                if best is None or sep.size < best[2].size:
                    best = [(el, nodes[a & ~b]), (er, nodes[b & ~a]), sep]
        return best

    # post-order: each half's nodes, then their separator
    stack: list = [(np.arange(element_nodes.shape[1]), np.unique(element_nodes))]
    order: list[np.ndarray] = []
    while stack:
        item = stack.pop()
        if isinstance(item, np.ndarray):
            order.append(item)
            continue
        elements, nodes = item
        parts = split(elements, nodes) if nodes.size > leaf and elements.size > 1 else None
        if parts is None:
            order.append(nodes)
        else:
            stack.extend(parts[::-1])  # the left half popped first, the separator last
    return np.concatenate(order)
