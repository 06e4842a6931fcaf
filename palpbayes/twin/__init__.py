"""The specimen as tested: a finite-element twin of the palpation and of the compression test.

The contact laws of :mod:`palpbayes.contact` model a half-space or an infinitely wide layer;
the twin models the block the user tested, L × W × H (or D × H) on its plate, pressed by any
registered tip (:mod:`.palpation`), and the same block between the platens of a compression
test (:mod:`.compression`), on scikit-fem (axisymmetric, the block as the cylinder of equal
footprint area: :mod:`.specimen`; linear elasticity with mixed elements up to nu = 0.5:
:mod:`.fe`, graded meshes: :mod:`.mesh`).  The palpation law is tabulated once per geometry ×
tip × nu × base and cached on disk (:mod:`.table`, :mod:`.cache`).

At finite strain (any law of :mod:`palpbayes.material`): the hyperelastic solid
(:mod:`.hyper`), the tips' true surfaces in frictionless contact (:mod:`.hyper_contact`),
palpation (:mod:`.hyper_palpation`) and compression (:mod:`.hyper_compression`) to large
strain, and their force curves tabulated for a fit (:mod:`.hyper_table`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:  # the same names, for static tools
    from .compression import (
        PLATENS,
        compression_factor,
        oedometric_factor,
        platen_factor,
        pressure_solution_factor,
    )
    from .hyper import HyperSolid
    from .hyper_compression import HyperCompression, solve_hyper_compression
    from .hyper_contact import PenaltyContact, TipSurface, tip_surface
    from .hyper_palpation import (
        HYPER_RESOLUTIONS,
        HyperCurve,
        HyperResolution,
        solve_hyper_palpation,
    )
    from .hyper_table import HyperTable, hyper_table, prepare_hyper_table, solid_table
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

#: Public name -> the submodule that defines it; imported on first use (PEP 562), so that
#: importing one submodule (e.g. :mod:`.specimen`) does not load the finite elements.
_LAZY = {
    "PLATENS": "compression",
    "compression_factor": "compression",
    "oedometric_factor": "compression",
    "platen_factor": "compression",
    "pressure_solution_factor": "compression",
    "HyperSolid": "hyper",
    "HyperCompression": "hyper_compression",
    "solve_hyper_compression": "hyper_compression",
    "PenaltyContact": "hyper_contact",
    "TipSurface": "hyper_contact",
    "tip_surface": "hyper_contact",
    "HYPER_RESOLUTIONS": "hyper_palpation",
    "HyperCurve": "hyper_palpation",
    "HyperResolution": "hyper_palpation",
    "solve_hyper_palpation": "hyper_palpation",
    "HyperTable": "hyper_table",
    "hyper_table": "hyper_table",
    "prepare_hyper_table": "hyper_table",
    "solid_table": "hyper_table",
    "TWIN_BASES": "palpation",
    "PalpationCurve": "palpation",
    "solve_palpation": "palpation",
    "FOOTPRINT_COLUMNS": "specimen",
    "SPECIMEN_KINDS": "specimen",
    "Specimen": "specimen",
    "check_specimen_plausible": "specimen",
    "parse_specimen": "specimen",
    "specimen_from_sizes": "specimen",
    "MAX_ASPECT": "table",
    "TWIN_SOLVER_VERSION": "table",
    "TwinTable": "table",
    "clear_memory": "table",
    "prepare_tables": "table",
    "table_key": "table",
    "twin_depth_limit": "table",
    "twin_depth_limit_reason": "table",
    "twin_factor": "table",
    "twin_shape": "table",
    "twin_table": "table",
}

__all__ = [
    "PLATENS", "compression_factor", "oedometric_factor", "platen_factor",
    "pressure_solution_factor", "TWIN_BASES", "PalpationCurve", "solve_palpation",
    "FOOTPRINT_COLUMNS", "SPECIMEN_KINDS", "Specimen", "check_specimen_plausible",
    "parse_specimen", "specimen_from_sizes",
    "TWIN_SOLVER_VERSION", "TwinTable", "prepare_tables", "table_key", "twin_depth_limit",
    "twin_depth_limit_reason", "twin_factor", "twin_shape", "twin_table", "clear_memory",
    "MAX_ASPECT", "HyperSolid", "HyperCompression", "solve_hyper_compression",
    "PenaltyContact", "TipSurface", "tip_surface", "HYPER_RESOLUTIONS", "HyperCurve",
    "HyperResolution", "solve_hyper_palpation", "HyperTable", "hyper_table",
    "prepare_hyper_table", "solid_table",
]


__getattr__, __dir__ = lazy_exports(__name__, _LAZY)
