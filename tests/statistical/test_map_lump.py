"""The stiff lump of a map is found: centre within one grid step, intervals that cover.

Phantoms are simulated at the level of the per-point summaries (the exact engine's calibration
is tested in test_exact.py, and test_map_cli.py runs whole traces): log E_i = log E_app(p_i) +
heterogeneity·N(0, 1) + s_i·N(0, 1), with E_app from the forward model of
palpbayes.inclusion, and go through the same spatial field and lump model as
``palpbayes map`` (:func:`palpbayes.maps.run.map_from_points`).
"""

from __future__ import annotations

import concurrent.futures as cf
import math

import numpy as np
import pandas as pd
import pytest

from palpbayes.inclusion import Inclusion, apparent_modulus, contact_radius
from palpbayes.maps.pertrace import POINT_COLUMNS
from palpbayes.maps.run import MapOptions, map_from_points
from palpbayes.paper import PAPER_TIPS

TIP = PAPER_TIPS["paraboloid"]
H, DEPTH, STEP, E_B = 0.02, 2e-3, 3e-3, 50e3


def phantom_points(seed: int, inc: Inclusion | None, n: int = 13, het: float = 0.05,
                   s: float = 0.002) -> tuple[pd.DataFrame, float]:
    """Per-point summaries of an n × n phantom and its true apparent peak ratio."""
    rng = np.random.default_rng(seed)
    ix, iy = np.meshgrid(np.arange(n), np.arange(n))
    x, y = ix.ravel() * STEP, iy.ravel() * STEP
    a = contact_radius(TIP, DEPTH)
    E_app = apparent_modulus(x, y, E_background=E_B, inclusion=inc, contact_radius=a,
                             thickness=H)
    logE = np.log(E_app) + het * rng.standard_normal(x.size) + s * rng.standard_normal(x.size)
    pts = pd.DataFrame({c: np.nan for c in POINT_COLUMNS}, index=range(x.size))
    pts = pts.assign(trace_id=[f"p{k}" for k in range(x.size)], x_m=x, y_m=y, logE_mean=logE,
                     logE_sd=s, E_median_pa=np.exp(logE), E_lo_pa=np.exp(logE - 1.645 * s),
                     E_hi_pa=np.exp(logE + 1.645 * s), E_lsq_pa=np.exp(logE), depth_m=DEPTH,
                     notes="", flag_codes="", flag_level="", error="")
    peak = 1.0 if inc is None else float(apparent_modulus(
        np.array([inc.x]), np.array([inc.y]), E_background=E_B, inclusion=inc,
        contact_radius=a, thickness=H)[0] / E_B)
    return pts, peak


def _run(seed: int, inc: Inclusion | None, detect: float = 0.5, **kw):
    pts, peak = phantom_points(seed, inc, **kw)
    res = map_from_points(pts, tip=TIP, thickness=H,
                          options=MapOptions(threshold=1.05, seed=seed, detect=detect))
    out = {"peak": peak, "detection": res.detection, "flags": res.flags, "p_lump": res.p_lump,
           "found": res.lump_found}
    if res.lump is not None:
        s = res.lump.summary().set_index("quantity")
        out.update({q: (s.loc[q, "median"], s.loc[q, "lo"], s.loc[q, "hi"])
                    for q in ("x_m", "y_m", "apparent_ratio", "ratio", "E_background_pa")})
    return out


def _covers(est: tuple[float, float, float], truth: float) -> bool:
    return est[1] <= truth <= est[2]


