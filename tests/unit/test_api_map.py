"""The map's Python door refuses what the command line refuses, naming the option (issue 57);
the whole run is tested against ``palpbayes map`` in tests/integration/test_map_cli.py."""

from __future__ import annotations

import pytest

import palpbayes as pb
from palpbayes.api_map import MapRequest, prepare_map
from palpbayes.errors import InputError


@pytest.mark.parametrize(("options", "message"), [
    ({"seed": -1}, "seed -1 must be a non-negative whole number"),
    ({"seed": 1.5}, "seed 1.5 must be"),
    ({"seed": True}, "seed True must be"),
    ({"f_unc": -1.0}, "f_unc -1.0 must be a positive force"),
    ({"tip": "sphere"}, "tip 'sphere' must be a palpbayes.Tip"),
    ({"thickness": 0.0}, "^thickness: for an AFM force map"),
    ({"lump_max_steps": 10}, "lump_max_steps 10 is too few"),
    ({"colour": "red"}, "unknown option.*colour"),
])
def test_fit_map_names_the_bad_option(tmp_path, options, message):
    """Checked before any file is read (the manifest here does not exist)."""
    seed = options.pop("seed", 0)
    with pytest.raises(InputError, match=message):
        pb.fit_map(tmp_path / "manifest.csv", seed=seed, **options)


def test_a_missing_manifest_is_named_as_written(tmp_path):
    with pytest.raises(InputError, match="nowhere/manifest.csv"):
        prepare_map("nowhere/manifest.csv", MapRequest())


def test_fit_options_names_an_unknown_noise_model_before_the_engine():
    with pytest.raises(InputError, match="unknown noise model 'pink'"):
        pb.fit_options(engine="exact", noise="pink")


@pytest.mark.parametrize("f_unc", [0.0, -1.0, float("nan"), float("inf")])
def test_fit_options_refuse_a_contact_threshold_that_is_not_a_positive_force(f_unc):
    """The check lives in FitOptions, so every door that builds one (fit, map, campaign)
    has it."""
    from palpbayes.campaign.options import FitOptions

    with pytest.raises(InputError, match="f_unc .* must be a positive force in newtons"):
        FitOptions(f_unc=f_unc)
