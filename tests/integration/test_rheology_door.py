"""``pb.fit_rheology`` on a file and on a manifest is ``palpbayes fit --rheology``: the same
options builder and run, the same tables (every column but the fit's wall time, ``seconds``),
the same stored fits; a trace is still one :class:`RheologyFit`."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

import palpbayes as pb
from palpbayes.api_rheology import RheologyRun, rheology_options
from palpbayes.cli import main
from palpbayes.contact.viscoelastic import PowerLawKernel
from palpbayes.errors import InputError
from palpbayes.io.atomic import write_csv_atomic
from palpbayes.io.manifest import write_manifest
from palpbayes.io.trace_csv import write_trace
from palpbayes.paper import PAPER_TIPS
from palpbayes.rheology.fit import RheologyFit
from palpbayes.sim import simulate_viscoelastic

KERNEL = PowerLawKernel(80e3, 0.2)
PARA = ["--tip", "paraboloid", "--radius", "0.0117"]


def _record(speed_mm_min: float, rng: int, trace_id: str):
    return simulate_viscoelastic(KERNEL, PAPER_TIPS["paraboloid"], depth=2e-3,
                                 speed=speed_mm_min / 6e4, hold_time=3.0, rate=300.0,
                                 z_surf=2e-4, noise_sd=0.008, phi=0.2, rng=rng,
                                 trace_id=trace_id)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    root = tmp_path_factory.mktemp("visco-door")
    paths = [write_trace(_record(v, 20 + k, f"v{v:g}"), root / f"v{v:g}.csv",
                         float_format="%.12g") for k, v in enumerate((50.0, 200.0))]
    manifest = write_manifest(pd.DataFrame({
        "trace_id": ["v50", "v200"], "file": [str(p) for p in paths],
        "material": ["silicone"] * 2, "specimen": ["block"] * 2, "tip": ["paraboloid"] * 2,
        "radius_m": [0.0117] * 2, "thickness_m": [0.02] * 2, "nu": [0.45] * 2}),
        root / "manifest.csv")
    return root, paths, manifest


def _without_seconds(path) -> pd.DataFrame:
    return pd.read_csv(path).drop(columns="seconds")


def test_a_file_gives_the_command_line_s_table_and_stored_fit(files, tmp_path):
    _, (path, _), _ = files
    assert main(["fit", str(path), "--rheology", "power-law", "--nu", "0.45", "--thickness",
                 "0.02", "--seed", "2", "--out", str(tmp_path / "cli"), "--no-progress",
                 *PARA]) == 0
    run = pb.fit_rheology(path, "power-law", tip="paraboloid", radius=0.0117, nu=0.45,
                          thickness=0.02, seed=2, progress=False)
    assert isinstance(run, RheologyRun) and repr(run).startswith("RheologyRun('v50.csv': 1 ")
    saved = run.save(tmp_path / "api")
    cli = tmp_path / "cli" / "rheology.csv"
    # summary() is the file save() wrote, byte for byte, and the command line's but its time
    write_csv_atomic(run.summary(), tmp_path / "again.csv", index=False)
    assert (tmp_path / "again.csv").read_bytes() == (saved / "rheology.csv").read_bytes()
    pd.testing.assert_frame_equal(_without_seconds(saved / "rheology.csv"),
                                  _without_seconds(cli), check_exact=True)
    assert sorted(p.name for p in (saved / "rheology").iterdir()) == sorted(
        p.name for p in (tmp_path / "cli" / "rheology").iterdir()) == ["v50_power-law.nc"]
    row = run.summary().iloc[0]
    assert row["E0_star_lo_pa"] < KERNEL.E0 < row["E0_star_hi_pa"]
    stored = run.fit("v50")
    assert stored.trace_id == "v50" and stored.rheology == "power-law"
    e0 = next(v for k, v in stored.draws.items() if k.startswith("E0"))  # thinned draws
    assert np.median(e0) == pytest.approx(row["E0_star_pa"], rel=0.01)
    with pytest.raises(InputError, match="exists; pass force=True"):
        run.save(saved)
    assert run.save(saved, force=True) == saved


def test_a_manifest_pools_its_speeds_as_the_command_line_does(files, tmp_path):
    _, _, manifest = files
    assert main(["fit", str(manifest), "--rheology", "power-law", "--out",
                 str(tmp_path / "cli"), "--no-progress"]) == 0
    run = pb.fit_rheology(manifest, "power-law", progress=False)
    saved = run.save(tmp_path / "api")
    for name in ("rheology.csv", "rheology_pooled.csv"):
        pd.testing.assert_frame_equal(_without_seconds(saved / name),
                                      _without_seconds(tmp_path / "cli" / name),
                                      check_exact=True)
    pooled = run.pooled.iloc[0]
    assert (pooled["n_traces"], pooled["n_speeds"], pooled["nu"]) == (2, 2, 0.45)
    assert pooled["E0_star_lo_pa"] < KERNEL.E0 < pooled["E0_star_hi_pa"]
    fig = run.plot()
    assert isinstance(fig, Figure)
    labels = {t.get_text() for t in fig.axes[0].get_legend().get_texts()}
    assert {"v50", "v200"} <= {s.split(" ")[0] for s in labels}


def test_a_trace_is_one_fit_and_options_are_checked_once(files):
    _, (path, _), manifest = files
    trace = pb.read(path, tip="paraboloid", radius=0.0117)
    one = pb.fit_rheology(trace, "power-law", seed=2)
    assert isinstance(one, RheologyFit)
    with pytest.raises(InputError, match="unknown option.*maxsteps"):
        pb.fit_rheology(path, tip="paraboloid", radius=0.0117, maxsteps=3)
    with pytest.raises(InputError, match="is a manifest: it gives each row's tip"):
        pb.fit_rheology(manifest, tip="sphere", radius=0.01)
    with pytest.raises(InputError, match="--t0 0 must be a positive time"):
        rheology_options(t0=0)
    for bad, message in (({"engine": "emce"}, "engine 'emce': use one of grid, emcee"),
                         ({"baseline": "tilted"}, "baseline 'tilted'"),
                         ({"adhesion": "peel"}, "adhesion 'peel'")):
        with pytest.raises(InputError, match=message):  # before any trace is read
            pb.fit_rheology(path, tip="paraboloid", radius=0.0117, **bad)
    with pytest.raises(InputError, match="with the power law only"):
        rheology_options("sls", segments="approach,retract")
    opts = rheology_options("power-law", peer="pyfmrheo")
    assert opts.segments == "approach,retract" and opts.drag is None
    assert rheology_options("elastic, power-law,sls", drag="on").rheology == (
        "elastic", "power-law", "sls")
