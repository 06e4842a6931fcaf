#!/usr/bin/env python
"""Real AFM curves: half-space model against a layer of unknown thickness on a rigid base.

For every curve palpbayes' readers return from the shared real-data folders

* ``<shared>/afm-curves/*.csv`` (approach curves converted from JPK files), and
* ``<shared>/afm-files/*`` (JPK force curves, force maps and QI data, an AFM Workshop zip:
  every curve of every map is read on its own, so one refused curve does not hide the others),

this script fits, with the Bayesian model (``palpbayes.campaign.fitjob.fit_trace``, nu = 0.5,
``--engine`` exact by default, ``--noise`` as given),

(a) the half-space (``FitOptions(layer="off")``, the paper's model), and
(b) a layer of unknown thickness on a rigid base (``layer="unknown"``: log-uniform h over 1.5
    to 1,000 times the indentation depth, plus a half-space component of prior 0.5; the base
    bonded, free or, by default, unknown: ``--bonding``).

No file records the tip: a paraboloid of R = 5 µm for PyFMRheo's map (the radius its example
notebook uses), R = 10 µm for every other file (the afm-curves references' radius).  Files or
curves the readers refuse (and fits the package refuses) are recorded with the message.

One CSV row per curve and model (``--out``): file, curve index, n_points, E and its 90 %
interval (full: with the model form; budget; statistical), the model form's share of the
width and its alternatives, model_ok, the failed checks, m_free and the law's m
(``details["m_law"]`` of the exponent check), the thickness' median and 90 % interval, its
prior range, p_halfspace, p_bonded, the fitted concrete model, the fit time, numpy/runtime
warnings raised inside the fit, and the flags.  Then a summary is printed: per model the curves
fitted, how many pass every check, how many fail only the posterior-predictive/residual checks,
failure counts per check, the distribution of m_free and of m_free - m_law, p_halfspace, the
curves with an identified thickness (p_halfspace < 0.05 and h_hi/h_lo < 3, and whether that h
sits on the prior's lower edge), and fit times.

Run from the repository root::

    .venv/bin/python tools/real_curves_layer_study.py --out /tmp/layers.csv
    .venv/bin/python tools/real_curves_layer_study.py --noise ar1 --out /tmp/layers-ar1.csv
    .venv/bin/python tools/real_curves_layer_study.py --only afm-curves --bonding bonded \\
        --out /tmp/layers-bonded.csv

(``--shared PATH`` the shared data folder, default ``../shared/data`` beside the repository;
``--limit N`` at most N curves per file; ``--only TEXT`` only files whose path contains TEXT,
repeatable; ``--models off unknown`` which models to fit.)
"""

from __future__ import annotations

import argparse
import sys
import time
import traceback
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from palpbayes.bayes.modelform import SEPARATOR
from palpbayes.campaign.fitjob import FitOptions, fit_trace
from palpbayes.contact import Tip
from palpbayes.errors import ConvergenceWarning, PalpbayesError
from palpbayes.flagcodes import split_flags
from palpbayes.io.afm import describe_afm, is_afm_file
from palpbayes.io.recording import read_recording

REPO = Path(__file__).resolve().parents[1]
DEFAULT_SHARED = REPO.parent / "shared" / "data"
FOLDERS = ("afm-curves", "afm-files")
#: Files of the folders that are no recordings.
NOT_DATA = {"README.md", "references.csv"}
NU = 0.5
#: The checks whose failure alone says "residual structure" rather than a wrong law.
STRUCTURE_CHECKS = {"ppc", "residual_structure"}
CHECKS = ("exponent", "residual_structure", "depth_consistency", "ppc")
#: An identified thickness: the data exclude the half-space and pin h within this ratio.
P_HALF_MAX, H_RATIO_MAX = 0.05, 3.0
#: h_lo within this factor of the prior's lower end: the posterior sits on the prior's edge.
EDGE = 1.05


@dataclass
class Curve:
    """One readable curve (trace) or a refusal (trace None, message)."""

    file: str
    index: int | None
    tip_radius: float
    trace: object = None
    message: str = ""


