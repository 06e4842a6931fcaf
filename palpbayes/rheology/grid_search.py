"""Where the collapsed viscoelastic posterior's fine grid goes: the sheared box and its search.

:func:`~palpbayes.rheology.posterior.grid_posterior` integrates a density on (θ, z_s, phi),
θ = alpha or log tau, whose (θ, z_s) ridge may be tilted (the surface and alpha trade off) and
far narrower than the coarse grid's nodes.  This module moves a sheared box of nodes onto it:

* :func:`box_search`: θ_i spans ±:data:`SPAN_SD` marginal sd of θ, and on each θ_i the
  surface nodes span ±SPAN_SD *conditional* sd of z_s around the regression line of z_s on θ;
  the box's moments are recomputed and the box rebuilt until they are steady and every sd is
  at least :data:`RESOLVE` node steps (clipped at the prior bounds).  While the box still moves
  it has :data:`SEARCH_THETA` θ nodes (each costs one hereditary matrix); the settled box is
  computed once more with :data:`FINE` (its search rows kept, the rows between them added:
  :func:`refined`) and must give the same moments.  While the ridge is
  narrower than the surface nodes, the box follows the line through every θ row's best node
  and narrows in z_s alone (θ's moments then come from whichever row's node fell nearest the
  ridge); a row whose best node is its first or last, within :data:`KEEP` of the box's best,
  widens the box in z_s.
* :func:`climb`: where the box starts, the mode itself, found on the profile
  max_z log p(θ, z_s) near the coarse grid's best node (bounded Brent on θ, zoomed surface
  rows for the max), with the profile's curvature (θ's marginal sd), a row's curvature (z_s's
  conditional sd) and the ridge's slope.  From there the box settles in two boxes, about
  half the hereditary matrices of a search from the coarse node.  A ridge narrower than the
  coarse θ nodes *and* the surface nodes (a record pressed slowly, its mode hundreds in log
  density above every node the box sees) left a search from the coarse node cycling
  between widening and narrowing in z_s, its θ nodes never closer than the coarse grid's.

The density is evaluated by a ``NodeEvaluator`` (:mod:`~palpbayes.rheology.posterior`):
``logp(thetas, z)`` on a product grid, ``logp_rows(thetas, z_rows)`` on a sheared one.
"""

# Long module: one job, where the grid posterior's fine grid goes: the sheared box, its search and
#   its climb.

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from ..bayes.exact import cell_widths
from ..errors import FitError

__all__ = ["FINE", "SEARCH_THETA", "SPAN_SD", "RESOLVE", "KEEP", "BoxResult", "box_search",
           "climb", "moments", "log_cells", "sheared", "refined"]

#: Nodes per axis of the fine box.
FINE = 25
#: Theta nodes of the fine box while it is still moving (the last box has :data:`FINE`:
#: twice the steps, so that the settled search box's rows are kept).
SEARCH_THETA = 13
assert FINE - 1 == 2 * (SEARCH_THETA - 1)
#: Half-width of the fine grid in (marginal, conditional) standard deviations.
SPAN_SD = 6.0
#: Smallest sd of the final grid, in node steps.
RESOLVE = 1.5
#: Basins lower than the best by more than this (log density) are not reported.
KEEP = 14.0
#: Surface nodes per zoom of :func:`climb`'s rows, and the most zooms per row.
ZOOM_NODES, MAX_ZOOMS = 25, 12

Bounds = tuple[tuple[float, float], tuple[float, float]]


@dataclass
class BoxResult:
    """The last box of :func:`box_search`: θ coordinates ``gt`` (Gt,), surface nodes ``gz``
    (Gt, FINE) [m], log density ``lp`` (Gt, FINE) marginal over phi, the node posteriors
    ``post``, the box's ``slope`` dz_s/dθ and whether it settled."""

    gt: np.ndarray
    gz: np.ndarray
    lp: np.ndarray
    post: object
    slope: float
    converged: bool


def moments(ct: np.ndarray, z: np.ndarray, lp: np.ndarray) -> tuple[float, ...]:
    """Mean and sd of θ, the slope of z on θ, the conditional mean of z at the mean θ and its
    conditional sd, from the grid's masses (lp + log cell areas)."""
    w = np.exp(lp - lp.max())
    w /= w.sum()
    mt = float((w.sum(1)) @ ct)
    vt = float(w.sum(1) @ (ct - mt) ** 2)
    mz = float((w * z).sum())
    vz = float((w * (z - mz) ** 2).sum())
    cov = float((w * (ct[:, None] - mt) * (z - mz)).sum())
    slope = cov / vt if vt > 0 else 0.0
    return mt, math.sqrt(max(vt, 0.0)), slope, mz, math.sqrt(max(vz - slope * cov, 0.0))


