"""What a viscoelastic fit costs, measured in one run on this machine.

For simulated ramp–hold palpations (paraboloid of the paper, 50 and 5 mm/min, an 8 s hold,
800 Hz: 7,000 and 40,000 samples) and, when ``../shared/data`` is there, the three real AFM
curves with a hold, prints the median time of :func:`palpbayes.rheology.fit_rheology` with
each relaxation model, the time of PSIS-LOO on top (:func:`palpbayes.rheology.choice.loo`),
and the ratio of the power-law fit to the elastic exact-engine fit of the same record's
loading part (``fit_bayes(..., engine="exact")``, budget and checks included), timed in the
same run.

The issue's targets (issue 47) are stated for a 4,000-sample cycle: a full posterior in
<= 0.5 s with the collapsed (grid) engine and <= 2 s with emcee, on 2 cores, as the user's
call runs it.  The first table times them so: the whole :func:`fit_rheology` call (cycle,
posterior, draws, checks, flags) on simulated approach – 2 s hold – retract cycles of 4,081
samples (paraboloid of the paper, 50 mm/min to 3 mm, 400 Hz), power law and SLS on the
default segments (approach and hold), and with ``--retract`` the power law with the retract
too; median wall and CPU time of ``--repeat`` runs, the goal and wall/goal beside each, and
the posterior that came out.  ``--profile`` adds a cProfile breakdown of each; ``--targets``
stops after the table.

Run: ``python benchmarks/bench_rheology.py [--targets] [--profile] [--repeat N]``.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import pstats
import time
import warnings
from pathlib import Path

import numpy as np
from common import median_time

from palpbayes.bayes import fit_bayes
from palpbayes.contact import Tip
from palpbayes.contact.viscoelastic import PowerLawKernel, standard_linear_solid
from palpbayes.fitdata import ModelSpec
from palpbayes.paper import PAPER_TIPS
from palpbayes.rheology import fit_rheology
from palpbayes.rheology.choice import loo
from palpbayes.rheology.posterior import grid_posterior
from palpbayes.rheology.sampler import sample_emcee
from palpbayes.sim import simulate_viscoelastic

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "afm-files"
REAL = ("fmt-jpk-sr_cell1-0008.jpk-force", "fmt-jpk-cc_pr14-brain-2021.06.30.jpk-force",
        "fmt-jpk-cc_pr14-polymergel-2021.06.30.jpk-force")


def records() -> list[tuple[str, object, Tip]]:
    tip = PAPER_TIPS["paraboloid"]
    out = [(f"sim {v:g} mm/min", simulate_viscoelastic(
        PowerLawKernel(80e3, 0.2), tip, depth=3e-3, speed=v / 6e4, hold_time=8.0,
        rate=800.0, z_surf=2e-4, noise_sd=0.008, phi=0.3, rng=1), tip) for v in (50.0, 5.0)]
    if SHARED.is_dir():
        from palpbayes.io.afm import read_afm

        afm_tip = Tip("paraboloid", radius=5e-6)
        for name in REAL:
            out.append((name[8:28], read_afm(SHARED / name, tip=afm_tip, segments="all")[0],
                        afm_tip))
    else:
        print(f"(no {SHARED}: the real AFM curves are skipped)")
    return out


#: The issue's targets [s] for a 4,000-sample cycle: the grid (collapsed) engine and emcee.
TARGET_GRID, TARGET_EMCEE = 0.5, 2.0
#: Models of the target table: (label, rheology, kernel, segments).
TARGET_CASES = (
    ("power law", "power-law", PowerLawKernel(80e3, 0.2), ("approach", "hold")),
    ("SLS", "sls", standard_linear_solid(50e3, 30e3, 1.0), ("approach", "hold")),
    ("power law + retract", "power-law", PowerLawKernel(80e3, 0.2),
     ("approach", "hold", "retract")),
)


def target_trace(kernel) -> object:
    """A simulated approach – 2 s hold – retract cycle of 4,081 samples (module docstring)."""
    return simulate_viscoelastic(kernel, PAPER_TIPS["paraboloid"], depth=3e-3,
                                 speed=50.0 / 6e4, hold_time=2.0, rate=400.0, retract=True,
                                 z_surf=2e-4, noise_sd=0.008, phi=0.3, rng=1)


def timed(fn, repeat: int) -> tuple[float, float]:
    """Median wall time [s] and median CPU time [s] (this process, all threads) of ``fn()``:
    the CPU time is the steadier on shared cores."""
    wall, cpu = [], []
    for _ in range(repeat):
        w, c = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - w)
        cpu.append(time.process_time() - c)
    return float(np.median(wall)), float(np.median(cpu))


def target_cycle(repeat: int = 5, profile: bool = False, retract: bool = False) -> None:
    """The targets as the issue states them: the whole :func:`fit_rheology` call (cycle
    preparation, posterior, draws, checks, flags) on the 4,081-sample cycles, per engine,
    median of ``repeat`` runs after a warm-up; the goal and measured/goal beside each.
    ``profile``: a cProfile breakdown of one run of each (the functions of most own time);
    ``retract``: the power law with the retract too (Ting's rule: minutes)."""
    print(f"{'4,081-sample cycle':<20} {'engine':<6} {'blocks':>6} {'wall':>8} {'cpu':>8} "
          f"{'goal':>6} {'wall/goal':>9}  posterior medians [90 % interval]")
    for label, model, kernel, segments in TARGET_CASES[: None if retract else 2]:
        trace = target_trace(kernel)
        for engine, goal in (("grid", TARGET_GRID), ("emcee", TARGET_EMCEE)):
            def run(trace=trace, model=model, segments=segments, engine=engine):
                return fit_rheology(trace, model, segments=segments, engine=engine, rng=0)

            fit = run()  # warm-up: imports, caches
            wall, cpu = timed(run, repeat)
            print(f"{label:<20} {engine:<6} {fit.data.n_points:>6} {wall:>6.2f} s "
                  f"{cpu:>6.2f} s {goal:>4.1f} s {wall / goal:>9.2f}  {fit.summary_line()}",
                  flush=True)
            if profile:
                prof = cProfile.Profile()
                prof.enable()
                run()
                prof.disable()
                out = io.StringIO()
                pstats.Stats(prof, stream=out).sort_stats("tottime").print_stats(PROFILE_ROWS)
                body = out.getvalue()
                print(body[body.index("ncalls"):].rstrip() + "\n", flush=True)
    print()


#: Rows of the cProfile breakdown (``--profile``).
PROFILE_ROWS = 14


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--targets", action="store_true", help="the target table only")
    parser.add_argument("--profile", action="store_true", help="cProfile of each target fit")
    parser.add_argument("--repeat", type=int, default=5, help="timed runs of each target fit")
    parser.add_argument("--retract", action="store_true",
                        help="the power law with the retract too in the target table")
    args = parser.parse_args()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        target_cycle(args.repeat, args.profile, args.retract)
    if args.targets:
        return
    print(f"{'record':<22} {'samples':>8} {'power law':>10} {'sls':>8} {'loo':>7} "
          f"{'elastic':>8} {'ratio':>6}")
    emcee_rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for label, trace, tip in records():
            fits = {}

            def run(model, trace=trace, fits=fits):
                fits[model] = fit_rheology(trace, model, nu=0.5)

            t_pl = median_time(lambda: run("power-law"), repeat=3)
            t_sls = median_time(lambda: run("sls"), repeat=3)
            fitted = fits["power-law"]
            t_loo = median_time(lambda f=fitted: loo(f), repeat=3)
            loading = trace.segments("approach")
            spec = ModelSpec(tip, nu=0.5)
            t_el = median_time(lambda lt=loading, s=spec: fit_bayes(lt, s, engine="exact"),
                               repeat=3)
            print(f"{label:<22} {trace.n_points:>8} {t_pl:>8.2f} s {t_sls:>6.2f} s "
                  f"{t_loo:>5.2f} s {t_el:>6.2f} s {t_pl / t_el:>6.1f}")
            data, grid = fitted.data, fitted.grid
            opts = {"t0": fitted.t0, "drag": grid.drag, "tilt": grid.tilt}
            t_grid = median_time(lambda d=data, o=opts: grid_posterior(d, "power-law", **o),
                                 repeat=3)
            res = sample_emcee(data, "power-law", grid=grid, **opts)  # warm-up: arviz import
            t_mc = median_time(lambda d=data, g=grid, o=opts: sample_emcee(
                d, "power-law", grid=g, **o), repeat=3)
            emcee_rows.append((label, data.n_points, t_grid, t_mc, t_el, res))
    print(f"\nemcee engine (power law; whole = grid start + emcee):\n{'record':<22} "
          f"{'blocks':>6} {'grid':>8} {'emcee':>8} {'whole':>8} {'/grid':>6} {'/elastic':>8} "
          f"{'steps':>6} {'R-hat':>6} {'ESS':>6}")
    for label, n, t_grid, t_mc, t_el, res in emcee_rows:
        whole = t_grid + t_mc
        print(f"{label:<22} {n:>6} {t_grid:>6.2f} s {t_mc:>6.2f} s {whole:>6.2f} s "
              f"{whole / t_grid:>6.1f} {whole / t_el:>8.1f} {res.diagnostics.n_steps:>6} "
              f"{max(res.rhat.values()):>6.3f} {min(res.ess.values()):>6.0f}")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
