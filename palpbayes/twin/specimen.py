"""The specimen as tested, seen from the twin: :mod:`palpbayes.specimen` (the block's geometry
lives outside the twin, so that the readers of :mod:`palpbayes.io` can parse a manifest's
footprint without importing the finite elements, and the twin can write its cache with
:mod:`palpbayes.io.atomic`: no cycle between the two parts)."""

from ..specimen import (  # noqa: F401 - the twin's public names (palpbayes.twin.Specimen, ...)
    FOOTPRINT_COLUMNS,
    SPECIMEN_KINDS,
    Specimen,
    check_specimen_plausible,
    parse_specimen,
    specimen_from_sizes,
)

__all__ = ["FOOTPRINT_COLUMNS", "SPECIMEN_KINDS", "Specimen", "check_specimen_plausible",
           "parse_specimen", "specimen_from_sizes"]
