"""The regular palpation lattice: nodes, inference from positions, graph Laplacian, padding.

A stiffness map is palpated on a regular grid: node (ix, iy) sits at
``(x0 + ix·step, y0 + iy·step)`` [m], ``ix = 0 … nx − 1``, ``iy = 0 … ny − 1``, and is numbered
``iy·nx + ix`` (row-major), so a vector over the nodes reshapes to an ``(ny, nx)`` image.  One
step serves both axes; a grid palpated with different x and y spacings is represented on the
finer one when the coarser is a multiple of it (the extra nodes carry no data), else the
caller passes a common divisor as ``step``.

:func:`lattice_from_positions` infers the grid from the palpation positions,
:func:`laplacian` is the 5-point graph Laplacian with free (Neumann) boundary that the
field prior of :mod:`palpbayes.maps.gmrf` is built from, and :func:`pad` surrounds a lattice
with a margin of nodes without data.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..errors import InputError

__all__ = ["Lattice", "lattice_from_positions", "laplacian", "laplacian_eigenvalues", "pad",
           "MAX_NODES", "COORDINATE_DIGITS", "clean_coordinates"]

#: Largest lattice :func:`lattice_from_positions` builds (an outlying position or a wrong
#: ``step`` otherwise asks for an absurd grid).
MAX_NODES = 1_000_000

#: Digits kept below the lattice step in node coordinates: a coordinate is rounded to
#: 10**-COORDINATE_DIGITS of the step's order of magnitude (1e-12 m for a 3 mm step, 1e-15 m
#: for a 5 µm AFM step), far below any palpation's positioning and far above the
#: floating-point residue of ``x0 + ix·step`` (a node at 0 written as -2.7e-18).
COORDINATE_DIGITS = 9


def clean_coordinates(v, step: float) -> np.ndarray:
    """Coordinates ``v`` [m] rounded to :data:`COORDINATE_DIGITS` digits below ``step`` [m].

    Removes the floating-point residue of the grid arithmetic, so a node at 0 is 0.0 (not
    -2.7e-18, nor -0.0) and one at 9 mm is 0.009 (not 0.009000000000000001).

    Parameters
    ----------
    v
        Coordinates [m] (a number or an array).
    step
        The lattice step [m] (positive, finite).

    Returns
    -------
    numpy.ndarray
        The rounded coordinates [m], float, the shape of ``v``.
    """
    decimals = COORDINATE_DIGITS - math.floor(math.log10(step))
    return np.round(np.asarray(v, dtype=float), decimals) + 0.0  # + 0.0: -0.0 becomes 0.0


@dataclass(frozen=True)
class Lattice:
    """A regular square lattice.

    Attributes
    ----------
    x0, y0
        Position of node (0, 0) [m].
    step
        Node spacing along x and y [m].
    nx, ny
        Number of nodes along x and y.
    """

    x0: float
    y0: float
    step: float
    nx: int
    ny: int

    def __post_init__(self) -> None:
        if not (np.isfinite(self.step) and self.step > 0):
            raise InputError(f"lattice step must be a positive length in metres, got {self.step!r}")
        if self.nx < 1 or self.ny < 1:
            raise InputError(f"lattice needs at least one node per axis, got {self.nx} × {self.ny}")

    @property
    def n_nodes(self) -> int:
        """Number of nodes, nx·ny."""
        return self.nx * self.ny

    @property
    def xs(self) -> np.ndarray:
        """x of the lattice's columns [m] (length ``nx``; :func:`clean_coordinates`)."""
        return clean_coordinates(self.x0 + self.step * np.arange(self.nx), self.step)

    @property
    def ys(self) -> np.ndarray:
        """y of the lattice's rows [m] (length ``ny``; :func:`clean_coordinates`)."""
        return clean_coordinates(self.y0 + self.step * np.arange(self.ny), self.step)

    @property
    def node_x(self) -> np.ndarray:
        """x of every node [m], in node order (length ``n_nodes``)."""
        return np.tile(self.xs, self.ny)

    @property
    def node_y(self) -> np.ndarray:
        """y of every node [m], in node order (length ``n_nodes``)."""
        return np.repeat(self.ys, self.nx)

    def index(self, ix, iy):
        """Node number(s) ``iy·nx + ix`` of column ``ix`` and row ``iy`` (ints or arrays)."""
        ix, iy = np.asarray(ix), np.asarray(iy)
        if np.any((ix < 0) | (ix >= self.nx) | (iy < 0) | (iy >= self.ny)):
            raise InputError(f"node ({ix}, {iy}) is outside the {self.nx} × {self.ny} lattice")
        out = iy * self.nx + ix
        return int(out) if out.ndim == 0 else out