def tip_for(path: Path) -> Tip:
    """The assumed tip: PyFMRheo's map with its notebook's R = 5 µm, else R = 10 µm."""
    radius = 5e-6 if path.name.startswith("pyfmrheo") else 10e-6
    return Tip("paraboloid", radius=radius)


def _read(path: Path, tip: Tip, **options) -> list:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return read_recording(path, tip=tip, **options)


def curves_of(path: Path, limit: int | None) -> list[Curve]:
    """Every curve of ``path`` the readers return (each map curve read on its own), and the
    refusals with their messages."""
    tip = tip_for(path)
    rel = f"{path.parent.name}/{path.name}"
    if not is_afm_file(path):
        try:
            traces = _read(path, tip)
        except PalpbayesError as exc:
            return [Curve(rel, None, tip.radius, message=f"{type(exc).__name__}: {exc}")]
        return [Curve(rel, i, tip.radius, trace=t) for i, t in enumerate(traces[:limit])]
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            n = len(describe_afm(path))
    except PalpbayesError as exc:
        return [Curve(rel, None, tip.radius, message=f"{type(exc).__name__}: {exc}")]
    out = []
    for i in range(n if limit is None else min(n, limit)):
        try:
            (trace,) = _read(path, tip, curves=[i])
        except PalpbayesError as exc:
            out.append(Curve(rel, i, tip.radius, message=f"{type(exc).__name__}: {exc}"))
            continue
        out.append(Curve(rel, i, tip.radius, trace=trace))
    return out


def _finite(x) -> float:
    try:
        return float(x)
    except (TypeError, ValueError):
        return float("nan")


def fit_one(curve: Curve, layer: str, args: argparse.Namespace) -> dict:
    """One fit as a CSV row (a refusal or an unexpected exception recorded, not raised)."""
    tr = curve.trace
    row = {"file": curve.file, "curve": curve.index, "trace_id": tr.trace_id,
           "tip_radius_m": curve.tip_radius, "n_points": tr.n_points, "model": layer,
           "noise": args.noise, "bonding": args.bonding, "engine": args.engine}
    opts = FitOptions(method="bayes", nu=NU, layer=layer, engine=args.engine,
                      noise=args.noise, bonding=args.bonding, seed=args.seed)
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            out = fit_trace(tr, opts)
        except PalpbayesError as exc:
            row.update(status="refused", message=f"{type(exc).__name__}: {exc}",
                       fit_s=time.perf_counter() - t0)
            return row
        except Exception as exc:  # a crash inside the package: keep the traceback
            row.update(status="error", message=f"{type(exc).__name__}: {exc}",
                       traceback=traceback.format_exc(), fit_s=time.perf_counter() - t0)
            return row
    row["fit_s"] = time.perf_counter() - t0
    noisy = [w for w in caught if not issubclass(w.category, ConvergenceWarning)]
    row["warnings"] = " | ".join(sorted({f"{w.category.__name__}: {w.message} "
                                         f"({Path(w.filename).name}:{w.lineno})"
                                         for w in noisy}))
    r = out.rows[0]
    res = out.bayes
    checks = {c.name: c for c in res.checks}
    failed = [c.name for c in res.checks if not c.passed]
    ex = checks.get("exponent")
    model = res.data.model
    h_prior = model.thickness_range or (np.nan, np.nan)
    flags = split_flags(str(r.get("notes") or ""))
    row.update(
        status="ok", message="",
        E_pa=r["E_pa"], E_lo_pa=r["E_lo_pa"], E_hi_pa=r["E_hi_pa"], E_stat_pa=r["E_stat_pa"],
        E_stat_lo_pa=r["E_stat_lo_pa"], E_stat_hi_pa=r["E_stat_hi_pa"],
        E_budget_lo_pa=r["E_budget_lo_pa"], E_budget_hi_pa=r["E_budget_hi_pa"],
        modelform_share_pct=r["modelform_share_pct"], modelform_models=r["modelform_models"],
        z_surf_m=r["z_surf_m"], sigma_n=r["sigma_n"], converged=r["converged"],
        model_ok=r["model_ok"], n_checks=len(res.checks), failed_checks="+".join(failed),
        misfit_effect=_finite(r.get("misfit_effect")), misfit_checks=r.get("misfit_checks", ""),
        **{f"effect_{c.name}": _finite(c.details.get("effect")) for c in res.checks},
        **{f"severity_{c.name}": c.details.get("severity", "") for c in res.checks},
        m_free=_finite(r["m_free"]),
        m_se=_finite(ex.details.get("m_se")) if ex else np.nan,
        m_law=_finite(ex.details.get("m_law")) if ex else np.nan,
        depth_ratio=_finite(checks["depth_consistency"].statistic)
        if "depth_consistency" in checks else np.nan,
        residual_pattern=checks["residual_structure"].details.get("pattern", "")
        if "residual_structure" in checks else "",
        thickness_m=_finite(r.get("thickness_m")),
        thickness_lo_m=_finite(r.get("thickness_lo_m")),
        thickness_hi_m=_finite(r.get("thickness_hi_m")),
        h_prior_lo_m=_finite(h_prior[0]), h_prior_hi_m=_finite(h_prior[1]),
        p_halfspace=_finite(r.get("p_halfspace")), p_bonded=_finite(r.get("p_bonded")),
        model_fitted=r.get("model_fitted", ""),
        E_halfspace_pa=_finite(r.get("E_halfspace_pa")),
        E_bonded_pa=_finite(r.get("E_bonded_pa")), E_free_pa=_finite(r.get("E_free_pa")),
        notes=" | ".join(f for f in flags if f.startswith("info:")),
        flags=" | ".join(f for f in flags if not f.startswith("info:")),
    )
    numbers = [row[k] for k in ("E_pa", "E_lo_pa", "E_hi_pa", "E_stat_pa", "m_free")]
    row["nonfinite"] = ",".join(k for k, v in zip(("E", "E_lo", "E_hi", "E_stat", "m_free"),
                                                  numbers, strict=True)
                                if not np.isfinite(v))
    return row


