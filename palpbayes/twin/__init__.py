"""The specimen as tested: a finite-element twin of the palpation and of the compression test.

The contact laws of :mod:`palpbayes.contact` model a half-space or an infinitely wide layer;
the twin models the block the user tested, L × W × H (or D × H) on its plate, pressed by any
registered tip (:mod:`.palpation`), and the same block between the platens of a compression
test (:mod:`.compression`), on scikit-fem (axisymmetric, the block as the cylinder of equal
footprint area: :mod:`.specimen`; linear elasticity with mixed elements up to nu = 0.5:
:mod:`.fe`, graded meshes: :mod:`.mesh`).  The palpation law is tabulated once per geometry ×
tip × nu × base and cached on disk (:mod:`.table`, :mod:`.cache`).
"""

from .compression import (
    PLATENS,
    compression_factor,
    oedometric_factor,
    platen_factor,
    pressure_solution_factor,
)
from .palpation import TWIN_BASES, PalpationCurve, solve_palpation
from .specimen import (
    FOOTPRINT_COLUMNS,
    SPECIMEN_KINDS,
    Specimen,
    check_specimen_plausible,
    parse_specimen,
    specimen_from_sizes,
)
from .table import (
    MAX_ASPECT,
    TWIN_SOLVER_VERSION,
    TwinTable,
    clear_memory,
    prepare_tables,
    table_key,
    twin_depth_limit,
    twin_depth_limit_reason,
    twin_factor,
    twin_shape,
    twin_table,
)

__all__ = [
    "PLATENS", "compression_factor", "oedometric_factor", "platen_factor",
    "pressure_solution_factor", "TWIN_BASES", "PalpationCurve", "solve_palpation",
    "FOOTPRINT_COLUMNS", "SPECIMEN_KINDS", "Specimen", "check_specimen_plausible",
    "parse_specimen", "specimen_from_sizes",
    "TWIN_SOLVER_VERSION", "TwinTable", "prepare_tables", "table_key", "twin_depth_limit",
    "twin_depth_limit_reason", "twin_factor", "twin_shape", "twin_table", "clear_memory",
    "MAX_ASPECT",
]
