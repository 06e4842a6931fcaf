"""Reading compression-test exports: the real Instron 5900 files and simulator-style files."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from palpbayes.errors import DataFileError
from palpbayes.io.instron import (
    CompressionTest,
    looks_like_compression_test,
    material_from_label,
    read_compression_test,
)

AREA_50MM = math.pi * 0.05**2 / 4

SIM_HEADER = ["White_S1", "Compression test;", "Block Width: 40mm;", "Block Length: 60mm;",
              "Block Height: 25mm;", "Speed (mm/min): 50;",
              "Machine: INSTRON 4502 (simulated);", "Load cell: 1kN;"]


def need_phantoms(shared_data) -> Path:
    """The real phantoms in ../shared/data (skip when absent, fail on CI; tests/conftest.py)."""
    return shared_data("phantom-compression", files=["EF10_50T/EF10_50T_A1.csv"])


def write(path: Path, lines: list[str]) -> Path:
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def sim_rows(n: int = 40) -> list[str]:
    """Extension and load negative (Instron convention), mm and kN."""
    t = np.arange(n) / 25.0
    x_mm = t * 50 / 60  # 50 mm/min
    f_kn = 14.4 * x_mm / 1e3  # 14.4 N/mm
    return [f"{a:.6f},{-b:.6f},{-c:.8f}" for a, b, c in zip(t, x_mm, f_kn, strict=True)]


def sim_file(tmp_path: Path, name: str = "White_S1.csv", header=None, columns=None,
             rows=None) -> Path:
    lines = list(SIM_HEADER if header is None else header)
    lines.append(columns or "Time (s),Extension (mm),Load (kN)")
    lines += sim_rows() if rows is None else rows
    return write(tmp_path / name, lines)


# ----------------------------------------------------------------------------- real files


def test_real_instron_export_in_si(shared_data):
    path = need_phantoms(shared_data) / "EF10_50T" / "EF10_50T_A1.csv"
    t = read_compression_test(path)
    assert isinstance(t, CompressionTest)
    assert t.specimen == "EF10_50T_A1" and t.material == "EF10_50T"
    assert t.area_m2 == pytest.approx(AREA_50MM, rel=1e-12)
    assert t.height_m == pytest.approx(0.03, rel=1e-12)
    assert t.header["Sample name"] == "EF10_50T_A_sample_1"
    assert t.header["Machine"] == "INSTRON 5900" and t.header["Cylinder Diameter"] == "50mm"
    assert t.n_points == 1202 and t.source == str(path)
    # values straight from the file, converted mm -> m, positive in compression
    raw = pd.read_csv(path, skiprows=7)
    np.testing.assert_allclose(t.compression_m, raw["Compression (mm)"] * 1e-3, rtol=1e-12)
    np.testing.assert_allclose(t.load_n, raw["Load (N)"], rtol=1e-12)
    assert t.compression_m[-1] == pytest.approx(0.02000006)
    assert t.load_n[-1] == pytest.approx(152.6765)
    # the file's own (negative) engineering columns agree with ours up to the sign
    np.testing.assert_allclose(t.strain, -raw["Engineering Strain [-]"], atol=2e-6)
    np.testing.assert_allclose(t.stress_pa, -raw["Engineering Stress (kPa)"] * 1e3, rtol=1e-4,
                               atol=1e-2)


def test_every_real_export_reads(shared_data):
    root = need_phantoms(shared_data)
    files = sorted(root.glob("*/*.csv"))
    assert len(files) == 30
    for f in files:
        t = read_compression_test(f)
        assert t.material == f.parent.name and t.specimen == f.stem
        assert t.n_points >= 1200
        assert t.compression_m.max() == pytest.approx(0.02, abs=1e-6)
        assert t.load_n.max() > 100 and t.load_n[np.argmax(t.compression_m)] > 0


def test_non_test_files_are_recognised(shared_data):
    root = need_phantoms(shared_data)
    assert looks_like_compression_test(root / "EF30_0T" / "EF30_0T_B2.csv")
    assert not looks_like_compression_test(root / "published_moduli.csv")
    assert not looks_like_compression_test(root / "README.md")
    with pytest.raises(DataFileError, match="published_moduli.csv.*not a compression-test"):
        read_compression_test(root / "published_moduli.csv")


# ----------------------------------------------------------------------------- simulator style


def test_simulator_style_negative_kn_block(tmp_path):
    t = read_compression_test(sim_file(tmp_path))
    assert t.specimen == "White_S1" and t.material == "White"
    assert t.area_m2 == pytest.approx(0.04 * 0.06, rel=1e-12)
    assert t.height_m == pytest.approx(0.025, rel=1e-12)
    assert t.header["Machine"] == "INSTRON 4502 (simulated)"
    assert t.header["Speed (mm/min)"] == "50"
    assert np.all(np.diff(t.compression_m) > 0) and t.compression_m[0] == 0
    k = np.polyfit(t.compression_m, t.load_n, 1)[0]
    assert k == pytest.approx(14.4e3, rel=1e-5)  # N/m: kN -> N and mm -> m, signs flipped
    assert t.time_s[-1] == pytest.approx(39 / 25)


def test_reads_the_simulators_own_export(tmp_path):
    sim = pytest.importorskip("palpbayes.sim")
    df = sim.simulate_compression_test(136e3, height=0.02, rng=3)
    path = sim.write_compression_export(df, tmp_path / "Pink_S2.csv", sample_name="Pink_S2")
    t = read_compression_test(path)
    assert t.material == "Pink" and t.specimen == "Pink_S2"
    assert t.area_m2 == pytest.approx(df.attrs["area_m2"]) and t.height_m == pytest.approx(0.02)
    np.testing.assert_allclose(t.compression_m, df["compression_m"], atol=1e-9)
    np.testing.assert_allclose(t.load_n, df["force_n"], atol=1e-5)


def test_units_synonyms_and_position(tmp_path):
    header = ["Sample X", "Diameter (mm): 20;", "Thickness: 1cm;"]
    # Position is absolute and decreases while compressing; force in mN; time in ms; µm
    rows = [f"{100 * k},{5000 - 10 * k},{-3 * k}" for k in range(20)]
    p = write(tmp_path / "odd.csv", header + ["Time (ms),Position (µm),Force (mN)"] + rows)
    t = read_compression_test(p)
    assert t.area_m2 == pytest.approx(math.pi * 0.02**2 / 4)
    assert t.height_m == pytest.approx(0.01)
    np.testing.assert_allclose(t.time_s, 0.1 * np.arange(20))
    np.testing.assert_allclose(t.compression_m, 10e-6 * np.arange(20), atol=1e-15)
    np.testing.assert_allclose(t.load_n, 3e-3 * np.arange(20))
    rows = [f"{k / 600},{k * 5},{k * 0.5}" for k in range(10)]
    p2 = write(tmp_path / "plain.csv", ["Area: 400mm^2;", "Height: 10mm;",
                                        "Time [min],Displacement [um],Load [N]"] + rows)
    t2 = read_compression_test(p2)
    assert t2.area_m2 == pytest.approx(4e-4)
    np.testing.assert_allclose(t2.time_s, 0.1 * np.arange(10))
    np.testing.assert_allclose(t2.compression_m, 5e-6 * np.arange(10))



@pytest.mark.parametrize("load_col, factor", [("load_nn", 1e-9), ("load_pn", 1e-12),
                                              ("load_un", 1e-6), ("load_µn", 1e-6),
                                              ("Load (nN)", 1e-9), ("Load (pN)", 1e-12),
                                              ("Load (µN)", 1e-6)])
def test_small_force_units(tmp_path, load_col, factor):
    rows = [f"{k / 10},{k * 0.5},{k * 2}" for k in range(10)]
    p = write(tmp_path / "small.csv", ["Area: 1mm^2;", "Height: 1mm;",
                                       f"time_s,displacement_nm,{load_col}"] + rows)
    t = read_compression_test(p)
    np.testing.assert_allclose(t.compression_m, 0.5e-9 * np.arange(10))
    np.testing.assert_allclose(t.load_n, 2 * factor * np.arange(10))

def test_keyword_geometry_takes_precedence(tmp_path):
    p = sim_file(tmp_path)
    t = read_compression_test(p, area_m2=1e-3, height_m=0.04, material="Foam", specimen="s1")
    assert (t.area_m2, t.height_m, t.material, t.specimen) == (1e-3, 0.04, "Foam", "s1")


def test_signs_can_be_forced(tmp_path):
    # +1 keeps the file's (negative) values; -1 flips them
    t = read_compression_test(sim_file(tmp_path), compression_sign=1, load_sign=1)
    assert t.compression_m[-1] < 0 and t.load_n[-1] < 0
    t = read_compression_test(sim_file(tmp_path), compression_sign=-1, load_sign=-1)
    assert t.compression_m[-1] > 0 and t.load_n[-1] > 0


def test_trailing_footer_is_dropped(tmp_path):
    rows = sim_rows(30) + ["", "Test ended;", "Max load,0.0123", ",,", ""]
    t = read_compression_test(sim_file(tmp_path, rows=rows))
    assert t.n_points == 30


@pytest.mark.parametrize("label, material", [
    ("EF10_50T_A1", "EF10_50T"), ("EF50_12_5T_B5", "EF50_12_5T"), ("White_S1", "White"),
    ("Grey_S12", "Grey"), ("EF10_50T_A_sample_1", "EF10_50T"), ("Foam", "Foam"),
    ("S1", "S1"),
])
def test_material_from_label(label, material):
    assert material_from_label(label) == material


# ----------------------------------------------------------------------------- bad files


def test_missing_column(tmp_path):
    p = sim_file(tmp_path, "noload.csv", columns="Time (s),Extension (mm),Strain (-)")
    with pytest.raises(DataFileError, match=r"noload\.csv: no load column \(Load / Force\)"):
        read_compression_test(p)
    assert not looks_like_compression_test(p)


def test_non_numeric_cell_in_the_middle(tmp_path):
    rows = sim_rows(30)
    rows[11] = rows[11].rsplit(",", 1)[0] + ",oops"
    p = sim_file(tmp_path, "bad.csv", rows=rows)
    line = len(SIM_HEADER) + 1 + 12  # header, column row, 12th data row
    with pytest.raises(DataFileError, match=rf"bad\.csv: line {line}, column 'Load \(kN\)': "
                                            r"the non-numeric value 'oops'"):
        read_compression_test(p)
    rows = sim_rows(30)
    rows[5] = ""
    with pytest.raises(DataFileError, match=r"line 15, column 'Time \(s\)': an empty cell"):
        read_compression_test(sim_file(tmp_path, "blank.csv", rows=rows))


@pytest.mark.parametrize("content, problem", [
    ("", "the file is empty"),
    ("\n  \n", "the file is empty"),
    ("\n".join(SIM_HEADER + ["Time (s),Extension (mm),Load (kN)"]), "only a header"),
    ("\n".join(SIM_HEADER), "only a header"),
    ("\n".join(sim_rows(5)), "no column-name row"),
])
def test_empty_or_header_only(tmp_path, content, problem):
    p = tmp_path / "T_S1.csv"
    p.write_text(content)
    with pytest.raises(DataFileError, match=rf"T_S1\.csv: .*{problem}"):
        read_compression_test(p)


def test_missing_geometry_names_the_header_line_or_option(tmp_path):
    no_area = [h for h in SIM_HEADER if not h.startswith(("Block Width", "Block Length"))]
    p = sim_file(tmp_path, "noarea.csv", header=no_area)
    with pytest.raises(DataFileError, match=r"noarea\.csv: .*cross-section.*Cylinder Diameter.*"
                                            r"area_m2.*--area-m2"):
        read_compression_test(p)
    assert read_compression_test(p, area_m2=2e-3).area_m2 == 2e-3
    no_len = [h for h in SIM_HEADER if not h.startswith("Block Length")]
    with pytest.raises(DataFileError, match="'Block Length' line"):
        read_compression_test(sim_file(tmp_path, "nolen.csv", header=no_len))
    no_h = [h for h in SIM_HEADER if not h.startswith("Block Height")]
    p = sim_file(tmp_path, "noh.csv", header=no_h)
    with pytest.raises(DataFileError, match=r"noh\.csv: .*no specimen height.*Cylinder Height.*"
                                            r"height_m"):
        read_compression_test(p)
    assert read_compression_test(p, height_m=0.02).height_m == 0.02
    bad = [h.replace("25mm", "25") for h in SIM_HEADER]
    with pytest.raises(DataFileError, match="'Block Height: 25' is not a length with a unit"):
        read_compression_test(sim_file(tmp_path, "nounit.csv", header=bad))


def test_bad_units_and_paths(tmp_path):
    with pytest.raises(DataFileError, match=r"lbf\.csv: column 'Load \(lbf\)'.*unknown force"):
        read_compression_test(sim_file(tmp_path, "lbf.csv",
                                       columns="Time (s),Extension (mm),Load (lbf)"))
    with pytest.raises(DataFileError, match=r"column 'Load' has no unit"):
        read_compression_test(sim_file(tmp_path, "nu.csv", columns="Time (s),Extension (mm),Load"))
    with pytest.raises(DataFileError, match=r"missing\.csv: file not found"):
        read_compression_test(tmp_path / "missing.csv")
    flat = [f"{k},0.5,{k}" for k in range(10)]
    with pytest.raises(DataFileError, match=r"flat\.csv: column 'Extension \(mm\)' never changes"):
        read_compression_test(sim_file(tmp_path, "flat.csv", rows=flat))
