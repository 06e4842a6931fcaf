"""Active search for a lump against a raster and random presses, in a closed loop.

Run from the repository root (~80 min on 2 cores with the defaults; 37 min before press
depths, with ``--depths 0.1``)::

    python benchmarks/bench_active.py                      # 50 phantoms, eig, 2 depths
    python benchmarks/bench_active.py --criteria eig,lse,ucb --phantoms 20
    python benchmarks/bench_active.py --phantoms 4 --budget 40   # a quick look
    python benchmarks/bench_active.py --background correlated --model correlated --phantoms 10

Phantoms: the map phantom of ``palpbayes simulate --map`` (:class:`palpbayes.sim.phantom.
MapPhantom`: a 20 mm block of 50 kPa, heterogeneity 3 %, the paper's paraboloid pressed 2 mm,
a 42 × 42 mm footprint as the default 15 × 15 map at 3 mm).  Phantom i has a lump when i is
even: 10 mm across (radius 5 mm), its centre 5-10 mm deep (uniform), modulus ratio 10, its
centre uniform over the footprint less 5 mm at each edge.  ``--background correlated`` adds a
spatially correlated heterogeneity to every phantom (a Matérn-1 field of ln E, sd
``--field-sd`` 0.03, length ``--field-length`` 5 mm, :class:`~palpbayes.sim.phantom.MapPhantom`)
on top of the white 3 %; ``--model correlated`` makes every strategy's posterior carry one
(:mod:`palpbayes.active.background`); the same stopping rule either way.  Every press is
simulated as a whole trace (:func:`~palpbayes.sim.phantom.press_trace`, the code
``simulate --map`` uses) and fitted by the exact engine as ``palpbayes map`` fits a point
(:func:`palpbayes.maps.pertrace.fit_point`); its posterior of log E goes into the search
state.  ``--lumps twin`` (the default) scales each lump's log excess at each press depth to
what the finite-element twin reads over its centre (:func:`twin_gains`; ``screening``: the
screening model's Reuss reading, several times weaker).  ``--depths 0.1,0.2`` (the default):
the first is the fixed depth; with two or more, ``active-eig-depths`` chooses each press's
depth by information per second (:mod:`palpbayes.active.depth`), and the raster and random
presses run at each depth (``raster@0.2``, ...).

Strategies, all judged by the same posterior and stopping rule (P(lump) >= 0.95 with the
centre's 90 % radius <= 2 mm, or P(lump) <= 0.05):

* ``active-<criterion>``: :func:`palpbayes.active.next_presses` after every press;
* ``random``: presses uniform over the footprint, the rule checked after every 5th;
* ``raster``: an m × m raster over the footprint, fixed in advance, for m = 3, 4, ...: the
  presses it needs are m² for the first m whose raster decides.

Prints per strategy: phantoms decided within the budget, presses to decide (median, mean;
undecided count as the budget), the press time (:meth:`~palpbayes.active.depth.PressDepths.
seconds`), wrong decisions, the centre within 2 mm of the truth on lump phantoms called
"lump" (and on those of >= 7 % excess), the lumps below 6.5 % by the screening model found,
presses deeper than the first, presses until the apparent size (FWHM) is within 20 % of the
truth,
and the wall time per decision (median, p90, and at the largest state).  Writes the
per-phantom table and the press sequences to ``--out`` (default reports/active).
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

FOOTPRINT = (0.0, 0.042, 0.0, 0.042)
#: Random presses are judged by the rule after every 5th press (a posterior each: 0.1-0.2 s).
RANDOM_EVERY = 5


#: The correlated background of ``--background correlated``: sd of ln E and length [m].
FIELD = {"field_sd": 0.03, "field_length": 5e-3}


#: The phantom's lumps: ``twin`` (the screening model's profile, its log excess scaled at each
#: press depth to what the finite-element twin reads over the lump's centre) or ``screening``.
LUMPS = {"kind": "twin", "depths": (0.1,)}


def twin_gains(ph, inc, fractions) -> tuple[tuple[float, float], ...]:
    """(press depth [m], gain) for each press depth: ln(twin's centre ratio) / ln(the
    screening model's), the twin a 120 mm wide block bonded to its plate (coarse mesh)."""
    from palpbayes.inclusion import apparent_ratio, contact_radius, sensitivity
    from palpbayes.twin.palpation import CentredLump, pressed_ratio

    depths = [f * ph.thickness for f in fractions]
    twin = pressed_ratio(0.06, ph.thickness, ph.tip, ph.nu, "bonded", depths,
                         CentredLump(inc.radius, inc.depth, inc.ratio), "coarse")
    out = []
    for d, t in zip(depths, twin, strict=True):
        V = sensitivity(0.0, radius=inc.radius, depth=inc.depth,
                        contact_radius=contact_radius(ph.tip, d), thickness=ph.thickness)
        out.append((d, math.log(t) / math.log(float(apparent_ratio(V, inc.ratio)))))
    return tuple(out)


def make_phantom(i: int, seed: int, background: str = "white", field: dict | None = None):
    from dataclasses import replace

    from palpbayes.inclusion import Inclusion
    from palpbayes.sim.phantom import MapPhantom

    rng = np.random.default_rng([seed, i])
    inc = None
    if i % 2 == 0:
        x, y = rng.uniform(5e-3, 37e-3, 2)
        inc = Inclusion(x=float(x), y=float(y), depth=float(rng.uniform(5e-3, 10e-3)),
                        radius=5e-3, ratio=10.0)
    extra = {**FIELD, **(field or {})} if background == "correlated" else {}
    ph = MapPhantom(inclusion=inc, seed=seed * 1000 + i, **extra)
    if inc is not None and LUMPS["kind"] == "twin":
        ph = replace(ph, lump_gain=twin_gains(ph, inc, LUMPS["depths"]))
    return ph


def truth_of(ph) -> dict:
    from palpbayes.inclusion import apparent_ratio, sensitivity
    from palpbayes.sim.map import lump_summary

    inc = ph.inclusion
    if inc is None:
        return {"has_lump": False, "x": math.nan, "y": math.nan, "size": math.nan,
                "A": 1.0, "A_screening": 1.0, "depth": math.nan}
    s = lump_summary(inc, contact_radius=ph.contact_radius, thickness=ph.thickness)
    V = sensitivity(0.0, radius=inc.radius, depth=inc.depth, contact_radius=ph.contact_radius,
                    thickness=ph.thickness)
    screening = float(apparent_ratio(V, inc.ratio))
    return {"has_lump": True, "x": inc.x, "y": inc.y, "size": s["apparent_fwhm_diameter_m"],
            "A": screening ** ph.gain(ph.indentation), "A_screening": screening,
            "depth": inc.depth}


class Presser:
    """Simulate and fit one press (a real trace through the exact engine)."""

    def __init__(self, ph):
        from palpbayes.campaign.fitjob import FitOptions
        from palpbayes.maps.pertrace import PointOptions

        self.ph = ph
        self.opts = PointOptions(fit=FitOptions(layer="off", nu=ph.nu), draws=1000)
        self.count = 0

    def __call__(self, x: float, y: float, key: str, depth: float | None = None
                 ) -> tuple[float, float]:
        from palpbayes.maps.pertrace import fit_point

        trace = self.ph.press(float(x), float(y), key, depth=depth)
        row = pd.Series({"trace_id": key, "x_m": x, "y_m": y})
        rec = fit_point(row, self.opts, self.count, trace=trace)
        self.count += 1
        if rec["error"] or not np.isfinite(rec["logE_mean"]):
            raise RuntimeError(f"press {key} at ({x}, {y}) did not fit: {rec['error']}")
        return float(rec["logE_mean"]), float(rec["logE_sd"])


#: The posterior's background model in this process (``--model``).
MODEL = {"background": "white"}


def _state(ph, depths: tuple[float, ...] | None = None):
    """A search state with no press, at one depth [m] (None: the phantom's) or choosing
    among ``depths`` (two or more)."""
    from palpbayes.active import SearchState
    from palpbayes.active.depth import PressDepths
    from palpbayes.active.search import PRESS_COLUMNS
    from palpbayes.inclusion import contact_radius

    depths = depths or (ph.indentation,)
    choice = PressDepths.for_tip(ph.tip, depths) if len(depths) > 1 else None
    return SearchState(pd.DataFrame(columns=PRESS_COLUMNS), FOOTPRINT,
                       contact_radius(ph.tip, depths[0]), ph.thickness,
                       background=MODEL["background"], press_depths=choice)


def seconds(depth: float) -> float:
    """[s] The time of one press to ``depth`` [m] at the default overhead and speed."""
    from palpbayes.active.depth import press_seconds

    return float(press_seconds(depth))


def _score(decision: str, info: dict, truth: dict, n: int) -> dict:
    wrong = bool(decision) and ((decision == "lump") != truth["has_lump"])
    centre = math.nan
    if truth["has_lump"] and decision == "lump":
        centre = math.hypot(info["x_m"] - truth["x"], info["y_m"] - truth["y"])
    return {"presses": n, "decision": decision, "wrong": wrong, "centre_err_m": centre}


class Milestones:
    """The first press count at which the lump is detected (P(lump) >= 0.95) with its centre
    within 2 mm of the truth, and with its apparent size (FWHM) within 20 %."""

    def __init__(self, truth: dict):
        self.truth, self.centre, self.size = truth, None, None

    def see(self, n: int, p_lump: float, centre: tuple[float, float], size: float) -> None:
        t = self.truth
        if not t["has_lump"] or p_lump < 0.95:
            return
        if self.centre is None and math.hypot(centre[0] - t["x"], centre[1] - t["y"]) <= 2e-3:
            self.centre = n
        if self.size is None and abs(size / t["size"] - 1.0) <= 0.2:
            self.size = n

    def row(self) -> dict:
        return {"centre_presses": self.centre, "size_presses": self.size}


def run_active(ph, truth, criterion: str, budget: int, depths=None
               ) -> tuple[dict, list[dict]]:
    from palpbayes.active import SearchStopRule, next_presses

    rule = SearchStopRule(max_presses=budget)
    press, state, seq, times, ms = Presser(ph), _state(ph, depths), [], [], Milestones(truth)
    used = 0.0
    d0 = (depths or (ph.indentation,))[0]
    while True:
        t0 = time.perf_counter()
        r = next_presses(state, criterion=criterion, rule=rule)
        times.append((state.n, time.perf_counter() - t0))
        if state.n:
            seq.append({"n": state.n, **r.summary})
            i = r.summary
            ms.see(state.n, i["p_lump"], (i["x_m"], i["y_m"]), i["size_m"])
        if r.stop:
            break
        x, y = float(r.presses.x_m.iloc[0]), float(r.presses.y_m.iloc[0])
        d = float(r.presses.depth_m.iloc[0]) if "depth_m" in r.presses else d0
        tag = "" if len(depths or ()) < 2 else "depths-"
        m, s = press(x, y, f"{criterion}-{tag}{state.n}", d)
        used += seconds(d)
        extra = {"depth_m": d} if "depth_m" in r.presses else {}
        state = state.with_press(x, y, m, s, **extra)
    xy = state.presses[["x_m", "y_m"]].to_numpy(dtype=float)
    for row in seq:  # the summary after n presses, and where the n-th one was
        row.update(press_x_m=xy[row["n"] - 1, 0], press_y_m=xy[row["n"] - 1, 1])
    out = _score(r.decision, r.summary, truth, state.n)
    deep = (state.presses["depth_m"].to_numpy(dtype=float) > d0 * 1.001).sum() if (
        "depth_m" in state.presses) else 0
    out.update(**ms.row(), times=times, press_s=used, deeper=int(deep))
    return out, seq, state


def run_random(ph, truth, budget: int, seed: int, depth: float) -> dict:
    from palpbayes.active import SearchStopRule
    from palpbayes.active.search import decide, summary

    rule = SearchStopRule(max_presses=budget)
    rng = np.random.default_rng([seed, 7])
    press, state, ms = Presser(ph), _state(ph, (depth,)), Milestones(truth)
    x0, x1, y0, y1 = FOOTPRINT
    while True:
        x, y = rng.uniform(x0, x1), rng.uniform(y0, y1)
        m, s = press(x, y, f"random-{depth:g}-{state.n}", depth)
        state = state.with_press(x, y, m, s)
        if state.n % RANDOM_EVERY and state.n < budget:
            continue
        post = state.posterior()
        decision, reason = decide(post, rule)
        ms.see(state.n, post.p_lump, post.centre, post.size)
        if reason:
            break
    out = _score(decision, summary(state, post, rule), truth, state.n)
    out.update(**ms.row(), press_s=state.n * seconds(depth))
    return out


def run_raster(ph, truth, budget: int, depth: float) -> dict:
    from palpbayes.active import SearchStopRule
    from palpbayes.active.search import decide, summary

    rule = SearchStopRule()
    x0, x1, y0, y1 = FOOTPRINT
    ms, last = Milestones(truth), None
    for m in range(3, int(math.isqrt(budget)) + 1):
        press, state = Presser(ph), _state(ph, (depth,))
        g = (np.arange(m) + 0.5) / m
        for j, (gx, gy) in enumerate((a, b) for b in g for a in g):
            x, y = x0 + gx * (x1 - x0), y0 + gy * (y1 - y0)
            mm, s = press(x, y, f"raster{m}-{depth:g}-{j}", depth)
            state = state.with_press(x, y, mm, s)
        post = state.posterior()
        decision, reason = decide(post, rule)
        ms.see(m * m, post.p_lump, post.centre, post.size)
        last = (decision, summary(state, post, rule), m * m)
        if reason:
            break
    out = _score(last[0], last[1], truth, last[2])
    out.update(**ms.row(), press_s=last[2] * seconds(depth))
    return out


def run_phantom(job: dict) -> dict:
    import warnings

    warnings.simplefilter("ignore")
    i, seed, budget = job["i"], job["seed"], job["budget"]
    MODEL["background"] = job["model"]
    LUMPS.update(job["lumps"])
    ph = make_phantom(i, seed, job["background"], job["field"])
    truth = truth_of(ph)
    depths = tuple(f * ph.thickness for f in LUMPS["depths"])
    rows, seqs = [], {}
    for crit in job["criteria"]:
        t0 = time.perf_counter()
        res, seq, _ = run_active(ph, truth, crit, budget)
        rows.append({"strategy": f"active-{crit}", **res, "wall_s": time.perf_counter() - t0})
        seqs[crit] = seq
        if len(depths) > 1 and crit == "eig":
            t0 = time.perf_counter()
            res, seq, _ = run_active(ph, truth, crit, budget, depths)
            rows.append({"strategy": f"active-{crit}-depths", **res,
                         "wall_s": time.perf_counter() - t0})
            seqs[f"{crit}-depths"] = seq
    if job["baselines"]:
        for k, d in enumerate(depths):
            tag = "" if k == 0 else f"@{d / ph.thickness:g}"
            t0 = time.perf_counter()
            rows.append({"strategy": "random" + tag,
                         **run_random(ph, truth, budget, seed * 1000 + i, d),
                         "wall_s": time.perf_counter() - t0})
            t0 = time.perf_counter()
            rows.append({"strategy": "raster" + tag, **run_raster(ph, truth, budget, d),
                         "wall_s": time.perf_counter() - t0})
    for r in rows:
        r.update(phantom=i, has_lump=truth["has_lump"], A_true=truth["A"],
                 A_screening=truth["A_screening"], depth_true_m=truth["depth"],
                 size_true_m=truth["size"])
    return {"rows": rows, "seqs": seqs, "truth": truth}


def report(table: pd.DataFrame, budget: int) -> pd.DataFrame:
    out = []
    for name, g in table.groupby("strategy", sort=False):
        decided = g["decision"].astype(bool)
        n = np.where(decided, g["presses"], budget)
        lump = g[g["has_lump"] & (g["decision"] == "lump")]
        lumps = g[g["has_lump"]]
        big = lump[lump["A_true"] >= 1.07]  # found lumps of >= 7 % excess at the first depth
        out.append({
            "strategy": name, "phantoms": len(g), "decided": int(decided.sum()),
            "presses_median": float(np.median(n)), "presses_mean": float(np.mean(n)),
            "presses_lump_mean": float(np.mean(n[g["has_lump"].to_numpy()])),
            "presses_none_mean": float(np.mean(n[~g["has_lump"].to_numpy()])),
            "wrong": int(g["wrong"].sum()),
            "wrong_rate": float(g["wrong"].sum() / max(1, decided.sum())),
            "centre_2mm": f"{int((lump['centre_err_m'] <= 2e-3).sum())}/"
                          f"{int(g['has_lump'].sum())}",
            "centre_2mm_7pct": f"{int((big['centre_err_m'] <= 2e-3).sum())}"
                               f"/{int((lumps['A_true'] >= 1.07).sum())}",
            "deep_found": f"{int((lump['A_screening'] < 1.065).sum())}/"
                          f"{int((lumps['A_screening'] < 1.065).sum())}",
            "press_s_mean": float(g["press_s"].mean()),
            "deeper_mean": float(g["deeper"].mean()) if "deeper" in g else 0.0,
            **{f"{what}_{stat}": v for what in ("centre", "size")
               for stat, v in _milestone(lumps[f"{what}_presses"], budget).items()},
        })
    return pd.DataFrame(out)


def _milestone(v: pd.Series, budget: int) -> dict:
    """Median presses to a milestone (not reached: the budget) and how many reached it."""
    v = v.astype(float)
    return {"median": float(np.median(np.where(v.notna(), v, budget))) if len(v) else math.nan,
            "reached": int(v.notna().sum())}


def time_posteriors(n: int, states: int, seed: int) -> dict:
    """Wall time [s] of one posterior on ``states`` states of ``n`` presses (simulated
    readings on correlated-background phantoms, no fit: the posterior's cost only), per
    model: {model: array}."""
    from palpbayes.active.posterior import hypotheses, posterior

    ph = make_phantom(0, seed, "correlated")
    out = {}
    for model in ("white", "correlated"):
        hyp = hypotheses(FOOTPRINT, contact_radius=ph.contact_radius, thickness=ph.thickness,
                         background=model)
        t = []
        for i in range(states):
            rng = np.random.default_rng([seed, 98, i])
            x, y = rng.uniform(FOOTPRINT[0], FOOTPRINT[1], (2, n))
            s = rng.uniform(0.005, 0.015, n)
            m = (np.log(ph.apparent_modulus(x, y)) + ph.background_field(x, y)
                 + 0.03 * rng.standard_normal(n))
            t0 = time.perf_counter()
            posterior(hyp, x, y, m, s)
            t.append(time.perf_counter() - t0)
        out[model] = np.array(t)
    return out


def time_large_states(n: int, states: int, seed: int) -> np.ndarray:
    """Wall time [s] of next_presses (eig, k = 1) on ``states`` states of ``n`` random presses
    (simulated and fitted on lump phantoms, undecided so that the candidates are scored)."""
    from palpbayes.active import SearchStopRule, next_presses

    out = []
    for i in range(states):
        ph = make_phantom(2 * i, seed + 99)
        press, state = Presser(ph), _state(ph)
        rng = np.random.default_rng([seed, 99, i])
        x0, x1, y0, y1 = FOOTPRINT
        for j in range(n):
            x, y = rng.uniform(x0, x1), rng.uniform(y0, y1)
            state = state.with_press(x, y, *press(x, y, f"time-{j}"))
        rule = SearchStopRule(centre_radius=1e-6)  # never placed: always score the candidates
        next_presses(state, rule=rule)  # the grid is built once per specimen: not timed
        t0 = time.perf_counter()
        next_presses(state, rule=rule)
        out.append(time.perf_counter() - t0)
    return np.array(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--phantoms", type=int, default=50)
    ap.add_argument("--criteria", default="eig")
    ap.add_argument("--no-baselines", action="store_true")
    ap.add_argument("--budget", type=int, default=225)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--background", choices=("white", "correlated"), default="white",
                    help="the phantoms' heterogeneity: white only, or with a correlated field")
    ap.add_argument("--field-sd", type=float, default=FIELD["field_sd"],
                    help="sd of ln E of the correlated field (--background correlated)")
    ap.add_argument("--field-length", type=float, default=FIELD["field_length"],
                    help="[m] its correlation length")
    ap.add_argument("--model", choices=("white", "correlated"), default="white",
                    help="the search posterior's background model")
    ap.add_argument("--depths", default="0.1,0.2", metavar="F1,F2",
                    help="press depths as fractions of the thickness, the first the fixed "
                         "one; two or more add active-eig-depths and the baselines at each")
    ap.add_argument("--lumps", choices=("twin", "screening"), default="twin",
                    help="the phantoms' lumps: scaled to the twin's centre reading, or the "
                         "screening model's")
    ap.add_argument("--out", default="reports/active")
    ap.add_argument("--figure", type=int, default=0, metavar="I",
                    help="draw the searches of phantoms I (a lump) and I + 1 (none); -1: none")
    ap.add_argument("--time-states", type=int, default=5,
                    help="states of 200 presses to time a decision on (0: skip)")
    args = ap.parse_args(argv)
    criteria = [c for c in args.criteria.split(",") if c]
    field = {"field_sd": args.field_sd, "field_length": args.field_length}
    MODEL["background"] = args.model
    lumps = {"kind": args.lumps, "depths": tuple(float(v) for v in args.depths.split(","))}
    LUMPS.update(lumps)
    jobs = [{"i": i, "seed": args.seed, "budget": args.budget, "criteria": criteria,
             "baselines": not args.no_baselines, "background": args.background,
             "field": field, "model": args.model, "lumps": lumps}
            for i in range(args.phantoms)]
    t0 = time.perf_counter()
    results = []
    with cf.ProcessPoolExecutor(args.workers) as pool:
        for k, res in enumerate(pool.map(run_phantom, jobs), 1):
            results.append(res)
            print(f"  phantom {k}/{len(jobs)}: " + "; ".join(
                f"{r['strategy']} {r['presses']} {r['decision'] or '-'}"
                + (" WRONG" if r["wrong"] else "") for r in res["rows"]), flush=True)
    rows = [r for res in results for r in res["rows"]]
    times = [t for r in rows for t in r.pop("times", [])]
    table = pd.DataFrame(rows)
    pd.set_option("display.width", 200)
    print(f"\n{args.phantoms} phantoms ({args.background} background"
          + (f", field sd {args.field_sd:g}, length {1e3 * args.field_length:g} mm"
             if args.background == "correlated" else "")
          + f"; {args.model} model; {args.lumps} lumps; depths {args.depths}), budget "
          f"{args.budget}, "
          f"{time.perf_counter() - t0:.0f} s on {args.workers} workers")
    summ = report(table, args.budget)
    print(summ.to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    base = summ.set_index("strategy")
    for ref in (r for r in base.index if r.startswith("raster")):
        for name in base.index:
            if name.startswith("active"):
                b, a = base.loc[ref], base.loc[name]
                print(f"{ref} / {name}: mean presses to decide "
                      f"{b['presses_mean'] / a['presses_mean']:.2f}, mean press time "
                      f"{b['press_s_mean'] / a['press_s_mean']:.2f}")
    if times:
        t = np.array([s for _, s in times])
        n = np.array([k for k, _ in times])
        big = t[n >= np.percentile(n, 90)]
        print(f"decision time: median {1e3 * np.median(t):.0f} ms, p90 "
              f"{1e3 * np.percentile(t, 90):.0f} ms, at the largest states (>= "
              f"{int(np.percentile(n, 90))} presses) median {1e3 * np.median(big):.0f} ms "
              f"(on {args.workers} busy workers)")
    if args.figure >= 0:
        from palpbayes.active import SearchStopRule
        from palpbayes.plots.active import plot_search

        for i in (args.figure, args.figure + 1):
            ph = make_phantom(i, args.seed, args.background, field)
            truth = truth_of(ph)
            depths = tuple(f * ph.thickness for f in LUMPS["depths"])
            _, _, state = run_active(ph, truth, criteria[0], args.budget,
                                     depths if len(depths) > 1 else None)
            where = (truth["x"], truth["y"]) if truth["has_lump"] else None
            what = (f"lump {2e3 * ph.inclusion.radius:g} mm across, centre "
                    f"{1e3 * ph.inclusion.depth:.1f} mm deep" if truth["has_lump"] else
                    "no lump")
            fig = plot_search(state, rule=SearchStopRule(max_presses=args.budget), truth=where,
                              title=f"phantom {i} ({what}): {state.n} presses, "
                                    f"{criteria[0]}"
                                    + (" over depths" if len(depths) > 1 else ""))
            Path(args.out).mkdir(parents=True, exist_ok=True)
            fig.savefig(Path(args.out) / f"search-phantom{i}.png", dpi=130,
                        bbox_inches="tight")
            print(f"wrote {args.out}/search-phantom{i}.png")
    if args.time_states:
        for n in (50, 200):
            tp = time_posteriors(n, args.time_states, args.seed)
            print(f"posterior at {n} presses, idle machine, {args.time_states} states: "
                  + ", ".join(f"{k} median {1e3 * np.median(v):.0f} ms (max "
                              f"{1e3 * v.max():.0f})" for k, v in tp.items()))
        t = time_large_states(200, args.time_states, args.seed)
        print(f"decision time at 200 presses, idle machine, {len(t)} states: median "
              f"{1e3 * np.median(t):.0f} ms, max {1e3 * t.max():.0f} ms (target <= 500 ms)")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    table.to_csv(out / "bench_active.csv", index=False)
    summ.to_csv(out / "bench_active_summary.csv", index=False)
    seqs = {f"{res['rows'][0]['phantom']}-{c}": s for res in results
            for c, s in res["seqs"].items()}
    (out / "sequences.json").write_text(json.dumps(seqs, default=float))
    print(f"wrote {out}/bench_active.csv, bench_active_summary.csv, sequences.json")
    return 0


if __name__ == "__main__":
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    sys.exit(main())
