"""``palpbayes inspect`` on real AFM files: positions in the right unit, the calibration the
file records, and a ``palpbayes fit`` command that runs once the tip radius is filled in
(issue 46, item 8).  The files are afmformats' and PyFMRheo's examples (MIT), read through the
``shared_data`` fixture."""

from __future__ import annotations

import shlex
from collections.abc import Callable
from pathlib import Path

import pandas as pd
import pytest

from palpbayes.cli import build_parser, main
from palpbayes.io.afm import afm_calibration

SPOT3 = "fmt-jpk-fd_spot3-0192.jpk-force"
RELAX = "fmt-jpk-sr_cell1-0008.jpk-force"
QI = "fmt-jpk-fd_2020.02.07-16.29.05.036.jpk-qi-data"
WORKSHOP = "fmt-afm-workshop-fd_mapping_16_2018-08-01_13.07.zip"

#: What the test fills in for the placeholders of the printed command (tip radius R [m],
#: spring constant K [N/m], sensitivity S [m/V]).
FILL = {"R": "5e-6", "K": "0.05", "S": "5e-8", "HZ": "1000"}


@pytest.fixture(scope="module")
def afm_dir(shared_data: Callable[..., Path]) -> Path:
    """The folder of real AFM files (skips when absent, fails on CI)."""
    return shared_data("afm-files", files=[SPOT3, RELAX, QI, WORKSHOP])


def _inspect(path: Path, capsys: pytest.CaptureFixture[str]) -> str:
    """What ``palpbayes inspect path`` prints (exit status 0)."""
    assert main(["inspect", str(path)]) == 0
    return capsys.readouterr().out


def _commands(out: str, command: str = "fit") -> list[list[str]]:
    """The ``palpbayes COMMAND ...`` lines of ``out`` as argv lists (without ``palpbayes``),
    their placeholders filled in with :data:`FILL`."""
    found = []
    for line in out.splitlines():
        if not line.strip().startswith(f"palpbayes {command} "):
            continue
        words = shlex.split(line)
        if words[:2] == ["palpbayes", command]:
            found.append([FILL.get(w, w) for w in words[1:]])
    return found


