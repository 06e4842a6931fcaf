"""Where to press next: candidates, criteria, batches and the stopping rule."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

import palpbayes as pb
from palpbayes.active import SearchState, SearchStopRule, next_presses
from palpbayes.active.criteria import CRITERIA, eig, level_probability, predictive
from palpbayes.active.search import PRESS_COLUMNS, decide, history
from palpbayes.errors import InputError
from palpbayes.inclusion import Inclusion
from palpbayes.sim.phantom import MapPhantom

FOOT = (0.0, 0.042, 0.0, 0.042)
PH = MapPhantom(inclusion=Inclusion(x=0.014, y=0.027, depth=5.5e-3, radius=5e-3, ratio=10.0))


def _state(x, y, lump=True, seed=0, **kw) -> SearchState:
    """Presses whose log E is the phantom's smooth field plus 3 % heterogeneity."""
    rng = np.random.default_rng(seed)
    x, y = np.asarray(x, float), np.asarray(y, float)
    E = PH.apparent_modulus(x, y) if lump else np.full(x.size, PH.E_background)
    df = pd.DataFrame({"x_m": x, "y_m": y, "logE_mean": np.log(E) + 0.03 *
                       rng.standard_normal(x.size), "logE_sd": 0.0015})
    return SearchState(df, FOOT, PH.contact_radius, PH.thickness, **kw)


def _empty(**kw) -> SearchState:
    return SearchState(pd.DataFrame(columns=PRESS_COLUMNS), FOOT, PH.contact_radius,
                       PH.thickness, **kw)


def _raster(m):
    g = (np.arange(m) + 0.5) / m * 0.042
    X, Y = np.meshgrid(g, g)
    return X.ravel(), Y.ravel()


def test_the_first_press_is_the_middle_of_the_footprint():
    ans = next_presses(_empty())
    assert not ans.stop and ans.summary["n"] == 0 and ans.summary["p_lump"] == 0.5
    assert (ans.presses.x_m.iloc[0], ans.presses.y_m.iloc[0]) == pytest.approx((0.022, 0.022))
    four = next_presses(_empty(), 4).presses
    assert len(four) == 4 and len({(a, b) for a, b in zip(four.x_m, four.y_m, strict=True)}) == 4


def test_candidates_keep_out_of_zones_and_away_from_presses():
    st = _state(*_raster(4), keep_out=((0.03, 0.03, 0.006),), min_spacing=3e-3)
    qx, qy = st.candidates()
    assert qx.size > 50
    assert np.all(np.hypot(qx - 0.03, qy - 0.03) > 0.006)
    d = np.hypot(qx[:, None] - st.presses.x_m.to_numpy(), qy[:, None] - st.presses.y_m.to_numpy())
    assert d.min() >= 3e-3
    assert qx.min() >= 0 and qx.max() <= 0.042 + 1e-12


def test_a_batch_is_k_distinct_presses_at_the_minimum_spacing():
    st = _state(*_raster(4), min_spacing=4e-3)
    ans = next_presses(st, 3, rule=SearchStopRule(centre_radius=1e-6))
    p = ans.presses
    assert list(p.order) == [1, 2, 3]
    xy = p[["x_m", "y_m"]].to_numpy()
    d = np.hypot(*(xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1))
    assert d[np.triu_indices(3, 1)].min() >= 4e-3
    first = next_presses(st, 1, rule=SearchStopRule(centre_radius=1e-6)).presses
    assert (first.x_m.iloc[0], first.y_m.iloc[0]) == (p.x_m.iloc[0], p.y_m.iloc[0])


def test_eig_presses_where_the_hypotheses_disagree_not_where_it_already_pressed():
    # dense presses over the left half, none on the right: the right half is where a lump
    # could still hide, so information is there
    x, y = np.meshgrid(np.linspace(0.001, 0.02, 8), np.linspace(0.001, 0.041, 12))
    st = _state(x.ravel(), y.ravel(), lump=False)
    post = st.posterior()
    qx, qy = st.candidates()
    g = eig(post, qx, qy, 0.0015)
    assert np.all(g >= 0)
    left, right = g[qx < 0.018], g[qx > 0.03]
    assert right.mean() > 3 * left.mean()
    ans = next_presses(st)
    assert ans.presses.x_m.iloc[0] > 0.02


