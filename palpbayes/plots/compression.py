"""Compression tests: each test's stress-strain curve with the line its modulus is the slope of."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
from matplotlib import rcParams
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ..units import format_pressure
from .style import KPA, METHOD_COLORS

if TYPE_CHECKING:
    from ..io.instron import CompressionTest

__all__ = ["plot_compression_tests"]

#: The measured curve is drawn up to this multiple of the panel's largest fitted strain.
CURVE_REACH = 2.0


def plot_compression_tests(tests: Sequence[CompressionTest], per_file: pd.DataFrame, *,
                           fig: Figure | None = None) -> Figure:
    """One panel per material: each test's loading curve, engineering stress [kPa] against
    measured strain [%], and its fitted line sigma = E·(eps - eps0) over the points it was
    fitted to (``strain_lo`` to ``strain_hi``).

    Parameters
    ----------
    tests
        The tests, in the order of ``per_file``'s rows (as
        :func:`palpbayes.compression.analyse` read them).
    per_file
        ``groundtruth.csv``: ``file``, ``material``, ``E_pa`` [Pa], ``strain_lo``,
        ``strain_hi`` and ``strain_toe`` [-] per test.
    fig
        Figure to draw on (default: a new one, 4.5 in wide per panel).

    Returns
    -------
    Figure
        Each curve's line has the gid ``"curve <file>"``, each fitted line ``"fit <file>"``.
        The curve is drawn to :data:`CURVE_REACH` times the panel's largest fitted strain, so
        that the window stays readable on a test compressed far beyond it.
    """
    if len(tests) != len(per_file):
        raise ValueError(f"{len(tests)} test(s) for {len(per_file)} row(s) of per_file")
    materials = list(dict.fromkeys(per_file["material"].astype(str)))
    if fig is None:
        fig = Figure(figsize=(4.5 * max(len(materials), 1), 4.0), layout="constrained")
    axes = fig.subplots(1, max(len(materials), 1), squeeze=False)[0]
    colours = rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, material in zip(axes, materials, strict=False):
        mine = [(t, r) for t, (_, r) in zip(tests, per_file.iterrows(), strict=True)
                if str(r["material"]) == material]
        reach = CURVE_REACH * max(float(r["strain_hi"]) for _, r in mine)
        for i, (test, r) in enumerate(mine):
            colour = colours[i % len(colours)]
            eps, sig = test.strain, test.stress_pa
            k = int(np.argmax(eps))  # the loading branch, as the fit uses it
            eps, sig = eps[: k + 1], sig[: k + 1]
            keep = eps <= reach
            ax.plot(100 * eps[keep], KPA * sig[keep], lw=0.8, color=colour, alpha=0.8,
                    gid=f"curve {r['file']}", rasterized=bool(keep.sum() > 2000))
            x = np.array([r["strain_lo"], r["strain_hi"]], dtype=float)
            ax.plot(100 * x, KPA * r["E_pa"] * (x - r["strain_toe"]), lw=2.2, color=colour,
                    gid=f"fit {r['file']}")
        E = np.array([r["E_pa"] for _, r in mine], dtype=float)
        spread = f" ± {format_pressure(E.std(ddof=1), 2)}" if E.size > 1 else ""
        ax.set_title(f"{material}: E {format_pressure(E.mean(), 4)}{spread} ({E.size} "
                     f"test{'s' if E.size != 1 else ''})", fontsize="medium")
        ax.set_xlabel("engineering strain [%]")
        ax.set_ylabel("engineering stress [kPa]")
        ax.set_xlim(left=0)
        ax.set_ylim(bottom=0)
    axes[0].legend(handles=[
        Line2D([], [], lw=0.8, color=METHOD_COLORS["data"], label="measured (loading)"),
        Line2D([], [], lw=2.2, color=METHOD_COLORS["data"],
               label="fitted line: slope E over its window")],
        loc="upper left", fontsize="x-small", frameon=False)
    return fig
