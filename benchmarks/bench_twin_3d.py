"""The axisymmetric twin's equal-area cylinder against a 3-D cuboid, measured in one run.

The specimen twin (:mod:`palpbayes.twin`) models a block L × W × H as the cylinder of equal
footprint area (radius sqrt(L·W/pi)); :mod:`palpbayes.twin.solid3d` solves the cuboid itself.
For a 50 × 50 mm block (nu 0.3), prints:

* **palpation**, heights 20 and 30 mm, free and bonded base, the paper's tips (sphere R 10 mm
  and paraboloid R 11.7 mm at depth 0.1·H, flat punch of radius 10 mm), at two 3-D
  resolutions: F/E* of the 3-D block and of the axisymmetric equal-area cylinder
  (:func:`~palpbayes.twin.palpation.solve_palpation`), and their ratio ("direct").  That ratio
  carries both models' discretization errors, so the same is solved on a footprint ten times
  as wide (3-D: the same mesh near the contact, the same height; axisymmetric: ten times the
  radius), and the width effects F(block)/F(wide) − 1 of the two are compared: their
  difference ("EQUIV") is the error of the equivalence; likewise for the equal-shape-factor
  cylinder D = L.  The wide 3-D block against the exact infinite layer
  (:func:`palpbayes.contact.shape` with ``thickness_m``) is the 3-D mesh's own error (the
  layer's sphere is itself an approximation, within ~0.1 % here: :mod:`palpbayes.contact.layer`).
* **compression** between bonded platens, heights 20 and 30 mm, nu 0.1, 0.3, 0.45: E_app/E of
  the 3-D block at two resolutions (three at nu 0.45, the slowest to converge) against the
  axisymmetric :func:`~palpbayes.twin.compression.platen_factor` of (a) the equal-area
  cylinder and (b) the equal-shape-factor cylinder (D = L: S = L/(4H) for both); lubricated
  platens (exactly 1).
* the number of unknowns and the wall time of every 3-D solve (mesh, assembly, nested
  dissection, SuperLU factorization, and for curved tips the contact flexibility), run two at a
  time on ``--workers`` processes (so each time includes some contention).

The axisymmetric twin runs at its ``fine`` resolution (its ``default`` moves the paraboloid's
width effect by 0.06 %).  Run: ``python benchmarks/bench_twin_3d.py`` (about 6 minutes on 2
idle cores: two worker processes of at most 2.6 GB each).
"""

from __future__ import annotations

import multiprocessing
import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")  # one BLAS thread per worker process

import argparse  # noqa: E402
import math  # noqa: E402
import resource  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402

import numpy as np  # noqa: E402
from common import TIPS  # noqa: E402

from palpbayes.contact import get_law, shape  # noqa: E402
from palpbayes.errors import GeometryError  # noqa: E402
from palpbayes.procs import lifeline  # noqa: E402
from palpbayes.twin.compression import platen_factor  # noqa: E402
from palpbayes.twin.palpation import solve_palpation  # noqa: E402
from palpbayes.twin.solid3d import Palpation3D, solve_compression_3d  # noqa: E402

SIDE = 0.05  # [m] the block's footprint, SIDE × SIDE
WIDE = 10.0  # the wide footprint's scale
NU_PALPATION = 0.3
HEIGHTS = (0.02, 0.03)
BASES = ("free", "bonded")
CURVED = ("sphere", "paraboloid")
KINDS = ("sphere", "paraboloid", "flat")
NUS = (0.1, 0.3, 0.45)
AXI_RESOLUTION = "fine"


def _depth(h: float) -> float:
    return 0.1 * h


