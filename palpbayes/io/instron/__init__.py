"""Compression-test exports (Instron style): read them into :class:`CompressionTest` (SI units).

>>> from palpbayes.io.instron import read_compression_test       # doctest: +SKIP
>>> test = read_compression_test("EF10_50T_A1.csv")               # doctest: +SKIP

Modules: :mod:`.reader` (the public readers and the rules they follow), :mod:`.record`
(:class:`CompressionTest`, material labels), :mod:`.columns` (column names, units, signs),
:mod:`.geometry` (cross-section and height from the header) and :mod:`.text` (lines, cells,
the column row, the free header).  The public names of each are imported here.
"""

from . import columns, reader, record
from .columns import *  # noqa: F403 - the names in columns.__all__
from .reader import *  # noqa: F403
from .record import *  # noqa: F403

__all__ = [*record.__all__, *reader.__all__, *columns.__all__]
