"""The example notebooks: committed clean, regenerated from their script, and they run.

Executing them takes minutes (notebook 01 fits the whole shipped campaign twice: once through
the CLI, once in the notebook), so those tests are marked ``slow`` (``pytest -m slow``).
"""

from __future__ import annotations

import importlib.util
import time
from pathlib import Path

import pandas as pd
import pytest

nbformat = pytest.importorskip("nbformat")

ROOT = Path(__file__).resolve().parents[2]
NB_DIR = ROOT / "notebooks"
NOTEBOOKS = ["01_paper_tables.ipynb", "02_lsq_vs_bayes.ipynb", "03_stiffening.ipynb"]


def _generator():
    spec = importlib.util.spec_from_file_location("make_notebooks",
                                                  NB_DIR / "make_notebooks.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_notebook_committed_clean_and_current(name):
    nb = nbformat.read(NB_DIR / name, as_version=4)
    nbformat.validate(nb)
    assert nb.metadata["kernelspec"]["name"] == "python3"
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert cell.outputs == [], f"{name}: committed with outputs; clear them"
            assert cell.execution_count is None
    # the committed file is what the generator writes (edit make_notebooks.py, not the .ipynb)
    gen = _generator()
    cells = {"01_paper_tables.ipynb": gen.NB01, "02_lsq_vs_bayes.ipynb": gen.NB02,
             "03_stiffening.ipynb": gen.NB03}[name]
    assert [c.source for c in nb.cells] == [c.source for c in cells]


def test_notebook_01_names_its_ground_truth_and_the_two_bayes_quantities():
    """The text table gets the analysed ground truth (not 'none found'), and the pooled
    material modulus and the new-specimen prediction carry different labels."""
    src = "\n".join(c.source for c in _generator().NB01)
    assert "format_comparison(res.comparison, groundtruth_source=" in src
    assert "Bayes material E ± sd [kPa]" in src and "Bayes new specimen E ± sd [kPa]" in src
    assert "from palpbayes.campaign import" in src
    assert "run_pipeline" in src and "load_results" in src


def _execute(name: str, cwd: Path, timeout: int = 900):
    nbclient = pytest.importorskip("nbclient")
    nb = nbformat.read(NB_DIR / name, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=timeout, kernel_name="python3",
                                     resources={"metadata": {"path": str(cwd)}})
    t0 = time.perf_counter()
    client.execute()
    elapsed = time.perf_counter() - t0
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs
              if o.get("output_type") == "error"]
    assert not errors
    return nb, elapsed


def _text(nb) -> str:
    out = []
    for c in nb.cells:
        for o in c.get("outputs", []):
            if "text" in o:
                out.append(o["text"])
            data = o.get("data", {})
            out.append(data.get("text/plain", ""))
    return "\n".join(out)


@pytest.mark.slow
def test_notebook_01_tables_equal_the_cli(tmp_path, monkeypatch):
    from palpbayes.cli import main

    manifest = ROOT / "data" / "example-campaign" / "manifest.csv"
    cli_dir = tmp_path / "cli"
    assert main(["fit", str(manifest), "--out", str(cli_dir), "--method", "both",
                 "--seed", "0", "--workers", "2"]) == 0
    assert main(["compare", str(cli_dir)]) == 0
    nb_dir = tmp_path / "nb"
    monkeypatch.setenv("PALPBAYES_NB_OUT", str(nb_dir))
    monkeypatch.setenv("PALPBAYES_NB_WORKERS", "2")
    nb, elapsed = _execute("01_paper_tables.ipynb", tmp_path)
    assert elapsed < 600
    for table in ("comparison.csv", "pooled.csv", "budget.csv", "summary.csv"):
        pd.testing.assert_frame_equal(pd.read_csv(nb_dir / table), pd.read_csv(cli_dir / table),
                                      check_exact=True, obj=table)
    assert "comparison table:" in _text(nb)


@pytest.mark.slow
def test_notebook_02_runs(tmp_path):
    nb, elapsed = _execute("02_lsq_vs_bayes.ipynb", tmp_path)
    assert elapsed < 600
    text = _text(nb)
    assert "Bayes, AR(1) model" in text and "Hertz, as the paper" in text


@pytest.mark.slow
def test_notebook_03_runs(tmp_path, monkeypatch):
    monkeypatch.setenv("PALPBAYES_NB_WORKERS", "2")
    nb, elapsed = _execute("03_stiffening.ipynb", tmp_path)
    assert elapsed < 600
    assert "preferred law" in _text(nb)