def log_cells(ct: np.ndarray, z: np.ndarray) -> np.ndarray:
    """log area (Gt, Gz) of every node's cell of a sheared grid (θ width × its row's z width;
    a shear keeps areas)."""
    return np.log(cell_widths(ct))[:, None] + np.log(np.stack([cell_widths(r) for r in z]))


def sheared(centre, sd, slope, bounds: Bounds, n_theta: int = FINE
            ) -> tuple[np.ndarray, np.ndarray]:
    """θ coordinates (n_theta,) and surface rows (n_theta, FINE) of the box around ``centre``
    (θ, z_s) spanning ±:data:`SPAN_SD` × ``sd`` (θ's marginal, z_s's conditional), its rows
    centred on the line of ``slope``, every node inside ``bounds``."""
    (tlo, thi), (zlo, zhi) = bounds
    (mt, mz), (st, sz) = (min(max(centre[0], tlo), thi), centre[1]), sd
    ct = np.linspace(max(tlo, mt - SPAN_SD * st), min(thi, mt + SPAN_SD * st),
                     n_theta if thi > tlo else 1)  # the elastic law: one theta node
    mid = mz + slope * (ct - mt)
    mid = np.clip(mid, zlo, zhi)  # a ridge may leave the prior: keep every row inside it
    z = np.stack([np.linspace(max(zlo, c - SPAN_SD * sz), min(zhi, c + SPAN_SD * sz), FINE)
                  for c in mid])
    return ct, z


def rows_leave_ridge(lp: np.ndarray, z: np.ndarray, z_bounds: tuple[float, float]) -> bool:
    """True when a theta row of a sheared box (``lp`` and ``z`` of shape (rows, FINE)) has its
    largest log density on its first or last surface node (not a prior bound) within
    :data:`KEEP` of the box's best: the ridge of (theta, z_s) leaves the box there, so the
    best node of the box is not the posterior's mode, only the best point of a line that
    crosses the ridge (the regression line of z_s on theta was off).  Such a box must widen
    in z_s, however steady its moments look."""
    arg = np.argmax(lp, axis=1)
    rows = np.arange(lp.shape[0])
    at_edge = (((arg == 0) & (z[:, 0] > z_bounds[0]))
               | ((arg == lp.shape[1] - 1) & (z[:, -1] < z_bounds[1])))
    return bool(np.any(at_edge & (lp[rows, arg] > np.max(lp) - KEEP)))


def ridge_line(lp: np.ndarray, gt: np.ndarray, gz: np.ndarray, theta: float, slope: float
               ) -> tuple[tuple[float, float], float, float]:
    """The line z_s = a + slope·theta through the best node of every theta row of a sheared
    box whose best log density lies within :data:`KEEP` of the box's and inside the row (not
    on its first or last node, which the ridge may lie beyond); least squares, or the
    previous ``slope`` through the best row when only that row qualifies.  Returns the centre
    (theta, the line's z_s there), the slope, and the largest distance [m] of those rows' best
    nodes from the line."""
    rows = np.arange(lp.shape[0])
    arg = np.argmax(lp, axis=1)
    best = lp[rows, arg]
    near = (best > np.max(best) - KEEP) & (arg > 0) & (arg < lp.shape[1] - 1)
    near[int(np.argmax(best))] = True
    zs = gz[rows, arg]
    if near.sum() >= 2 and np.ptp(gt[near]) > 0:
        slope, icpt = np.polyfit(gt[near], zs[near], 1)
    else:
        k = int(np.argmax(best))
        icpt = zs[k] - slope * gt[k]
    off = np.abs(zs[near] - (icpt + slope * gt[near]))
    return (theta, float(icpt + slope * theta)), float(slope), float(off.max())


