"""The next press, and when to stop: :func:`next_presses` on a :class:`SearchState`.

A search state is the presses so far (position and posterior of log E) and the specimen:
its footprint, keep-out zones, the tip's contact radius and the block thickness.  After each
press the lump posterior (:mod:`palpbayes.active.posterior`) is updated; the stopping rule
(:class:`SearchStopRule`) says whether a decision is reached; if not, the candidates of a regular
grid over the footprint (outside the keep-out zones and at least ``min_spacing`` from every
press) are scored by a criterion (:mod:`palpbayes.active.criteria`) and the best is returned.
A batch of k for a robot that plans a path is chosen greedily, each pick added to the state
as a press that reads its predictive mean (the "kriging believer" of Ginsbourger, Le Riche &
Carraro 2010, in *Computational Intelligence in Expensive Optimization Problems*, 131–162).
With several press depths (:class:`~palpbayes.active.depth.PressDepths`) a press is
(x, y, depth) and ``eig`` picks the most information per second of pressing
(:mod:`palpbayes.active.depth`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from ..errors import InputError
from .background import check_background
from .criteria import CRITERIA, level_probability, predictive
from .depth import PressDepths, choose
from .posterior import LumpHypotheses, SearchPosterior, hypotheses, posterior
from .rule import SearchStopRule, decide

__all__ = ["PRESS_COLUMNS", "SearchState", "SearchStopRule", "NextPresses", "next_presses",
           "decide", "summary", "history"]

#: Columns of a search state's presses (``presses.csv``).
PRESS_COLUMNS = ["x_m", "y_m", "logE_mean", "logE_sd"]
#: sd of log E assumed for a press not made yet, when there is no press to take it from.
_DEFAULT_PRESS_SD = 0.01
_MAX_CANDIDATES = 900


@dataclass(frozen=True)
class SearchState:
    """The presses so far and the specimen they were made on.

    Parameters
    ----------
    presses
        One row per press: ``x_m``, ``y_m`` [m], ``logE_mean``, ``logE_sd`` (the press's
        posterior of log(E/Pa)); other columns are kept.
    footprint
        [m] (x0, x1, y0, y1): the rectangle that may be pressed and may hold the lump.
    contact_radius, thickness
        [m] The tip's contact radius at the indentation depth and the block thickness.
    keep_out
        [m] Discs (x, y, radius) not to press (a clamp, a suture, a marker).
    min_spacing
        [m] No press closer than this to another.
    candidate_step
        [m] Spacing of the candidate grid (coarsened to at most 900 candidates).
    resolution
        [m] Spacing of the lump-centre grid.
    min_excess, max_ratio
        The apparent peak excess that counts as a lump, and the prior's largest ratio.
    k_level
        k of the level set {E > k × background} (the ``lse`` criterion and the
        misclassified area); default 1 + ``min_excess``.
    prior_lump
        Prior probability of a lump.
    press_sd
        sd of log E expected of the next press (None: the median of the presses').
    background
        The heterogeneity's model: ``"white"`` or ``"correlated"`` (:mod:`~.background`).
    press_depths
        The depths the search may choose and their cost (:class:`~.depth.PressDepths`; its
        first contact radius is ``contact_radius``); a press's depth is its ``depth_m``
        column (missing or NaN: the first).  None: one depth.
    """

    presses: pd.DataFrame
    footprint: tuple[float, float, float, float]
    contact_radius: float
    thickness: float
    keep_out: tuple[tuple[float, float, float], ...] = ()
    min_spacing: float = 1e-3
    candidate_step: float = 2e-3
    resolution: float = 1e-3
    min_excess: float = 0.03
    max_ratio: float = 3.0
    k_level: float | None = None
    prior_lump: float = 0.5
    press_sd: float | None = None
    background: str = "white"
    press_depths: PressDepths | None = None
    _hyp: list = field(default_factory=list, repr=False, compare=False)

    def __post_init__(self) -> None:
        p = self.presses
        if not isinstance(p, pd.DataFrame):
            raise InputError("presses must be a pandas DataFrame with columns "
                             + ", ".join(PRESS_COLUMNS))
        missing = [c for c in PRESS_COLUMNS if c not in p.columns]
        if missing:
            raise InputError(f"presses: missing column(s) {', '.join(missing)}; a press needs "
                             + ", ".join(PRESS_COLUMNS))
        vals = p[PRESS_COLUMNS].to_numpy(dtype=float)
        bad = ~np.isfinite(vals).all(axis=1) | ~(vals[:, 3] > 0)
        if bad.any():
            j = int(np.flatnonzero(bad)[0])
            row = ", ".join(f"{c} {v:g}" for c, v in zip(PRESS_COLUMNS, vals[j], strict=True))
            raise InputError(f"presses: press {j + 1} has a non-finite value or an sd <= 0 "
                             f"({row}); drop presses without a fit")
        for i, z in enumerate(self.keep_out):
            if len(z) != 3 or not all(math.isfinite(v) for v in z) or not z[2] > 0:
                raise InputError(f"keep-out zone {i} {z!r} must be x, y, radius [m] with "
                                 "radius > 0")
        if not self.min_spacing >= 0 or not self.candidate_step > 0:
            raise InputError(f"min_spacing (--min-spacing) {self.min_spacing!r} must be >= 0 "
                             f"and candidate_step {self.candidate_step!r} > 0 [m]")
        fp = tuple(self.footprint)
        if (len(fp) != 4 or not all(math.isfinite(float(v)) for v in fp)
                or not (fp[1] > fp[0] and fp[3] > fp[2])):
            raise InputError(f"footprint (--footprint) {self.footprint!r} must be x0, x1, y0, y1 "
                             "[m] with x1 > x0 and y1 > y0")
        for name, v in (("contact_radius", self.contact_radius),
                        ("thickness (--thickness)", self.thickness),
                        ("resolution", self.resolution)):
            if not (math.isfinite(float(v)) and v > 0):
                raise InputError(f"{name} {v!r} must be > 0 [m]")
        if not 0.0 < self.prior_lump < 1.0:
            raise InputError(f"prior_lump {self.prior_lump!r} must lie in (0, 1)")
        if not (self.min_excess > 0 and self.max_ratio > 1 + self.min_excess):
            raise InputError(f"min_excess (--min-excess) {self.min_excess!r} must be > 0 and "
                             f"max_ratio {self.max_ratio!r} > 1 + min_excess")
        if self.k_level is not None and not self.k_level > 1:
            raise InputError(f"k_level {self.k_level!r} must be > 1")
        if self.press_sd is not None and not self.press_sd > 0:
            raise InputError(f"press_sd {self.press_sd!r} must be > 0")
        check_background(self.background)
        pd_ = self.press_depths
        if pd_ is not None and not math.isclose(pd_.contact_radii[0], self.contact_radius,
                                                rel_tol=1e-9):
            raise InputError(f"the first press depth's contact radius {pd_.contact_radii[0]:g}"
                             f" m differs from contact_radius {self.contact_radius:g} m")
        if pd_ is not None and "depth_m" in p.columns:
            pd_.index(p["depth_m"])  # every press at one of the depths

    def _grid_key(self) -> tuple:
        return (tuple(map(float, self.footprint)), self.radii,
                float(self.thickness), float(self.resolution), float(self.min_excess),
                float(self.max_ratio), self.background)

    @property
    def hyp(self) -> LumpHypotheses:
        """The hypothesis grid, built on first use and kept (with the specimen it was built
        for: a copy of the state with another footprint, tip or prior builds its own)."""
        key = self._grid_key()
        if not self._hyp or self._hyp[0][0] != key:
            self._hyp[:] = [(key, hypotheses(
                self.footprint, contact_radius=self.radii, thickness=self.thickness,
                resolution=self.resolution, min_excess=self.min_excess,
                max_ratio=self.max_ratio, background=self.background))]
        return self._hyp[0][1]

    @property
    def n(self) -> int:
        return len(self.presses)

    @property
    def radii(self) -> tuple[float, ...]:
        """[m] The contact radius at each press depth (one without :attr:`press_depths`)."""
        return ((float(self.contact_radius),) if self.press_depths is None
                else self.press_depths.contact_radii)

    def depth_index(self) -> np.ndarray | None:
        """Each press's index in :attr:`press_depths` (None: one depth)."""
        if self.press_depths is None or "depth_m" not in self.presses.columns:
            return None
        return self.press_depths.index(self.presses["depth_m"])

    @property
    def level(self) -> float:
        return 1.0 + self.min_excess if self.k_level is None else float(self.k_level)

    def expected_sd(self, depth: int = 0) -> float:
        """sd of log E expected of a press at depth index ``depth``: ``press_sd``, else the
        median of the presses at that depth, else of all presses."""
        if self.press_sd is not None:
            return float(self.press_sd)
        if self.n == 0:
            return _DEFAULT_PRESS_SD
        sd, j = self.presses["logE_sd"].to_numpy(dtype=float), self.depth_index()
        return float(np.median(sd if j is None or not (j == depth).any() else sd[j == depth]))

    def posterior(self) -> SearchPosterior:
        p = self.presses
        return posterior(self.hyp, p["x_m"], p["y_m"], p["logE_mean"], p["logE_sd"],
                         depth=self.depth_index(), prior_lump=self.prior_lump)

    def with_press(self, x: float, y: float, mean: float, sd: float, **extra) -> SearchState:
        """A new state with one more press (the grid is shared, not rebuilt)."""
        row = pd.DataFrame([{"x_m": x, "y_m": y, "logE_mean": mean, "logE_sd": sd, **extra}])
        presses = row if self.n == 0 else pd.concat([self.presses, row], ignore_index=True)
        return replace(self, presses=presses, _hyp=self._hyp)

    def candidates(self, taken: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The candidate positions [m]: a grid over the footprint, outside the keep-out
        zones, at least ``min_spacing`` from every press and from ``taken`` (m, 2)."""
        x0, x1, y0, y1 = self.footprint
        step = max(self.candidate_step,
                   math.sqrt((x1 - x0) * (y1 - y0) / _MAX_CANDIDATES))
        gx = np.linspace(x0, x1, max(1, int(round((x1 - x0) / step)) + 1))
        gy = np.linspace(y0, y1, max(1, int(round((y1 - y0) / step)) + 1))
        X, Y = (a.ravel() for a in np.meshgrid(gx, gy))
        ok = np.ones(X.size, dtype=bool)
        for zx, zy, r in self.keep_out:
            ok &= np.hypot(X - zx, Y - zy) > r
        pts = [self.presses[["x_m", "y_m"]].to_numpy(dtype=float)]
        if taken is not None and len(taken):
            pts.append(np.asarray(taken, dtype=float).reshape(-1, 2))
        done = np.vstack(pts)
        if done.size and self.min_spacing > 0:
            for lo in range(0, X.size, 256):
                sl = slice(lo, lo + 256)
                d = np.hypot(X[sl, None] - done[None, :, 0], Y[sl, None] - done[None, :, 1])
                ok[sl] &= d.min(axis=1) >= self.min_spacing
        return X[ok], Y[ok]


@dataclass
class NextPresses:
    """The answer of :func:`next_presses`.

    Attributes
    ----------
    presses
        The next press(es) in order: ``order``, ``x_m``, ``y_m``, ``score`` (the
        criterion's; ``eig/s``: nat per second of pressing), ``criterion``, and ``depth_m``
        [m] when the state has press depths; empty when the search stops.
    stop
        True when the rule has decided (or the budget or the candidates ran out).
    decision
        ``"lump"``, ``"no lump"`` or ``""`` (undecided).
    reason
        Why it stops, in words ("" when it goes on).
    summary
        The posterior after the presses so far (:func:`summary`).
    """

    presses: pd.DataFrame
    stop: bool
    decision: str
    reason: str
    summary: dict
    posterior: SearchPosterior | None = field(default=None, repr=False)

    def table(self) -> pd.DataFrame:
        """The file of ``palpbayes next DIR --out FILE``: a row per next press (the columns
        of :attr:`presses`; one empty row when the search stops), each with ``event``,
        ``decision``, ``reason`` and :attr:`summary` (its centre as ``x_m_centre``, ...)."""
        head = {"event": "done" if self.stop else "next", "decision": self.decision,
                "reason": self.reason}
        post = {(f"{k}_centre" if k in ("x_m", "y_m") else k): v
                for k, v in self.summary.items()}
        cols = [c for c in ("order", "x_m", "y_m", "score", "criterion", "depth_m")
                if c != "depth_m" or c in self.presses.columns]
        rows = self.presses[cols].to_dict("records") if len(self.presses) else [
            dict.fromkeys(cols)]
        return pd.DataFrame([{**head, **r, **post} for r in rows])


def summary(state: SearchState, post: SearchPosterior | None, rule: SearchStopRule) -> dict:
    """The posterior as plain numbers: ``n``, ``p_lump``, the centre ``x_m``/``y_m`` [m], its
    credible radius ``centre_radius_m``, the apparent diameter ``size_m`` (FWHM),
    ``apparent_ratio``, ``tau``, ``misclassified_area_m2`` of the level set (NaN: no press)."""
    if post is None:
        keys = ("x_m", "y_m", "centre_radius_m", "size_m", "apparent_ratio", "tau",
                "misclassified_area_m2")
        return {"n": 0, "p_lump": state.prior_lump, **dict.fromkeys(keys, math.nan)}
    x, y = post.centre
    gx, gy, cell = _area_grid(state)
    p = level_probability(post, gx, gy, state.level)
    return {"n": post.n, "p_lump": post.p_lump, "x_m": x, "y_m": y,
            "centre_radius_m": post.centre_radius(rule.level), "size_m": post.size,
            "apparent_ratio": post.apparent_ratio, "tau": post.tau,
            "misclassified_area_m2": float(np.minimum(p, 1 - p).sum() * cell)}


def _area_grid(state: SearchState) -> tuple[np.ndarray, np.ndarray, float]:
    """A 3 mm (at most 16 × 16) grid over the footprint and its cell area [m²]."""
    x0, x1, y0, y1 = state.footprint
    nx = int(min(16, max(2, round((x1 - x0) / 3e-3) + 1)))
    ny = int(min(16, max(2, round((y1 - y0) / 3e-3) + 1)))
    X, Y = np.meshgrid(np.linspace(x0, x1, nx), np.linspace(y0, y1, ny))
    return X.ravel(), Y.ravel(), (x1 - x0) * (y1 - y0) / (nx * ny)


def _initial(state: SearchState, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Before any press: the candidates nearest a centred √k × √k pattern."""
    x0, x1, y0, y1 = state.footprint
    m = int(math.ceil(math.sqrt(k)))
    gx = x0 + (np.arange(m) + 0.5) * (x1 - x0) / m
    gy = y0 + (np.arange(m) + 0.5) * (y1 - y0) / m
    X, Y = (a.ravel()[:k] for a in np.meshgrid(gx, gy))
    cx, cy = state.candidates()
    if cx.size == 0:
        raise InputError("no candidate press: the keep-out zones cover the footprint")
    j = [int(np.argmin(np.hypot(cx - a, cy - b))) for a, b in zip(X, Y, strict=True)]
    j = list(dict.fromkeys(j))
    return cx[j], cy[j]


def next_presses(state: SearchState, k: int = 1, *, criterion: str = "eig",
                 rule: SearchStopRule | None = None, deepest: float | None = None
                 ) -> NextPresses:
    """The next ``k`` presses of an active search, or the decision to stop (module docstring).

    Parameters
    ----------
    state
        The presses so far and the specimen (:class:`SearchState`).
    k
        Presses to return (a batch for a robot that plans its path).
    criterion
        ``"eig"``, ``"lse"`` or ``"ucb"`` (:data:`palpbayes.active.criteria.CRITERIA`).
    rule
        The stopping rule (default :class:`SearchStopRule`).
    deepest
        [m] The deepest press allowed now (a force limit; None: any of the state's depths).
    """
    if criterion not in CRITERIA:
        raise InputError(f"criterion {criterion!r}: choose one of {', '.join(CRITERIA)}")
    if int(k) < 1:
        raise InputError(f"k {k!r} must be >= 1")
    k, rule = int(k), rule or SearchStopRule()
    depths = state.press_depths
    cols = ["order", "x_m", "y_m", "score", "criterion", *(["depth_m"] if depths else [])]
    if state.n == 0:
        x, y = _initial(state, k)
        table = pd.DataFrame({"order": np.arange(1, x.size + 1), "x_m": x, "y_m": y,
                              "score": np.nan, "criterion": "start"})
        if depths is not None:
            table["depth_m"] = depths.depths[0]
        return NextPresses(table, False, "", "", summary(state, None, rule))
    post = state.posterior()
    decision, reason = decide(post, rule)
    info = summary(state, post, rule)
    if reason:
        return NextPresses(pd.DataFrame(columns=cols), True, decision, reason, info, post)
    fn = CRITERIA[criterion][0]
    # information per second over the depths (eig only: the others score no information)
    js = [0] if depths is None or criterion != "eig" else depths.usable(deepest)
    secs = np.ones(1) if len(js) == 1 else depths.seconds()[js]
    if rule.max_presses is not None:
        k = max(1, min(k, int(rule.max_presses) - state.n))
    kw = ({"k": state.level} if criterion == "lse" else
          {"p_decide": rule.p_decide} if criterion == "eig" else {})
    rows, cur, cur_post, taken = [], state, post, np.empty((0, 2))
    for order in range(1, k + 1):
        qx, qy = state.candidates(taken)
        if qx.size == 0:
            break
        sds = {d: cur.expected_sd(d) for d in js}
        d, j, score = choose([fn(cur_post, qx, qy, sds[d], depth=d, **kw) for d in js], secs)
        d = js[d]
        row = {"order": order, "x_m": float(qx[j]), "y_m": float(qy[j]), "score": score,
               "criterion": criterion + ("/s" if len(js) > 1 else "")}
        extra = {} if depths is None else {"depth_m": depths.depths[d]}
        rows.append({**row, **extra})
        taken = np.vstack([taken, [qx[j], qy[j]]])
        if order < k:  # believe the predictive mean, then choose the next
            w, mu, _ = predictive(cur_post, qx[j:j + 1], qy[j:j + 1], sds[d], d)
            cur = cur.with_press(float(qx[j]), float(qy[j]), float(w @ mu[:, 0]), sds[d],
                                 **extra)
            cur_post = cur.posterior()
    if not rows:
        return NextPresses(pd.DataFrame(columns=cols), True, "",
                           "no candidate left (keep-out zones and minimum spacing)", info,
                           post)
    return NextPresses(pd.DataFrame(rows, columns=cols), False, "", "", info, post)


def history(state: SearchState, rule: SearchStopRule | None = None) -> pd.DataFrame:
    """The posterior after each press of ``state`` in order: ``n``, ``press_x_m``,
    ``press_y_m`` (``press_depth_m`` with depths), the :func:`summary` fields but the
    misclassified area (a posterior per press: about 0.05-0.2 s each)."""
    rule = rule or SearchStopRule()
    rows = []
    for n in range(1, state.n + 1):
        sub = replace(state, presses=state.presses.iloc[:n], _hyp=state._hyp)
        post = sub.posterior()
        x, y = post.centre
        rows.append({"n": n, "press_x_m": float(state.presses["x_m"].iloc[n - 1]),
                     "press_y_m": float(state.presses["y_m"].iloc[n - 1]),
                     "p_lump": post.p_lump, "x_m": x, "y_m": y,
                     "centre_radius_m": post.centre_radius(rule.level), "size_m": post.size,
                     "decision": decide(post, rule)[0],
                     **({"press_depth_m": float(state.presses["depth_m"].iloc[n - 1])}
                        if "depth_m" in state.presses else {})})
    return pd.DataFrame(rows)