@pytest.mark.parametrize("target", ["joint", "presence", "centre"])
def test_eig_is_the_mutual_information_by_monte_carlo(target):
    st = _state(*_raster(3))  # P(lump) in between: both groups matter
    post = st.posterior()
    assert 0.05 < post.p_lump < 0.95
    qx, qy = np.array([0.014, 0.035]), np.array([0.027, 0.005])
    w, mu, sd = predictive(post, qx, qy, 0.0015)
    w = w / w.sum()
    rng = np.random.default_rng(5)
    for j in range(2):
        # I(y; T) = E[log p(y | T) - log p(y)], T the target: g itself (joint), lump or not
        # (presence), or the centre given a lump (centre)
        if target == "centre":
            wj = np.concatenate([[0.0], w[1:] / w[1:].sum()])
        else:
            wj = w
        g = rng.choice(w.size, size=60000, p=wj)
        yv = mu[g, j] + sd[g, j] * rng.standard_normal(g.size)
        dens = np.exp(-0.5 * ((yv[:, None] - mu[None, :, j]) / sd[None, :, j]) ** 2) \
            / (math.sqrt(2 * math.pi) * sd[None, :, j])
        p_y = dens @ wj
        if target == "presence":
            lump = g > 0
            p1 = dens[:, 1:] @ (w[1:] / w[1:].sum())
            cond = np.where(lump, p1, dens[:, 0])
        else:
            cond = dens[np.arange(g.size), g]
        mi = np.mean(np.log(cond) - np.log(p_y))
        got = eig(post, qx[j:j + 1], qy[j:j + 1], 0.0015, target=target)[0]
        assert got == pytest.approx(mi, abs=0.01 + 0.02 * mi), (j, got, mi)
    # auto is presence while undecided
    assert np.array_equal(eig(post, qx, qy, 0.0015),
                          eig(post, qx, qy, 0.0015, target="presence"))


def test_level_probability_matches_its_definition_on_the_grid():
    st = _state(*_raster(6))
    post = st.posterior()
    k = 1.05
    q = np.array([[0.014, 0.027], [0.02, 0.027], [0.04, 0.002]])
    p = level_probability(post, q[:, 0], q[:, 1], k)
    # by brute force over the kept centres, spheres and betas
    hyp = post.hyp
    ck = post.ck_weights[post.kept]
    ck = ck / ck.sum()
    surv = post.beta_survival
    pmf = -np.diff(np.concatenate([surv, np.zeros(surv.shape[:2] + (1,))], axis=-1), axis=-1)
    for j, (x, y) in enumerate(q):
        tot = 0.0
        for c_i, c in enumerate(post.kept):
            phi = hyp.profile(np.hypot(hyp.cx[c] - x, hyp.cy[c] - y))
            for k_i in range(phi.shape[0]):
                above = hyp.betas * phi[k_i] > math.log(k)
                tot += ck[c_i, k_i] * pmf[k_i, c_i][above].sum()
        assert p[j] == pytest.approx(post.p_lump * tot, abs=1e-9)
    assert p[0] > 0.9 and p[2] < 0.05


def test_each_criterion_chooses_a_candidate():
    st = _state(*_raster(5))
    for name in CRITERIA:
        ans = next_presses(st, criterion=name, rule=SearchStopRule(centre_radius=1e-6))
        assert len(ans.presses) == 1 and ans.presses.criterion.iloc[0] == name
    # ucb chases the stiffest place: near the lump
    p = next_presses(st, criterion="ucb", rule=SearchStopRule(centre_radius=1e-6)).presses
    assert math.hypot(p.x_m.iloc[0] - 0.014, p.y_m.iloc[0] - 0.027) < 0.008


def test_the_rule_decides_a_lump_and_none():
    lump = _state(*_raster(11))
    ans = next_presses(lump, rule=SearchStopRule(centre_radius=3e-3))
    assert ans.stop and ans.decision == "lump" and ans.presses.empty
    assert math.hypot(ans.summary["x_m"] - 0.014, ans.summary["y_m"] - 0.027) < 2e-3
    strict = next_presses(lump, rule=SearchStopRule(centre_radius=1e-4))
    assert not strict.stop  # P(lump) is high, but the centre is not placed to 0.1 mm
    none = next_presses(_state(*_raster(14), lump=False, seed=3))
    assert none.stop and none.decision == "no lump", none.summary["p_lump"]
    budget = next_presses(_state(*_raster(3)), rule=SearchStopRule(max_presses=9))
    assert budget.stop and budget.decision == "" and "budget" in budget.reason


def test_decide_uses_the_thresholds():
    post = _state(*_raster(11)).posterior()
    assert decide(post, SearchStopRule(p_decide=0.95, centre_radius=3e-3))[0] == "lump"
    assert decide(post, SearchStopRule(p_decide=0.95, centre_radius=1e-5)) == ("", "")


