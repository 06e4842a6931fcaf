"""The hyperelastic (finite-strain) twin, validated and timed in one run on this machine.

Prints:

* the tangent against central differences of the residual, every registered law (worst
  relative error);
* homogeneous compression between lubricated platens against the closed form
  (:func:`palpbayes.material.compression_stress`), every law, nu 0.3 and 0.5, to 60 % strain;
  bonded platens on the issue's block beside it;
* small depths (d/R 0.0025-0.01) against the linear twin (:func:`~palpbayes.twin.
  solve_palpation`) on the same block and nu, the raw ratio and its value extrapolated to
  d = 0 (the finite-strain correction is linear in a/R);
* the literature: Lin et al. 2009 and Du et al. 2022 are not compared (their formulas could
  not be obtained here; see tests/unit/test_hyper.py); Shojaeifard & Bacca 2025's deep regime
  as the local exponent d ln F/d ln D drifting from 1.5 toward 2 (one-term Ogden);
* mesh convergence (coarse, default, fine) on the issue's block;
* the issue's cases (neo-Hookean 50 × 50 × 20 mm block, E0 60 kPa, nu 0.3 and 0.45, a 10 mm
  sphere to 3 mm; a 10 mm flat punch 2 mm into a 20 mm hyperfoam block, nu 0.1, alpha 8; an
  11.7 mm paraboloid 3 mm into a 30 mm block): the finite-strain force over the linear twin's;
* seconds per curve at the default resolution, and a table of three shape nodes.

Run: ``python benchmarks/bench_finite_twin.py`` (about 8 minutes on 2 cores; ``--part NAME``
runs one part: tangent, compression, small, deep, mesh, issue, table).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np

from palpbayes.contact import Tip
from palpbayes.material import compression_stress, material_law, registered_laws
from palpbayes.twin import Specimen, compression_factor, solve_palpation
from palpbayes.twin.hyper import HyperSolid
from palpbayes.twin.hyper_compression import solve_hyper_compression
from palpbayes.twin.hyper_palpation import solve_hyper_palpation

SPHERE = Tip("sphere", radius=1.0)
BLOCK = Specimen(0.020, length=0.050, width=0.050)


def _linear(radius, height, tip, nu, base, d):
    return solve_palpation(radius, height, tip, nu, base, d).shape / (1 - nu * nu)


def tangent() -> None:
    rng = np.random.default_rng(3)
    worst = 0.0
    for law in registered_laws():
        for nu in (0.3,) if law.kind == "foam" else (0.3, 0.5):
            solid = HyperSolid(np.linspace(0, 1, 5), np.linspace(0, 1, 5), law,
                               law.natural(1.0, law.shape_defaults(), nu), nu)
            x = np.zeros(solid.size)
            x[:solid.n_u] = 0.03 * rng.standard_normal(solid.n_u)
            ir = solid.dofs("r", lambda r, z: np.ones_like(r, dtype=bool))
            x[ir] *= solid.location(ir)[0]
            if solid.mixed:
                x[solid.n_u:] = 0.05 * rng.standard_normal(solid.n_p)
            while solid.state(x) is None:
                x[:solid.n_u] *= 0.5
            k = solid.tangent(solid.state(x))
            dx = rng.standard_normal(solid.size)
            h = 1e-7
            fd = (solid.residual(x + h * dx, solid.state(x + h * dx))
                  - solid.residual(x - h * dx, solid.state(x - h * dx))) / (2 * h)
            worst = max(worst, np.linalg.norm(fd - k @ dx) / np.linalg.norm(k @ dx))
    print(f"tangent vs central differences of the residual, {len(registered_laws())} laws x "
          f"nu 0.3/0.5: worst relative error {worst:.1e}")


def compression() -> None:
    eps = np.array([0.2, 0.4, 0.6])
    worst, name = 0.0, ""
    for law in registered_laws():
        for nu in (0.3,) if law.kind == "foam" else (0.3, 0.5):
            p = law.natural(1.0, law.shape_defaults(), nu)
            got = solve_hyper_compression(1.0, 1.0, law, p, nu, "lubricated", eps)
            err = np.max(np.abs(got.stress / compression_stress(law, p, eps, nu) - 1))
            if err > worst:
                worst, name = err, f"{law.name} nu {nu}"
    print(f"compression, lubricated platens vs the closed form to 60 % strain, every law: "
          f"worst relative error {worst:.1e} ({name})")
    for nu in (0.3, 0.45):
        p = material_law("neo-hookean").natural(1.0, {}, nu)
        strain = np.array([0.01, 0.1, 0.2])
        got = solve_hyper_compression(BLOCK.radius, BLOCK.height, "neo-hookean", p, nu,
                                      "bonded", strain)
        free = compression_stress("neo-hookean", p, strain, nu)
        print(f"  bonded platens, 50 x 50 x 20 mm block, neo-Hookean nu {nu}: nominal stress / "
              f"lubricated at 1, 10, 20 % = "
              + ", ".join(f"{v:.3f}" for v in got.stress / free)
              + f" (the linear twin: {compression_factor(BLOCK, nu, 'bonded'):.3f}; "
              f"{got.seconds:.1f} s)")


def small() -> None:
    d = np.array([0.0025, 0.005, 0.0075, 0.01])
    print("small depths vs the linear twin (sphere, bonded block 10 R x 10 R, default mesh):")
    for nu in (0.3, 0.45, 0.5):
        p = material_law("neo-hookean").natural(1.0, {}, nu)
        c = solve_hyper_palpation(10.0, 10.0, SPHERE, "neo-hookean", p, nu, "bonded", d)
        ratio = c.force / _linear(10.0, 10.0, SPHERE, nu, "bonded", d)
        slope, icpt = np.polyfit(np.sqrt(d), ratio, 1)
        print(f"  nu {nu}: F/F_linear at d/R {', '.join(f'{v:g}' for v in d)} = "
              f"{', '.join(f'{v:.4f}' for v in ratio)}; extrapolated to d = 0: {icpt:.4f} "
              f"(slope {slope:+.3f} per sqrt(d/R)); penetration/d <= "
              f"{np.max(c.penetration / d):.1e}; {c.seconds:.0f} s")


def deep() -> None:
    print("Lin et al. 2009, Du et al. 2022: not compared (formulas not obtainable here)")
    law = material_law("ogden")
    d = np.array([0.04, 0.06, 0.3, 0.35, 1.0, 1.15, 1.6, 1.8, 2.3, 2.5])
    for alpha in (2.5,):
        p = law.natural(1.0, {"alpha_1": alpha}, 0.5)
        c = solve_hyper_palpation(30.0, 30.0, SPHERE, law, p, 0.5, "bonded", d, "coarse")
        slope = np.diff(np.log(c.force))[::2] / np.diff(np.log(d))[::2]
        mid = np.sqrt(d[::2] * d[1::2])
        hertz = c.force[0] / (16 / 9 * d[0] ** 1.5)
        print(f"Shojaeifard & Bacca 2025, one-term Ogden alpha {alpha}, nu 0.5, sphere on its "
              f"stem: F/(16/9 E sqrt(R) D^1.5) at D = 0.04 R: {hertz:.3f}; local exponent "
              + ", ".join(f"{s:.2f} (D/R {m:.2f})" for s, m in zip(slope, mid, strict=True))
              + f"  [{c.seconds:.0f} s; the D^2 regime is not reached]")


def mesh() -> None:
    p = material_law("neo-hookean").natural(1.0, {}, 0.3)
    d = np.array([0.1, 0.2, 0.3])
    rad, h = BLOCK.radius / 0.01, BLOCK.height / 0.01
    curves = {res: solve_hyper_palpation(rad, h, SPHERE, "neo-hookean", p, 0.3, "free", d,
                                         res) for res in ("coarse", "default", "fine")}
    fine = curves["fine"].force
    for res, c in curves.items():
        dev = ", ".join(f"{v:+.2%}" for v in c.force / fine - 1)
        print(f"  mesh {res:8s} {c.dofs:6d} unknowns, {c.seconds:5.1f} s, {c.steps} steps, "
              f"{c.iterations} Newton iterations: F/F_fine - 1 at d/R 0.1, 0.2, 0.3 = {dev}")


def _issue_case(label, spec, tip, law, shape, nu, depths_mm):
    law = material_law(law)
    length = tip.radius
    p = law.natural(60e3, shape, nu)
    nu0 = law.nu0(p, nu)
    d = np.asarray(depths_mm) * 1e-3 / length
    rad, h = spec.radius / length, spec.height / length
    unit = Tip(tip.kind, radius=1.0)
    c = solve_hyper_palpation(rad, h, unit, law, p, nu, "free", d)
    lin = _linear(rad, h, unit, nu0, "free", d) * law.E0(p, nu)
    force = c.force * length ** 2
    print(f"  {label}: " + "; ".join(
        f"{dm:g} mm: F {f:.3g} N, F/F_linear {r:.3f}, a {a * length * 1e3:.2f} mm"
        for dm, f, r, a in zip(depths_mm, force, c.force / lin, c.contact_radius, strict=True))
        + f"  [{c.seconds:.0f} s, {c.dofs} unknowns, penetration/d <= "
        f"{np.max(c.penetration / d):.0e}]")


def issue() -> None:
    print("the issue's cases (free base, the block's equal-area cylinder, default mesh):")
    sphere = Tip("sphere", radius=0.010)
    for nu in (0.3, 0.45):
        _issue_case(f"neo-Hookean E0 60 kPa nu {nu}, 50x50x20 mm, sphere R 10 mm", BLOCK,
                    sphere, "neo-hookean", {}, nu, [1.0, 2.0, 3.0])
    _issue_case("hyperfoam nu 0.1 alpha 8, 50x50x20 mm, flat punch a 10 mm", BLOCK,
                Tip("flat", radius=0.010), "hyperfoam", {"nu": 0.1, "alpha_1": 8.0}, 0.1,
                [0.5, 1.0, 2.0])
    _issue_case("neo-Hookean nu 0.3, 50x50x30 mm, paraboloid R 11.7 mm", BLOCK.with_height(0.03),
                Tip("paraboloid", radius=0.0117), "neo-hookean", {}, 0.3, [1.0, 2.0, 3.0])


def table() -> None:
    from palpbayes.twin.hyper_table import prepare_hyper_table

    with tempfile.TemporaryDirectory() as folder:
        os.environ["PALPBAYES_CACHE_DIR"] = folder
        t0 = time.perf_counter()
        tab = prepare_hyper_table("mooney-rivlin", BLOCK, Tip("sphere", radius=0.010), 0.45,
                                  "free", {"f": [0.0, 0.3, 0.6]}, max_depth=0.003,
                                  progress=False)
        cold = time.perf_counter() - t0
        t0 = time.perf_counter()
        prepare_hyper_table("mooney-rivlin", BLOCK, Tip("sphere", radius=0.010), 0.45, "free",
                            {"f": [0.0, 0.3, 0.6]}, max_depth=0.003, progress=False)
        warm = time.perf_counter() - t0
        d = np.linspace(0, 0.003, 4000)
        t0 = time.perf_counter()
        for _ in range(100):
            tab.force(d, 60e3, {"f": 0.2})
        per = (time.perf_counter() - t0) / 100
    f3 = tab.force(np.array([0.003]), 60e3, {"f": 0.2})[0]
    print(f"table: Mooney-Rivlin on the 50x50x20 mm block, sphere R 10 mm, nu 0.45, 3 nodes of "
          f"f x {tab.depth.size} depths to 3 mm: {cold:.0f} s cold ({cold / 3:.0f} s per curve), "
          f"{warm * 1e3:.0f} ms from the cache; F(3 mm; 60 kPa, f 0.2) = {f3:.3g} N; "
          f"an evaluation of 4,000 depths {per * 1e3:.2f} ms")


PARTS = {"tangent": tangent, "compression": compression, "small": small, "deep": deep,
         "mesh": mesh, "issue": issue, "table": table}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--part", choices=sorted(PARTS), action="append")
    args = parser.parse_args()
    t0 = time.perf_counter()
    for name in args.part or PARTS:
        PARTS[name]()
    print(f"total {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
