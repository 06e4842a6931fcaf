"""Tests of the viscoelastic simulator (palpbayes.sim.viscoelastic): the motion, the force
against closed forms and quadrature (elastic limit, power-law ramp, SLS hold, Ting retract),
noise statistics, seeds, metadata, several speeds and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate
from scipy.special import gamma

from palpbayes.contact import (
    PowerLawKernel,
    PronyKernel,
    Tip,
    ramp_apparent_modulus,
    standard_linear_solid,
)
from palpbayes.errors import GeometryError, InputError
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim import multi_speed, ramp_hold_motion, simulate_viscoelastic
from palpbayes.trace import SEGMENTS

PARA = PAPER_TIPS["paraboloid"]  # R = 11.7 mm: g = 4·sqrt(R)/3, m = 3/2
FLAT = PAPER_TIPS["flat"]  # a = 10 mm: g = 2a, m = 1
G_PARA = 4 * math.sqrt(0.0117) / 3
V = 50 / 60e3  # the paper's 50 mm/min [m/s]
D = 3e-3
POWER = PowerLawKernel(100e3, 0.12, t0=1.0)
SLS = standard_linear_solid(60e3, 40e3, 0.8)


def _clean(kernel, tip=PARA, **kw):
    kw = {"depth": D, "speed": V, "hold_time": 1.0, "rng": 0, **kw, "noise_sd": 0.0}
    return simulate_viscoelastic(kernel, tip, **kw)


def _ramp_end(tr) -> int:
    """Index of the deepest sample (the last of the approach)."""
    return int(np.flatnonzero(tr.segment == 0)[-1])


# ----------------------------------------------------------------------------- motion

@pytest.mark.parametrize("z_surf", [0.0, 0.1])
def test_motion_reaches_depth_holds_and_returns_at_speed(z_surf):
    rate, hold = 800.0, 1.5
    t, z, seg = ramp_hold_motion(depth=D, speed=V, hold_time=hold, rate=rate, z_surf=z_surf)
    np.testing.assert_allclose(np.diff(t), 1 / rate, rtol=1e-9)
    assert t[0] == 0.0
    assert [SEGMENTS[c] for c in np.unique(seg)] == ["approach", "hold", "retract"]
    assert np.all(np.diff(seg) >= 0)
    down, on_hold, up = (np.flatnonzero(seg == c) for c in range(3))
    # depth reached exactly at the last approach sample, held there for hold_time
    assert z.min() == pytest.approx(z_surf - D, abs=1e-15)
    assert z[down[-1]] == pytest.approx(z_surf - D, abs=1e-15)
    assert on_hold.size == round(hold * rate)
    np.testing.assert_allclose(z[on_hold], z_surf - D, rtol=0, atol=1e-15)
    # speed: every step of the descent and of the retract moves speed/rate
    np.testing.assert_allclose(np.diff(z[down]), -V / rate, rtol=1e-9)
    np.testing.assert_allclose(np.diff(z[np.r_[on_hold[-1], up]]), V / rate, rtol=1e-9)
    # start: the default ~0.5 s baseline above the surface, raised by less than one step
    approach = z[0] - z_surf
    assert 0.5 * V * (1 - 1e-9) <= approach < 0.5 * V + V / rate
    assert np.count_nonzero(z > z_surf) == pytest.approx(2 * 0.5 * rate, abs=3)
    assert z[-1] == z[0] and up.size == down.size - 1


def test_motion_without_hold_or_retract_and_a_given_approach():
    t, z, seg = ramp_hold_motion(depth=2e-3, speed=1e-3, hold_time=0.0, rate=1000.0,
                                 approach=1e-3)
    assert 1 not in seg and z[-1] > z.min()  # no hold sample: straight back up
    assert z[0] == pytest.approx(1e-3) and z.min() == pytest.approx(-2e-3, abs=1e-15)
    assert t.size == 2 * 3000 + 1
    t, z, seg = ramp_hold_motion(depth=2e-3, speed=1e-3, hold_time=0.25, rate=1000.0,
                                 retract=False, approach=0.0)
    assert z[0] == 0.0 and z[-1] == pytest.approx(-2e-3) and seg[-1] == 1
    assert np.count_nonzero(seg == 1) == 250 and 2 not in seg


# ----------------------------------------------------------------------------- the force

@pytest.mark.parametrize("tip, g, m", [(PARA, G_PARA, 1.5), (FLAT, 0.02, 1.0)])
def test_alpha_zero_is_the_elastic_law(tip, g, m):
    E0 = 80e3
    tr = _clean(PowerLawKernel(E0, 0.0), tip=tip, z_surf=0.05)
    d = np.clip(0.05 - tr.z, 0, None)
    np.testing.assert_allclose(tr.force, E0 * g * d**m, rtol=1e-12, atol=1e-15)
    assert tr.force[tr.segment < 2].max() == pytest.approx(E0 * g * D**m, rel=1e-12)


@pytest.mark.parametrize("speed", [V, 5 * V])
def test_power_law_ramp_matches_the_closed_form(speed):
    tr = _clean(POWER, speed=speed, hold_time=0.0)
    k = _ramp_end(tr)
    expected = float(ramp_apparent_modulus(POWER, speed, D, 1.5)) * G_PARA * D**1.5
    assert tr.force[k] == pytest.approx(expected, rel=1e-7)
    # and along the ramp, against DESIGN §9's Gamma form (independent of the Beta form):
    # F = g·E(t)·d^1.5·(3·sqrt(pi)/4)·Gamma(1 - alpha)/Gamma(5/2 - alpha), t = d/v
    a = POWER.alpha
    d = -tr.z[: k + 1]
    on = d > 0.05 * D
    t = d[on] / speed
    form = G_PARA * POWER.E0 * t**-a * d[on] ** 1.5 * 3 * math.sqrt(math.pi) / 4 \
        * gamma(1 - a) / gamma(2.5 - a)
    np.testing.assert_allclose(tr.force[: k + 1][on], form, rtol=1e-6)


def test_sls_hold_relaxes_to_the_relaxed_modulus():
    E_inf, E1, tau = SLS.E_inf, SLS.E[0], SLS.tau[0]
    m = 1.5
    tr = _clean(SLS, hold_time=12 * tau)
    k = _ramp_end(tr)
    Tr = D / V
    # g·∫_0^Tr (E_inf + E1·exp(-(t - s)/tau))·d/ds[(v·s)^m] ds, by quadrature
    lag = integrate.quad(lambda s: math.exp(-(Tr - s) / tau) * m * V**m * s ** (m - 1),
                         0.0, Tr, epsabs=0, epsrel=1e-12)[0]
    hold = np.flatnonzero(tr.segment == 1)
    th = tr.time[hold] - tr.time[k]
    expected = G_PARA * (E_inf * D**m + E1 * np.exp(-th / tau) * lag)
    np.testing.assert_allclose(tr.force[hold], expected, rtol=1e-8)
    assert np.all(np.diff(tr.force[k:hold[-1] + 1]) < 0)  # relaxes from the peak
    assert tr.force[k] == tr.force[tr.segment < 2].max()
    elastic_t0 = G_PARA * (E_inf + E1) * D**m
    assert tr.force[hold[-1]] / elastic_t0 == pytest.approx(E_inf / (E_inf + E1), rel=1e-4)


def test_power_law_retract_follows_tings_closed_form():
    """No hold, equal speeds: t1 = t - 2^(1/(1-alpha))·(t - t_max) (DESIGN §9), F = 0 once t1
    is before first contact."""
    a, m = POWER.alpha, 1.5
    tr = _clean(POWER, hold_time=0.0)
    k = _ramp_end(tr)
    t_c = tr.time[k] - D / V  # first contact
    up = np.flatnonzero(tr.segment == 2)
    for i in up[[5, 200, 600, 1200, 1700, 2600]]:
        t = tr.time[i]
        t1 = t - 2 ** (1 / (1 - a)) * (t - tr.time[k])
        if t1 <= t_c:
            assert tr.force[i] == 0.0
            continue
        f = integrate.quad(lambda s, t=t: POWER.E0 * (t - s) ** -a * m * V**m
                           * (s - t_c) ** (m - 1), t_c, t1, epsabs=0, epsrel=1e-11)[0]
        assert tr.force[i] == pytest.approx(G_PARA * f, rel=1e-6)
    # hysteresis: below the loading force at the same depth, and off before the surface, at
    # the depth where t1 = t_c: D·(1 - 1/(2^(1/(1-alpha)) - 1)) (0.166·D here)
    down = np.flatnonzero(tr.segment == 0)
    assert np.all(tr.force[up] <= np.interp(-tr.z[up], -tr.z[down], tr.force[down]) + 1e-12)
    d_off, step = D * (1 - 1 / (2 ** (1 / (1 - a)) - 1)), V / 800
    d_up = -tr.z[up]
    assert np.all(tr.force[up][d_up < d_off - step] == 0.0)
    assert np.all(tr.force[up][d_up > d_off + step] > 0.0)


# ----------------------------------------------------------------------------- noise

def test_force_noise_sd_and_lag_one_correlation():
    sd, phi = 0.008, 0.7
    kw = {"hold_time": 30.0, "rng": 11}
    clean = _clean(SLS, **kw)
    e = simulate_viscoelastic(SLS, PARA, depth=D, speed=V, noise_sd=sd, phi=phi,
                              **kw).force - clean.force
    assert e.size > 24000
    assert e.std() == pytest.approx(sd, rel=0.03)
    assert np.corrcoef(e[:-1], e[1:])[0, 1] == pytest.approx(phi, abs=0.02)
    white = simulate_viscoelastic(SLS, PARA, depth=D, speed=V, **kw).force - clean.force
    assert white.std() == pytest.approx(0.008, rel=0.03)  # the paper's 48 mN p-p / 6
    assert abs(np.corrcoef(white[:-1], white[1:])[0, 1]) < 0.02


def test_offset_and_position_noise():
    clean = _clean(SLS, hold_time=10.0)
    tr = simulate_viscoelastic(SLS, PARA, depth=D, speed=V, hold_time=10.0, rng=0,
                               noise_sd=0.0, offset=-0.05, position_noise_sd=2e-6)
    # the force is that of the true motion (unchanged by the position noise) plus the offset
    np.testing.assert_allclose(tr.force - clean.force, -0.05, rtol=0, atol=1e-14)
    dz = tr.z - clean.z
    assert dz.std() == pytest.approx(2e-6, rel=0.05) and abs(dz.mean()) < 1e-7


def test_same_seed_same_trace_other_seed_other_noise():
    kw = {"depth": D, "speed": V, "hold_time": 0.5, "phi": 0.3, "position_noise_sd": 1e-6}
    a, b = (simulate_viscoelastic(POWER, PARA, rng=5, **kw) for _ in range(2))
    np.testing.assert_array_equal(a.force, b.force)
    np.testing.assert_array_equal(a.z, b.z)
    c = simulate_viscoelastic(POWER, PARA, rng=6, **kw)
    assert not np.allclose(a.force, c.force)
    g = simulate_viscoelastic(POWER, PARA, rng=np.random.default_rng(5), **kw)
    np.testing.assert_array_equal(a.force, g.force)


# ----------------------------------------------------------------------------- metadata

def test_metadata_holds_the_truth():
    tr = simulate_viscoelastic(POWER, PARA, depth=D, speed=V, hold_time=0.7, rng=3, phi=0.2,
                               offset=0.01, z_surf=0.02)
    md = tr.metadata
    assert md["simulated"] and md["kernel"] == "power-law" and md["seed"] == 3
    assert (md["E0_true"], md["alpha_true"], md["t0_true"]) == (100e3, 0.12, 1.0)
    assert md["z_surf_true"] == 0.02 and md["depth_true"] == D and md["speed"] == V
    assert md["sigma_true"] == pytest.approx(0.008) and md["noise_pp"] == pytest.approx(0.048)
    assert (md["phi_true"], md["force_offset_true"], md["position_noise_true"]) == \
        (0.2, 0.01, 0.0)
    assert md["rate"] == 800.0 and md["retract"] is True
    assert md["hold"] == pytest.approx(0.7) and md["hold_requested"] == 0.7
    assert md["approach"] == pytest.approx(0.5 * V, abs=V / 800)
    assert (md["m_true"], md["g_true"]) == (1.5, pytest.approx(G_PARA))
    assert md["max_force_true"] == pytest.approx(_clean(POWER, hold_time=0.7).force.max())
    assert tr.trace_id == "visco" and tr.tip == PARA
    md = _clean(SLS).metadata
    assert md["kernel"] == "sls" and (md["E_inf_true"], md["E1_true"], md["tau_true"]) == \
        (60e3, 40e3, 0.8)
    md = _clean(PronyKernel(30e3, (40e3, 20e3), (0.1, 3.0))).metadata
    assert md["kernel"] == "prony" and md["E_prony_true"] == (40e3, 20e3)
    assert md["tau_prony_true"] == (0.1, 3.0) and md["E_inf_true"] == 30e3


# ----------------------------------------------------------------------------- several speeds

def _apparent_modulus(tr) -> float:
    """Least-squares E* of F = E*·g·d^m on the approach, in contact (true surface)."""
    down = tr.segment == 0
    s = G_PARA * np.clip(tr.metadata["z_surf_true"] - tr.z[down], 0, None) ** 1.5
    return float(s @ tr.force[down] / (s @ s))


def test_multi_speed_apparent_modulus_rises_with_speed():
    speeds = [10 / 60e3, 50 / 60e3, 250 / 60e3]
    trs = multi_speed(POWER, PARA, speeds, depth=D, hold_time=0.2, rng=42)
    assert [tr.trace_id for tr in trs] == ["visco-10mm-min", "visco-50mm-min",
                                           "visco-250mm-min"]
    assert [tr.metadata["speed"] for tr in trs] == speeds
    assert [tr.metadata["speed_index"] for tr in trs] == [0, 1, 2]
    assert all(tr.metadata["seed"] == 42 for tr in trs)
    E = [_apparent_modulus(tr) for tr in trs]
    assert E[0] < E[1] < E[2]
    # E_app ∝ v^alpha at every depth: the ratio of the fits is 5^alpha
    np.testing.assert_allclose(np.diff(np.log(E)), POWER.alpha * math.log(5), rtol=0.02)
    # independent noise: the residuals of the first 800 samples are uncorrelated
    res = [tr.force[:800] - _clean(POWER, speed=v, hold_time=0.2).force[:800]
           for tr, v in zip(trs, speeds, strict=True)]
    for i, j in ((0, 1), (0, 2), (1, 2)):
        assert abs(np.corrcoef(res[i], res[j])[0, 1]) < 0.15
    again = multi_speed(POWER, PARA, speeds, depth=D, hold_time=0.2, rng=42)
    for x, y in zip(trs, again, strict=True):
        np.testing.assert_array_equal(x.force, y.force)


def test_multi_speed_ids_stay_distinct_and_generator_seeds_work():
    trs = multi_speed(SLS, PARA, [V, V], depth=D, hold_time=0.0, trace_id="sls",
                      rng=np.random.default_rng(1))
    assert [tr.trace_id for tr in trs] == ["sls-50mm-min-0", "sls-50mm-min-1"]
    assert not np.array_equal(trs[0].force, trs[1].force)
    assert "seed" not in trs[0].metadata


# ----------------------------------------------------------------------------- bad input

@pytest.mark.parametrize("kw, match", [
    ({"depth": 0.0}, r"depth \[m\]"),
    ({"depth": -1e-3}, r"depth \[m\]"),
    ({"speed": 0.0}, r"speed \[m/s\]"),
    ({"speed": float("nan")}, r"speed \[m/s\]"),
    ({"hold_time": -1.0}, r"hold time \[s\]"),
    ({"rate": 0.0}, r"sample rate \[Hz\]"),
    ({"approach": -1e-3}, r"approach distance \[m\]"),
    ({"z_surf": float("inf")}, r"z_surf \[m\]"),
    ({"noise_sd": -0.01}, r"noise_sd \[N\]"),
    ({"phi": 1.0}, r"phi = 1.0"),
    ({"offset": "x"}, r"force offset \[N\]"),
    ({"position_noise_sd": -1e-6}, r"position_noise_sd \[m\]"),
    ({"rate": 1.0, "approach": 0.0, "depth": 1e-4, "speed": 1.0, "retract": False,
      "hold_time": 0.0}, r"only 2 samples"),
])
def test_bad_input_names_the_argument_and_unit(kw, match):
    args = {"depth": D, "speed": V, "hold_time": 0.5, **kw}
    with pytest.raises(InputError, match=match):
        simulate_viscoelastic(POWER, PARA, **args)


def test_bad_kernel_tip_and_speeds():
    with pytest.raises(InputError, match="neither a PowerLawKernel"):
        simulate_viscoelastic(100e3, PARA, depth=D, speed=V, hold_time=0.0)
    with pytest.raises(InputError, match="palpbayes.contact.Tip"):
        simulate_viscoelastic(POWER, "paraboloid", depth=D, speed=V, hold_time=0.0)
    with pytest.raises(GeometryError, match="paraboloid"):
        simulate_viscoelastic(POWER, Tip("sphere", radius=0.01), depth=D, speed=V,
                              hold_time=0.0)
    with pytest.raises(InputError, match="non-empty"):
        multi_speed(POWER, PARA, [], depth=D, hold_time=0.0)
    with pytest.raises(InputError, match=r"speeds\[1\] \[m/s\]"):
        multi_speed(POWER, PARA, [V, -V], depth=D, hold_time=0.0)
    with pytest.raises(InputError, match="third argument"):
        multi_speed(POWER, PARA, [V], speed=V, depth=D, hold_time=0.0)