def _centres(v: np.ndarray, gap: float) -> np.ndarray:
    """Medians of the clusters of sorted coordinates ``v`` separated by more than ``gap``."""
    s = np.sort(v)
    cut = np.flatnonzero(np.diff(s) > gap) + 1
    return np.array([np.median(c) for c in np.split(s, cut)])


def _infer_step(x: np.ndarray, y: np.ndarray) -> float:
    pts = np.unique(np.column_stack([x, y]), axis=0)
    extent = float(np.ptp(pts, axis=0).max())
    k = min(len(pts), 9)
    d, _ = cKDTree(pts).query(pts, k=k)
    d = np.where(d > 1e-9 * extent, d, np.inf).min(axis=1)
    h0 = float(np.median(d[np.isfinite(d)]))
    cx, cy = _centres(x, 0.5 * h0), _centres(y, 0.5 * h0)
    gaps = np.concatenate([np.diff(cx), np.diff(cy)])
    near = gaps[(gaps > 0.5 * h0) & (gaps < 1.5 * h0)]  # neighbouring columns and rows
    h1 = float(np.median(near)) if near.size else h0
    # refine with least squares over the column/row centres (jitter averages out)
    kx, ky = np.round((cx - cx[0]) / h1), np.round((cy - cy[0]) / h1)
    k_all = np.concatenate([kx - kx.mean(), ky - ky.mean()])
    c_all = np.concatenate([cx - cx.mean(), cy - cy.mean()])
    return float(k_all @ c_all / (k_all @ k_all))


def _origin(v: np.ndarray, step: float) -> float:
    """Grid phase of coordinates ``v``: circular mean of ``v`` modulo ``step``, put at min(v)."""
    ang = 2 * np.pi * v / step
    phase = np.angle(np.mean(np.exp(1j * ang))) * step / (2 * np.pi)
    return float(phase + step * np.round((v.min() - phase) / step))


def lattice_from_positions(x, y, *, step: float | None = None, tol: float = 0.25,
                           line: bool = False) -> tuple[Lattice, np.ndarray]:
    """Infer the regular lattice of palpation positions and each observation's node.

    Parameters
    ----------
    x, y
        Palpation positions [m], one per observation, in any order; several observations may
        share a position, and grid nodes may have none.
    step
        Node spacing [m]; default: inferred — the median distance from each position to its
        nearest distinct neighbour, refined by least squares over the column and row centres.
        Pass it when the positions do not show it (e.g. only diagonal neighbours, or x and y
        spacings that are not multiples of one another).
    tol
        Largest accepted distance of a position from its node along x or y, in steps.
    line
        Accept positions on a single row or column (a line scan, e.g. an AFM's QI line):
        a lattice of one node across.

    Returns
    -------
    lattice
        The smallest lattice holding every position; an inferred step and the origin are
        rounded by :func:`clean_coordinates` (a grid starting at 0 starts at 0.0, not at the
        circular mean's residue of -2.7e-18 m).
    node
        Node number of each observation (int array, same length as ``x``).

    Raises
    ------
    InputError
        NaN or infinite positions, fewer than two distinct positions, fewer than two along x
        or along y (a single line is not a map) unless ``line``, a position more than
        ``tol``·step off the grid (the first such position is named), or a lattice of more
        than :data:`MAX_NODES` nodes.
    """
    x, y = np.asarray(x, dtype=float).ravel(), np.asarray(y, dtype=float).ravel()
    if x.shape != y.shape:
        raise InputError(f"x and y must have the same length, got {x.size} and {y.size}")
    bad = np.flatnonzero(~(np.isfinite(x) & np.isfinite(y)))
    if bad.size:
        i = int(bad[0])
        raise InputError(f"position {i} is ({x[i]}, {y[i]}): positions must be finite numbers "
                         f"(drop or fix the {bad.size} observation(s) without a position)")
    if not 0 < tol < 0.5:
        raise InputError(f"tol must be in (0, 0.5) steps, got {tol}")
    if step is not None and not (np.isfinite(step) and step > 0):
        raise InputError(f"step must be a positive length in metres, got {step!r}")
    if np.unique(np.column_stack([x, y]), axis=0).shape[0] < 2:
        raise InputError(f"{x.size} observation(s) at fewer than 2 distinct positions: a map "
                         "needs a 2-D grid of positions")
    h = float(step) if step is not None else _infer_step(x, y)
    ox, oy = _origin(x, h), _origin(y, h)
    ix, iy = np.round((x - ox) / h).astype(np.int64), np.round((y - oy) / h).astype(np.int64)
    off = np.maximum(np.abs(x - ox - ix * h), np.abs(y - oy - iy * h)) / h
    far = np.flatnonzero(off > tol)
    if far.size:
        i = int(far[0])
        raise InputError(
            f"position {i} ({x[i]:.6g}, {y[i]:.6g}) m is {off[i]:.2f} steps off the regular grid "
            f"with step {h:.6g} m (tolerance {tol} steps; {far.size} position(s) off): check the "
            "positions, pass step= explicitly (e.g. a common divisor of the x and y spacings), "
            "or raise tol")
    ox, oy = ox + h * ix.min(), oy + h * iy.min()
    if step is None:  # an inferred step: its least-squares residue too (a given one as is)
        h = float(clean_coordinates(h, h))
    ox, oy = (float(clean_coordinates(o, h)) for o in (ox, oy))
    ix, iy = ix - ix.min(), iy - iy.min()
    nx, ny = int(ix.max()) + 1, int(iy.max()) + 1
    for name, n in (("x", nx), ("y", ny)):
        if n < 2 and not line:
            raise InputError(f"the positions have a single {name} value on the grid of step "
                             f"{h:.6g} m: a map needs a 2-D grid (fit a line scan trace by "
                             "trace instead)")
    if nx * ny > MAX_NODES:
        raise InputError(f"the grid would have {nx} × {ny} nodes at step {h:.6g} m (more than "
                         f"{MAX_NODES}): check for an outlying position or pass step=")
    lat = Lattice(x0=float(ox), y0=float(oy), step=float(h), nx=nx, ny=ny)
    return lat, iy * nx + ix


