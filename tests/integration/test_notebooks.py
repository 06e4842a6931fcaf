"""The example notebooks: committed executed, current with their paired scripts, and they run.

The source of each notebook is a jupytext "percent" script ``notebooks/NN_name.py``; the
committed ``notebooks/NN_name.ipynb`` is that script executed (``python tools/run_notebooks.py``),
so that a reader sees the outputs on the web.  The fast tests check that the committed notebook
has the script's cells and was executed; executing the notebooks takes minutes (notebook 01
fits the whole shipped campaign twice: once through the CLI, once in the notebook), so those
tests are marked ``slow`` (``pytest -m slow``).

jupytext is needed to read the scripts: without it these tests are skipped, except on CI
(``CI=true``), where a missing jupytext is an error (a skip would hide that nothing was checked).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import pandas as pd
import pytest

nbformat = pytest.importorskip("nbformat")

ROOT = Path(__file__).resolve().parents[2]
NB_DIR = ROOT / "notebooks"
NOTEBOOKS = ["01_paper_tables", "02_lsq_vs_bayes", "03_stiffening", "04_robot_vs_instron",
             "05_viscoelastic"]


def _on_ci() -> bool:
    """As tests/conftest.py's ``on_ci``: the environment variable CI is true (or 1, yes)."""
    return os.environ.get("CI", "").strip().lower() in ("true", "1", "yes")


def _jupytext():
    """The jupytext module; skip without it, FAIL without it on CI."""
    try:
        import jupytext
    except ImportError:
        msg = ("jupytext is not installed (it is in the test extra: "
               "pip install -e '.[test]'); the notebooks' paired scripts cannot be read")
        if _on_ci():
            pytest.fail(f"{msg}; CI=true, so this is an error, not a skip", pytrace=False)
        pytest.skip(msg)
    return jupytext


def _script(name: str) -> nbformat.NotebookNode:
    """The notebook built from the paired script ``notebooks/<name>.py`` (no outputs)."""
    return _jupytext().read(NB_DIR / f"{name}.py")


def test_every_paired_script_is_listed():
    jupytext = _jupytext()
    paired = sorted(p.stem for p in NB_DIR.glob("*.py")
                    if "ipynb" in str(jupytext.read(p).metadata.get("jupytext", {})
                                      .get("formats", "")).split(","))
    assert paired == NOTEBOOKS
    assert sorted(p.stem for p in NB_DIR.glob("*.ipynb")) == NOTEBOOKS


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_notebook_committed_executed_and_current(name):
    script = _script(name)
    assert script.metadata["jupytext"]["formats"] == "ipynb,py:percent"
    assert script.metadata["kernelspec"]["name"] == "python3"
    nb = nbformat.read(NB_DIR / f"{name}.ipynb", as_version=4)
    nbformat.validate(nb)
    assert nb.metadata["kernelspec"]["name"] == "python3"
    # the committed notebook has the script's cells (edit the .py, then run
    # python tools/run_notebooks.py to regenerate the .ipynb)
    assert [c.cell_type for c in nb.cells] == [c.cell_type for c in script.cells], name
    assert [c.source for c in nb.cells] == [c.source for c in script.cells], (
        f"{name}.ipynb differs from {name}.py: run python tools/run_notebooks.py {name}")
    # committed executed, top to bottom in one kernel, without errors.  Some cells (imports,
    # definitions) print nothing, so "executed" is the execution count, and outputs overall.
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert [c.execution_count for c in code] == list(range(1, len(code) + 1)), (
        f"{name}.ipynb is not committed executed: run python tools/run_notebooks.py {name}")
    assert any(c.outputs for c in code), f"{name}.ipynb has no outputs"
    errors = [f"{o.get('ename')}: {o.get('evalue')}" for c in code for o in c.outputs
              if o.get("output_type") == "error"]
    assert not errors, f"{name}.ipynb was committed with errors: {errors}"


def test_notebook_01_names_its_ground_truth_and_the_two_bayes_quantities():
    """The text table gets the analysed ground truth (not 'none found'), and the pooled
    material modulus and the new-specimen prediction carry different labels."""
    src = "\n".join(c.source for c in _script("01_paper_tables").cells)
    assert "format_comparison(res.comparison, groundtruth_source=" in src
    assert "Bayes material E ± sd [kPa]" in src and "Bayes new specimen E ± sd [kPa]" in src
    assert "import palpbayes as pb" in src
    assert "pb.run_pipeline(" in src and "pb.load_results(" in src