@pytest.mark.slow
def test_a_visible_lump_is_found_and_its_numbers_cover_the_truth():
    inc = Inclusion(x=19.6e-3, y=16.9e-3, depth=6e-3, radius=5e-3, ratio=10.0)
    r = _run(11, inc)
    assert r["found"] and r["p_lump"] > 0.9 and r["detection"] > 0.9
    d = math.hypot(r["x_m"][0] - inc.x, r["y_m"][0] - inc.y)
    assert d <= STEP, f"centre {d * 1e3:.2f} mm from the truth (one step = 3 mm)"
    assert _covers(r["x_m"], inc.x) and _covers(r["y_m"], inc.y)
    assert _covers(r["apparent_ratio"], r["peak"]), (r["apparent_ratio"], r["peak"])
    assert _covers(r["ratio"], inc.ratio)
    # the ratio itself sits on the size-depth-stiffness ridge: said, not hidden
    assert any("not identified" in f or "upper end" in f for f in r["flags"]), r["flags"]


@pytest.mark.slow
def test_no_lump_is_found_in_a_homogeneous_block():
    r = _run(5, None)
    assert not r["found"] and r["p_lump"] < 0.5 and r["detection"] < 0.5
    assert any(f.startswith("info: no lump") for f in r["flags"])
    assert r["apparent_ratio"][1] < 1.05  # the largest bump the data allow includes none


def _draw_inclusion(rng: np.random.Generator, n: int = 13) -> Inclusion:
    radius = float(rng.uniform(3.5e-3, 6e-3))
    x, y = rng.uniform(3 * STEP, (n - 4) * STEP, 2)
    return Inclusion(x=float(x), y=float(y), depth=radius + float(rng.uniform(0.5e-3, 3e-3)),
                     radius=radius, ratio=float(math.exp(rng.uniform(math.log(3), math.log(30)))))


@pytest.mark.slow
@pytest.mark.long
def test_lump_coverage_over_simulated_phantoms():
    """20 phantoms with a lump drawn at random, the lump model fitted whether or not the map
    detects it (coverage conditional on detection would be biased by the selection): the 90 %
    intervals of the centre and of the apparent stiffness ratio cover the truth at the
    nominal rate, and at least 90 % of the found lumps' centres are within one grid step.
    Measured: 18/20 found, centres 0.44 step off (median; largest 1.11, a faint lump), coverage
    x 18/20, y 19/20, apparent ratio 16/20.  The inclusion's
    own ratio is not identified at one depth (see the flags); its coverage is printed."""
    rng = np.random.default_rng(2026)
    incs = [_draw_inclusion(rng) for _ in range(20)]
    with cf.ProcessPoolExecutor(max_workers=2) as pool:
        runs = list(pool.map(_run, range(100, 120), incs, [0.0] * 20))
    pairs = list(zip(runs, incs, strict=True))
    assert all("x_m" in r for r in runs)
    for r, i in pairs:
        print(f"p_lump {r['p_lump']:.2f} peak {r['peak']:.3f} A {r['apparent_ratio']} "
              f"dx {(r['x_m'][0] - i.x) / STEP:+.2f} dy {(r['y_m'][0] - i.y) / STEP:+.2f}")
    found = [(r, i) for r, i in pairs if r["p_lump"] >= 0.5]
    dist = np.array([math.hypot(r["x_m"][0] - i.x, r["y_m"][0] - i.y) / STEP for r, i in found])
    cov = {"x_m": np.mean([_covers(r["x_m"], i.x) for r, i in pairs]),
           "y_m": np.mean([_covers(r["y_m"], i.y) for r, i in pairs]),
           "apparent_ratio": np.mean([_covers(r["apparent_ratio"], r["peak"]) for r, _ in pairs])}
    cov_ratio = np.mean([_covers(r["ratio"], i.ratio) for r, i in pairs])
    print(f"detected {len(found)}/20; centre error of the detected [steps]: median "
          f"{np.median(dist):.2f}, max {dist.max():.2f}; coverage {cov}; inclusion ratio "
          f"(not identified) {cov_ratio:.2f}")
    assert len(found) >= 15
    assert np.mean(dist <= 1.0) >= 0.9
    for q, c in cov.items():  # binomial(20, 0.9): P(< 15/20) ~ 4 %
        assert 0.75 <= c <= 1.0, (q, c)
