"""Per-point throughput of palpbayes' map fits against nanite's Hertz fit, on real force maps.

For each real AFM force map in ``../shared/data/afm-files`` (the PyFMRheo 4 × 4 JPK map and
the AFM Workshop 16-curve zip) prints, side by side, the points per second and the
milliseconds per point of

* **palpbayes**: the per-point stage of ``palpbayes map FILE`` (:mod:`palpbayes.maps`): the
  map's rows from the file (:func:`~palpbayes.maps.afm_source.afm_map_rows`, which reads every
  curve's metadata), then :func:`~palpbayes.maps.pertrace.fit_points`: each curve read, checked
  (``check_fittable``), its exact posterior of E, 2,000 draws summarised (mean and sd of log E,
  median and 90 % interval of E) and the paper's least squares beside it;
* **nanite**, as its users fit a map: ``nanite.load_group(FILE)``, then per curve the
  preprocessing ``compute_tip_position``, ``correct_force_offset``, ``correct_tip_offset`` and
  ``fit_model("hertz_para")`` (lmfit; contact point and baseline fitted) with R and nu set;

both timed from the file to every point's E, loading included, in this one process on one
core (``scheduler="synchronous"`` for palpbayes: nanite has no parallel map fit).  With
``--workers N`` palpbayes is also timed on an N-worker Dask LocalCluster, cluster start-up
included (what ``palpbayes map`` does).  The goal: palpbayes' throughput >= nanite's.
Each time is the median of ``--repeat`` runs (the first run of each also warms the imports
and file caches and is not counted when ``--repeat`` > 1).

Tip: paraboloid R = 5 µm (the PyFMRheo example notebook's; no file records it), nu = 0.5.
The AFM Workshop zip records no spring constant, sensitivity or sample rate: both tools are
given 20 N/m, 1e-8 m/V and 1 kHz (``palpbayes map --spring-constant 20 --sensitivity 1e-8
--sample-rate 1000``).

nanite is GPL-3.0 and never a dependency of palpbayes: install it into the benchmark's own
environment only, e.g.::

    python3 -m venv /tmp/peer && /tmp/peer/bin/pip install -e . nanite afmformats \\
        -c requirements/constraints.txt && /tmp/peer/bin/python benchmarks/bench_map_peer.py

Without nanite the script says so and times palpbayes alone.
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

from palpbayes.campaign.fitjob import FitOptions
from palpbayes.contact import Tip
from palpbayes.maps.afm_source import afm_map_rows
from palpbayes.maps.pertrace import PointOptions, fit_points

FILES = Path(__file__).resolve().parents[2] / "shared" / "data" / "afm-files"
RADIUS, NU = 5e-6, 0.5
#: (label, file, afmformats metadata the file lacks: SI units)
MAPS = [
    ("PyFMRheo 4x4 JPK", "pyfmrheo-map-data-2022.10.29-12.27.34.564.jpk-force-map", {}),
    ("AFM Workshop zip", "fmt-afm-workshop-fd_mapping_16_2018-08-01_13.07.zip",
     {"spring constant": 20.0, "sensitivity": 1e-8, "rate approach": 1000.0}),
]


def palpbayes_map_points(path: Path, meta: dict, workers: int | None = None
                         ) -> tuple[int, np.ndarray]:
    """The per-point stage of ``palpbayes map``: rows from the file, every curve fitted.

    Returns the number of curves fitted and their E* = E/(1 − nu²) [Pa] (posterior median;
    NaN for a curve not fitted).  ``workers`` None: in this process."""
    tip = Tip("paraboloid", radius=RADIUS)
    rows = afm_map_rows(path, tip, meta_override=meta or None)
    opts = PointOptions(fit=FitOptions(nu=NU, engine="exact", layer="off"),
                        read_options={"meta_override": meta} if meta else {})
    sched = "synchronous" if workers is None else None
    pts = fit_points(rows, opts, scheduler=sched, workers=workers, progress=False)
    curves = rows["curve_index"].to_numpy() >= 0
    return int(curves.sum()), pts["E_median_pa"].to_numpy()[curves] / (1 - NU**2)


def nanite_map_points(path: Path, meta: dict) -> tuple[int, np.ndarray] | None:
    """nanite's Hertz fit of every curve of the map, as its users run it (benchmarks/
    bench_peer.py's recipe); E* [Pa] per curve (NaN when a fit fails); None without nanite."""
    try:
        import nanite
    except ImportError:
        return None
    grp = nanite.load_group(path, meta_override=dict(meta))
    out = []
    for idnt in grp:
        try:
            idnt.apply_preprocessing(["compute_tip_position", "correct_force_offset",
                                      "correct_tip_offset"])
            params = idnt.get_initial_fit_parameters(model_key="hertz_para")
            params["R"].set(value=RADIUS)
            params["nu"].set(value=NU)
            idnt.fit_model(model_key="hertz_para", params_initial=params,
                           x_axis="tip position", y_axis="force", weight_cp=0)
            out.append(float(idnt.fit_properties["params_fitted"]["E"].value) / (1 - NU**2))
        except Exception:  # noqa: BLE001 - a curve nanite cannot fit counts as done, NaN
            out.append(np.nan)
    return len(grp), np.array(out)


