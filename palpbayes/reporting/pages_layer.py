"""Finite-thickness pages: the campaign's half-space and layer estimates side by side, and why
the paper's robot reads stiffer than its Instron (``gap.csv``, :mod:`palpbayes.gap`)."""

from __future__ import annotations

from matplotlib.figure import Figure

from .. import plots
from ..campaign.results import ResultsFolder
from ..gap import gap_verdicts
from ..gap_strain import strain_verdicts
from ..gap_text import strain_paragraph
from .format import wrap
from .layout import Page, text_height, text_lines

_W = 150  # characters per line of the page text at 9 pt
_W_SMALL = 185  # at 8 pt


def layer_pages(res: ResultsFolder) -> list[Page]:
    """The campaign's estimates with and without the layer (when its comparison has the
    layer's columns), then the paper's gap decomposed (when ``gap.csv`` is there)."""
    pages = []
    cmp_ = res.comparison
    if (cmp_ is not None and not cmp_.empty and "E_free_pa" in cmp_
            and cmp_["E_free_pa"].notna().any()):
        bayes = cmp_[cmp_["method"] == "bayes"]
        pb = bayes["p_bonded"].dropna() if "p_bonded" in bayes else bayes.iloc[:0]
        text = (
            "The paper fitted its specimens as half-spaces (least squares, orange squares: "
            "the paper's method, kept as the baseline). Its blocks are 20-30 mm thick under "
            "tips of 10-11.7 mm pressed 10 % deep, so the plate under them carries load and a "
            "half-space reading is too stiff. The bars show the same least-squares fits read "
            "as a layer of the block's thickness, free on its plate to bonded to it; the "
            "Bayesian model (blue) includes the layer with its base unknown (the data weigh "
            "the two) and says for a new specimen where E lies.")
        if len(pb):
            text += (f" Posterior probability of a bonded base per group: "
                     f"{', '.join(f'{p:.2f}' for p in pb)} (a flat punch's curve cannot "
                     "tell the bases apart: 0.5).")

        def build(fig: Figure, text: str = text) -> None:
            text_lines(fig, [("t", ln) for ln in wrap(text, _W)], top=0.9, left=0.04,
                        size=9.0)
            ax = fig.add_axes((0.08, 0.1, 0.86, 0.62))
            plots.plot_halfspace_vs_layer(cmp_, ax=ax)
        pages.append(Page("Finite thickness: half-space and layer", build))
    if res.gap is not None and not res.gap.empty:
        verdicts = gap_verdicts(res.gap)
        lines = [("t", ln) for ln in wrap(
            "The paper's robot estimates against its Instron (the published numbers), beside "
            "what palpbayes' models predict its two tests read on elastic blocks of the "
            "paper's geometry with the Instron's E: the 50 x 50 mm block as tested, its "
            "finite-element twin on its plate (free to bonded base), compressed between "
            "lubricated or bonded platens, the foam's nu (0.1-0.35 against the 0.3 assumed), "
            "series compliance (0-2 µm/N), Hertz for the sphere. Foam nonlinearity: the next "
            "page (finite strain); not modelled: rate.", _W_SMALL)]
        for v in verdicts.values():
            lines += [("", "")] + [("t", ln) for ln in wrap(v, _W_SMALL)]

        def build_gap(fig: Figure, lines=lines) -> None:
            # the text above the footer, the chart above the text
            text_top = max(0.45, 0.05 + text_height(lines, size=8.0, left=0.04))
            ax = fig.add_axes((0.08, text_top + 0.11, 0.86, 0.91 - text_top - 0.11))
            plots.plot_gap(res.gap, ax=ax)
            text_lines(fig, lines, top=text_top, left=0.04, size=8.0)
        pages.append(Page("Why does the robot read stiffer than the Instron?", build_gap))
    if res.gap is not None and not res.gap.empty and res.gap_strain is not None \
            and not res.gap_strain.empty:
        text = strain_paragraph(strain_verdicts(res.gap, res.gap_strain), res.gap_strain,
                                res.gap)
        strain_lines = [("t", ln) for ln in wrap(text, _W_SMALL)]

        def build_strain(fig: Figure, lines=strain_lines) -> None:
            text_top = max(0.35, 0.05 + text_height(lines, size=8.0, left=0.04))
            ax = fig.add_axes((0.08, text_top + 0.11, 0.86, 0.91 - text_top - 0.11))
            plots.plot_strain_factors(res.gap_strain, ax=ax)
            text_lines(fig, lines, top=text_top, left=0.04, size=8.0)
        pages.append(Page("The gap at finite strain: foams that soften or stiffen",
                          build_strain))
    return pages
