"""One compression test in SI units (:class:`CompressionTest`) and its material label.

The record every reader of :mod:`palpbayes.io.instron` returns and :mod:`palpbayes.compression`
fits: validated, read-only arrays of time, platen travel and load, positive in compression, with
the specimen's initial cross-section and height.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from ...errors import DataFileError

__all__ = ["CompressionTest", "material_from_label", "MIN_ROWS"]

#: Fewer data rows than this cannot give a modulus with an error bar.
MIN_ROWS = 3
_SUFFIX = re.compile(r"[_\-\s](?:[A-Za-z]{1,2}\d+|[A-Za-z]_?sample_?\d+|sample_?\d+)$",
                     re.IGNORECASE)


@dataclass(frozen=True, eq=False)
class CompressionTest:
    """One uniaxial compression test in SI units.

    Parameters
    ----------
    time_s
        [s] Sample times.
    compression_m
        [m] Platen travel since the first sample, positive in compression.
    load_n
        [N] Load, positive in compression.
    specimen, material
        Labels (``material`` groups specimens for the summary).
    area_m2
        [m²] Initial cross-section of the specimen.
    height_m
        [m] Initial height of the specimen (loading direction).
    source
        The file read (or a description of the data's origin).
    header
        Header lines of the export, ``key -> value`` as strings.
    """

    time_s: np.ndarray
    compression_m: np.ndarray
    load_n: np.ndarray
    specimen: str
    material: str
    area_m2: float
    height_m: float
    source: str = ""
    header: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        where = self.source or f"compression test {self.specimen!r}"
        arrays = {}
        for name in ("time_s", "compression_m", "load_n"):
            a = np.asarray(getattr(self, name), dtype=float)
            if a.ndim != 1:
                raise DataFileError(where, f"{name} must be one-dimensional, got shape {a.shape}")
            if not np.all(np.isfinite(a)):
                raise DataFileError(where, f"{name} holds NaN or infinite values")
            arrays[name] = a
        sizes = {a.size for a in arrays.values()}
        if len(sizes) != 1:
            raise DataFileError(where, "time_s, compression_m and load_n differ in length "
                                f"({', '.join(str(a.size) for a in arrays.values())})")
        if arrays["time_s"].size < MIN_ROWS:
            raise DataFileError(where, f"only {arrays['time_s'].size} data row(s); a compression "
                                f"test needs at least {MIN_ROWS}")
        for name in ("area_m2", "height_m"):
            v = getattr(self, name)
            if not (isinstance(v, int | float | np.floating | np.integer)
                    and math.isfinite(v) and v > 0):
                raise DataFileError(where, f"{name} must be a positive number of metres "
                                    f"(squared for the area), got {v!r}",
                                    f"pass {name}= or fix the geometry in the header")
            object.__setattr__(self, name, float(v))
        for name, a in arrays.items():
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    @property
    def n_points(self) -> int:
        """Number of samples."""
        return int(self.time_s.size)

    @property
    def strain(self) -> np.ndarray:
        """[-] Engineering strain, compression / height (positive in compression)."""
        return self.compression_m / self.height_m

    @property
    def stress_pa(self) -> np.ndarray:
        """[Pa] Engineering stress, load / initial area (positive in compression)."""
        return self.load_n / self.area_m2


def material_from_label(label: str) -> str:
    """Material of a specimen label: strip a trailing replicate suffix.

    ``EF10_50T_A1`` -> ``EF10_50T``, ``White_S1`` -> ``White``,
    ``EF10_50T_A_sample_1`` -> ``EF10_50T``; a label without such a suffix is returned as is.
    """
    label = str(label).strip()
    stripped = _SUFFIX.sub("", label)
    return stripped or label