def timed_median(fn: Callable[[], object], repeat: int) -> tuple[float, float, object]:
    """Median wall time and median CPU time of this process [s] of ``repeat`` calls (a warm-up
    call first when repeat > 1).  The CPU time is the steadier on a shared machine (it
    leaves out the time other programs took the core); a Dask run's is that of this
    process only, not of its workers."""
    if repeat > 1:
        fn()
    wall, cpu, out = [], [], None
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return statistics.median(wall), statistics.median(cpu), out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3, help="runs per timing (median)")
    ap.add_argument("--workers", type=int, default=0,
                    help="also time palpbayes on an N-worker LocalCluster (0: not)")
    args = ap.parse_args(argv)
    if not FILES.is_dir():
        print(f"no {FILES}: nothing to time")
        return 0
    try:
        import nanite  # noqa: F401

        have_nanite = True
    except ImportError:
        have_nanite = False
        print("nanite is not installed in this environment: palpbayes is timed alone (see "
              "the module docstring to install it into a separate one)")
    warnings.simplefilter("ignore")
    print(f"file to per-point E, loading included, one process; median of {args.repeat} "
          f"run(s); paraboloid R = {RADIUS * 1e6:g} µm, nu = {NU}")
    head = (f"{'map':<18} {'curves':>6} {'palpbayes':>16} {'nanite':>16} "
            f"{'ratio':>6}  {'CPU ms/pt palpb. / nanite':>26} {'ratio':>6}  "
            f"{'median E* palpbayes / nanite':>30}")
    print(head + "\n" + "-" * len(head))
    for label, name, meta in MAPS:
        path = FILES / name
        if not path.is_file():
            print(f"{label:<18} missing {path}")
            continue
        t_pb, c_pb, (n, e_pb) = timed_median(
            lambda p=path, m=meta: palpbayes_map_points(p, m), args.repeat)
        pb = f"{n / t_pb:6.1f}/s {1e3 * t_pb / n:5.0f} ms"
        if have_nanite:
            t_nn, c_nn, (n_nn, e_nn) = timed_median(
                lambda p=path, m=meta: nanite_map_points(p, m), args.repeat)
            nn = f"{n_nn / t_nn:6.1f}/s {1e3 * t_nn / n_nn:5.0f} ms"
            ratio = f"{(n / t_pb) / (n_nn / t_nn):6.2f}"
            cpu = (f"{1e3 * c_pb / n:>12.0f} / {1e3 * c_nn / n_nn:<11.0f} "
                   f"{(n / c_pb) / (n_nn / c_nn):6.2f}")
            es = f"{np.nanmedian(e_pb):.4g} / {np.nanmedian(e_nn):.4g} Pa"
        else:
            nn, ratio, es = f"{'-':>16}", f"{'-':>6}", f"{np.nanmedian(e_pb):.4g} / - Pa"
            cpu = f"{1e3 * c_pb / n:>12.0f} / {'-':<11} {'-':>6}"
        print(f"{label:<18} {n:>6} {pb:>16} {nn:>16} {ratio}  {cpu}  {es:>30}")
        if args.workers:
            t_w, _, (n_w, _) = timed_median(
                lambda p=path, m=meta: palpbayes_map_points(p, m, args.workers), args.repeat)
            print(f"{'  ' + str(args.workers) + ' Dask workers':<18} {n_w:>6} "
                  f"{n_w / t_w:6.1f}/s {1e3 * t_w / n_w:5.0f} ms  (cluster start-up included)")
    print("ratio = palpbayes points/s over nanite's (goal >= 1), by wall time and by CPU "
          "time.  palpbayes per point: read, checks, exact posterior, 2,000 draws, "
          "summaries, least squares; nanite: one lmfit Hertz fit")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
