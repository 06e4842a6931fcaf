"""AFM files: the approach segment of every curve as a trace in SI units (z up,
pressing positive) with its segment codes, a force map as one trace per curve with its x, y; the
approach curve equals the canonical CSV the shared data were converted to; a missing extra is
named.  Segments of stress-relaxation and creep files: tests/unit/test_segments_io.py."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest
from afmfiles import write_afm_h5

from palpbayes.contact import Tip
from palpbayes.errors import DataFileError, MissingExtraError
from palpbayes.io import extras
from palpbayes.io.afm import describe_afm, read_afm
from palpbayes.io.recording import read_recording, recording_kind
from palpbayes.io.trace_csv import read_trace
from palpbayes.sim import simulate_trace

AFM_TIP = Tip("paraboloid", radius=10e-6)
GRID = [(0.0, 0.0), (20e-6, 0.0), (0.0, 20e-6), (20e-6, 20e-6)]


def afm_sim(E: float = 1000.0, rng: int = 1):
    """A simulated AFM approach: 10 µm paraboloid, 2 µm deep, 20 pN sd noise, 1 kHz."""
    return simulate_trace(E, AFM_TIP, nu=0.5, z_surf=50e-6, depth=2e-6, approach=4e-6,
                          speed=10e-6, rate=1000.0, noise_pp=6 * 20e-12, rng=rng)


def test_a_real_jpk_force_file_gives_its_approach_segment(spot3):
    import afmformats

    (trace,) = read_afm(spot3, tip=AFM_TIP)
    (raw,) = afmformats.load_data(spot3)
    appr = raw["segment"] == 0
    k = raw.metadata["spring constant"]
    assert trace.n_points == int(appr.sum()) == 2000
    np.testing.assert_array_equal(trace.force, raw["force"][appr])
    np.testing.assert_allclose(trace.z, raw["height (measured)"][appr] + raw["force"][appr] / k,
                               rtol=0, atol=1e-15)
    assert trace.z[0] > trace.z[-1] and trace.force[-1] > trace.force[0]  # z up, pressing +
    assert trace.time[0] == 0.0 and trace.sample_rate == pytest.approx(2000.0, rel=1e-6)
    assert trace.trace_id == "fmt-jpk-fd_spot3-0192" and trace.tip == AFM_TIP
    assert trace.metadata["x_m"] == pytest.approx(-16.67e-6, rel=1e-3)
    assert trace.metadata["spring_constant_n_per_m"] == pytest.approx(k)
    assert recording_kind(spot3) == "afm"
    assert trace.segment_names == ("approach",) and trace.metadata["afm_modality"] == \
        "force-distance" and trace.metadata["afm_segments"] == "0 approach, 1 retract"
    (both,) = read_afm(spot3, tip=AFM_TIP, segments="approach,retract")
    assert both.n_points == 4000 and both.segment_names == ("approach", "retract")
    np.testing.assert_array_equal(both.segments("approach").z, trace.z)


def test_a_one_segment_curve_with_hold_and_retract_is_read_whole(tmp_path):
    """An afmformats curve whose only segment (0) holds a whole cycle reads as before."""
    s = simulate_trace(1000.0, AFM_TIP, nu=0.5, z_surf=50e-6, depth=2e-6, approach=4e-6,
                       speed=10e-6, rate=1000.0, noise_pp=6 * 20e-12, rng=1, hold=0.1,
                       retract=True)
    path = write_afm_h5(tmp_path / "cycle.h5", [s])
    (got,) = read_afm(path)
    assert got.n_points == s.n_points and got.segment_names == ("approach",)
    np.testing.assert_array_equal(got.force, s.force)
    assert describe_afm(path)[0].segment_names == {0: "approach"}


def test_a_force_map_becomes_one_trace_per_curve_with_its_position(tmp_path):
    sims = [afm_sim(rng=i) for i in range(4)]
    path = write_afm_h5(tmp_path / "grid.h5", sims, GRID)
    traces = read_afm(path, tip=AFM_TIP, material="gel")
    assert [t.trace_id for t in traces] == ["grid-0", "grid-1", "grid-2", "grid-3"]
    for t, s, (x, y) in zip(traces, sims, GRID, strict=True):
        np.testing.assert_allclose(t.z, s.z, rtol=0, atol=1e-18)
        np.testing.assert_array_equal(t.force, s.force)
        np.testing.assert_allclose(t.time, s.time - s.time[0], atol=1e-12)
        assert (t.metadata["x_m"], t.metadata["y_m"]) == (x, y) and t.material == "gel"
    (one,) = read_afm(path, curves=[2])
    assert one.trace_id == "grid-2" and one.metadata["curve_index"] == 2
    with pytest.raises(DataFileError, match=r"has 4 curve\(s\), no curve 7"):
        read_afm(path, curves=[7])
    info = describe_afm(path)
    assert len(info) == 4 and info[1].segments == {0: sims[1].n_points}
    assert info[1].segment_names == {0: "approach"}
    assert all(t.segment_names == ("approach",) for t in traces)
    assert info[3].x_m == 20e-6 and "height (measured)" in info[0].columns
    assert len(read_recording(path, tip=AFM_TIP)) == 4


def test_the_approach_curve_equals_the_canonical_csv(shared_data, tmp_path):
    """The shared CSV (afmformats' conversion of nanite's force-save-example.jpk-force) written
    as an afmformats file and read back: equal to the CSV reader's trace."""
    csv = shared_data("afm-curves", files=["force-save-example.csv"]) / "force-save-example.csv"
    ref = read_trace(csv)
    path = write_afm_h5(tmp_path / "force-save-example.h5", [ref])
    (got,) = read_afm(path)
    assert got.trace_id == "force-save-example" and got.n_points == ref.n_points == 6000
    np.testing.assert_allclose(got.z, ref.z, rtol=0, atol=1e-18)
    np.testing.assert_array_equal(got.force, ref.force)
    np.testing.assert_allclose(got.time, ref.time, atol=1e-12)