# ------------------------------------------------------------------------------- summary
def _dist(x: pd.Series, fmt: str = "{:.3g}") -> str:
    x = pd.to_numeric(x, errors="coerce").dropna()
    if x.empty:
        return "-"
    q = np.quantile(x, [0, 0.25, 0.5, 0.75, 1])
    return "min {} / q25 {} / median {} / q75 {} / max {} (n={})".format(
        *(fmt.format(v) for v in q), x.size)


def _um(x: float) -> str:
    return f"{x * 1e6:.3g} µm" if np.isfinite(x) else "inf"


def identified(df: pd.DataFrame) -> pd.Series:
    """p_halfspace < P_HALF_MAX and a finite h interval of ratio < H_RATIO_MAX."""
    ratio = df["thickness_hi_m"] / df["thickness_lo_m"]
    return (df["p_halfspace"] < P_HALF_MAX) & np.isfinite(ratio) & (ratio < H_RATIO_MAX)


def summarize(df: pd.DataFrame, refusals: list[Curve]) -> str:
    lines = []
    n_curves = df.drop_duplicates(["file", "curve"]).shape[0] if not df.empty else 0
    lines.append(f"curves read: {n_curves}; refused by the readers: {len(refusals)}")
    for c in refusals:
        where = c.file if c.index is None else f"{c.file} curve {c.index}"
        lines.append(f"  refused: {where}: {c.message}")
    for layer, g in df.groupby("model", sort=False):
        ok = g[g["status"] == "ok"]
        lines.append("")
        lines.append(f"== model {layer!r} (noise {g['noise'].iloc[0]}, bonding "
                     f"{g['bonding'].iloc[0]}, engine {g['engine'].iloc[0]})")
        lines.append(f"fitted {len(ok)} of {len(g)}")
        for _, r in g[g["status"] != "ok"].iterrows():
            lines.append(f"  {r['status']}: {r['trace_id']}: {r['message']}")
        if ok.empty:
            continue
        failed = ok["failed_checks"].fillna("").map(lambda s: set(filter(None, s.split("+"))))
        lines.append(f"all checks passed: {int((failed.map(len) == 0).sum())}")
        only = failed.map(lambda s: bool(s) and s <= STRUCTURE_CHECKS)
        lines.append(f"failed only ppc/residual_structure: {int(only.sum())}")
        counts = ", ".join(f"{c} {int(failed.map(lambda s, c=c: c in s).sum())}"
                           for c in CHECKS)
        lines.append(f"failures per check: {counts}")
        combos = failed.map(lambda s: "+".join(c for c in CHECKS if c in s) or "(none)")
        lines.append("failure patterns: " + ", ".join(
            f"{k} x{v}" for k, v in combos.value_counts().items()))
        okm = ok["model_ok"].astype(str).str.lower() == "true"
        lines.append(f"no material misfit (model_ok): {int(okm.sum())}; material: "
                     f"{int((~okm).sum())}")
        for c in CHECKS:
            if f"severity_{c}" in ok:
                sev = ok[f"severity_{c}"].fillna("").replace("", "passed").value_counts()
                eff = ok.loc[ok[f"severity_{c}"] != "", f"effect_{c}"] * 100
                lines.append(f"  {c}: " + ", ".join(f"{k} {v}" for k, v in sev.items())
                             + (f"; effect of the failures on E [%]: {_dist(eff, '{:+.1f}')}"
                                if eff.size else ""))
        lines.append(f"largest material effect on E [%]: "
                     f"{_dist(ok.loc[~okm, 'misfit_effect'] * 100, '{:+.1f}')}")
        if "modelform_share_pct" in ok:
            share = pd.to_numeric(ok["modelform_share_pct"], errors="coerce")
            full = 100 * (ok["E_hi_pa"] - ok["E_lo_pa"]) / ok["E_pa"]
            bud = 100 * (ok["E_budget_hi_pa"] - ok["E_budget_lo_pa"]) / ok["E_pa"]
            lines.append(f"interval width [% of E]: budget {_dist(bud, '{:.1f}')}; full "
                         f"(with the model form) {_dist(full, '{:.1f}')}")
            lines.append(f"model-form share of the full width [%]: {_dist(share, '{:.0f}')}")
            alts = ok["modelform_models"].fillna("").str.split(SEPARATOR,
                                                               regex=False).explode()
            alts = alts[alts != ""]
            name = alts.str.extract(r"^([a-z ,]+?)(?: [\d.]| \(left out)")[0]
            left = alts.str.contains("(left out", regex=False)
            kept, out = name[~left], name[left]
            lines.append("model-form alternatives kept: " + ", ".join(
                f"{k} x{v}" for k, v in kept.value_counts().items())
                + "; left out: " + (", ".join(f"{k} x{v}" for k, v in
                                              out.value_counts().items()) or "none"))
        lines.append(f"m_free: {_dist(ok['m_free'])}")
        lines.append(f"m_law: {_dist(ok['m_law'])}")
        lines.append(f"m_free - m_law: {_dist(ok['m_free'] - ok['m_law'], '{:+.3f}')}")
        pats = ok["residual_pattern"].fillna("").replace("", "(none)").value_counts()
        lines.append("residual pattern: " + ", ".join(f"{k} x{v}" for k, v in pats.items()))
        lines.append(f"fit time [s]: {_dist(ok['fit_s'], '{:.2f}')}")
        bad = ok[ok["nonfinite"].fillna("") != ""]
        for _, r in bad.iterrows():
            lines.append(f"  NON-FINITE {r['nonfinite']}: {r['trace_id']}")
        warned = ok[ok["warnings"].fillna("") != ""]
        for _, r in warned.iterrows():
            lines.append(f"  warnings in {r['trace_id']}: {r['warnings']}")
        if layer != "unknown":
            continue
        ph = ok["p_halfspace"]
        bins = [int((ph < 0.05).sum()), int(((ph >= 0.05) & (ph < 0.5)).sum()),
                int(((ph >= 0.5) & (ph <= 0.95)).sum()), int((ph > 0.95).sum())]
        lines.append(f"p_halfspace: < 0.05: {bins[0]}, 0.05-0.5: {bins[1]}, 0.5-0.95: "
                     f"{bins[2]}, > 0.95: {bins[3]}")
        pb = ok["p_bonded"]
        lines.append(f"p_bonded: {_dist(pb, '{:.2f}')}; > 0.9: {int((pb > 0.9).sum())}, "
                     f"< 0.1: {int((pb < 0.1).sum())}")
        ident = ok[identified(ok)]
        edge = ident["thickness_lo_m"] < EDGE * ident["h_prior_lo_m"]
        lines.append(f"identified thickness (p_halfspace < {P_HALF_MAX}, h_hi/h_lo < "
                     f"{H_RATIO_MAX:g}): {len(ident)}; of which on the prior's lower edge "
                     f"(h_lo < {EDGE} x range lo): {int(edge.sum())}")
        for (_, r), e in zip(ident.iterrows(), edge, strict=True):
            lines.append(
                f"  {r['trace_id']}: h = {_um(r['thickness_m'])} [{_um(r['thickness_lo_m'])}, "
                f"{_um(r['thickness_hi_m'])}], prior from {_um(r['h_prior_lo_m'])}"
                f"{' (ON THE EDGE)' if e else ''}, p_bonded {r['p_bonded']:.2f}, "
                f"{r['model_fitted']}, E {r['E_pa']:.4g} Pa")
    both = df[df["status"] == "ok"].pivot_table(index="trace_id", columns="model",
                                                values=["E_pa", "E_lo_pa", "E_hi_pa"],
                                                aggfunc="first")
    if {"off", "unknown"} <= set(both.columns.get_level_values(1)):
        both = both.dropna()
        ratio = both[("E_pa", "unknown")] / both[("E_pa", "off")]
        inside = ((both[("E_lo_pa", "unknown")] <= both[("E_pa", "off")])
                  & (both[("E_pa", "off")] <= both[("E_hi_pa", "unknown")]))
        lines.append("")
        lines.append(f"E(unknown) / E(half-space): {_dist(ratio)}; half-space E inside the "
                     f"unknown-thickness interval: {int(inside.sum())} of {len(both)}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--shared", type=Path, default=DEFAULT_SHARED,
                    help="shared data folder (default ../shared/data beside the repository)")
    ap.add_argument("--out", type=Path, default=None, help="CSV of the per-curve results")
    ap.add_argument("--engine", default="exact", choices=("exact", "emcee"))
    ap.add_argument("--noise", default="gaussian", choices=("gaussian", "ar1"))
    ap.add_argument("--bonding", default="unknown", choices=("unknown", "bonded", "free"))
    ap.add_argument("--models", nargs="+", default=["off", "unknown"],
                    choices=("off", "unknown"))
    ap.add_argument("--limit", type=int, default=None, help="at most N curves per file")
    ap.add_argument("--only", action="append", default=None,
                    help="only files whose folder/name contains TEXT (repeatable)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)

    paths = []
    for folder in FOLDERS:
        root = args.shared / folder
        if not root.is_dir():
            print(f"missing: {root}", file=sys.stderr)
            return 2
        paths += [p for p in sorted(root.iterdir())
                  if p.is_file() and p.name not in NOT_DATA and not p.name.startswith("LICENSE")]
    if args.only:
        paths = [p for p in paths if any(s in f"{p.parent.name}/{p.name}" for s in args.only)]

    rows, refusals = [], []
    for path in paths:
        for curve in curves_of(path, args.limit):
            if curve.trace is None:
                refusals.append(curve)
                print(f"refused {curve.file} curve {curve.index}: {curve.message}", flush=True)
                continue
            for layer in args.models:
                row = fit_one(curve, layer, args)
                rows.append(row)
                print(f"{row['trace_id']:45s} {layer:8s} {row['status']:7s} "
                      f"{row.get('fit_s', np.nan):6.1f} s  E {row.get('E_pa', np.nan):9.4g} "
                      f"m {row.get('m_free', np.nan):.3f}/{row.get('m_law', np.nan):.3f} "
                      f"h {row.get('thickness_m', np.nan):.3g} "
                      f"pH {row.get('p_halfspace', np.nan):.2f} "
                      f"pB {row.get('p_bonded', np.nan):.2f} "
                      f"fail {row.get('failed_checks', '')} {row.get('message', '')}",
                      flush=True)
                if args.out is not None:
                    pd.DataFrame(rows).to_csv(args.out, index=False)
    df = pd.DataFrame(rows)
    if args.out is not None:
        df.to_csv(args.out, index=False)
    print()
    print(summarize(df, refusals) if not df.empty else "no curve fitted")
    return 0


if __name__ == "__main__":
    sys.exit(main())
