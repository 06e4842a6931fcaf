"""Recordings as they come off the instruments: ``palpbayes fit`` on a ROS 2 bag and
on AFM files with no conversion step, ``palpbayes inspect``, and one-line errors."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from afmfiles import write_afm_h5
from scipy.optimize import least_squares

from palpbayes.cli import main
from palpbayes.contact import Tip
from palpbayes.io.afm import read_afm
from palpbayes.io.rosbag_write import write_bag, write_trace_bag
from palpbayes.io.trace_csv import read_trace, write_trace
from palpbayes.sim import simulate_trace

PARA = Tip("paraboloid", radius=0.0117)
FT = "/force_torque_sensor_broadcaster/wrench"
AFM = ["--tip", "paraboloid", "--radius", "10e-6", "--nu", "0.5", "--no-progress"]


@pytest.fixture(scope="module")
def sim():
    return simulate_trace(50e3, PARA, depth=3e-3, rate=250.0, rng=5)


def _summary(out: Path) -> pd.DataFrame:
    return pd.read_csv(out / "summary.csv")


def test_fit_a_bag_from_the_command_line_recovers_E(sim, tmp_path, capsys):
    bag = write_trace_bag(sim, tmp_path / "palpation", storage="sqlite3",
                          extra_topics={"/rosout": 3})
    rc = main(["fit", str(bag), "--out", str(tmp_path / "res"), "--tip", "paraboloid",
               "--radius", "0.0117", "--force-topic", FT, "--pose-topic", "/tcp_pose",
               "--engine", "exact", "--no-progress", "--workers", "1"])
    assert rc == 0, capsys.readouterr().err
    row = _summary(tmp_path / "res").set_index("method").loc["bayes"]
    assert row["trace_id"] == "palpation" and row["n_points"] > 0
    assert row["E_lo_pa"] < 50e3 < row["E_hi_pa"]
    # the same trace through the canonical CSV fits to the same numbers
    csv = write_trace(sim, tmp_path / "palpation.csv", float_format="%.17g")
    assert main(["fit", str(csv), "--out", str(tmp_path / "csv"), "--tip", "paraboloid",
                 "--radius", "0.0117", "--engine", "exact", "--no-progress",
                 "--workers", "1"]) == 0
    ref = _summary(tmp_path / "csv").set_index("method").loc["bayes"]
    assert row["E_pa"] == pytest.approx(ref["E_pa"], rel=1e-9)


def test_fit_the_real_jpk_curve_with_no_conversion(tmp_path, capsys, spot3):
    """afmformats' real spot3 JPK curve (shared data) fits from the CLI; E* and contact point
    agree with the unconstrained least-squares optimum of the same model (Hertz paraboloid +
    constant baseline, R = 10 µm, nu = 0.5), computed here with scipy, as for the shared AFM
    curves."""
    rc = main(["fit", str(spot3), "--out", str(tmp_path / "res"), "--method", "both",
               "--workers", "1", *AFM])
    assert rc == 0, capsys.readouterr().err
    bayes = _summary(tmp_path / "res").set_index("method").loc["bayes"]
    (trace,) = read_afm(spot3)
    z, f, k = trace.z, trace.force, 4 / 3 / (1 - 0.25) * np.sqrt(10e-6)

    def resid(p):
        return (k * p[0] * np.clip(p[1] - z, 0, None) ** 1.5 + p[2] - f) * 1e9

    ref = least_squares(resid, [1e4, bayes["z_surf_m"], 0.0], x_scale=[1e4, 1e-6, 1e-10]).x
    assert bayes["Estar_pa"] * 0.75 == pytest.approx(ref[0], rel=0.02)  # measured 1.3 %
    assert abs(bayes["z_surf_m"] - ref[1]) < 20e-9  # measured 1 nm
    traces = pd.read_csv(tmp_path / "res" / "traces.csv")
    assert traces["x_m"].iloc[0] == pytest.approx(-16.67e-6, rel=1e-3)


def test_fit_an_afm_file_matches_the_shared_reference(shared_data, tmp_path, capsys):
    """The shared force-save-example curve as an afmformats file (the JPK original is GPL and
    not shipped): E* and contact point as the reference of references.csv (206.34 Pa)."""
    afm = shared_data("afm-curves", files=["references.csv", "force-save-example.csv"])
    ref = pd.read_csv(afm / "references.csv").set_index("file").loc["force-save-example.csv"]
    path = write_afm_h5(tmp_path / "force-save-example.h5",
                        [read_trace(afm / "force-save-example.csv")])
    rc = main(["fit", str(path), "--out", str(tmp_path / "res"), "--workers", "1", *AFM])
    assert rc == 0, capsys.readouterr().err
    bayes = _summary(tmp_path / "res").set_index("method").loc["bayes"]
    assert bayes["Estar_pa"] * 0.75 == pytest.approx(ref["E_pa"], rel=0.02)  # measured 3e-5
    assert abs(bayes["z_surf_m"] - ref["contact_point_m"]) < 20e-9


def test_a_force_map_is_fitted_as_a_campaign_with_positions(tmp_path, capsys):
    tip = Tip("paraboloid", radius=10e-6)
    sims = [simulate_trace(E, tip, nu=0.5, z_surf=50e-6, depth=2e-6, approach=4e-6,
                           speed=10e-6, rate=500.0, noise_pp=6 * 20e-12, rng=i)
            for i, E in enumerate([800.0, 1200.0, 1600.0])]
    grid = [(0.0, 0.0), (5e-6, 0.0), (10e-6, 0.0)]
    path = write_afm_h5(tmp_path / "line.h5", sims, grid)
    rc = main(["fit", str(path), "--out", str(tmp_path / "res"), "--engine", "exact",
               "--workers", "1", *AFM])
    assert rc == 0, capsys.readouterr().err
    rows = _summary(tmp_path / "res").set_index("trace_id")
    assert list(rows.index) == ["line-0", "line-1", "line-2"]
    for (tid, row), E in zip(rows.iterrows(), [800.0, 1200.0, 1600.0], strict=True):
        assert row["E_lo_pa"] < E < row["E_hi_pa"], tid
    traces = pd.read_csv(tmp_path / "res" / "traces.csv").set_index("trace_id")
    assert traces.loc["line-1", "x_m"] == 5e-6 and traces.loc["line-2", "y_m"] == 0.0
    rc = main(["fit", str(path), "--out", str(tmp_path / "one"), "--engine", "exact",
               "--curve", "1", "--workers", "1", *AFM])
    assert rc == 0 and list(_summary(tmp_path / "one")["trace_id"]) == ["line-1"]


def test_inspect_lists_bag_topics_and_afm_curves(sim, tmp_path, capsys, spot3):
    bag = write_trace_bag(sim, tmp_path / "b", extra_topics={"/rosout": 2})
    assert main(["inspect", str(bag)]) == 0
    out = capsys.readouterr().out
    assert "ROS 2 bag, 3 topic(s)" in out
    assert f"{FT}  geometry_msgs/msg/WrenchStamped" in out and "250 Hz" in out
    assert "/tcp_pose" in out and "std_msgs/msg/String" in out
    assert f"fit reads force from {FT}" in out
    assert main(["inspect", str(spot3)]) == 0
    out = capsys.readouterr().out
    assert "AFM file, 1 curve(s) (force-distance)" in out
    assert "curve 0: approach 2000 points (1 s), retract 2000 (1 s)" in out
    assert "x = -16.667 µm" in out


def test_bag_errors_are_one_line_with_exit_status_2(sim, tmp_path, capsys, spot3):
    bag = write_trace_bag(sim, tmp_path / "b")
    args = ["--out", str(tmp_path / "res"), "--tip", "paraboloid", "--radius", "0.0117"]
    assert main(["fit", str(bag), "--pose-topic", "/tool_pose", *args]) == 2
    err = capsys.readouterr().err
    assert "pose topic '/tool_pose' is not in the bag; the bag has " in err
    assert "/tcp_pose (geometry_msgs/msg/PoseStamped)" in err and err.count("\n") == 1
    (tp, z), t = (sim.time, sim.z), sim.time
    write_bag(tmp_path / "late", (t, -sim.force), pose=(tp + 120.0, z), t0_ns=10**18)
    assert main(["fit", str(tmp_path / "late"), *args]) == 2
    err = capsys.readouterr().err
    assert "do not overlap" in err and "--time-offset -120" in err
    csv = write_trace(sim, tmp_path / "t.csv")
    assert main(["fit", str(csv), "--force-topic", FT, *args]) == 2
    assert "--force-topic applies to ROS 2 bags only" in capsys.readouterr().err
    assert main(["fit", str(spot3), "--z-unit", "mm", *args]) == 2
    assert "--*-column and --*-unit apply to text tables only" in capsys.readouterr().err
    assert not (tmp_path / "res").exists()


def test_a_missing_extra_is_a_one_line_error(monkeypatch, capsys, tmp_path, spot3):
    monkeypatch.setitem(sys.modules, "afmformats", None)
    assert main(["fit", str(spot3), "--out", str(tmp_path / "r"), *AFM]) == 2
    err = capsys.readouterr().err
    assert "reading .jpk-force files needs the optional extra afm (afmformats is not " \
        "installed): pip install -e " in err and "pip install 'palpbayes[afm]'" in err
    assert len(err.strip().splitlines()) == 1