def _execute(name: str, cwd: Path, timeout: int = 900):
    """Build ``name`` from its paired script, execute it in ``cwd``; (notebook, seconds)."""
    nbclient = pytest.importorskip("nbclient")
    nb = _script(name)
    client = nbclient.NotebookClient(nb, timeout=timeout, kernel_name="python3",
                                     resources={"metadata": {"path": str(cwd)}})
    t0 = time.perf_counter()
    client.execute()
    elapsed = time.perf_counter() - t0
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs
              if o.get("output_type") == "error"]
    assert not errors
    # every cell that shows something when run shows it in the committed notebook too
    committed = nbformat.read(NB_DIR / f"{name}.ipynb", as_version=4)
    if [c.source for c in committed.cells] == [c.source for c in nb.cells]:
        silent = [i for i, (c, k) in enumerate(zip(nb.cells, committed.cells, strict=True))
                  if c.cell_type == "code" and c.outputs and not k.outputs]
        assert not silent, f"{name}.ipynb: cells {silent} committed without their outputs"
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
    nb, elapsed = _execute("01_paper_tables", tmp_path)
    assert elapsed < 600
    for table in ("comparison.csv", "pooled.csv", "budget.csv", "summary.csv"):
        pd.testing.assert_frame_equal(pd.read_csv(nb_dir / table), pd.read_csv(cli_dir / table),
                                      check_exact=True, obj=table)
    assert "comparison table:" in _text(nb)


@pytest.mark.slow
def test_notebook_02_runs(tmp_path):
    nb, elapsed = _execute("02_lsq_vs_bayes", tmp_path)
    assert elapsed < 600
    text = _text(nb)
    assert "Bayes, AR(1) model" in text and "Hertz, as the paper" in text


@pytest.mark.slow
def test_notebook_03_runs(tmp_path, monkeypatch):
    monkeypatch.setenv("PALPBAYES_NB_WORKERS", "2")
    nb, elapsed = _execute("03_stiffening", tmp_path)
    assert elapsed < 600
    assert "preferred law" in _text(nb)


@pytest.mark.slow
def test_notebook_04_decomposes_the_gap_and_covers_the_instron(tmp_path, monkeypatch):
    monkeypatch.setenv("PALPBAYES_NB_WORKERS", "2")
    monkeypatch.setenv("PALPBAYES_NB04_OUT", str(tmp_path / "res"))
    nb, elapsed = _execute("04_robot_vs_instron", tmp_path)
    assert elapsed < 600
    text = _text(nb)
    assert "4 of 9 with the specimen as tested, 1 with the infinite layer" in text
    assert "explains the paper's errors" in text and "sharper than its nominal profile" in text
    assert "covers the true E in 27/27" in text and "reads in 27/27" in text
    cmp_ = pd.read_csv(tmp_path / "res" / "comparison.csv")
    bayes = cmp_[cmp_["method"] == "bayes"]
    # 9/9: what a new specimen's compression test would read covers the Instron's reading
    assert bayes["gt_in_instron_interval"].all()


@pytest.mark.slow
def test_notebook_05_flags_the_elastic_fit_and_matches_the_instron(tmp_path):
    """Run from another folder (the real AFM file is found beside the checkout): the elastic
    fit's rate flag, the power law preferred on the simulated foam, the
    compression-equivalent modulus within 0.5 % of the simulated Instron at every speed, and
    on spot3 the drag gap flagged without the drag term and fitted with it."""
    nb, elapsed = _execute("05_viscoelastic", tmp_path)
    assert elapsed < 600
    text = _text(nb)
    assert "rate dependence: over the" in text and "--rheology power-law,sls" in text
    assert "power-law: E0* 7.99" in text or "power-law: E0* 8.00" in text
    worst = float(text.split("largest difference from the Instron: ")[1].split(" %")[0])
    assert worst < 0.5
    without, with_drag = text.split("drag fitted: False: ")[1].split("drag fitted: True: ")
    assert "viscous drag on the probe" in without
    b = float(with_drag.split("; drag ")[1].split(" ")[0])
    lines = with_drag.splitlines()
    flags = [x for x in lines[1:next((i for i, x in enumerate(lines[1:], 1)
                                      if not x.startswith("   flag:")), len(lines))]]
    assert 1e-6 < b < 6e-6 and not any("viscous drag" in x for x in flags), flags