def box_search(ev, from_c: Callable, bounds: Bounds, centre: tuple[float, float],
               sd: tuple[float, float], slope: float, max_iterations: int) -> BoxResult:
    """Move the sheared box until it settles (module docstring).

    Parameters
    ----------
    ev
        A ``NodeEvaluator`` (:mod:`~palpbayes.rheology.posterior`): ``logp_rows(thetas,
        z_rows)``.
    from_c
        θ from its coordinate (alpha itself, or exp of log tau).
    bounds
        ((θ coordinate low, high), (z_s low, high) [m]): the priors' support.
    centre, sd, slope
        The first box: its centre (θ coordinate, z_s [m]), half-widths ``SPAN_SD·sd`` (θ's
        marginal sd, z_s's conditional sd [m]) and the slope dz_s/dθ of its rows' centres.
    max_iterations
        Boxes at most (and the full-resolution box of a search that settles on the last).

    Returns
    -------
    BoxResult
        The last box; ``converged`` False when it had not settled within
        ``max_iterations``.

    Raises
    ------
    FitError
        A box holds no finite density.
    """
    (c_lo, c_hi) = bounds[0]
    converged = False
    n_theta = SEARCH_THETA  # theta nodes cost one hereditary matrix each: search on fewer
    pending, iteration = None, 0
    while iteration < max_iterations or pending is not None:  # a refined box gets its check
        iteration += 1
        if pending is None:
            gt, gz = sheared(centre, sd, slope, bounds, n_theta)
            lp, post = ev.logp_rows(from_c(gt), gz)
        else:
            (gt, gz, lp, post), pending = pending, None
        if not np.isfinite(lp).any():
            raise FitError("the fine grid holds no finite density; report this record")
        a, b = np.unravel_index(np.argmax(lp), lp.shape)
        mt, st, new_slope, mz, sz = moments(gt, gz, lp + log_cells(gt, gz))
        spacing = (max(np.diff(gt).min(), 0.0) * (n_theta - 1) / (FINE - 1)
                   if gt.size > 1 else 0.0, float(np.diff(gz, axis=1).min()))
        edge = (a in (0, gt.size - 1) and gt[a] not in bounds[0],
                b in (0, gz.shape[1] - 1) and gz[a, b] not in bounds[1]
                or rows_leave_ridge(lp, gz, bounds[1]))
        resolved = all(s_ >= RESOLVE * h or s_ == 0.0 and h == 0.0
                       for s_, h in zip((st, sz), spacing, strict=True))
        steady = (abs(st - sd[0]) <= 0.3 * sd[0] and abs(sz - sd[1]) <= 0.3 * sd[1]
                  and abs(mt - centre[0]) <= 0.5 * sd[0]
                  and abs(mz - centre[1]) <= 0.5 * max(sd[1], abs(slope) * sd[0]))
        if edge[0] or edge[1]:  # the mode sits on the grid's edge: go there, widen
            centre = (float(gt[a]), float(gz[a, b]))
            sd = (sd[0] * (2 if edge[0] else 1), sd[1] * (2 if edge[1] else 1))
            continue
        if steady and resolved:
            if gt.size == 1 or n_theta == FINE:
                converged = True
                break
            # the search has settled: the same box at full resolution, its theta rows kept
            # (the new rows fall halfway between them), checked as any box
            n_theta = FINE
            pending = refined(ev, from_c, (centre, sd, slope), bounds, (gt, gz, lp, post))
            continue
        floor = (spacing[0] / 4, spacing[1] / 4)  # all mass on one node: shrink, do not stop
        if gt.size > 1 and sz < RESOLVE * spacing[1]:
            # the ridge of (theta, z_s) is narrower than the z nodes: which row's best node
            # falls nearest it is luck, so theta's moments say nothing yet (they shrank the
            # box onto one row, off the mode, and a picometre in the record moved the result):
            # follow the line through the rows' best nodes and narrow z alone
            centre, slope, half_z = ridge_line(lp, gt, gz, centre[0], slope)
            sd = (sd[0], max(sd[1] / 2, 2 * half_z / SPAN_SD, floor[1], 1e-15))
            continue
        if gt.size > 1 and st < RESOLVE * spacing[0]:
            # theta not resolved: the moments' slope of z_s on theta comes from one row and is
            # noise; the ridge's line through the rows' best nodes is not
            (_, mz), new_slope, _ = ridge_line(lp, gt, gz, mt, slope)
        centre, slope = (mt, mz), new_slope
        sd = (max(st, floor[0], (c_hi - c_lo) * 1e-9), max(sz, floor[1], 1e-15))
    return BoxResult(gt, gz, lp, post, float(slope), converged)


