"""A force in another unit than the one given (issue 46, item 1): the data's noise against the
noise the user declared for the sensor names --force-unit, as a warning or, with --strict, an
error; without a declared noise (issue 58, item 1) the tip's size is the reference, in `fit`,
`fit --rheology`, `map`, `replay` and `follow`."""

from __future__ import annotations

import io
from dataclasses import replace

import pandas as pd
import pytest

from palpbayes.cli import main
from palpbayes.contact import Tip
from palpbayes.flagcodes import CODES
from palpbayes.io.trace_csv import write_trace
from palpbayes.sensor_noise import NOISE_SCALE_FACTOR, noise_scale_mismatch
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


# --- without --noise-pp (issue 58, item 1): the tip's size is the reference -----------------
# The README's worked example: a robot log in newtons (10 mm sphere, 3 mm deep, 60 kPa, the
# paper's 48 mN p-p sensor), its force declared as mN.  Before, `fit` read "E 60 Pa",
# converged, model_ok True, and said nothing.
README_FLAG = "force scale: the force reads 1,000 times too small"


@pytest.fixture(scope="module")
def robot_log(tmp_path_factory):
    d = tmp_path_factory.mktemp("robot")
    tr = simulate_trace(60e3, Tip("sphere", radius=0.01), nu=0.45, thickness=0.02, depth=0.003,
                        force_offset=-0.21, rng=3)
    pd.DataFrame({"timestamp": tr.time, "tcp_z_mm": tr.z * 1e3, "fz": -tr.force}).to_csv(
        d / "press.csv", index=False)
    return d / "press.csv"


ROBOT = ["--time-column", "timestamp", "--z-column", "tcp_z_mm", "--force-column", "fz",
         "--z-unit", "mm", "--force-sign", "-1", "--tip", "sphere", "--radius", "0.01",
         "--nu", "0.45"]


@pytest.mark.parametrize("unit, flagged", [("mN", True), ("N", False)])
def test_fit_without_noise_pp_names_the_force_unit(tmp_path, capsys, robot_log, unit, flagged):
    out = tmp_path / "fit"
    rc = main(["fit", str(robot_log), "--out", str(out), *ROBOT, "--thickness", "0.02",
               "--force-unit", unit, "--engine", "exact"])
    text = capsys.readouterr().out
    assert rc == 0
    row = pd.read_csv(out / "summary.csv").iloc[0]
    assert ("force_scale" in str(row["flag_codes"]).split(";")) is flagged
    assert (README_FLAG in text and "check --force-unit" in text) is flagged
    if flagged:
        assert row["flag_level"] == "warning" and row["E_pa"] < 100  # E 60 Pa, 1,000 too small
        assert "N read as mN" in row["notes"]


def test_fit_without_noise_pp_is_an_error_with_strict(tmp_path, capsys, robot_log):
    out = tmp_path / "fit"
    rc = main(["fit", str(robot_log), "--out", str(out), *ROBOT, "--force-unit", "mN",
               "--strict"])
    err = capsys.readouterr().err
    assert rc == 2 and "press.csv" in err and README_FLAG in err and "--strict" in err
    assert not (out / "summary.csv").exists()


@pytest.mark.parametrize("command", ["replay", "follow"])
def test_replay_and_follow_name_the_force_unit(tmp_path, capsys, monkeypatch, robot_log,
                                                command):
    args = [command, *ROBOT, "--force-unit", "mN", "--target", "5%"]
    if command == "replay":
        args.insert(1, str(robot_log))
    else:
        monkeypatch.setattr("sys.stdin", io.StringIO(robot_log.read_text()))
    main(args)
    cap = capsys.readouterr()
    assert f"warning: {README_FLAG}" in cap.out + cap.err


def test_follow_with_the_right_unit_says_nothing_of_the_force(capsys, monkeypatch, robot_log):
    monkeypatch.setattr("sys.stdin", io.StringIO(robot_log.read_text()))
    main(["follow", *ROBOT, "--target", "5%"])
    cap = capsys.readouterr()
    assert "force scale" not in cap.out + cap.err


def test_map_names_the_force_unit_first(tmp_path, capsys):
    folder = tmp_path / "block"
    assert main(["simulate", str(folder), "--map", "--grid", "4x4", "--step", "3e-3",
                 "--seed", "1"]) == 0
    out = tmp_path / "map"
    capsys.readouterr()
    rc = main(["map", str(folder / "manifest.csv"), "--out", str(out), "--force-unit", "mN",
               "--no-lump", "--scheduler", "synchronous", "--no-progress"])
    text = capsys.readouterr().out
    assert rc == 0
    points = pd.read_csv(out / "points.csv")
    assert points["flag_codes"].fillna("").str.contains("force_scale").all()
    first = next(ln for ln in text.splitlines() if "warning:" in ln)
    assert README_FLAG in first and "16 of 16 fitted points" in first


def test_rheology_names_the_force_unit():
    from palpbayes.contact.viscoelastic import PowerLawKernel
    from palpbayes.flagcodes import RHEOLOGY_CODES, listed_flag_columns
    from palpbayes.rheology.fit import fit_rheology
    from palpbayes.sim.viscoelastic import simulate_viscoelastic

    tip = Tip("paraboloid", radius=0.01)
    tr = simulate_viscoelastic(PowerLawKernel(42e3, 0.2), tip, depth=0.002, speed=50 / 60e3,
                               hold_time=2.0, rate=200, rng=1)
    right = fit_rheology(tr, nu=0.45, rng=1)
    wrong = fit_rheology(replace(tr, force=tr.force * 1e-3), nu=0.45, rng=1)
    assert not any("force scale" in f for f in right.flags)
    assert wrong.flags[0].startswith(README_FLAG)
    assert "force_scale" in listed_flag_columns(wrong.flags, RHEOLOGY_CODES)["flag_codes"]