def _palpation_3d(h: float, base: str, scale: float, family: str, resolution: str) -> dict:
    """F/E* [m²] of the family's tips in the 3-D block (one mesh and factorization)."""
    t0 = time.perf_counter()
    side, depth = SIDE * scale, _depth(h)
    if family == "flat":
        a, kinds = float(TIPS["flat"].radius), ("flat",)
    else:
        kinds = CURVED
        a = max(float(get_law(TIPS[k]).contact_radius(np.array([depth]), TIPS[k])[0])
                for k in kinds)
    while True:
        model = Palpation3D(side, side, h, NU_PALPATION, base, a, punch=family == "flat",
                            resolution=resolution)
        try:
            shapes = {k: model.shape(TIPS[k], depth)[0] for k in kinds}
            break
        except GeometryError as err:  # the contact reached the mesh's zone: widen it
            if "reaches the edge" not in str(err):
                raise
            a *= 1.3
    return {"shapes": shapes, "dofs": model.size, "seconds": time.perf_counter() - t0,
            "factor": model.factor_seconds}


def _radius(cylinder: str) -> float:
    """[m] The axisymmetric twin's radius: equal area, equal shape factor (D = L), or the
    wide equal-area cylinder."""
    area = math.sqrt(SIDE * SIDE / math.pi)
    return {"area": area, "shape": 0.5 * SIDE, "wide": WIDE * area}[cylinder]


def _palpation_axi(h: float, base: str, cylinder: str, kind: str) -> dict:
    t0 = time.perf_counter()
    radius = _radius(cylinder)
    curve = solve_palpation(radius, h, TIPS[kind], NU_PALPATION, base,
                            np.array([_depth(h)]), AXI_RESOLUTION)
    return {"shape": float(curve.shape[0]), "dofs": curve.dofs,
            "seconds": time.perf_counter() - t0}


def _compression_3d(h: float, nu: float, platens: str, resolution: str) -> dict:
    r = solve_compression_3d(SIDE, SIDE, h, nu, platens, resolution)
    return {"factor": r.factor, "dofs": r.dofs, "seconds": r.seconds}


def _compression_axi(h: float, nu: float) -> dict:
    t0 = time.perf_counter()
    area = platen_factor(math.sqrt(SIDE * SIDE / math.pi) / h, nu, "bonded", AXI_RESOLUTION)
    shape_factor = platen_factor(0.5 * SIDE / h, nu, "bonded", AXI_RESOLUTION)
    return {"area": area, "shape_factor": shape_factor, "seconds": time.perf_counter() - t0}


def _tasks(palpation: list[str], compression: list[str]) -> dict:
    """Every task, keyed, with a guess of its cost [s] (largest first on the workers)."""
    tasks = {}
    for h in HEIGHTS:
        for base in BASES:
            for scale in (1.0, WIDE):
                for family in ("curved", "flat"):
                    for res in palpation:
                        cost = (8.0 if family == "curved" else 10.0) * (1.5 if scale > 1 else 1)
                        cost *= (2.5 if res == "fine" else 1.0) * h / 0.02
                        tasks[("p3", h, base, scale, family, res)] = (
                            cost, _palpation_3d, (h, base, scale, family, res))
            for cylinder in ("area", "shape", "wide"):
                for kind in KINDS:
                    tasks[("pa", h, base, cylinder, kind)] = (
                        {"sphere": 7.0, "paraboloid": 14.0, "flat": 1.0}[kind], _palpation_axi,
                        (h, base, cylinder, kind))
        for nu in NUS:
            for res in compression:
                if res == compression[-1] and len(compression) > 2 and nu != max(NUS):
                    continue  # the finest only where convergence is slowest
                tasks[("c3", h, nu, "bonded", res)] = (
                    {"coarse": 0.5, "default": 6.0, "fine": 40.0}.get(res, 10.0),
                    _compression_3d, (h, nu, "bonded", res))
            tasks[("c3", h, nu, "lubricated", compression[0])] = (
                0.5, _compression_3d, (h, nu, "lubricated", compression[0]))
            tasks[("ca", h, nu)] = (2.0, _compression_axi, (h, nu))
    return tasks


def _run(tasks: dict, workers: int) -> dict:
    order = sorted(tasks, key=lambda k: -tasks[k][0])
    if workers <= 1:
        return {k: tasks[k][1](*tasks[k][2]) for k in order}
    ctx = multiprocessing.get_context()  # workers end with this process (procs.lifeline)
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx, **lifeline(ctx)) as pool:
        futures = {k: pool.submit(tasks[k][1], *tasks[k][2]) for k in order}
        return {k: f.result() for k, f in futures.items()}


