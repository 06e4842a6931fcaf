"""The paper's gap in words: one verdict per tip from :func:`palpbayes.gap.gap_table`.

Every claim a sentence makes is a column of the table, so that the tests pin its physics:
``thickness_*`` (a layer only stiffens), ``width_*`` (free sides soften), ``platens_bonded_pct``
(bonded platens make the Instron read stiffer, the ratio lower), ``sharper_tip_pct`` and
``blunter_tip_pct`` (a sharper tip reads softer, a blunter one stiffer), ``strain_*`` (how far
each test strains the foam).
"""

from __future__ import annotations

import pandas as pd

__all__ = ["gap_verdicts", "strain_paragraph"]


def _range(lo: float, hi: float, sign: str = "+") -> str:
    return (f"{lo:{sign}.0f} %" if round(lo) == round(hi)
            else f"{lo:{sign}.0f} to {hi:{sign}.0f} %")


def _span(g: pd.DataFrame, *cols: str, sign: str = "+") -> str:
    values = pd.concat([g[c] for c in cols])
    return _range(values.min(), values.max(), sign)


def _mm(values: pd.Series) -> str:
    lo, hi = 1e3 * values.min(), 1e3 * values.max()
    return f"{lo:.3g} mm" if round(lo, 3) == round(hi, 3) else f"{lo:.3g}-{hi:.3g} mm"


def _plain(lo: float, hi: float, digits: int = 2) -> str:
    a, b = f"{lo:.{digits}f}", f"{hi:.{digits}f}"
    return a if a == b else f"{a}-{b}"


def gap_verdicts(table: pd.DataFrame) -> dict[str, str]:
    """One plain paragraph per tip: what the block as tested (thickness, width, the Instron's
    platens, nu, Hertz, compliance) predicts against the published ratios, how many it
    explains, and what the rest needs."""
    out = {}
    for tip, g in table.groupby("tip", sort=False):
        n, n_ok = len(g), int(g["explained"].sum())
        nu_fit = _plain(g["nu_fit"].min(), g["nu_fit"].max())
        nu_true = _plain(g["nu_true_lo"].min(), g["nu_true_hi"].max())
        width = _mm(pd.concat([g["length_m"], g["width_m"]]))
        head = (
            f"{tip}: the paper reads {_span(g, 'observed_pct')} against its Instron. A layer "
            f"of the block's thickness alone predicts "
            f"{_span(g, 'thickness_free_pct', 'thickness_bonded_pct')} (free to bonded base, "
            f"nu {nu_fit}); the block's {width} width changes that by "
            f"{_span(g, 'width_free_pct', 'width_bonded_pct')}, and bonded platens "
            f"make the Instron read stiffer, moving the ratio by "
            f"{_span(g, 'platens_bonded_pct')}. With nu {nu_true} and compliance, everything "
            f"modelled predicts {_range(g['predicted_lo_pct'].min(), g['predicted_hi_pct'].max())}"
            f": {n_ok} of {n} published values lie inside (the infinite layer with an exact "
            f"Instron: {int(g['explained_layer'].sum())}; {int(g['consistent'].sum())} of {n} "
            "within their sd).")
        below = g["observed_pct"] < g["predicted_lo_pct"]
        softer_than_any_block = (
            below.all() and (g["observed_pct"] < 0).all() and (g["predicted_lo_pct"] > 0).all()
            and g["radius_factor"].notna().all() and (g["sharper_tip_pct"] < 0).all()
            and (g["blunter_tip_pct"] > 0).all())
        if n_ok == n:
            rest = (" The specimen as tested explains the paper's errors: the plate's bottom "
                    f"effect, less the free sides of a {width} block and the friction at the "
                    "Instron's platens.")
        elif softer_than_any_block:
            rest = (
                " Every elastic block reads this tip stiffer, not softer: the softer published "
                "values need a tip sharper than its nominal profile, "
                f"R_true/R = {_plain(g['radius_factor'].min(), g['radius_factor'].max())} on "
                "the free block (Hertz: E_read/E = sqrt(R_true/R); tested here, a tip of R/2 "
                f"reads {_span(g, 'sharper_tip_pct')} and one of 2R "
                f"{_span(g, 'blunter_tip_pct')}), e.g. a profile printed as z = r²/R where "
                "z = r²/(2R) was assumed (R_true = R/2). A blunter or wider tip reads stiffer: "
                "the wrong way.")
        else:
            low = g[below & ~g["explained"]]
            high = g[(g["observed_pct"] > g["predicted_hi_pct"]) & ~g["explained"]]
            parts = []
            if len(low):
                gaps = low["predicted_lo_pct"] - low["observed_pct"]
                parts.append(f"{' and '.join(low['material'])} read "
                             f"{' and '.join(f'{v:.1f}' for v in gaps)} points below the "
                             "prediction's lower end")
            if len(high):
                gaps = high["observed_pct"] - high["predicted_hi_pct"]
                parts.append(f"{' and '.join(high['material'])} read "
                             f"{' and '.join(f'{v:.1f}' for v in gaps)} points above the "
                             "prediction's upper end")
            rest = (" " + "; ".join(parts) + "." if parts
                    else " Part of the error is left unexplained.")
        strain = (
            " Not modelled: the foam's nonlinearity, which both tests reach beyond the ~5 % "
            f"strain where foams stay linear (the Instron's 5 mm is "
            f"{_span(g, 'strain_instron_pct', sign='')} nominal strain, the palpation "
            f"{_span(g, 'strain_palpation_pct', sign='')} of the thickness")
        if g["strain_contact_pct"].notna().all():
            strain += (f", a contact strain of {_span(g, 'strain_contact_pct', sign='')}"
                       " by Tabor's 0.2·a/R")
        out[str(tip)] = head + rest + strain + "), and its rate."
    return out


