"""Posterior flags reach ``summary.csv``: a flagged fit is reported as not converged.

The Bayesian fit flags failure modes that R-hat and ESS cannot see
(``bayes.flags.posterior_flags``): a bimodal surface posterior, a prior-dominated surface and
a posterior at a prior bound.  These tests check that each flag is raised on inputs that show
it and that it ends up in the ``notes`` column of ``summary.csv`` with its code in
``flag_codes`` and ``converged = False``, although the chains themselves pass their
diagnostics.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import palpbayes.bayes.fit as bayes_fit
from palpbayes import campaign
from palpbayes.bayes import PriorSpec
from palpbayes.campaign.fitjob import FitOptions, check_fittable, fit_trace
from palpbayes.cli import main
from palpbayes.contact import Tip
from palpbayes.io.trace_csv import write_trace
from palpbayes.sim import simulate_trace

TIP = Tip("sphere", radius=0.01)
BIMODAL = "bimodal z_surf"
PRIOR_DOMINATED = "prior-dominated z_surf"
AT_UPPER = "z_surf posterior at its upper prior bound"


@pytest.fixture(scope="module")
def clean():
    return simulate_trace(136e3, TIP, thickness=0.02, rng=1, trace_id="clean")


def _theta(post):
    return {"log_Estar": np.log(post["E_star"]), "z_surf": post["z_surf"]}


def test_bimodal_detector_on_a_synthetic_posterior(clean):
    data = check_fittable(clean, FitOptions())
    prior = PriorSpec().for_trace(data, "gaussian")
    rng = np.random.default_rng(0)
    z0, sd = clean.metadata["z_surf_true"], 1e-6
    one = {"z_surf": z0 + sd * rng.standard_normal(4000),
           "E_star": 1.5e5 * np.exp(0.01 * rng.standard_normal(4000))}
    assert bayes_fit.posterior_flags(one, _theta(one), prior) == []
    two = dict(one, z_surf=np.concatenate([one["z_surf"][:2000], one["z_surf"][2000:] + 20 * sd]))
    flags = bayes_fit.posterior_flags(two, _theta(two), prior)
    assert any(f.startswith(BIMODAL) for f in flags), flags


@pytest.mark.slow
def test_bimodal_flag_reaches_summary_csv(clean, tmp_path, monkeypatch):
    """A real fit whose z_surf draws are split in two before the flags are computed."""
    opts = FitOptions(method="bayes", seed=1)
    control = campaign.fit_campaign([clean], tmp_path / "control", opts, workers=1)
    assert bool(control["converged"].iloc[0]) and not control["notes"].iloc[0]

    real = bayes_fit.posterior_flags

    def split_surface(post, post_theta, prior):
        z = np.array(post["z_surf"], dtype=float)
        flat = z.reshape(-1)
        flat[: flat.size // 2] += 20 * np.std(flat)  # two separated surface heights
        return real(dict(post, z_surf=z), dict(post_theta, z_surf=z), prior)

    monkeypatch.setattr(bayes_fit, "posterior_flags", split_surface)
    out = tmp_path / "res"
    campaign.fit_campaign([clean], out, opts, workers=1)
    row = pd.read_csv(out / "summary.csv").iloc[0]
    assert BIMODAL in row["notes"], row["notes"]
    assert "bimodal_surface" in row["flag_codes"].split(";") and row["flag_level"] == "warning"
    assert not bool(row["converged"])
    assert row["rhat_max"] < 1.05  # the chains pass: only the flag makes it "not converged"


def test_bound_flag_end_to_end_through_the_cli(tmp_path, capsys):
    """13 samples at 5 Hz with 0.6 N peak-to-peak noise; the first sample is taken 0.12 mm
    *below* the true surface (50 µm approach, 0.17 mm per sample), so the surface lies above
    the recorded loading range: its posterior piles up at the prior's upper bound, and that
    must be said (it used to be reported as merely prior-dominated)."""
    tr = simulate_trace(136e3, TIP, thickness=0.02, rng=1, rate=5, noise_pp=0.6,
                        approach=5e-5, trace_id="sparse")
    outcome = fit_trace(tr, FitOptions(method="bayes", seed=1, f_unc=0.6,
                                       priors=PriorSpec(noise_pp=0.6)))
    assert outcome.bayes.diagnostics.converged  # R-hat and ESS pass ...
    assert not outcome.bayes.converged  # ... the flag alone fails the fit
    assert tr.z.max() < tr.metadata["z_surf_true"]
    assert any(w.startswith(AT_UPPER) for w in outcome.bayes.warnings), outcome.bayes.warnings

    path = write_trace(tr, tmp_path / "sparse.csv", float_format="%.17g")
    out = tmp_path / "res"
    rc = main(["fit", str(path), "--tip", "sphere", "--radius", "0.01", "--noise-pp", "0.6",
               "--out", str(out), "--seed", "1"])
    stdout = capsys.readouterr().out
    assert rc == 0
    row = pd.read_csv(out / "summary.csv").iloc[0]
    assert AT_UPPER in row["notes"] and "start in contact" in row["notes"], row["notes"]
    assert not bool(row["converged"])
    # on screen: the fit is named as not converged, with the flag's headline
    assert "sparse (bayes): did not converge" in stdout
    assert f"  - {AT_UPPER}" in stdout and "warning: 1 fit(s) above failed a check" in stdout


def test_prior_dominated_detector():
    """A surface posterior as wide as the prior is prior-dominated; a narrow one is not."""
    tr = simulate_trace(136e3, TIP, thickness=0.02, rng=1, trace_id="clean")
    data = check_fittable(tr, FitOptions())
    prior = PriorSpec().for_trace(data, "gaussian")
    rng = np.random.default_rng(1)
    lo, hi = prior.z_bounds
    wide = {"z_surf": rng.uniform(lo + 0.3 * (hi - lo), hi, 4000),
            "E_star": 1.5e5 * np.exp(0.01 * rng.standard_normal(4000))}
    flags = bayes_fit.posterior_flags(wide, _theta(wide), prior)
    assert any(f.startswith(PRIOR_DOMINATED) for f in flags)
    narrow = dict(wide, z_surf=0.5 * (lo + hi) + 1e-7 * rng.standard_normal(4000))
    assert bayes_fit.posterior_flags(narrow, _theta(narrow), prior) == []


def test_a_reloaded_fit_keeps_its_flags_and_model_checks(tmp_path):
    """load_fit used to drop the flags, so a flagged fit came back as converged."""
    from palpbayes.campaign.results import load_fit

    tr = simulate_trace(136e3, TIP, thickness=0.02, rng=1, rate=5, noise_pp=0.6,
                        approach=5e-5, trace_id="sparse")
    opts = FitOptions(method="bayes", seed=1, f_unc=0.6, priors=PriorSpec(noise_pp=0.6))
    summary = campaign.fit_campaign([tr], tmp_path / "res", opts, workers=1)
    assert not bool(summary["converged"].iloc[0])
    back = load_fit(tmp_path / "res", "sparse")
    assert not back.converged
    assert any(w.startswith(AT_UPPER) for w in back.warnings), back.warnings
    assert back.checks == []  # 13 samples: too few for the model checks, which are skipped
    assert np.isnan(summary["model_ok"].iloc[0])


def test_a_reloaded_fit_keeps_its_model_checks(tmp_path):
    from palpbayes.campaign.results import load_fit

    tr = simulate_trace(136e3, Tip("paraboloid", radius=0.0117), thickness=0.03, depth=3e-3,
                        base="bonded", rng=3, trace_id="layer")
    summary = campaign.fit_campaign([tr], tmp_path / "res", FitOptions(seed=1, layer="off"),
                                    workers=1)
    back = load_fit(tmp_path / "res", "layer")
    assert [c.name for c in back.checks] == ["exponent", "residual_structure",
                                             "depth_consistency", "ppc"]
    assert back.summary_row()["model_ok"] == summary["model_ok"].iloc[0] == False  # noqa: E712
    assert back.summary_row()["notes"] == summary["notes"].iloc[0]
