"""Viscoelastic campaigns (palpbayes.sim.visco_campaign, ``palpbayes simulate --rheology``):
byte-identical for a seed, other traces unchanged when a speed is added, traces that carry
their segments and agree with truth.csv, the SLS's truth columns, one-line errors."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from palpbayes.cli import main
from palpbayes.io.manifest import load_trace, read_manifest
from palpbayes.rheology.compression import compression_moduli
from palpbayes.sim import POWER_LAW_FOAMS, SLS_FOAMS, VISCO_TIPS, simulate_visco_campaign
from palpbayes.trace import SEGMENTS

#: A small, fast campaign: one foam, one tip, 200 Hz, half a second of hold.
SMALL = {"materials": {"Medium": POWER_LAW_FOAMS["Medium"]},
         "tips": {"paraboloid": VISCO_TIPS["paraboloid"]}, "rate": 200.0, "hold": 0.5,
         "depth": 1e-3}
V = (100 / 6e4, 500 / 6e4)


def _files(folder) -> dict:
    return {p.relative_to(folder): p.read_bytes() for p in sorted(folder.rglob("*.csv"))}


def test_same_seed_same_bytes_and_a_new_speed_leaves_the_others(tmp_path):
    a = simulate_visco_campaign(tmp_path / "a", seed=5, speeds=V, **SMALL)
    b = simulate_visco_campaign(tmp_path / "b", seed=5, speeds=V, **SMALL)
    assert _files(a) == _files(b)
    c = simulate_visco_campaign(tmp_path / "c", seed=6, speeds=V, **SMALL)
    name = Path("traces/Medium_paraboloid_v100_r01.csv")
    assert _files(c)[name] != _files(a)[name]
    d = simulate_visco_campaign(tmp_path / "d", seed=5, speeds=(50 / 6e4, *V), **SMALL)
    fa, fd = _files(a), _files(d)
    assert all(fd[k] == fa[k] for k in fa if k.parts[0] == "traces")
    assert len(fd) == len(fa) + 1


def test_traces_carry_their_segments_and_the_truth(tmp_path):
    """Every trace read back through its manifest row has approach, hold and retract; its
    deepest point is the true surface minus the depth, its approach runs at the true speed,
    its hold lasts the true hold; the pre-contact force scatters about the true offset with
    the true sigma (z-scores, 48 mN p-p: sigma 8 mN); truth.csv's compression modulus is the
    ground truth's rule on the true kernel."""
    out = simulate_visco_campaign(tmp_path / "c", seed=11, speeds=V, repetitions=2, **SMALL)
    manifest = read_manifest(out / "manifest.csv")
    truth = pd.read_csv(out / "truth.csv").set_index("trace_id")
    assert list(manifest["trace_id"]) == list(truth.index) == [
        "Medium_paraboloid_v100_r01", "Medium_paraboloid_v100_r02",
        "Medium_paraboloid_v500_r01", "Medium_paraboloid_v500_r02"]
    assert (manifest["nu"] == 0.3).all() and (manifest["thickness_m"] == 0.05).all()
    for _, row in manifest.iterrows():
        t = truth.loc[row["trace_id"]]
        tr = load_trace(row)
        assert [SEGMENTS[c] for c in np.unique(tr.segment)] == ["approach", "hold", "retract"]
        assert tr.metadata["nu"] == 0.3 and tr.thickness == 0.05
        assert tr.z.min() == pytest.approx(t["z_surf_true_m"] - t["depth_m"], abs=1e-9)
        down = tr.segment == 0
        slope = np.polyfit(tr.time[down], tr.z[down], 1)[0]
        assert -slope == pytest.approx(t["speed_m_s"], rel=1e-6)
        assert np.count_nonzero(tr.segment == 1) / 200.0 == pytest.approx(t["hold_s"])
        free = tr.z > t["z_surf_true_m"]  # out of contact: offset + noise only
        f = tr.force[free]
        z_mean = (f.mean() - t["force_offset_true_n"]) / (t["sigma_true_n"] / np.sqrt(f.size))
        assert abs(z_mean) < 4.0, z_mean
        assert f.std() == pytest.approx(t["sigma_true_n"], rel=0.25)
        assert (t["E0_star_pa"], t["alpha"], t["rheology"]) == (80e3, 0.15, "power-law")
    k = POWER_LAW_FOAMS["Medium"].kernel
    expect = compression_moduli([k], 0.3, 50 / 6e4, 0.05)[0]
    assert truth["E_compression_true_pa"].to_numpy() == pytest.approx(expect)
    mats = pd.read_csv(out / "truth_materials.csv")
    assert list(mats["material"]) == ["Medium"] and mats["E0_star_pa"].iloc[0] == 80e3


def test_sls_campaign_truth(tmp_path, capsys):
    out = tmp_path / "sls"
    assert main(["simulate", str(out), "--rheology", "sls", "--materials", "Soft,Firm",
                 "--tips", "flat", "--speeds", "500", "--rate", "200", "--hold", "0.5",
                 "--depth", "1e-3", "--seed", "3"]) == 0
    said = capsys.readouterr().out
    assert "2 traces (2 materials x 1 tip x 1 speed x 1 repetition; 500 mm/min)" in said
    assert "Soft: E_inf* 25 kPa, E1* 20 kPa, tau 0.5 s" in said
    truth = pd.read_csv(out / "truth.csv")
    assert list(truth["trace_id"]) == ["Soft_flat_v500_r01", "Firm_flat_v500_r01"]
    assert "E0_star_pa" not in truth and (truth["rheology"] == "sls").all()
    firm = SLS_FOAMS["Firm"].kernel
    assert tuple(truth.iloc[1][["E_inf_star_pa", "E1_star_pa", "tau_s"]]) == (
        firm.E_inf, firm.E[0], firm.tau[0])
    assert (read_manifest(out / "manifest.csv")["tip"] == "flat").all()


@pytest.mark.parametrize("argv, match", [
    (["--rheology", "power-law", "--speeds", "5,5"], "repeat a speed"),
    (["--rheology", "power-law", "--speeds", "5,-1"], "must be positive numbers in mm/min"),
    (["--rheology", "power-law", "--speeds", "fast"], "not numbers in mm/min"),
    (["--rheology", "power-law", "--materials", "Jelly"],
     "unknown material 'Jelly'; choose from Soft, Medium, Firm"),
    (["--rheology", "sls", "--tips", "sphere"], "unknown tip 'sphere'; choose from flat, "
                                                 "paraboloid"),
    (["--rheology", "power-law", "--hold", "-1"], "hold time \\[s\\] must be non-negative"),
    (["--rheology", "power-law", "--depth", "0"], "indentation depth \\[m\\] must be positive"),
    (["--rheology", "power-law", "--repetitions", "0"], "repetitions 0 must be an integer >= 1"),
    (["--rheology", "power-law", "--gt-specimens", "2"],
     "--gt-specimens only apply to the elastic campaign"),
    (["--rheology", "sls", "--map"], "--map writes a stiffness map, --rheology a viscoelastic"),
    (["--rheology", "sls", "--grid", "3x3"], "--grid only apply with --map"),
    (["--speeds", "5,50"], "--speeds only apply with --rheology"),
    (["--rheology", "maxwell"], "invalid choice: 'maxwell'"),
])
def test_bad_options_are_one_line(tmp_path, capsys, argv, match):
    out = tmp_path / "bad"
    try:
        code = main(["simulate", str(out), *argv])
    except SystemExit as exc:  # argparse's own usage errors
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and re.search(match, err), err
    assert not out.exists()