def _pct(x: float) -> str:
    return f"{100.0 * x:+7.3f}%"


def _range(values: list[float]) -> str:
    return f"{_pct(min(values)).strip()} .. {_pct(max(values)).strip()}"


def _axi_table(out: dict) -> None:
    print(f"\nPALPATION, axisymmetric twin at '{AXI_RESOLUTION}' (F/E* in mm^2): equal-area "
          f"cylinder R = sqrt(L*W/pi) = {_radius('area') * 1e3:.2f} mm, equal-shape-factor "
          f"cylinder D = L (R = {_radius('shape') * 1e3:.1f} mm), the wide cylinder "
          f"({WIDE:g} R), the exact infinite layer")
    print(f"{'H':>3} {'base':<6} {'tip':<10} {'area cyl':>10} {'D=L cyl':>10} {'wide cyl':>10} "
          f"{'layer':>10} {'wide/layer':>10} {'unknowns':>9} {'time [s]':>8}")
    for h in HEIGHTS:
        for base in BASES:
            for kind in KINDS:
                r = {c: out[("pa", h, base, c, kind)] for c in ("area", "shape", "wide")}
                lay = _layer(h, base, kind)
                print(f"{h * 1e3:3.0f} {base:<6} {kind:<10} {r['area']['shape'] * 1e6:10.5f} "
                      f"{r['shape']['shape'] * 1e6:10.5f} {r['wide']['shape'] * 1e6:10.5f} "
                      f"{lay * 1e6:10.5f} {_pct(r['wide']['shape'] / lay - 1):>10} "
                      f"{r['area']['dofs']:9d} {r['area']['seconds']:8.1f}")


def _layer(h: float, base: str, kind: str) -> float:
    return float(shape(np.array([_depth(h)]), TIPS[kind], thickness_m=h, nu=NU_PALPATION,
                       base=base)[0])


def _palpation_table(out: dict, res: str) -> dict[str, list[float]]:
    print(f"\nPALPATION, 50 x 50 mm block, nu {NU_PALPATION}, depth 0.1*H, 3-D at '{res}' "
          f"(F/E* in mm^2; wide = {WIDE:g}x footprint, the same mesh near the contact).  Width "
          "effect = F(block)/F(wide) - 1; EQUIV = (1 + width effect 3-D)/(1 + width effect "
          "axi) - 1, the cylinder's error; direct = F(3-D block)/F(area cyl) - 1")
    print(f"{'H':>3} {'base':<6} {'tip':<10} {'3-D block':>10} {'3-D wide':>10} "
          f"{'width 3-D':>9} | {'width area':>10} {'EQUIV area':>10} | {'width D=L':>9} "
          f"{'EQUIV D=L':>9} | {'direct':>8} {'3Dwide/layer':>12}")
    errors: dict[str, list[float]] = {"area": [], "shape": []}
    for h in HEIGHTS:
        for base in BASES:
            for kind in KINDS:
                fam = "flat" if kind == "flat" else "curved"
                s3 = out[("p3", h, base, 1.0, fam, res)]["shapes"][kind]
                s3w = out[("p3", h, base, WIDE, fam, res)]["shapes"][kind]
                axi = {c: out[("pa", h, base, c, kind)]["shape"]
                       for c in ("area", "shape", "wide")}
                width = {c: axi[c] / axi["wide"] for c in ("area", "shape")}
                equiv = {c: (s3 / s3w) / width[c] - 1.0 for c in width}
                for c in equiv:
                    errors[c].append(equiv[c])
                print(f"{h * 1e3:3.0f} {base:<6} {kind:<10} {s3 * 1e6:10.5f} {s3w * 1e6:10.5f} "
                      f"{_pct(s3 / s3w - 1)} | {_pct(width['area'] - 1):>10} "
                      f"{_pct(equiv['area']):>10} | {_pct(width['shape'] - 1):>9} "
                      f"{_pct(equiv['shape']):>9} | {_pct(s3 / axi['area'] - 1):>8} "
                      f"{_pct(s3w / _layer(h, base, kind) - 1):>12}")
    return errors


