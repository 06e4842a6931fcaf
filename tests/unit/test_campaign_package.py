"""The campaign and pooling packages: public names from the submodules' ``__all__``, one owner
per name, and ``palpbayes.outputs`` importable alone (no import cycle through the package)."""

from __future__ import annotations

import importlib
import subprocess
import sys

import pytest

import palpbayes.campaign as campaign
import palpbayes.pooling as pooling


def test_campaign_exports_are_the_api_modules_all():
    expected = []
    for sub in campaign.API_MODULES:
        expected += importlib.import_module(f"palpbayes.campaign.{sub}").__all__
    assert campaign.__all__ == expected
    assert len(set(expected)) == len(expected)  # one owner per name
    for name in ("fit_campaign", "FitOptions", "load_results", "load_fit", "run_pipeline",
                 "compare", "format_comparison"):
        assert name in campaign.__all__
    for name in campaign.__all__:
        owner = next(s for s in campaign.API_MODULES
                     if name in importlib.import_module(f"palpbayes.campaign.{s}").__all__)
        assert getattr(campaign, name) is getattr(
            importlib.import_module(f"palpbayes.campaign.{owner}"), name)
    assert set(campaign.__all__) <= set(dir(campaign))


def test_pooling_exports_are_its_modules_all():
    assert pooling.__all__ == [*pooling.model.__all__, *pooling.inputs.__all__]
    assert len(set(pooling.__all__)) == len(pooling.__all__)


def test_layout_and_reference_import_alone_without_the_fitting_code():
    """``campaign.reference`` (imported by campaign.comparison) imports palpbayes.outputs: importing
    it first must neither fail nor load the campaign run, the sampler or arviz."""
    code = ("import sys, palpbayes.campaign.reference, palpbayes.outputs\n"
            "heavy = [m for m in ('palpbayes.campaign.run', 'palpbayes.campaign.comparison', "
            "'arviz', 'emcee') if m in sys.modules]\n"
            "assert not heavy, heavy\n")
    subprocess.run([sys.executable, "-c", code], check=True)


@pytest.mark.slow
def test_every_campaign_and_pooling_module_imports_first_in_a_fresh_interpreter():
    mods = [f"palpbayes.campaign.{m}" for m in (*campaign.API_MODULES, "partial")]
    mods += ["palpbayes.outputs", "palpbayes.pooling.model", "palpbayes.pooling.inputs",
             "palpbayes.campaign.reference"]
    for mod in mods:
        subprocess.run([sys.executable, "-c", f"import {mod}"], check=True)