def strain_paragraph(verdicts: dict, strain: pd.DataFrame, gap: pd.DataFrame) -> str:
    """The gap at finite strain in words (:func:`palpbayes.gap_strain.strain_verdicts` of the
    shipped table, against :func:`palpbayes.gap.gap_table`): what softening and stiffening do
    to the ratios, the single law per foam that explains most, and whether finite strain tells
    the paraboloid from the sphere."""
    soft = strain[(strain["law"] == "hyperfoam") & (strain["nu0"] < 0.2)
                  & (strain["alpha"] >= 5)]["strain_factor"]
    nh = 100.0 * (1.0 - strain[strain["law"] == "neo-hookean"]["strain_factor"])
    per = "; ".join(f"{m}: {name}, {n} of {k} tips"
                    for m, (name, n, k) in verdicts["best"].items())
    g = gap.set_index(["material", "tip"])["observed_pct"].unstack("tip")
    behind = g["sphere"] - g["paraboloid"]
    need = gap.loc[gap["tip"] == "paraboloid", "radius_factor"]
    return (
        "At finite strain (the blocks' finite-strain twins; the Instron's least-squares line "
        "over its whole 5 mm): a foam that softens into a plateau (hyperfoam, nu 0.1, alpha "
        f"5-20) reads softer in the Instron than under the tips and raises every ratio by "
        f"{_range(100 * (soft.min() - 1), 100 * (soft.max() - 1))}, widening the gap; a "
        "compressible neo-Hookean solid (nu 0.3), whose nominal stress stiffens in "
        f"compression, lowers every ratio by {_range(nh.min(), nh.max(), '')}. The linear "
        f"blocks explain {verdicts['explained_linear']} of 9 published ratios; with one law "
        f"per foam for all three tips, {verdicts['best_total']} of 9 lie in the ranges, each "
        f"tip free to take its own base, nu, compliance and platens ({per}). Finite strain "
        "does not tell the paraboloid from the sphere: on one block, base and law the "
        "paraboloid's factor is "
        f"{_plain(verdicts['paraboloid_over_sphere_min'], verdicts['paraboloid_over_sphere_max'])}"
        f" times the sphere's, while its published values lie {behind.min():.0f} to "
        f"{behind.max():.0f} points below the sphere's on the same blocks: that difference "
        "needs a tip sharper than nominal, as the paper's own half-radius convention would "
        f"make it (R_true/R = 0.5 against the {_plain(need.min(), need.max())} needed).")