ORIGINALS = os.environ.get("PALPBAYES_AFM_ORIGINALS")


@pytest.mark.skipif(not ORIGINALS, reason="the GPL-3.0 originals (nanite's "
                    "force-save-example.jpk-force, fmt-jpk-fd_map1d_2016-11-07.jpk-force-map) "
                    "are not shipped; set PALPBAYES_AFM_ORIGINALS to a folder holding them")
@pytest.mark.parametrize("original, curve, csv", [
    ("force-save-example.jpk-force", 0, "force-save-example.csv"),
    ("fmt-jpk-fd_map1d_2016-11-07.jpk-force-map", 7, "map1d-curve7.csv")])
def test_the_original_jpk_files_equal_their_shared_csv(shared_data, original, curve, csv):
    ref = read_trace(shared_data("afm-curves", files=[csv]) / csv)
    (got,) = read_afm(Path(ORIGINALS) / original, curves=[curve])
    assert got.n_points == ref.n_points
    np.testing.assert_allclose(got.z, ref.z, rtol=1e-9, atol=0)  # the CSV has 10 digits
    np.testing.assert_allclose(got.force, ref.force, rtol=1e-9, atol=1e-21)


def test_signs_can_be_flipped_and_bad_files_are_data_file_errors(tmp_path):
    s = afm_sim()
    path = write_afm_h5(tmp_path / "c.h5", [s])
    (flipped,) = read_afm(path, force_sign=-1, check=False)
    np.testing.assert_array_equal(flipped.force, -s.force)
    with pytest.raises(DataFileError, match="flip the force sign"):
        read_afm(path, force_sign=-1)
    junk = tmp_path / "junk.jpk-force"
    junk.write_bytes(b"not a zip archive" * 10)
    with pytest.raises(DataFileError, match=r"junk.jpk-force: afmformats cannot read it"):
        read_afm(junk)
    with pytest.raises(DataFileError, match="file not found"):
        read_afm(tmp_path / "none.jpk-force")


def test_a_curve_without_spring_constant_cannot_give_the_tip_position(tmp_path):
    s = afm_sim()
    path = write_afm_h5(tmp_path / "c.h5", [s])
    import h5py

    with h5py.File(path, "a") as h5:
        del h5["0"].attrs["spring constant"]
    with pytest.raises(DataFileError, match="cannot compute the tip position without the "
                       "spring constant"):
        read_afm(path)


def test_the_missing_extra_is_named(monkeypatch, spot3):
    monkeypatch.setitem(sys.modules, "afmformats", None)
    with pytest.raises(MissingExtraError) as err:
        read_afm(spot3)
    assert str(err.value).startswith("reading .jpk-force files needs the optional extra afm "
                                     "(afmformats is not installed): pip install ")
    with pytest.raises(MissingExtraError, match=r"reading .jpk-force-map files needs"):
        read_recording("map.jpk-force-map")


def test_the_missing_extras_command_is_the_readmes_and_names_the_index_one(monkeypatch):
    """Issue 58, item 7: the error said ``pip install 'palpbayes[afm]'``, the README (an
    install from the clone) ``pip install -e '.[afm]' -c requirements/constraints.txt``.  From
    a clone the error now gives the README's command with the clone's absolute paths (it works
    from any folder) and, in brackets, the index one; without a clone, the index one first.
    One line either way."""
    root = Path(__file__).resolve().parents[2]
    monkeypatch.setitem(sys.modules, "afmformats", None)
    with pytest.raises(MissingExtraError) as err:
        read_recording("cells.jpk-force")
    msg = str(err.value)
    assert "\n" not in msg
    assert (f"pip install -e '{root}[afm]' -c {root}/requirements/constraints.txt (a palpbayes "
            "installed from a package index: pip install 'palpbayes[afm]')") in msg
    assert "pip install -e '.[afm]' -c requirements/constraints.txt" in (
        root / "README.md").read_text()  # the same command, run in the clone's root
    monkeypatch.setattr(extras, "source_root", lambda: None)
    with pytest.raises(MissingExtraError) as err:
        read_recording("cells.jpk-force")
    assert str(err.value).endswith(
        ": pip install 'palpbayes[afm]' (a clone of the repository: pip install -e '.[afm]' "
        "-c requirements/constraints.txt in its root)")
