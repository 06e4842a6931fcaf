"""Progress bars on stderr, one definition for every long loop of the package (fits of a
campaign, tables of the twin, hyperelastic fits of compression tests): tqdm, shown when stderr
is a terminal unless asked."""

from __future__ import annotations

import sys

__all__ = ["progress_bar"]


def progress_bar(total: int, progress: bool | None, *, initial: int = 0,
                 desc: str = "fitting", unit: str = "trace"):
    """A tqdm bar on stderr; ``progress`` None shows it when stderr is a terminal."""
    from tqdm.auto import tqdm

    show = sys.stderr.isatty() if progress is None else bool(progress)
    return tqdm(total=total, initial=initial, disable=not show, desc=desc, unit=unit,
                file=sys.stderr, dynamic_ncols=True)
