"""``pb.groundtruth`` and ``palpbayes groundtruth`` are one path (issue 57): the same inputs and
options give the same bytes in every file, from the real phantom exports, the shipped example
campaign and simulated tests; bad options are named; the figure draws what was fitted."""

from __future__ import annotations

import filecmp
from pathlib import Path

import numpy as np
import pytest

import palpbayes as pb
from palpbayes import api_groundtruth, outputs
from palpbayes.campaign import comparison
from palpbayes.cli import main
from palpbayes.errors import InputError
from palpbayes.io.atomic import write_csv_atomic
from palpbayes.material import Solid
from palpbayes.sim import simulate_compression_test, write_compression_export


@pytest.fixture(scope="module")
def phantoms(shared_data) -> Path:
    """The real phantom exports (30 tests, three materials, and published_moduli.csv, which
    is not a test and is skipped)."""
    return shared_data("phantom-compression", files=["published_moduli.csv"])


@pytest.fixture(scope="module")
def example() -> Path:
    """The shipped example campaign's compression exports and their manifest."""
    return pb.example_campaign_dir() / "groundtruth"


@pytest.fixture(scope="module")
def simulated(tmp_path_factory) -> Path:
    """Two simulated neo-Hookean blocks pressed to 40 % strain, exported as the Instron does."""
    folder = tmp_path_factory.mktemp("sim") / "gt"
    solid = Solid.from_E0("neo-hookean", 80e3)
    for seed in (1, 2):
        df = simulate_compression_test(solid, height=0.02, max_compression=0.4 * 0.02,
                                       rate=5.0, speed=10 / 60e3, rng=seed)
        write_compression_export(df, folder / f"Gel_S{seed}.csv", height=0.02)
    return folder


def _same_files(a: Path, b: Path) -> list[str]:
    names = sorted(p.name for p in a.iterdir())
    assert names == sorted(p.name for p in b.iterdir())
    for name in names:
        assert filecmp.cmp(a / name, b / name, shallow=False), name
    return names


def _cli_and_door(tmp_path: Path, inputs: list[Path], argv: list[str], **kwargs):
    """``palpbayes groundtruth INPUTS ARGV --out A`` and ``pb.groundtruth(INPUTS, **kwargs)
    .save(B)``: the files of each, compared byte by byte; the door's result."""
    a, b = tmp_path / "cli", tmp_path / "door"
    assert main(["groundtruth", *map(str, inputs), *argv, "--out", str(a)]) == 0
    gt = pb.groundtruth(inputs, **kwargs)
    assert gt.save(b) == b
    names = _same_files(a, b)
    # summary() is the per-material table exactly as written
    mine = write_csv_atomic(gt.summary(), tmp_path / "summary.csv", float_format="%.10g")
    assert mine.read_bytes() == (a / outputs.GROUNDTRUTH_SUMMARY).read_bytes()
    return gt, names


def test_the_door_is_the_command(tmp_path, phantoms, capsys):
    gt, names = _cli_and_door(tmp_path, [phantoms], [], seed=0)
    assert names == [outputs.GROUNDTRUTH, outputs.GROUNDTRUTH_SUMMARY]
    assert "1 other CSV file(s) skipped" in capsys.readouterr().out
    assert [p.name for p in gt.skipped] == ["published_moduli.csv"] and gt.laws is None
    assert len(gt.tests) == 30 and list(gt.materials["material"]) == [
        "EF10_50T", "EF30_0T", "EF50_12_5T"]
    # the phantoms' published neighbourhood (compression/tables.py: 16.0, 103.5, 121.8 kPa)
    assert gt.materials["E_mean_pa"].to_numpy() / 1e3 == pytest.approx([16.0, 103.5, 121.8],
                                                                        abs=0.1)
    assert repr(gt).startswith("GroundTruth(30 tests, 3 materials: EF10_50T E 16 kPa ± ")
    summary = gt.summary()
    summary.loc[0, "E_mean_pa"] = 0.0  # a copy: the result keeps its table
    assert gt.materials.loc[0, "E_mean_pa"] > 0


def test_platens_and_a_window_in_percent_on_the_command_line(tmp_path, phantoms):
    """``--strain-window 1 4`` is ``strain_window=(0.01, 0.04)``; the platen correction."""
    gt, _ = _cli_and_door(tmp_path, [phantoms / "EF30_0T"],
                          ["--strain-window", "1", "4", "--platens", "bonded", "--nu", "0.45"],
                          strain_window=(0.01, 0.04), platens="bonded", nu=0.45)
    assert list(gt.materials[["window_lo", "window_hi"]].iloc[0]) == [0.01, 0.04]
    assert (gt.tests["platen_factor"] > 1).all()
    assert "corrected for bonded platens at nu 0.45" in repr(gt)


