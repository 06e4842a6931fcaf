#!/usr/bin/env python
"""Write the finite-element tables the shipped example campaign needs into data/twin-cache.

``palpbayes report`` on a fresh machine solves the example blocks' twins before it fits (about a
minute on two cores); the source checkout ships them instead (:mod:`palpbayes.twin.cache` reads
``data/twin-cache`` when its own folder lacks a table).  Run after changing the twin's solver,
the example or the locked numpy/scipy versions (their versions are part of a lookup grid's
key; a release without them solves the tables as before)::

    python tools/ship_twin_cache.py

It runs the report of the example into a temporary folder with an empty cache and the shipped
tables ignored, and copies every table it solved, but the gap table (keyed by the whole
package: stale at the next commit), into ``data/twin-cache/twin-v1``.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    from palpbayes.twin.cache import SHIPPED_DIR

    with tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "PALPBAYES_CACHE_DIR": str(Path(tmp) / "cache"),
               "PALPBAYES_SHIPPED_TABLES": "off"}
        subprocess.run([sys.executable, "-m", "palpbayes", "report", "--out",
                        str(Path(tmp) / "results"), "-o", str(Path(tmp) / "report.pdf"),
                        "--no-progress"], check=True, env=env, cwd=ROOT)
        solved = sorted((Path(tmp) / "cache" / SHIPPED_DIR.name).glob("*.npz"))
        keep = [f for f in solved if not f.name.startswith("gap-")]
        if SHIPPED_DIR.exists():
            shutil.rmtree(SHIPPED_DIR)
        SHIPPED_DIR.mkdir(parents=True)
        for f in keep:
            shutil.copy2(f, SHIPPED_DIR / f.name)
    size = sum(f.stat().st_size for f in SHIPPED_DIR.glob("*.npz"))
    print(f"wrote {len(keep)} tables ({size / 1e6:.1f} MB) into {SHIPPED_DIR.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