def test_a_position_at_the_stage_origin_is_shown_as_zero_not_in_fractions_of_a_pm(
        afm_dir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The JPK header of the stress-relaxation curve records x = -1.434e-15 m (a stage at
    its origin); it was printed as ``x = -0.0014343 pm``, below format_length's smallest
    prefix.  Real offsets keep their unit and digits."""
    out = _inspect(afm_dir / RELAX, capsys)
    assert "at x = 0 m, y = 0 m" in out
    assert " pm" not in out
    out = _inspect(afm_dir / QI, capsys)
    assert ("curve 0: approach 300 points (0.028 s), retract 300 (0.028 s)  at x = -4.9609 µm, "
            "y = -6.9609 µm") in out


def test_inspect_shows_the_calibration_and_approach_settings_the_file_records(
        afm_dir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Spring constant, deflection sensitivity, setpoint, speed and rate from afmformats'
    metadata, in SI with prefixes (the durations come from the data: the next test); none for
    the AFM Workshop zip (which lacks them: the placeholders inspect reads it with are not
    shown)."""
    (cal,) = afm_calibration(afm_dir / SPOT3)
    assert cal["spring constant"] == pytest.approx(0.043493666407368466)
    assert cal["sensitivity"] == pytest.approx(7.000143623002982e-08)
    assert cal["setpoint"] == pytest.approx(4e-9)
    out = _inspect(afm_dir / SPOT3, capsys)
    assert "  calibration: spring constant 0.04349 N/m, deflection sensitivity 70 nm/V\n" in out
    assert "  approach: setpoint 4 nN, speed 5 µm/s, sampled at 2 kHz\n" in out
    assert "curve 0: approach 2000 points (1 s), retract 2000 (1 s)" in out
    out = _inspect(afm_dir / RELAX, capsys)
    assert "spring constant 1.068 N/m, deflection sensitivity 110.3 nm/V" in out
    placeholders = {"spring constant": 1.0, "sensitivity": 1.0}
    assert all(c == {} for c in afm_calibration(afm_dir / WORKSHOP, placeholders))
    out = _inspect(afm_dir / WORKSHOP, capsys)
    assert "calibration: none recorded" in out and "spring constant 1 N/m" not in out


def test_the_hold_is_measured_on_the_data_not_read_from_the_header(
        afm_dir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The JPK stress-relaxation cell holds 30 s (7,680 points at 256 Hz) but its header's
    ``duration intermediate`` says 1 s, which inspect printed as ``hold 1 s`` (issue 58, item
    7): each segment's duration is now measured on the time column, and inspect says so."""
    out = _inspect(afm_dir / RELAX, capsys)
    assert ("curve 0: approach 256 + 2048 points (1 + 1 s), hold 7680 (30 s), retract 1951 "
            "(0.9526 s)") in out
    assert "durations measured on the time column" in out
    assert "hold 1 s" not in out and "duration 1 s" not in out
    # the Workshop zip has no time column: nothing measured, nothing claimed
    out = _inspect(afm_dir / WORKSHOP, capsys)
    assert "curve 0: approach 391, retract 391 points" in out
    assert "durations measured" not in out


def test_the_printed_fit_command_runs_with_the_radius_filled_in(
        afm_dir: Path, capsys: pytest.CaptureFixture[str], tmp_path: Path,
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The one ``palpbayes fit`` line inspect prints for a single curve, with R = 5e-6 and
    nothing else changed, fits it and writes its --out folder (relative: the working
    directory)."""
    out = _inspect(afm_dir / SPOT3, capsys)
    assert "no AFM file records the tip" in out
    (argv,) = _commands(out)
    assert argv[argv.index("--tip") + 1] == "paraboloid" and "--nu" in argv
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 0, capsys.readouterr().err
    summary = pd.read_csv(tmp_path / "fmt-jpk-fd_spot3-0192-fit" / "summary.csv")
    assert list(summary["trace_id"]) == ["fmt-jpk-fd_spot3-0192"]


def test_a_deep_indentation_needs_the_max_depth_inspect_names(
        afm_dir: Path, capsys: pytest.CaptureFixture[str], tmp_path: Path,
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The stress-relaxation cell is indented ~19 µm: with a 5 µm tip fit refuses the printed
    command, and runs once --max-depth is added as inspect's note says; inspect also points
    to --rheology for the hold."""
    out = _inspect(afm_dir / RELAX, capsys)
    assert "add --max-depth M (e.g. the radius)" in out
    assert "--rheology power-law,sls fits the hold" in out
    (argv,) = _commands(out)
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    assert "--max-depth" in capsys.readouterr().err
    assert main([*argv, "--max-depth", "5e-6"]) == 0, capsys.readouterr().err
    assert (tmp_path / "fmt-jpk-sr_cell1-0008-fit" / "summary.csv").is_file()


@pytest.mark.parametrize("name", [QI, WORKSHOP])
def test_a_force_map_gets_a_one_curve_fit_and_a_map_command(
        afm_dir: Path, capsys: pytest.CaptureFixture[str], name: str) -> None:
    """A force map: ``fit ... --curve 0`` and ``map``; the Workshop zip's commands carry the
    spring constant and sensitivity it lacks.  Both parse as fit's and map's options."""
    out = _inspect(afm_dir / name, capsys)
    (fit,) = _commands(out)
    (mapped,) = _commands(out, "map")
    assert fit[fit.index("--curve") + 1] == "0"
    assert ("--spring-constant" in fit and "--sensitivity" in mapped) == (name == WORKSHOP)
    assert ("--sample-rate" in fit) == (name == WORKSHOP)
    parser = build_parser()
    for argv in (fit, mapped):
        args = parser.parse_args(argv)
        assert args.tip == "paraboloid" and args.radius == 5e-6 and args.nu == 0.5


def test_the_workshop_zips_fit_command_runs_once_filled_in(
        afm_dir: Path, capsys: pytest.CaptureFixture[str], tmp_path: Path,
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The AFM Workshop zip has no calibration and no time column: its printed command asks
    for K, S and HZ, and runs once they are filled in (review of issue 46: without
    --sample-rate it could not)."""
    (fit,) = _commands(_inspect(afm_dir / WORKSHOP, capsys))
    monkeypatch.chdir(tmp_path)
    assert main([*fit, "--method", "lsq"]) == 0, capsys.readouterr().err
    out = tmp_path / fit[fit.index("--out") + 1]
    assert (out / "summary.csv").is_file()


def test_a_robot_csv_gets_a_fit_command_with_the_options_its_header_and_data_tell(
        capsys: pytest.CaptureFixture[str], tmp_path: Path,
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 58, item 7: inspect printed a plain CSV's columns and no fit command.  The
    README's robot log (timestamp, tcp_z_mm, fz; pressing reads negative) now gets
    ``--time-column timestamp --z-column tcp_z_mm --z-unit mm --force-column fz`` from its
    header and ``--force-sign -1`` from its data, and the command fits once R is filled in; a
    canonical CSV needs no option; a header palpbayes does not know gets placeholders."""
    from palpbayes.contact import Tip
    from palpbayes.sim import simulate_trace

    tr = simulate_trace(6e5, Tip("sphere", radius=0.01), thickness=0.02, depth=3e-3,
                        force_offset=0.21, rng=1, rate=250.0, base=None)
    monkeypatch.chdir(tmp_path)
    pd.DataFrame({"timestamp": tr.time, "tcp_z_mm": 1e3 * tr.z, "fz": -tr.force}).to_csv(
        "press.csv", index=False)
    out = _inspect(Path("press.csv"), capsys)
    (argv,) = _commands(out)
    assert argv[:4] == ["fit", "press.csv", "--out", "press-fit"]
    assert " ".join(argv[4:]) == ("--time-column timestamp --z-column tcp_z_mm --z-unit mm "
                                  "--force-column fz --force-sign -1 --tip sphere --radius 5e-6")
    assert "timestamp, fz: no unit in the name, read in s, N" in out
    assert main([*argv[:-1], "0.01", "--engine", "exact", "--nu", "0.3"]) == 0, \
        capsys.readouterr().err
    summary = pd.read_csv(tmp_path / "press-fit" / "summary.csv")
    assert summary["E_pa"].iloc[0] == pytest.approx(6e5, rel=0.05)

    pd.DataFrame({"time_s": tr.time, "z_m": tr.z, "force_n": tr.force}).to_csv(
        "plain.csv", index=False)
    (argv,) = _commands(_inspect(Path("plain.csv"), capsys))
    assert argv[4:] == ["--tip", "sphere", "--radius", "5e-6"]
    pd.DataFrame({"t": [0, 1], "height": [0, 1], "load": [0, 1]}).to_csv("odd.csv", index=False)
    out = _inspect(Path("odd.csv"), capsys)
    assert "--z-column Z --force-column FORCE" in out and "header names none" in out
