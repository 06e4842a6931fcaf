"""The specimen as tested: the campaign's palpation, fitted with each block's finite-element
twin, set beside its compression tests like for like (``comparison.csv``'s Instron-equivalent
columns, :mod:`palpbayes.campaign.instron`)."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .. import plots
from ..campaign.results import ResultsFolder
from ..io.tabular import parse_bool
from .format import wrap
from .layout import Page, text_lines

__all__ = ["twin_pages"]

_W = 150  # characters per line of the page text at 9 pt


def _blocks(res: ResultsFolder) -> str:
    s = res.summary
    rows = s[s["method"] == "bayes"] if "method" in s else s.iloc[:0]
    layers = sorted({str(v).split(",")[0] for v in rows.get("layer", []) if "block" in str(v)
                     or "cylinder" in str(v)})
    return ", ".join(layers)


def twin_pages(res: ResultsFolder) -> list[Page]:
    """One page when the comparison has the Instron-equivalent columns (a footprint was
    known), none otherwise."""
    cmp_ = res.comparison
    if cmp_ is None or cmp_.empty or "E_instron_pa" not in cmp_:
        return []
    bayes = cmp_[(cmp_["method"] == "bayes") & cmp_["E_instron_pa"].notna()]
    if bayes.empty:
        return []
    platens = str(bayes["platens"].dropna().iloc[0]) if bayes["platens"].notna().any() \
        else "unknown"
    ratio = (bayes["E_instron_pa"] / bayes["E_pa"]).to_numpy(float)
    covered = bayes["gt_in_instron_interval"].map(parse_bool) \
        if "gt_in_instron_interval" in bayes else None
    n_gt = int(covered.notna().sum()) if covered is not None else 0
    text = (
        f"Each trace was fitted with the finite-element twin of the block it was pressed into "
        f"({_blocks(res) or 'the manifest footprint'}), on its plate: an axisymmetric model "
        "of the block (the cylinder of equal footprint area) under the tip, its contact radius "
        "solved, so that E is the material's, not a half-space's or an infinitely wide "
        "layer's. A compression test does not read E either: between bonded platens the "
        "block's faces cannot expand and it reads c(nu)·E, c > 1, growing with nu and with the "
        "block's width over its height; between lubricated ones E. The diamonds are what a "
        "compression test "
        f"of a new specimen's block would read with the run's platens ({platens}"
        + ("; the interval spans lubricated to bonded" if platens == "unknown" else "")
        + f"; median E_instron/E = {np.nanmin(ratio):.3f}-{np.nanmax(ratio):.3f}): the "
        "number to set beside the Instron (grey band), like for like.")
    if n_gt:
        text += (f" It covers the Instron mean in {int(covered.sum())} of {n_gt} "
                 "material × tip groups.")

    def build(fig: Figure, text: str = text) -> None:
        text_lines(fig, [("t", ln) for ln in wrap(text, _W)], top=0.9, left=0.04, size=9.0)
        ax = fig.add_axes((0.08, 0.1, 0.86, 0.58))
        plots.plot_specimen_as_tested(cmp_, ax=ax)
    return [Page("The specimen as tested: palpation and compression like for like", build)]
