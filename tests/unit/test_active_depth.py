"""How deep to press: profiles per depth, the posterior over presses at several depths, the
choice of depth per second, the state files, the phantom's press depth and the twin's gain."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

from palpbayes.active import SearchState, next_presses
from palpbayes.active.criteria import eig
from palpbayes.active.depth import PAPER_SPEED, PressDepths
from palpbayes.active.files import PRESSES_FILE, append_press, read_state
from palpbayes.active.posterior import hypotheses, posterior
from palpbayes.active.profiles import A_REF, profile_table
from palpbayes.cli import main
from palpbayes.cli.next import EXIT_GO_ON
from palpbayes.contact import Tip
from palpbayes.errors import DataFileError, InputError
from palpbayes.inclusion import Inclusion, apparent_ratio, contact_radius, sensitivity
from palpbayes.sim.phantom import MapPhantom

FOOT = (0.0, 0.042, 0.0, 0.042)
H = 0.02
TIP = Tip("paraboloid", radius=0.0117)
D1, D2 = 0.002, 0.004
A1, A2 = contact_radius(TIP, D1), contact_radius(TIP, D2)
LUMP = Inclusion(x=0.014, y=0.027, depth=6e-3, radius=5e-3, ratio=10.0)


def test_press_depths_cost_index_and_errors():
    pd_ = PressDepths.for_tip(TIP, (D1, D2))
    assert pd_.contact_radii == pytest.approx((A1, A2))
    assert pd_.seconds() == pytest.approx([3 + 2 * D1 / PAPER_SPEED, 3 + 2 * D2 / PAPER_SPEED])
    assert pd_.seconds()[0] == pytest.approx(7.8)  # 2 mm down and up at 50 mm/min + 3 s
    assert list(pd_.index([D2, np.nan, D1 * 1.005])) == [1, 0, 0]
    with pytest.raises(InputError, match=r"press 2 has depth_m 0.003 m, none of"):
        pd_.index([D1, 0.003])
    for bad in [dict(depths=(D1,), contact_radii=()), dict(depths=(D1, D1), contact_radii=(1, 1)),
                dict(depths=(-D1,), contact_radii=(A1,)),
                dict(depths=(D1,), contact_radii=(A1,), speed=0.0)]:
        with pytest.raises(InputError):
            PressDepths(**bad)


def test_profile_table_first_depth_is_the_one_depth_table_and_the_second_the_model():
    s1, one, *_ = profile_table((A1,), H)
    s, two, fwhm, radius, cover = profile_table((A1, A2), H)
    assert two.shape[:2] == (2, one.shape[1])
    # the same spheres; the grid reaches further for the wider contact
    assert np.allclose(two[0, :, 0], 1.0) and np.allclose(one[0, :, 0], 1.0)
    for k in range(two.shape[1]):
        V1 = sensitivity(0.0, radius=radius[k], depth=radius[k] + cover[k], contact_radius=A1,
                         thickness=H)
        g = (1 - 1 / A_REF) / V1
        if g >= 1:
            continue
        ratio = 1 / (1 - g)  # the sphere's modulus ratio that reads A_REF at the first depth
        V2 = sensitivity(0.0, radius=radius[k], depth=radius[k] + cover[k], contact_radius=A2,
                         thickness=H)
        expect = math.log(float(apparent_ratio(V2, ratio))) / math.log(A_REF)
        assert two[1, k, 0] == pytest.approx(expect, rel=1e-9)
        # shallow spheres read less at the centre from the deeper press (wider contact)
        if cover[k] == 0:
            assert two[1, k, 0] < 1.0
    # a single-depth table interpolated onto the two-depth grid is the first depth's
    for k in (0, two.shape[1] - 1):
        assert np.allclose(np.interp(s[:-1], s1[:-1], one[0, k, :-1], right=0.0), two[0, k, :-1],
                           atol=2e-3)


def _readings(x, y, depth_m, seed, tau=0.03, lump=LUMP):
    ph = MapPhantom(inclusion=lump, tip=TIP, thickness=H)
    rng = np.random.default_rng(seed)
    m = np.array([np.log(ph.apparent_modulus(a, b, d)) for a, b, d in zip(x, y, depth_m,
                                                                           strict=True)])
    return m.ravel() + tau * rng.standard_normal(len(x))


def test_presses_at_the_deeper_depth_recover_the_reference_amplitude():
    """All 150 presses at 4 mm: with their depth the posterior reads the lump's apparent
    ratio at the reference 2 mm (1.138 where the forward model says 1.164); taken as 2 mm
    presses it reads the smaller 4 mm signature (1.099; the model 1.105)."""
    rng = np.random.default_rng(3)
    n = 150
    x, y = rng.uniform(0, 0.042, (2, n))
    m = _readings(x, y, np.full(n, D2), 4)
    s = np.full(n, 0.0015)
    two = hypotheses(FOOT, contact_radius=(A1, A2), thickness=H)
    right = posterior(two, x, y, m, s, depth=np.ones(n, int))
    wrong = posterior(two, x, y, m, s)  # as if pressed 2 mm
    V = [sensitivity(0.0, radius=5e-3, depth=6e-3, contact_radius=a, thickness=H)
         for a in (A1, A2)]
    at1, at2 = (float(apparent_ratio(v, 10.0)) for v in V)
    assert right.p_lump > 0.999 and wrong.p_lump > 0.999
    # the lump (radius 5 mm, cover 1 mm) is not one of the profile set's spheres: the
    # amplitude is read through the nearest ones (1.154 from the same presses at 2 mm)
    assert right.apparent_ratio == pytest.approx(at1, abs=0.03)
    assert wrong.apparent_ratio == pytest.approx(at2, abs=0.015)
    assert right.apparent_ratio - wrong.apparent_ratio > 0.03
    cx, cy = right.centre
    assert math.hypot(cx - LUMP.x, cy - LUMP.y) < 2e-3
    with pytest.raises(InputError, match="depth indices"):
        posterior(two, x, y, m, s, depth=np.full(n, 2))


def test_mixed_depths_equal_the_one_depth_posterior_when_every_press_is_at_the_reference():
    rng = np.random.default_rng(5)
    x, y = rng.uniform(0, 0.042, (2, 30))
    m = _readings(x, y, np.full(30, D1), 6)
    s = np.full(30, 0.002)
    one = posterior(hypotheses(FOOT, contact_radius=A1, thickness=H), x, y, m, s)
    two = posterior(hypotheses(FOOT, contact_radius=(A1, A2), thickness=H), x, y, m, s,
                    depth=np.zeros(30, int))
    assert two.log_bayes_factor == pytest.approx(one.log_bayes_factor, abs=0.02)
    assert two.centre == pytest.approx(one.centre, abs=2e-4)


def _state(n, seed=1, **kw):
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(0, 0.042, (2, n))
    df = pd.DataFrame({"x_m": x, "y_m": y, "logE_mean": _readings(x, y, np.full(n, D1), seed),
                       "logE_sd": 0.0015, "depth_m": D1})
    return SearchState(df, FOOT, A1, H, press_depths=PressDepths.for_tip(TIP, (D1, D2), **kw))


def test_next_press_is_the_most_information_per_second_over_depths():
    st = _state(12)
    ans = next_presses(st)
    row = ans.presses.iloc[0]
    assert row["criterion"] == "eig/s" and row["depth_m"] in (D1, D2)
    post = st.posterior()
    qx, qy = st.candidates()
    secs = st.press_depths.seconds()
    rates = [eig(post, qx, qy, st.expected_sd(j), depth=j) / secs[j] for j in (0, 1)]
    best = max(float(r.max()) for r in rates)
    assert row["score"] == pytest.approx(best, rel=1e-9)
    # priced out: a deep press that takes 100 times longer is never chosen
    slow = _state(12, speed=PAPER_SPEED / 100)
    assert next_presses(slow).presses["depth_m"].iloc[0] == D1
    # a force limit that allows only the first depth: eig at it, per press
    only = next_presses(st, deepest=D1).presses.iloc[0]
    assert (only["criterion"], only["depth_m"]) == ("eig", D1)
    # a batch carries a depth per press, believed at its depth
    batch = next_presses(st, k=3).presses
    assert len(batch) == 3 and batch["depth_m"].isin([D1, D2]).all()
    # a state whose press is at none of its depths is refused, naming the press
    bad = st.presses.copy()
    bad.loc[3, "depth_m"] = 0.003
    with pytest.raises(InputError, match="press 4 has depth_m"):
        SearchState(bad, FOOT, A1, H, press_depths=st.press_depths)
    with pytest.raises(InputError, match="contact radius"):
        SearchState(bad.iloc[:0], FOOT, A2, H, press_depths=st.press_depths)


def test_cli_init_with_depths_records_them_and_next_names_a_depth(tmp_path, capsys):
    d = str(tmp_path / "s")
    assert main(["next", d, "--init", "--footprint", "0,0.042,0,0.042", "--thickness", "0.02",
                 "--tip", "paraboloid", "--radius", "0.0117", "--depths", "0.2,0.1",
                 "--press-overhead", "5"]) == 0
    rec = json.loads((tmp_path / "s" / "search.json").read_text())
    assert rec["press_depths_m"] == pytest.approx([D1, D2])
    assert rec["contact_radii_m"] == pytest.approx([A1, A2])
    st = read_state(d)
    assert st.press_depths.overhead == 5 and st.press_depths.depths == pytest.approx((D1, D2))
    rng = np.random.default_rng(0)
    for i in range(10):
        x, y = rng.uniform(0, 0.042, 2)
        dep = D2 if i % 3 == 0 else D1
        mean = float(_readings([x], [y], [dep], i)[0])
        st = append_press(d, st, x, y, mean, 0.0015, depth_m=dep)
    capsys.readouterr()
    assert main(["next", d, "--json"]) == EXIT_GO_ON
    ans = json.loads(capsys.readouterr().out)
    assert min(abs(ans["presses"][0]["depth_m"] - v) for v in (D1, D2)) < 1e-12
    assert main(["next", d]) == EXIT_GO_ON
    assert ", depth " in capsys.readouterr().out
    # a depth that is not a number is named with its row
    p = tmp_path / "s" / PRESSES_FILE
    df = pd.read_csv(p)
    df["depth_m"] = df["depth_m"].astype(object)
    df.loc[2, "depth_m"] = "deep"
    df.to_csv(p, index=False)
    with pytest.raises(DataFileError, match="row 4, column depth_m"):
        read_state(d)
    assert main(["next", d, "--press-overhead", "2"]) == 2
    assert "--init" in capsys.readouterr().err


def test_phantom_presses_at_another_depth_with_the_twins_gain():
    ph = MapPhantom(inclusion=LUMP, tip=TIP, thickness=H, lump_gain=((D1, 3.0), (D2, 2.5)))
    plain = MapPhantom(inclusion=LUMP, tip=TIP, thickness=H)
    for d, g in ((D1, 3.0), (D2, 2.5)):
        r = ph.apparent_modulus(LUMP.x, LUMP.y, d) / ph.E_background
        r0 = plain.apparent_modulus(LUMP.x, LUMP.y, d) / ph.E_background
        assert math.log(r) == pytest.approx(g * math.log(r0), rel=1e-12)
    tr = ph.press(0.03, 0.01, key=1, depth=D2)
    assert np.ptp(tr.z) == pytest.approx(ph.approach + D2, rel=0.02)  # approach + press
    with pytest.raises(InputError, match="no lump gain for press depth 0.003"):
        ph.apparent_modulus(0.0, 0.0, 0.003)
    with pytest.raises(InputError, match="lump_gain"):
        MapPhantom(lump_gain=((D1, -1.0),))
    with pytest.raises(InputError, match="press depth"):
        ph.press(0.0, 0.0, depth=0.03)


@pytest.mark.parametrize("ratio", [1.0, 10.0])
def test_twin_pressed_ratio(ratio):
    from palpbayes.twin.palpation import CentredLump, pressed_ratio

    r = pressed_ratio(0.06, H, TIP, 0.3, "bonded", [D1, D2], CentredLump(5e-3, 9e-3, ratio),
                      "coarse")
    if ratio == 1.0:
        assert r == pytest.approx([1.0, 1.0], abs=1e-9)
    else:  # reports/active/lump_depth.csv (F = k d^1.5 fits): 1.2597 and 1.2236
        assert r == pytest.approx([1.2597, 1.2236], rel=2e-3)
        assert r[1] < r[0]  # the centre's signature falls from a 10 % to a 20 % press


def test_the_live_loop_names_no_depth_over_the_force_limit():
    from palpbayes.active.safety import PressLimits
    from palpbayes.cli.follow_safety import deepest_allowed, state_modulus

    st = _state(12)
    E = state_modulus(st)

    def force(E_, d):  # [N] 1 N at 2 mm, 2.83 N at 4 mm (d^1.5), at the plausible E
        assert E_ == E
        return (d / D1) ** 1.5

    lim = dict(depths=(0.1, 0.2), depth=D1)
    assert deepest_allowed(st, PressLimits(max_force=3.0, **lim), force) == D2
    assert deepest_allowed(st, PressLimits(max_force=2.0, **lim), force) == D1
    assert deepest_allowed(st, PressLimits(max_force=0.5, **lim), force) == D1  # none: the
    assert deepest_allowed(st, PressLimits(**lim), force) is None               # shallowest
    empty = SearchState(st.presses.iloc[:0], FOOT, A1, H, press_depths=st.press_depths)
    assert deepest_allowed(empty, PressLimits(max_force=2.0, **lim), force) is None  # no E