def test_eig_quadrature_holds_when_the_heterogeneity_is_small(monkeypatch):
    """Narrow predictives (tau 0.3 %) over a wide spread of lump means: the information is
    the converged quadrature's (4,000 nodes) and never above the entropy it is about."""
    import palpbayes.active.criteria as crit

    rng = np.random.default_rng(7)
    x, y = rng.uniform(0, 0.042, 8), rng.uniform(0, 0.042, 8)
    df = pd.DataFrame({"x_m": x, "y_m": y, "logE_sd": 0.002,
                       "logE_mean": np.log(5e4) + 0.003 * rng.standard_normal(8)})
    st = SearchState(df, FOOT, PH.contact_radius, PH.thickness)
    post = st.posterior()
    qx, qy = st.candidates()
    assert 0.05 < post.p_lump < 0.95
    h = -(post.p_lump * math.log(post.p_lump) + (1 - post.p_lump) * math.log(1 - post.p_lump))
    got = eig(post, qx, qy, 0.002, target="presence")
    monkeypatch.setattr(crit, "_Y_NODES", 4000)
    fine = eig(post, qx, qy, 0.002, target="presence")
    assert np.abs(got - fine).max() < 1e-3 and got.max() <= h + 1e-12
    assert np.argmax(got) == np.argmax(fine)


def test_a_copy_for_another_specimen_builds_its_own_grid():
    from dataclasses import replace

    st = _state(*_raster(3))
    st.posterior()
    other = replace(st, footprint=(0.0, 0.1, 0.0, 0.1), min_excess=0.2)
    assert other.hyp.cx.max() == 0.1 and other.hyp.betas[0] == pytest.approx(math.log(1.2))
    assert st.hyp.cx.max() == 0.042 and st.hyp.betas[0] == pytest.approx(math.log(1.03))


def test_a_batch_stops_at_the_budget():
    ans = next_presses(_state(*_raster(3)), 5, rule=SearchStopRule(max_presses=11))
    assert len(ans.presses) == 2


def test_history_gives_p_lump_after_each_press():
    st = _state(*_raster(4))
    h = history(st)
    assert list(h.n) == list(range(1, 17))
    assert np.all((h.p_lump >= 0) & (h.p_lump <= 1))
    assert h.p_lump.iloc[-1] == pytest.approx(st.posterior().p_lump)


def test_front_door_takes_a_state_or_overrides():
    st = _state(*_raster(4))
    before = st.hyp.cx.max()
    ans = pb.next_presses(st, footprint=(0.0, 0.03, 0.0, 0.03))
    assert ans.presses.x_m.iloc[0] <= 0.03 and ans.presses.y_m.iloc[0] <= 0.03
    assert st.hyp.cx.max() == before == 0.042  # the state keeps its own grid


@pytest.mark.parametrize("kw, match", [
    (dict(criterion="best"), "criterion"),
    (dict(k=0), "k 0"),
])
def test_bad_arguments_are_refused(kw, match):
    with pytest.raises(InputError, match=match):
        next_presses(_state(*_raster(3)), **kw)


def test_bad_states_are_refused():
    with pytest.raises(InputError, match="missing column"):
        SearchState(pd.DataFrame({"x_m": [0.0]}), FOOT, 0.005, 0.02)
    df = pd.DataFrame({"x_m": [0.0, 0.01], "y_m": [0.0, 0.01], "logE_mean": [10.0, np.nan],
                       "logE_sd": [0.01, 0.01]})
    with pytest.raises(InputError, match="press 2 has"):
        SearchState(df, FOOT, 0.005, 0.02)
    with pytest.raises(InputError, match="keep-out zone 0"):
        _empty(keep_out=((0.01, 0.01),))
    with pytest.raises(InputError, match="p_decide"):
        SearchStopRule(p_decide=0.4)
    for kw, match in ((dict(footprint=(0, -0.01, 0, 0.01)), "footprint"),
                      (dict(footprint=(0, np.nan, 0, 0.01)), "footprint"),
                      (dict(thickness=0.0), "thickness"), (dict(prior_lump=1.0), "prior_lump"),
                      (dict(min_excess=0.0), "min_excess"), (dict(k_level=0.9), "k_level")):
        args = {"footprint": FOOT, "contact_radius": 0.005, "thickness": 0.02, **kw}
        with pytest.raises(InputError, match=match):
            SearchState(pd.DataFrame(columns=PRESS_COLUMNS), **args)
    every = _empty(keep_out=((0.021, 0.021, 0.05),))
    with pytest.raises(InputError, match="keep-out zones cover"):
        next_presses(every)


def test_the_old_name_of_the_search_rule_warns_and_is_the_new_one():
    """``StopRule`` became ``SearchStopRule`` (issue 57: beside the online ``StoppingRule`` the
    two names did not say what they stop)."""
    import palpbayes.active as active

    with pytest.warns(DeprecationWarning, match="SearchStopRule"):
        assert active.StopRule is SearchStopRule
    assert "StopRule" not in active.__all__
    with pytest.raises(AttributeError):
        active.NoSuchRule  # noqa: B018
