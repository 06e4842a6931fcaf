"""Write afmformats HDF5 files from traces, for the AFM reader tests (import as
``from afmfiles import write_afm_h5``; ``tests/`` is on ``sys.path``, see presets.py).

afmformats writes its own HDF5 format (``AFMData.export_data(fmt="hdf5")``) and reads it back
through the same ``load_data`` as JPK and Igor files, so a force map with known curves and
positions can be made at run time instead of committing a binary.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from palpbayes.trace import IndentationTrace

__all__ = ["write_afm_h5", "SPRING_CONSTANT"]

#: [N/m] Cantilever spring constant written to the files (a typical soft cantilever).
SPRING_CONSTANT = 0.0223


def write_afm_h5(path: Path, traces: Sequence[IndentationTrace],
                 positions: Sequence[tuple[float, float]] | None = None,
                 k: float = SPRING_CONSTANT) -> Path:
    """One curve per trace: its time, force and ``height (measured)`` = z - force/k (so that the
    tip position is z), all in the approach segment; ``position x/y`` [m] when given."""
    import h5py
    from afmformats import AFMForceDistance

    with h5py.File(path, "w") as h5:
        for i, t in enumerate(traces):
            data = {"force": np.asarray(t.force), "height (measured)": t.z - t.force / k,
                    "segment": np.zeros(t.n_points, dtype=np.uint8),
                    "time": np.asarray(t.time)}
            meta = {"spring constant": k, "imaging mode": "force-distance", "enum": i,
                    "path": Path(path), "duration": float(t.time[-1] - t.time[0]),
                    "point count": t.n_points}
            if positions is not None:
                meta["position x"], meta["position y"] = positions[i]
            AFMForceDistance(data, meta).export_data(h5, fmt="hdf5")
    return Path(path)
