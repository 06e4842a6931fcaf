"""Results-folder layout (palpbayes.outputs): stale files after --force, lsq-only
compare/report."""

from __future__ import annotations

import pandas as pd
import pytest

from palpbayes.cli import main
from palpbayes.sim import simulate


@pytest.fixture(scope="module")
def camp(tmp_path_factory):
    out = tmp_path_factory.mktemp("layout-campaign")
    simulate(out, seed=3, repetitions=2)
    return out


def _fit_lsq(camp, out, *extra):
    assert main(["fit", str(camp / "manifest.csv"), "--out", str(out), "--method", "lsq",
                 *extra]) == 0


def test_force_removes_every_table_of_the_previous_run(camp, tmp_path):
    """A refit with --force must not leave tables of the old fit (stiffening.csv was kept)."""
    out = tmp_path / "res"
    _fit_lsq(camp, out)
    assert main(["compare", str(out)]) == 0
    # a previous compare on a series with rest times, and a previous report
    for name in ("stiffening.csv", "report.pdf"):
        (out / name).write_text("stale\n")
    (out / "notes.txt").write_text("mine")
    _fit_lsq(camp, out, "--force")
    left = sorted(p.name for p in out.iterdir() if p.is_file())
    for name in ("comparison.csv", "pooled.csv", "budget.csv", "stiffening.csv", "report.pdf"):
        assert name not in left, left
    assert (out / "notes.txt").read_text() == "mine"


def test_lsq_only_results_compare_and_report(camp, tmp_path, capsys):
    """compare after an lsq-only fit wrote a pooled.csv without a header that report rejected
    with exit 2; now it holds the header and report reads it as 'no pooled groups'."""
    out = tmp_path / "res"
    _fit_lsq(camp, out)
    assert main(["compare", str(out)]) == 0
    pooled = pd.read_csv(out / "pooled.csv")
    assert pooled.empty and {"material", "tip", "E_pa", "converged"} <= set(pooled.columns)
    capsys.readouterr()
    rc = main(["report", str(out), "-o", str(tmp_path / "r.pdf")])
    assert rc == 0, capsys.readouterr().err
    assert (tmp_path / "r.pdf").stat().st_size > 0
