#!/usr/bin/env python
"""Execute the example notebooks from their paired scripts, or check the committed ones.

The source of each notebook is a jupytext "percent" script ``notebooks/NN_name.py`` (edit
that, in any editor, or open it in Jupyter with jupytext installed); the committed
``notebooks/NN_name.ipynb`` is that script executed, outputs included, so that a reader sees
the results on the web.  After editing a script, or when the package's results change,
regenerate the notebooks and commit both files::

    python tools/run_notebooks.py                    # all notebooks (a few minutes)
    python tools/run_notebooks.py 02_lsq_vs_bayes    # only these (name, file name or prefix)
    python tools/run_notebooks.py --check            # committed .ipynb == script, executed?

Each notebook is built from its script with jupytext, executed with nbclient (kernel
``python3``, working directory the repository root, at most ``--timeout`` seconds per cell),
and written atomically (a temporary file in ``notebooks/``, then ``os.replace``), so an
interrupted or failed run leaves the committed notebook as it was.  The kernel inherits the
environment: notebook 01 reads ``PALPBAYES_NB_OUT`` (results folder to keep / reuse) and
``PALPBAYES_NB_WORKERS`` (worker processes, default 2).

``--check`` executes nothing: for every paired script it verifies that the committed
``.ipynb`` exists, is a valid notebook, has the script's cells (types and sources), and was
executed top to bottom (every code cell has an execution count, 1, 2, 3, ... in order, at least
one cell has outputs, and no output is an error).  It exits 1, naming the notebook, otherwise.

Requires ``jupytext``, ``nbclient``, ``nbformat`` and ``ipykernel`` (the ``test`` extra).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import stat
import sys
import tempfile
import time
from pathlib import Path

import jupytext
import nbformat

ROOT = Path(__file__).resolve().parents[1]
NB_DIR = ROOT / "notebooks"
KERNEL = "python3"
TIMEOUT = 900  # seconds per cell


def paired_scripts(nb_dir: Path = NB_DIR) -> list[Path]:
    """The ``*.py`` files in ``nb_dir`` whose jupytext header pairs them with an ``.ipynb``."""
    scripts = []
    for path in sorted(nb_dir.glob("*.py")):
        formats = jupytext.read(path).metadata.get("jupytext", {}).get("formats", "")
        if "ipynb" in str(formats).split(","):
            scripts.append(path)
    return scripts


def _cell_ids(nb: nbformat.NotebookNode) -> None:
    """Deterministic cell ids (a hash of type and source), so a re-run changes no id."""
    seen: dict[str, int] = {}
    for cell in nb.cells:
        base = hashlib.sha1(f"{cell.cell_type}\n{cell.source}".encode()).hexdigest()[:8]
        seen[base] = seen.get(base, 0) + 1
        cell["id"] = base if seen[base] == 1 else f"{base}-{seen[base]}"


def build(script: Path) -> nbformat.NotebookNode:
    """The notebook of a paired script, without outputs."""
    nb = jupytext.read(script)
    _cell_ids(nb)
    return nb


def _file_mode(target: Path) -> int:
    """The permission bits of ``target`` if it exists, else those of a new file (umask)."""
    if target.exists():
        return stat.S_IMODE(target.stat().st_mode)
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def execute(script: Path, timeout: int = TIMEOUT) -> tuple[Path, float]:
    """Build ``script``'s notebook, execute it and write it beside the script (atomically).

    Returns the notebook's path and the execution time in seconds; raises nbclient's
    ``CellExecutionError`` (nothing written) when a cell fails.
    """
    from nbclient import NotebookClient

    nb = build(script)
    client = NotebookClient(nb, timeout=timeout, kernel_name=KERNEL, record_timing=False,
                            resources={"metadata": {"path": str(ROOT)}})
    t0 = time.perf_counter()
    client.execute()
    elapsed = time.perf_counter() - t0
    nbformat.validate(nb)
    target = script.with_suffix(".ipynb")
    text = jupytext.writes(nb, fmt="ipynb").rstrip("\n") + "\n"  # as nbformat.write
    fd, tmp = tempfile.mkstemp(prefix=f".{target.stem}-", suffix=".ipynb.tmp",
                               dir=target.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)
        os.chmod(tmp, _file_mode(target))  # mkstemp's file is private (0600)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return target, elapsed


def check(script: Path) -> list[str]:
    """Problems of the committed notebook of ``script`` (empty when it is current and run)."""
    target = script.with_suffix(".ipynb")
    name = target.relative_to(ROOT)
    if not target.exists():
        return [f"{name}: missing; run python tools/run_notebooks.py {script.stem}"]
    nb = nbformat.read(target, as_version=4)
    try:
        nbformat.validate(nb)
    except nbformat.ValidationError as exc:
        return [f"{name}: not a valid notebook: {exc.message}"]
    problems = []
    want = [(c.cell_type, c.source) for c in build(script).cells]
    have = [(c.cell_type, c.source) for c in nb.cells]
    if have != want:
        diff = next((i for i, (a, b) in enumerate(zip(have, want, strict=False)) if a != b),
                    min(len(have), len(want)))
        problems.append(f"{name}: cells differ from {script.relative_to(ROOT)} (first at cell "
                        f"{diff}; {len(have)} vs {len(want)} cells): edited one without "
                        "re-running the other")
    code = [c for c in nb.cells if c.cell_type == "code"]
    counts = [c.get("execution_count") for c in code]
    if counts != list(range(1, len(code) + 1)):
        problems.append(f"{name}: not executed top to bottom in one kernel (execution counts "
                        f"{counts}, expected 1..{len(code)}); commit it executed")
    if code and not any(c.get("outputs") for c in code):
        problems.append(f"{name}: no outputs; commit it executed")
    errors = [f"cell {i}: {o.get('ename')}: {o.get('evalue')}"
              for i, c in enumerate(nb.cells) if c.cell_type == "code"
              for o in c.get("outputs", []) if o.get("output_type") == "error"]
    if errors:
        problems.append(f"{name}: error outputs ({'; '.join(errors)})")
    return problems


def _select(scripts: list[Path], names: list[str]) -> list[Path]:
    if not names:
        return scripts
    by_stem = {s.stem: s for s in scripts}
    chosen, unknown = [], []
    for name in names:  # a name, a file name (.py or .ipynb) or a unique prefix ("02")
        stem = Path(name).name.removesuffix(".py").removesuffix(".ipynb")
        match = [s for s in by_stem if s == stem] or [s for s in by_stem if s.startswith(stem)]
        if len(match) == 1:
            chosen.append(by_stem[match[0]])
        else:
            unknown.append(name)
    if unknown:
        raise SystemExit(f"no (unique) paired notebook script {', '.join(unknown)} in {NB_DIR} "
                         f"(have: {', '.join(by_stem) or 'none'})")
    return chosen


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description="Execute notebooks/*.py (jupytext percent scripts) into notebooks/*.ipynb, "
                    "or check the committed notebooks.")
    parser.add_argument("notebooks", nargs="*", metavar="NAME",
                        help="only these notebooks (e.g. 01_paper_tables, or 01); default: all")
    parser.add_argument("--check", action="store_true",
                        help="execute nothing; exit 1 if a committed .ipynb differs from its "
                             "script or was not executed")
    parser.add_argument("--timeout", type=int, default=TIMEOUT,
                        help=f"seconds per cell (default {TIMEOUT})")
    args = parser.parse_args(argv)
    scripts = _select(paired_scripts(), args.notebooks)
    if not scripts:
        print(f"no paired notebook scripts in {NB_DIR}", file=sys.stderr)
        return 1

    if args.check:
        problems = [p for s in scripts for p in check(s)]
        for p in problems:
            print(p, file=sys.stderr)
        if not problems:
            print(f"{len(scripts)} notebooks current and executed")
        return 1 if problems else 0

    from nbclient.exceptions import CellExecutionError, CellTimeoutError, DeadKernelError

    failed = []
    for script in scripts:
        print(f"executing {script.relative_to(ROOT)} ...", flush=True)
        try:
            target, elapsed = execute(script, timeout=args.timeout)
        except (CellExecutionError, CellTimeoutError, DeadKernelError) as exc:
            print(f"{script.relative_to(ROOT)}: FAILED, notebook not written:\n{exc}",
                  file=sys.stderr)
            failed.append(script.stem)
            continue
        print(f"wrote {target.relative_to(ROOT)} ({elapsed:.0f} s)", flush=True)
    if failed:
        print(f"failed: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