def _compression_table(out: dict, resolutions: list[str]) -> dict[str, list[float]]:
    print("\nCOMPRESSION, 50 x 50 mm block between bonded platens: E_app/E (3-D at each "
          f"resolution; axisymmetric at '{AXI_RESOLUTION}': equal-area cylinder R = "
          "sqrt(L*W/pi), equal-shape-factor cylinder D = L; errors against the finest 3-D)")
    head = " ".join(f"{'3-D ' + r:>13}" for r in resolutions)
    print(f"{'H':>3} {'nu':>5} {head} {'axi area':>10} {'error':>8} {'axi D=L':>10} "
          f"{'error':>8} {'lubricated-1':>12}")
    errors: dict[str, list[float]] = {"area": [], "shape_factor": []}
    for h in HEIGHTS:
        for nu in NUS:
            e3 = [out.get(("c3", h, nu, "bonded", r), {}).get("factor") for r in resolutions]
            best = [e for e in e3 if e is not None][-1]
            ax = out[("ca", h, nu)]
            lub = out[("c3", h, nu, "lubricated", resolutions[0])]["factor"]
            cells = " ".join(f"{e:13.6f}" if e is not None else f"{'-':>13}" for e in e3)
            for c in errors:
                errors[c].append(ax[c] / best - 1)
            print(f"{h * 1e3:3.0f} {nu:5.2f} {cells} {ax['area']:10.6f} "
                  f"{_pct(ax['area'] / best - 1):>8} {ax['shape_factor']:10.6f} "
                  f"{_pct(ax['shape_factor'] / best - 1):>8} {lub - 1:12.1e}")
    return errors


def _timing_table(out: dict) -> None:
    print("\n3-D SOLVES: unknowns and wall time (mesh, assembly, ordering, factorization, "
          "contact flexibility; run concurrently on the workers)")
    print(f"{'solve':<52} {'unknowns':>9} {'time [s]':>9} {'of which LU':>11}")
    for key, r in out.items():
        if key[0] == "p3":
            _, h, base, scale, family, res = key
            what = (f"palpation {family:<6} H {h * 1e3:.0f} {base:<6} "
                    f"{'wide ' if scale > 1 else 'block'} {res}")
            print(f"{what:<52} {r['dofs']:9d} {r['seconds']:9.1f} {r['factor']:11.1f}")
    for key, r in out.items():
        if key[0] == "c3":
            _, h, nu, platens, res = key
            what = f"compression {platens:<10} H {h * 1e3:.0f} nu {nu:.2f} {res}"
            print(f"{what:<52} {r['dofs']:9d} {r['seconds']:9.2f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    ap.add_argument("--palpation", default="default,fine",
                    help="3-D palpation resolutions, comma-separated (default: default,fine)")
    ap.add_argument("--compression", default="coarse,default,fine",
                    help="3-D compression resolutions, coarse to fine (of three or more, the "
                         "finest at the largest nu only)")
    args = ap.parse_args()
    palpation = args.palpation.split(",")
    compression = args.compression.split(",")
    t0 = time.perf_counter()
    out = _run(_tasks(palpation, compression), args.workers)
    _axi_table(out)
    errors = {res: _palpation_table(out, res) for res in palpation}
    comp = _compression_table(out, compression)
    _timing_table(out)
    print("\nSUMMARY (ranges over H, base, nu)")
    for res, err in errors.items():
        for c, label in (("area", "equal-area"), ("shape", "D = L")):
            by_kind = {k: err[c][i::3] for i, k in enumerate(KINDS)}
            cells = ", ".join(f"{k} {_range(v)}" for k, v in by_kind.items())
            print(f"  palpation, {label:<10} cylinder's error (3-D '{res}'): {cells}")
    for c, label in (("area", "equal-area"), ("shape_factor", "D = L")):
        print(f"  compression, {label:<10} cylinder's error: {_range(comp[c])}")
    rss = max(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss,
              resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss) / 2**20
    print(f"  whole run {time.perf_counter() - t0:.0f} s on {args.workers} worker(s); largest "
          f"process {rss:.1f} GB")


if __name__ == "__main__":
    main()