def refined(ev, from_c: Callable, box: tuple, bounds: Bounds, search: tuple) -> tuple:
    """The box ``box`` = (centre, sd, slope) with :data:`FINE` θ rows, from its
    :data:`SEARCH_THETA`-row ``search`` = (gt, gz, lp, post): FINE − 1 = 2·(SEARCH_THETA − 1),
    so the search's rows are every other row and only the rows between them are evaluated.
    Returns (gt, gz, lp, post) of the full box."""
    gt, gz, lp, post = search
    ct, z = sheared(*box, bounds, FINE)
    ct[::2], z[::2] = gt, gz  # the same nodes up to rounding: keep the evaluated ones
    lp_new, post_new = ev.logp_rows(from_c(ct[1::2]), z[1::2])
    out = np.empty((FINE, z.shape[1]))
    out[::2], out[1::2] = lp, lp_new
    n_z = z.shape[1]

    def weave(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        w = np.empty((FINE, n_z) + a.shape[1:], dtype=a.dtype)
        w[::2] = a.reshape((-1, n_z) + a.shape[1:])
        w[1::2] = b.reshape((-1, n_z) + b.shape[1:])
        return w.reshape((FINE * n_z,) + a.shape[1:])

    merged = None if post is None else type(post)(
        *(weave(getattr(post, f), getattr(post_new, f)) for f in ("logp", "beta", "scale", "S")),
        post.nu)
    return ct, z, out, merged


def _vertex(x: np.ndarray, y: np.ndarray, k: int) -> tuple[float, float, float]:
    """Vertex (x, y) of the parabola through the three nodes around ``k`` (kept within one
    node step of x_k) and the sd of the Gaussian whose log it is; the node itself and NaN
    where the three are not concave or not finite (a surface with too few samples in
    contact)."""
    j = min(max(k, 1), x.size - 2)
    xs, ys = x[j - 1:j + 2] - x[k], y[j - 1:j + 2]
    if not np.all(np.isfinite(ys)):
        return float(x[k]), float(y[k]), math.nan
    a, b, c = np.polyfit(xs, ys, 2)
    if not a < 0:
        return float(x[k]), float(y[k]), math.nan
    h = float(x[1] - x[0])
    v = min(max(-b / (2 * a), -h, x[0] - x[k]), h, x[-1] - x[k])  # inside the window
    return float(x[k] + v), float(max(a * v * v + b * v + c, y[k])), math.sqrt(-0.5 / a)


def _row_max(ev, theta: float, z_guess: float, width: float, z_bounds: tuple[float, float]
             ) -> tuple[float, float, float]:
    """Largest log density over z_s on the row θ, by zooming: :data:`ZOOM_NODES` nodes over
    ``z_guess ± width`` (moved and doubled while the best node is the window's first or last
    and not a prior bound), then ±2 node steps around the best, until the row's curvature
    spans :data:`RESOLVE` steps.

    Returns
    -------
    tuple
        z_s [m] and log density of the vertex of the parabola through the best node and its
        neighbours, and the conditional sd [m] of z_s from its curvature (NaN where the row
        has none: no concave neighbourhood, the maximum on the prior's bound, or the zooms
        ran out while the window moved).
    """
    zlo, zhi = z_bounds
    lo, hi = max(zlo, z_guess - width), min(zhi, z_guess + width)
    best = (z_guess, -math.inf, math.nan)
    for _ in range(MAX_ZOOMS):
        z = np.linspace(lo, hi, ZOOM_NODES)
        lp = ev.logp(np.array([theta]), z)[0][0]
        k = int(np.argmax(lp))
        h = z[1] - z[0]
        if (k == 0 and z[0] > zlo) or (k == z.size - 1 and z[-1] < zhi):  # beyond: move on
            width = hi - lo
            lo, hi = max(zlo, z[k] - width), min(zhi, z[k] + width)
            best = (float(z[k]), float(lp[k]), math.nan)
            continue
        best = _vertex(z, lp, k)
        if not best[2] < RESOLVE * h or h <= 1e-15:  # resolved, or no curvature to resolve
            break
        lo, hi = max(zlo, z[k] - 2 * h), min(zhi, z[k] + 2 * h)
    if best[0] <= zlo or best[0] >= zhi:  # on the prior's bound: not a point of the ridge
        return best[0], best[1], math.nan
    return best


def climb(ev, from_c: Callable, bounds: Bounds, centre: tuple[float, float],
          step: tuple[float, float]) -> tuple[tuple[float, float], tuple[float, float], float]:
    """The mode of log p(θ, z_s) on the profile max_z log p near the coarse grid's best node.

    Bounded Brent (:func:`scipy.optimize.minimize_scalar`) on θ within one coarse step of
    ``centre``, moved on (at most three times) while its result sits at that bracket's edge;
    each row's maximum over z_s by :func:`_row_max`, its window predicted from the rows
    already seen (the ridge's line through the two nearest; two coarse surface steps wide
    until two rows are known).  θ's sd comes from the profile's drop at the mode ± delta
    (delta chosen so that the drop is 0.5–30; the profile of a Gaussian has the marginal's
    curvature), the slope from the rows' maxima there.

    Parameters
    ----------
    ev
        A ``NodeEvaluator`` (:mod:`~palpbayes.rheology.posterior`): ``logp(thetas, z)``.
    from_c
        θ from its coordinate (alpha itself, or exp of log tau).
    bounds
        ((θ coordinate low, high), (z_s low, high) [m]): the priors' support.
    centre
        (θ coordinate, z_s [m]) of the coarse grid's best node.
    step
        The coarse grid's node steps (θ coordinate, z_s [m]).

    Returns
    -------
    tuple
        The mode (θ coordinate, z_s [m]); (θ's sd, capped at one coarse step; z_s's
        conditional sd [m] at the mode, or the coarse surface step where the row has no
        curvature); the ridge's slope dz_s/dθ [m per unit coordinate].  The box search
        (:func:`box_search`) starts from them.
    """
    (c_lo, c_hi), z_bounds = bounds
    seen: dict[float, tuple[float, float, float]] = {}

    def guess(c: float) -> tuple[float, float]:
        known = [k for k in seen if math.isfinite(seen[k][2])]
        if len(known) < 2:
            return (seen[known[0]][0] if known else centre[1]), 2.0 * step[1]
        cs = np.array(sorted(known, key=lambda k: abs(k - c))[:2])
        zs = np.array([seen[k][0] for k in cs])
        width = 4.0 * min(seen[k][2] for k in cs)
        z = zs[0] + (c - cs[0]) * (zs[1] - zs[0]) / (cs[1] - cs[0])
        return float(z), float(max(width, abs(z - zs[0]), 1e-12))

    def negative_profile(c: float) -> float:
        c = float(c)
        if c not in seen:
            seen[c] = _row_max(ev, float(from_c(c)), *guess(c), z_bounds)
        return -seen[c][1]

    half = step[0]
    lo, hi = max(c_lo, centre[0] - half), min(c_hi, centre[0] + half)
    for _ in range(4):
        xatol = 1e-4 * (hi - lo)
        c_best = float(minimize_scalar(negative_profile, bounds=(lo, hi), method="bounded",
                                       options={"xatol": xatol}).x)
        negative_profile(c_best)
        at_edge = ((c_best - lo < 3 * xatol and lo > c_lo)
                   or (hi - c_best < 3 * xatol and hi < c_hi))
        if not at_edge:
            break
        lo, hi = max(c_lo, c_best - half), min(c_hi, c_best + half)
    lp_best = seen[c_best][1]
    # theta's sd and the ridge's slope from the profile at c_best ± delta, delta chosen so
    # that the profile drops by 0.5-30 there (Brent's last evaluations are too close)
    drops = [(abs(c - c_best) / math.sqrt(2 * (lp_best - v[1])))
             for c, v in seen.items() if 0.5 < lp_best - v[1] < 30]
    delta = 2.0 * float(np.median(drops)) if drops else step[0] / 4  # a drop of ~2
    st, slope = step[0] / 4, 0.0
    for _ in range(8):
        sides = [c for c in (c_best - delta, c_best + delta) if c_lo <= c <= c_hi]
        if not sides or delta <= 1e-12 * (c_hi - c_lo):
            break
        for c in sides:
            negative_profile(c)
        drop = lp_best - float(np.mean([seen[c][1] for c in sides]))
        if drop > 30:
            delta /= 4
            continue
        if drop < 0.5 and delta < step[0]:
            delta *= 4
            continue
        st = delta / math.sqrt(2 * max(drop, 1e-3))
        ends = sides if len(sides) == 2 else [sides[0], c_best]
        slope = (seen[ends[0]][0] - seen[ends[-1]][0]) / (ends[0] - ends[-1])
        break
    c_mode = max(seen, key=lambda c: seen[c][1])  # a side row above Brent's best: the mode
    z_mode, _, sz = seen[c_mode]
    if not math.isfinite(sz):
        sz = step[1]
    return (c_mode, z_mode), (min(st, step[0]), sz), float(slope)
