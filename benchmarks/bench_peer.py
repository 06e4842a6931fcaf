"""palpbayes against the peer a user would pick instead (nanite), on the same real AFM curves.

For every approach curve of the real AFM files in ``../shared/data/afm-files`` (force-distance
curves, force maps, QI data: afmformats reads them), prints the time of

* nanite's Hertz fit as its users run it (tip position, force offset and tip offset
  preprocessing, then ``fit_model("hertz_para")`` by lmfit with the contact point and a
  baseline), R = 10 µm, nu = 0.5;
* palpbayes' paper least squares (``fit_lsq``);
* palpbayes' full Bayesian fit with the exact engine (``fit_trace``: posterior, model checks,
  uncertainty budget, InferenceData, and the model-form alternatives that widen the interval
  of a curve whose checks fail), the same without the model-form alternatives
  (``--no-model-form``), and, on the first curves nanite reads, with emcee;

and the ratios to nanite, with the median over the curves, and E* of both.  The times are
measured in this one run, one process.

nanite is GPL-3.0 and never a dependency of palpbayes: install it into the benchmark's own
environment only, e.g.::

    python3 -m venv /tmp/peer && /tmp/peer/bin/pip install -e . nanite \\
        -c requirements/constraints.txt && /tmp/peer/bin/python benchmarks/bench_peer.py

Without nanite the script says so and times palpbayes alone.
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

from palpbayes.campaign.fitjob import FitOptions, fit_trace
from palpbayes.contact import Tip
from palpbayes.errors import PalpbayesError
from palpbayes.fitdata import ModelSpec
from palpbayes.io.afm import read_afm
from palpbayes.lsq import fit_lsq

FILES = Path(__file__).resolve().parents[2] / "shared" / "data" / "afm-files"
RADIUS, NU = 10e-6, 0.5
READABLE = (".jpk-force", ".jpk-force-map", ".jpk-qi-data")


def curves() -> list[tuple[str, int]]:
    """(file, curve index) of every approach curve afmformats reads."""
    out = []
    for path in sorted(FILES.iterdir()):
        if path.name.endswith(READABLE):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                n = len(read_afm(path, tip=Tip("paraboloid", radius=RADIUS), check=False))
            out += [(path.name, i) for i in range(n)]
    return out


def nanite_fit(path: Path, index: int):
    """nanite's usual Hertz fit of one curve: (seconds, E* [Pa]); NaN for a curve nanite does
    not load (creep, stress relaxation); None without nanite."""
    try:
        import nanite
    except ImportError:
        return None
    grp = nanite.load_group(path)  # force-distance curves only (not creep or relaxation)
    if index >= len(grp):
        return np.nan, np.nan
    idnt = grp[index]
    t0 = time.perf_counter()
    idnt.apply_preprocessing(["compute_tip_position", "correct_force_offset",
                              "correct_tip_offset"])
    params = idnt.get_initial_fit_parameters(model_key="hertz_para")
    params["R"].set(value=RADIUS)
    params["nu"].set(value=NU)
    idnt.fit_model(model_key="hertz_para", params_initial=params, x_axis="tip position",
                   y_axis="force", weight_cp=0)
    seconds = time.perf_counter() - t0
    E = float(idnt.fit_properties["params_fitted"]["E"].value)
    return seconds, E / (1 - NU**2)


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--emcee", type=int, default=4, metavar="N",
                    help="also time emcee on the first N curves (default 4)")
    args = ap.parse_args()
    if not FILES.is_dir():
        print(f"no {FILES}: nothing to time")
        return
    try:
        import nanite  # noqa: F401
        have_nanite = True
    except ImportError:
        have_nanite = False
        print("nanite is not installed in this environment: palpbayes is timed alone "
              "(see the module docstring to install it into a separate one)")
    tip = Tip("paraboloid", radius=RADIUS)
    print(f"{'curve':<30} {'n':>6} {'nanite':>7} {'lsq':>6} {'exact':>7} {'no mf':>7} "
          f"{'emcee':>7} {'exact/nan.':>10} {'no mf/nan.':>10} {'E* nanite':>10} "
          f"{'E* exact':>10}")
    rows, n_emcee = [], 0
    opts = {"method": "bayes", "nu": NU, "seed": 1}
    for name, index in curves():
        path = FILES / name
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            trace = read_afm(path, tip=tip, curves=[index])[0]
            t_peer, e_peer = nanite_fit(path, index) if have_nanite else (np.nan, np.nan)
            try:  # the paper's least squares on the tared force, data preparation included
                t_lsq, _ = timed(lambda t=trace: fit_lsq(t, ModelSpec(tip, nu=NU), tare=True))
            except PalpbayesError:
                t_lsq = np.nan
            try:
                t_exact, out = timed(lambda t=trace: fit_trace(
                    t, FitOptions(engine="exact", **opts)))
                estar = next(r for r in out.rows if r["method"] == "bayes")["Estar_pa"]
                t_plain, _ = timed(lambda t=trace: fit_trace(
                    t, FitOptions(engine="exact", model_form=False, **opts)))
            except PalpbayesError as exc:
                t_exact = t_plain = estar = np.nan
                print(f"  {name} #{index}: not fitted ({str(exc)[len(str(path)) + 2:][:90]})")
            t_emcee = np.nan
            if n_emcee < args.emcee and np.isfinite(t_exact) and np.isfinite(t_peer):
                n_emcee += 1
                t_emcee, _ = timed(lambda t=trace: fit_trace(
                    t, FitOptions(engine="emcee", **opts)))
        rows.append((t_peer, t_lsq, t_exact, t_plain, t_emcee))
        label = f"{name[:24]} #{index}"
        print(f"{label:<30} {trace.n_points:>6} {1e3 * t_peer:>4.0f} ms {1e3 * t_lsq:>3.0f} ms "
              f"{t_exact:>5.2f} s {t_plain:>5.2f} s {t_emcee:>5.1f} s "
              f"{t_exact / t_peer:>10.0f} {t_plain / t_peer:>10.1f} {e_peer:>10.4g} "
              f"{estar:>10.4g}")
    r = np.array(rows)

    def med(x):  # NaN, quietly, for a column never timed (emcee with --emcee 0)
        x = np.asarray(x, dtype=float)
        return float(np.nanmedian(x)) if np.isfinite(x).any() else float("nan")

    print(f"\n{len(rows)} curves ({int(np.isfinite(r[:, 2]).sum())} fitted by palpbayes, "
          f"{int(np.isfinite(r[:, 0]).sum())} by nanite); medians: nanite "
          f"{1e3 * med(r[:, 0]):.0f} ms, paper least squares {1e3 * med(r[:, 1]):.0f} ms, "
          f"exact engine {med(r[:, 2]):.2f} s (without the model-form alternatives "
          f"{med(r[:, 3]):.2f} s), emcee {med(r[:, 4]):.1f} s")
    if have_nanite:
        print(f"exact engine / nanite: median {med(r[:, 2] / r[:, 0]):.1f} (goal <= 10); "
              f"without the model-form alternatives {med(r[:, 3] / r[:, 0]):.1f} (goal <= 4); "
              f"emcee / nanite: median {med(r[:, 4] / r[:, 0]):.0f} (goal <= 30)")


if __name__ == "__main__":
    main()
