"""palpbayes' viscoelastic fit beside PyFMRheo's Ting fit, on the peer's own 4 × 4 map and on
simulations of known truth.

The peer runs in its own virtual environment, installed from PyPI (MIT; never committed)::

    python3 -m venv /tmp/pyfm && /tmp/pyfm/bin/pip install pyfmrheo==0.1.3
    python benchmarks/bench_visco_peer.py --peer-python /tmp/pyfm/bin/python

(``benchmarks/pyfmrheo_worker.py`` is what that interpreter runs.)  ~14 min on 2 cores
(``--part map``: ~7 min; ``--part sim``: ~7 min).

Part 1, the map (``../shared/data/afm-files/pyfmrheo-map-...jpk-force-map``): per curve,
the peer with its notebook's settings (analytical Ting model: constant speeds) and the
range its notebook's own choices span (contact-point window ×0.5, ×2; fit range 0.5, 2 µm
above the contact); the peer's numerical model (the measured indentation) and its range;
palpbayes with its defaults (approach and retract, drag fitted), with ``adhesion="cut"`` and
a linear baseline, and with ``--peer-compatible pyfmrheo``
(:func:`palpbayes.rheology.peer.pyfmrheo_compatible`).  E0 is Young's modulus at nu 0.5
(palpbayes' E0* × 0.75), alpha PyFMRheo's betaE.  "agrees" means palpbayes' 90 % interval
overlaps the peer's range (the peer gives no interval of its own).

Part 2, simulations (what decides who is right): curve 0's recorded motion (the heights
smoothed per segment) or straight ramps between the same heights, a power-law half-space of
known E0* and alpha (palpbayes' answer for curve 0, and the peer's), white noise of the
map's sd, the notebook's drag, fitted by both.  Then the artefacts of the real curves one at
a time on the recorded motion (adhesion at pull-off, a tilted baseline), fitted by palpbayes
with and without the options that model them.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

from palpbayes.contact import PowerLawKernel, Tip
from palpbayes.contact.viscoelastic import hereditary_force
from palpbayes.io.afm import read_afm
from palpbayes.rheology import fit_rheology
from palpbayes.rheology.peer import PYFMRHEO_DRAG, nominal_ramps, pyfmrheo_compatible

ROOT = Path(__file__).resolve().parents[1]
MAP = ROOT.parent / "shared/data/afm-files/pyfmrheo-map-data-2022.10.29-12.27.34.564.jpk-force-map"
WORKER = Path(__file__).with_name("pyfmrheo_worker.py")
TIP = Tip("paraboloid", radius=5e-6)
NU = 0.5
YOUNG = 1.0 - NU**2  # E = E*(1 - nu^2)
ANALYTICAL = ["notebook", "poc_win 200 nm", "poc_win 800 nm", "range 0.5 um", "range 2 um"]
NUMERICAL = ["numerical"] + [f"numerical, {v}" for v in ANALYTICAL[1:]]
EXACT = ["exact 2F1"] + [f"exact 2F1, {v}" for v in ANALYTICAL[1:]]
SPRING = 0.191  # [N/m] the map's cantilever (its header)


def peer(python: str, mode: str, path: Path, variants: list[str]) -> pd.DataFrame:
    out = subprocess.run([python, str(WORKER), mode, str(path), ";".join(variants)],
                         capture_output=True, text=True, check=True)
    return pd.DataFrame([json.loads(line) for line in out.stdout.splitlines()])


# ---------------------------------------------------------------------------- palpbayes
def _summary(fit, label: str) -> dict:
    d = fit.draws
    e0 = np.quantile(d["E0"], [0.05, 0.5, 0.95]) * YOUNG
    al = np.quantile(d["alpha"], [0.05, 0.5, 0.95])
    return {"how": label, "E0": e0[1], "E0_lo": e0[0], "E0_hi": e0[2], "alpha": al[1],
            "alpha_lo": al[0], "alpha_hi": al[2], "ok": bool(fit.model_ok),
            "flags": "; ".join(f.split(":")[0][:40] for f in fit.flags)}


def _fit_map_curve(i: int) -> list[dict]:
    tr = read_afm(MAP, tip=TIP, curves=[i], segments="all")[0]
    rows = [_summary(fit_rheology(tr, "power-law", nu=NU, segments="approach,retract"),
                     "default")]
    rows.append(_summary(fit_rheology(tr, "power-law", nu=NU, segments="approach,retract",
                                      baseline="linear", adhesion="cut"), "cut+linear"))
    like, kw = pyfmrheo_compatible(tr)
    rows.append(_summary(fit_rheology(like, "power-law", nu=NU, **kw), "peer-compatible"))
    return [{"curve": i, **r} for r in rows]


def _range(df: pd.DataFrame, variants: list[str], col: str) -> tuple[float, float, float]:
    x = df[df.variant.isin(variants)][col].dropna()
    main = df[df.variant == variants[0]][col]
    return float(main.iloc[0]) if main.size else np.nan, float(x.min()), float(x.max())


def _overlap(lo: float, hi: float, a: float, b: float) -> bool:
    return bool(hi >= a and lo <= b)


def part_map(python: str, workers: int) -> pd.DataFrame:
    t = time.perf_counter()
    pe = peer(python, "map", MAP, ANALYTICAL + EXACT + NUMERICAL + ["speeds from data"])
    t_peer = time.perf_counter() - t
    t = time.perf_counter()
    with ProcessPoolExecutor(workers) as ex:
        ours = pd.DataFrame([r for rows in ex.map(_fit_map_curve, range(16)) for r in rows])
    t_ours = time.perf_counter() - t
    lines = []
    for i in range(16):
        p = pe[pe.curve == i]
        row = {"curve": i}
        for name, vs in (("nb", ANALYTICAL), ("ex", EXACT), ("num", NUMERICAL)):
            for col, out in (("E0", "E0"), ("beta", "alpha")):
                v, lo, hi = _range(p, vs, col)
                row.update({f"{name}_{out}": v, f"{name}_{out}_lo": lo, f"{name}_{out}_hi": hi})
        row["v_E0"], row["v_alpha"] = _range(p, ["speeds from data"], "E0")[0], \
            _range(p, ["speeds from data"], "beta")[0]
        for _, r in ours[ours.curve == i].iterrows():
            k = {"default": "pb", "cut+linear": "cut", "peer-compatible": "like"}[r.how]
            row.update({f"{k}_{c}": r[c] for c in ("E0", "E0_lo", "E0_hi", "alpha", "alpha_lo",
                                                   "alpha_hi", "ok", "flags")})
        for ours_k, peer_k in (("pb", "num"), ("pb", "nb"), ("like", "nb"), ("like", "ex"),
                               ("cut", "num")):
            row[f"{ours_k}~{peer_k}"] = all(
                _overlap(row[f"{ours_k}_{c}_lo"], row[f"{ours_k}_{c}_hi"],
                         row[f"{peer_k}_{c}_lo"], row[f"{peer_k}_{c}_hi"])
                for c in ("E0", "alpha"))
        lines.append(row)
    tab = pd.DataFrame(lines)
    print(f"\n== PyFMRheo's 4 x 4 map: E0 [Pa] (Young's, nu 0.5) and alpha; peer "
          f"{t_peer:.0f} s, palpbayes {t_ours:.0f} s on {workers} workers ==")
    print("peer nb = its notebook (analytical Ting: constant speeds), [range over its notebook's"
          " contact window x0.5/x2 and fit range 0.5/2 um]; exact 2F1 = the notebook with "
          "scipy's 2F1 in place of its approximation; peer num = its numerical model "
          "(measured indentation), same variants; pb = palpbayes defaults, [90 % interval]; "
          "cut = --adhesion cut --baseline linear; like = --peer-compatible pyfmrheo")
    fmt = []
    for _, r in tab.iterrows():
        fmt.append({
            "curve": r.curve,
            "peer nb E0": f"{r.nb_E0:.0f} [{r.nb_E0_lo:.0f}, {r.nb_E0_hi:.0f}]",
            "nb alpha": f"{r.nb_alpha:.3f} [{r.nb_alpha_lo:.2f}, {r.nb_alpha_hi:.2f}]",
            "exact 2F1 E0": f"{r.ex_E0:.0f}", "ex alpha": f"{r.ex_alpha:.3f}",
            "peer num E0": f"{r.num_E0:.0f} [{r.num_E0_lo:.0f}, {r.num_E0_hi:.0f}]",
            "num alpha": f"{r.num_alpha:.3f} [{r.num_alpha_lo:.2f}, {r.num_alpha_hi:.2f}]",
            "pb E0": f"{r.pb_E0:.0f} [{r.pb_E0_lo:.0f}, {r.pb_E0_hi:.0f}]",
            "pb alpha": f"{r.pb_alpha:.3f} [{r.pb_alpha_lo:.2f}, {r.pb_alpha_hi:.2f}]",
            "cut E0": f"{r.cut_E0:.0f}", "cut alpha": f"{r.cut_alpha:.3f}",
            "cut ok": "yes" if r.cut_ok else "no",
            "like E0": f"{r.like_E0:.0f}", "like alpha": f"{r.like_alpha:.3f}",
        })
    with pd.option_context("display.width", 250, "display.max_columns", 30):
        print(pd.DataFrame(fmt).to_string(index=False))
    n = len(tab)
    print("\nagreement (90 % interval overlaps the peer's range, E0 and alpha both):")
    print(f"  palpbayes defaults ~ peer numerical model: {int(tab['pb~num'].sum())}/{n}")
    print(f"  palpbayes defaults ~ peer notebook:        {int(tab['pb~nb'].sum())}/{n}")
    print(f"  --peer-compatible  ~ peer notebook:        {int(tab['like~nb'].sum())}/{n}")
    print(f"  --peer-compatible  ~ notebook, exact 2F1:  {int(tab['like~ex'].sum())}/{n}")
    print(f"  cut+linear         ~ peer numerical model: {int(tab['cut~num'].sum())}/{n}")
    for k in ("pb~num", "like~nb", "like~ex", "cut~num"):
        print(f"  {k} disagree: curves {', '.join(str(c) for c in tab.curve[~tab[k]]) or 'none'}")
    print(f"  medians: peer notebook alpha {tab.nb_alpha.median():.3f}, exact 2F1 "
          f"{tab.ex_alpha.median():.3f}, speeds from data "
          f"{tab.v_alpha.median():.3f}, numerical {tab.num_alpha.median():.3f}; palpbayes "
          f"{tab.pb_alpha.median():.3f}, cut+linear {tab.cut_alpha.median():.3f}, "
          f"peer-compatible {tab.like_alpha.median():.3f}")
    print(f"  every check passed: defaults {int(tab.pb_ok.sum())}/{n}, cut+linear "
          f"{int(tab.cut_ok.sum())}/{n}")
    for _, r in tab[~tab.cut_ok.astype(bool)].iterrows():
        print(f"    curve {r.curve} (cut+linear) fails: {r.cut_flags}")
    return tab


# ---------------------------------------------------------------------------- simulations
def _smooth_motion() -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
    """Curve 0's time, heights smoothed per segment (degree-7 polynomial), segments, its
    surface (palpbayes' median) and its force noise sd (first differences of the approach's
    first half)."""
    tr = read_afm(MAP, tip=TIP, curves=[0], segments="all")[0]
    z = np.empty_like(tr.z)
    for code in (0, 2):
        m = tr.segment == code
        u = (tr.time[m] - tr.time[m][0]) / np.ptp(tr.time[m])
        z[m] = np.polynomial.Polynomial.fit(u, tr.z[m], 7)(u)
    first = (tr.segment == 0) & (tr.time < 0.1)
    sd = float(np.std(np.diff(tr.force[first])) / np.sqrt(2))
    return tr.time, z, tr.segment, 10.13e-6, sd


def _ramps(t, z, seg):
    """Straight ramps between each segment's first and last height (the peer's motion)."""
    from palpbayes.trace import IndentationTrace
    return nominal_ramps(IndentationTrace(time=t, z=z, force=np.zeros_like(z), tip=TIP,
                                          segment=seg)).z


def simulate(E0s: float, alpha: float, motion: str, seed: int, *, adhesion: float = 0.0,
             tilt: float = 0.0):
    t, z, seg, zs, sd = _smooth_motion()
    if motion == "ramps":
        z = _ramps(t, z, seg)
    from palpbayes.contact import prefactor
    g = prefactor(TIP)
    f = hereditary_force(t, zs - z, g, 1.5, PowerLawKernel(E0s, alpha, 1.0))
    if adhesion:  # palpbayes.sim.adhesive_pull_off's pull, on this recorded motion
        ret = np.flatnonzero((seg == 2) & (np.arange(t.size) > np.argmax(f)) & (f <= 0))
        s = np.clip(z - z[ret[0]], 0.0, None) * (np.arange(t.size) >= ret[0])
        f = f - adhesion * (s / 0.3e-6) * np.exp(1.0 - s / 0.3e-6)
    from palpbayes.sim.viscoelastic import add_baseline_terms
    from palpbayes.trace import IndentationTrace
    rng = np.random.default_rng(seed)
    tr = IndentationTrace(time=t, z=z, force=f + sd * rng.standard_normal(t.size) - 9e-9,
                          tip=TIP, trace_id=f"sim-{motion}-{seed}", segment=seg)
    return add_baseline_terms(tr, drag=PYFMRHEO_DRAG, tilt=tilt, z_ref=float(z.mean()))


def _fit_sim(args) -> dict:
    case, E0s, alpha, motion, seed, kw, extra = args
    tr = simulate(E0s, alpha, motion, seed, **extra)
    fit = fit_rheology(tr, "power-law", nu=NU, segments="approach,retract", **kw)
    s = _summary(fit, case)
    e0_true = E0s * YOUNG
    return {**s, "seed": seed, "E0_true": e0_true, "alpha_true": alpha,
            "E0_err": s["E0"] / e0_true - 1, "alpha_err": s["alpha"] - alpha,
            "covers": bool(s["E0_lo"] <= e0_true <= s["E0_hi"]
                           and s["alpha_lo"] <= alpha <= s["alpha_hi"])}


def part_sim(python: str, workers: int, seeds: int) -> None:
    truths = {"palpbayes' curve 0": (127.0, 0.40), "peer's curve 0": (445.0, 0.17)}
    jobs, arrays, keys = [], {"spring": SPRING}, []
    for label, (E0s, alpha) in truths.items():
        for motion in ("recorded", "ramps"):
            for seed in range(seeds):
                case = f"{label}, {motion}"
                jobs.append((case, E0s, alpha, motion, seed, {}, {}))
                tr = simulate(E0s, alpha, motion, seed)
                k = len(keys)
                arrays.update({f"t{k}": tr.time, f"z{k}": tr.z, f"f{k}": tr.force,
                               f"s{k}": tr.segment})
                keys.append((case, E0s * YOUNG, alpha, seed))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "sims.npz"
        np.savez(path, **arrays)
        pe = peer(python, "sim", path, ["notebook", "exact 2F1", "numerical"])
    rows = []
    for _, r in pe.iterrows():
        case, e0, alpha, seed = keys[int(r.curve)]
        if isinstance(r.get("error"), str):
            rows.append({"how": f"peer {r.variant}", "case": case, "failed": 1})
            continue
        rows.append({"how": f"peer {r.variant}", "case": case, "E0_err": r.E0 / e0 - 1,
                     "alpha_err": r.beta - alpha, "failed": 0})
    with ProcessPoolExecutor(workers) as ex:
        ours = list(ex.map(_fit_sim, jobs))
    rows += [{"how": "palpbayes", "case": j[0], "E0_err": o["E0_err"],
              "alpha_err": o["alpha_err"], "covers": o["covers"], "failed": 0}
             for j, o in zip(jobs, ours, strict=True)]
    df = pd.DataFrame(rows)
    print(f"\n== Simulations of known truth ({seeds} seeds each): median error of E0 and alpha ==")
    print("recorded = curve 0's measured heights (smoothed); ramps = straight ramps between "
          "the same heights (what the peer's analytical model assumes); drag 2.5e-6 N·s/m, "
          "white noise of the map's sd")
    g = df.groupby(["case", "how"]).agg(E0_err=("E0_err", "median"),
                                       alpha_err=("alpha_err", "median"),
                                       failed=("failed", "sum"), n=("failed", "size"))
    cov = df[df.how == "palpbayes"].groupby("case").covers.mean()
    with pd.option_context("display.width", 200):
        print(g.assign(E0_err=lambda x: (100 * x.E0_err).map("{:+.1f} %".format),
                       alpha_err=lambda x: x.alpha_err.map("{:+.3f}".format)).to_string())
    print("palpbayes' 90 % intervals cover both truths:", cov.round(2).to_dict())

    # artefacts on the recorded motion, palpbayes' truth
    E0s, alpha = truths["palpbayes' curve 0"]
    art = []
    for name, extra in (("adhesion 100 pN", {"adhesion": 100e-12}),
                        ("tilt 2.3e-5 N/m", {"tilt": 2.3e-5})):
        for how, kw in (("defaults", {}), ("cut+linear", {"adhesion": "cut",
                                                          "baseline": "linear"})):
            art += [(f"{name}: {how}", E0s, alpha, "recorded", s, kw, extra)
                    for s in range(seeds)]
    with ProcessPoolExecutor(workers) as ex:
        res = pd.DataFrame(list(ex.map(_fit_sim, art)))
    print("\n== Artefacts of the real curves, palpbayes' truth, recorded motion ==")
    with pd.option_context("display.width", 200):
        print(res.groupby("how").agg(
            E0_err=("E0_err", lambda x: f"{100 * np.median(x):+.1f} %"),
            alpha_err=("alpha_err", lambda x: f"{np.median(x):+.3f}"),
            covers=("covers", "mean"), checks_pass=("ok", "mean")).to_string())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--peer-python", default="/tmp/pyfm/bin/python",
                    help="the interpreter of the venv holding pyfmrheo 0.1.3")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seeds", type=int, default=4, help="simulations per case")
    ap.add_argument("--part", choices=("map", "sim", "both"), default="both")
    a = ap.parse_args(argv)
    if not Path(a.peer_python).exists():
        print(f"no peer interpreter at {a.peer_python}: python3 -m venv /tmp/pyfm && "
              "/tmp/pyfm/bin/pip install pyfmrheo==0.1.3", file=sys.stderr)
        return 2
    if not MAP.exists():
        print(f"the map is not at {MAP} (../shared/data beside the project)", file=sys.stderr)
        return 2
    if a.part in ("map", "both"):
        part_map(a.peer_python, a.workers)
    if a.part in ("sim", "both"):
        part_sim(a.peer_python, a.workers, a.seeds)
    return 0


if __name__ == "__main__":
    sys.exit(main())
