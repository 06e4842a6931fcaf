"""A force in another unit than the one given (issue 46, item 1): the data's noise against the
noise the user declared for the sensor names --force-unit, as a warning or, with --strict, an
error."""

from __future__ import annotations

import pandas as pd
import pytest

from palpbayes.cli import main
from palpbayes.contact import Tip
from palpbayes.flagcodes import CODES
from palpbayes.io.trace_csv import write_trace
from palpbayes.noise import NOISE_SCALE_FACTOR, noise_scale_mismatch
from palpbayes.sim import simulate_trace

# a 10 mm sphere in a 136 kPa block, forces up to a few N, the paper's 48 mN p-p sensor
TIP = ["--tip", "sphere", "--radius", "0.01", "--method", "lsq"]


@pytest.fixture(scope="module")
def press(tmp_path_factory):
    d = tmp_path_factory.mktemp("press")
    tr = simulate_trace(136e3, Tip("sphere", radius=0.01), thickness=0.02, rng=3, base=None)
    return write_trace(tr, d / "press.csv")


def _fit(tmp_path, capsys, press, *extra):
    out = tmp_path / "out"
    rc = main(["fit", str(press), "--out", str(out), *TIP, *extra])
    cap = capsys.readouterr()
    return rc, cap.err, out, cap.out


def test_mismatch_ratio():
    assert noise_scale_mismatch(48e-6, 48e-3) == pytest.approx(1e-3)
    assert noise_scale_mismatch(48.0, 48e-3) == pytest.approx(1e3)
    for ratio in (1 / NOISE_SCALE_FACTOR, 0.2, 1.0, 5.0, NOISE_SCALE_FACTOR):
        assert noise_scale_mismatch(48e-3 * ratio, 48e-3) is None
    assert noise_scale_mismatch(48e-3, None) is None
    assert noise_scale_mismatch(0.0, 48e-3) is None
    assert ("force scale", "force_scale") in CODES


def test_force_in_newtons_read_as_millinewtons_is_a_warning(tmp_path, capsys, press):
    # the user's mistake: the file is in N, --force-unit mN; sensor noise declared 48 mN p-p,
    # contact threshold 1 mN (the forces, 1,000 times too small, still cross it)
    rc, err, out, text = _fit(tmp_path, capsys, press, "--force-unit", "mN", "--noise-pp", "0.048",
                        "--f-unc", "0.001")
    assert rc == 0
    row = pd.read_csv(out / "summary.csv").iloc[0]
    assert "force_scale" in row["flag_codes"].split(";")
    assert row["flag_level"] == "warning"
    assert "--force-unit" in row["notes"] and " times below the declared --noise-pp" in row["notes"]
    assert "force scale" in text and "--force-unit" in text


def test_force_in_newtons_read_as_millinewtons_is_an_error_with_strict(tmp_path, capsys, press):
    rc, err, out, text = _fit(tmp_path, capsys, press, "--force-unit", "mN", "--noise-pp", "0.048",
                        "--f-unc", "0.001", "--strict")
    assert rc != 0
    assert "press.csv" in err and "--force-unit" in err and "--strict" in err
    assert not (out / "summary.csv").exists()


def test_right_unit_has_no_force_scale_flag(tmp_path, capsys, press):
    rc, err, out, text = _fit(tmp_path, capsys, press, "--noise-pp", "0.048")
    assert rc == 0
    row = pd.read_csv(out / "summary.csv").iloc[0]
    assert "force_scale" not in str(row["flag_codes"]).split(";")
    assert "force scale" not in err + text


def test_no_contact_under_the_declared_noise_names_the_force_unit(tmp_path, capsys, press):
    # the same mistake with the threshold at the declared noise: the forces never cross it
    rc, err, _, _ = _fit(tmp_path, capsys, press, "--force-unit", "mN", "--noise-pp", "0.048")
    assert rc != 0
    assert "no contact" in err and "--force-unit" in err