def test_the_example_campaign_its_manifest_and_the_toe_options(tmp_path, example):
    _cli_and_door(tmp_path / "a", [example], [])
    gt, _ = _cli_and_door(tmp_path / "b", [example / "manifest.csv"],
                          ["--skip-toe", "--no-toe-compensation"],
                          skip_toe=True, toe_compensation=False)
    assert len(gt.tests) == 15 and not gt.options.toe_compensation


def test_a_law_and_its_chord(tmp_path, simulated):
    gt, names = _cli_and_door(tmp_path, [simulated],
                              ["--law", "neo-hookean", "--strain", "0.05,0.20", "--no-progress"],
                              law="neo-hookean", strain=(0.05, 0.20), seed=0, progress=False)
    assert outputs.GROUNDTRUTH_LAWS in names
    assert list(gt.laws["law"]) == ["neo-hookean"]
    assert ((gt.tests["E0_lo_pa"] <= 80e3) & (80e3 <= gt.tests["E0_hi_pa"])).all()
    assert repr(gt).endswith("; law neo-hookean)")


def test_one_path_for_both(tmp_path, example, monkeypatch):
    """The command calls the door: what the door is patched to return is what it writes."""
    calls = []
    real = api_groundtruth.analyse_groundtruth

    def spy(inputs, options, *, progress=None):
        calls.append(options)
        return real(inputs, options, progress=progress)

    monkeypatch.setattr(api_groundtruth, "analyse_groundtruth", spy)
    assert main(["groundtruth", str(example), "--strain-window", "0", "4",
                 "--out", str(tmp_path / "out")]) == 0
    assert calls == [api_groundtruth.GroundTruthOptions(strain_window=(0.0, 0.04))]


@pytest.mark.parametrize(("options", "words"), [
    ({"area_m2": -1.0}, "area_m2 must be a positive number, got -1.0"),
    ({"height_m": "tall"}, "height_m must be a positive number"),
    ({"platens": "bonded"}, "platens and nu go together"),
    ({"nu": 0.3}, "platens and nu go together"),
    ({"platens": "glued", "nu": 0.3}, "platens 'glued': use 'lubricated' or 'bonded'"),
    ({"platens": "bonded", "nu": 0.7}, "Poisson ratio nu = 0.7 is outside"),
    ({"strain_window": (0, 5)}, "strain_window is a fraction of the height"),
    ({"strain_window": (0.05, 0.01)}, "strain_window must satisfy 0 <= lo < hi"),
])
def test_a_bad_option_is_named_before_anything_is_read(tmp_path, options, words):
    with pytest.raises(InputError, match=words):
        pb.groundtruth(tmp_path / "absent", **options)  # the option, not the missing path


def test_law_and_chord_errors_name_them(example):
    with pytest.raises(InputError, match="unknown material law 'gent'"):
        pb.groundtruth(example, law="gent")
    with pytest.raises(InputError, match="strains are fractions"):
        pb.groundtruth(example, strain="5,20")


def test_save_refuses_a_file(tmp_path, example):
    gt = pb.groundtruth(str(example))  # one path as a string: not its characters
    (tmp_path / "taken").write_text("x")
    with pytest.raises(InputError, match="exists and is not a folder"):
        gt.save(tmp_path / "taken")
    assert gt.save(tmp_path / "new" / "deeper").is_dir()


def test_plot_draws_each_test_and_the_line_its_modulus_is_the_slope_of(example):
    gt = pb.groundtruth(example)
    fig = gt.plot()
    materials = list(gt.materials["material"])
    assert [ax.get_title().split(":")[0] for ax in fig.axes] == materials
    for ax, material in zip(fig.axes, materials, strict=True):
        rows = gt.tests[gt.tests["material"] == material]
        lines = {line.get_gid(): line for line in ax.lines}
        assert sorted(lines) == sorted([f"curve {f}" for f in rows["file"]]
                                       + [f"fit {f}" for f in rows["file"]])
        for _, r in rows.iterrows():
            x, y = (np.asarray(v, float) for v in lines[f"fit {r['file']}"].get_data())
            # strain [%] against stress [kPa]: the slope is E [Pa] / 1e3 / 100
            assert (y[1] - y[0]) / (x[1] - x[0]) == pytest.approx(r["E_pa"] / 1e5, rel=1e-9)
            assert x == pytest.approx(100 * np.array([r["strain_lo"], r["strain_hi"]]))
            curve_x, curve_y = lines[f"curve {r['file']}"].get_data()
            assert len(curve_x) > 20 and max(curve_x) >= x[1]  # the curve spans the window


def test_the_public_names():
    assert pb.groundtruth is api_groundtruth.groundtruth
    assert pb.compare is comparison.compare and comparison.compare.__name__ == "compare"
    assert pb.compression.analyse is pb.compression.tables.analyse
    assert {"groundtruth", "compression", "compare"} <= set(dir(pb)) & set(pb.__all__)