def _path_laplacian(n: int) -> sp.csc_matrix:
    if n == 1:
        return sp.csc_matrix((1, 1))
    d = np.full(n, 2.0)
    d[[0, -1]] = 1.0
    off = -np.ones(n - 1)
    return sp.diags([off, d, off], [-1, 0, 1], format="csc")


def laplacian(nx: int, ny: int) -> sp.csc_matrix:
    """5-point graph Laplacian of an ``nx`` × ``ny`` lattice with free (Neumann) boundary.

    Node order as :class:`Lattice` (``iy·nx + ix``).  Each row holds the number of neighbours
    on the diagonal and −1 for every neighbour, so rows sum to zero; this is −h² times the
    finite-difference Laplacian with zero normal derivative at the edge (dimensionless).
    """
    return (sp.kron(sp.identity(ny), _path_laplacian(nx))
            + sp.kron(_path_laplacian(ny), sp.identity(nx))).tocsc()


def laplacian_eigenvalues(nx: int, ny: int) -> np.ndarray:
    """Eigenvalues of :func:`laplacian` ``(nx, ny)`` in closed form, shape ``(ny, nx)``.

    The Neumann Laplacian of a full rectangular lattice is diagonalised by the 2-D discrete
    cosine transform (DCT-II): λ_jk = 4 sin²(πj / 2nx) + 4 sin²(πk / 2ny).
    """
    lx = 4 * np.sin(np.pi * np.arange(nx) / (2 * nx)) ** 2
    ly = 4 * np.sin(np.pi * np.arange(ny) / (2 * ny)) ** 2
    return ly[:, None] + lx[None, :]


def pad(lattice: Lattice, margin: int) -> tuple[Lattice, np.ndarray]:
    """Surround ``lattice`` with ``margin`` nodes on each side.

    Returns
    -------
    padded
        The lattice of ``(nx + 2·margin) × (ny + 2·margin)`` nodes, same step, origin moved by
        ``−margin·step``.
    index
        Node number in ``padded`` of every node of ``lattice`` (int array, length
        ``lattice.n_nodes``).
    """
    m = int(margin)
    if m < 0 or m != margin:
        raise InputError(f"margin must be a non-negative whole number of nodes, got {margin!r}")
    p = Lattice(x0=lattice.x0 - m * lattice.step, y0=lattice.y0 - m * lattice.step,
                step=lattice.step, nx=lattice.nx + 2 * m, ny=lattice.ny + 2 * m)
    ix = np.tile(np.arange(lattice.nx), lattice.ny) + m
    iy = np.repeat(np.arange(lattice.ny), lattice.nx) + m
    return p, iy * p.nx + ix
