"""The command line's material-law options (``fit`` and ``report``): ``--law``,
``--law-shape``, ``--law-mesh`` and ``--instron-strain``, and what they become
(:class:`~palpbayes.campaign.options.LawOptions`).  The online estimator and the maps keep the
linear law (``replay``, ``follow``, ``map`` have no ``--law``)."""

from __future__ import annotations

import argparse

from ..material import law_names
from ..twin.hyper_shape import INSTRON_STRAIN, LAW_MESHES

__all__ = ["add_law_options", "law_options_from_args"]


def add_law_options(p: argparse.ArgumentParser) -> None:
    """The group ``material law (finite strain)`` of ``fit`` and ``report``."""
    g = p.add_argument_group(
        "material law (finite strain: docs/reference.md, 'Finite strain in the fits')")
    g.add_argument("--law", choices=law_names(), default="linear", metavar="linear|NAME",
                   help="the material law of the Bayesian fit: linear (the paper's, default) "
                        f"or a hyperelastic law at finite strain ({', '.join(law_names()[1:])}); "
                        "E is then its small-strain modulus E0, and each row carries "
                        "E_instron_law, what a compression test would read")
    g.add_argument("--law-shape", metavar="NAME=VALUE|NAME=LO:HI[,...]",
                   help="fix a shape parameter of the law (alpha_1=8) or narrow its range "
                        "(alpha_1=4:12); the others are integrated over their ranges (--engine "
                        "exact, at most two); a foam's nu is fixed by --nu when given")
    g.add_argument("--law-mesh", choices=LAW_MESHES, default="default",
                   help="the finite-strain twin's mesh (coarse: 3-4x faster, within 0.1-0.4 %% "
                        "of default)")
    g.add_argument("--instron-strain", type=float, default=INSTRON_STRAIN, metavar="EPS",
                   help="compressive strain of E_instron_law's chord from 0 (default "
                        f"{INSTRON_STRAIN:g}: the paper's 5 mm of 20-30 mm)")


def law_options_from_args(args: argparse.Namespace) -> dict:
    """:func:`palpbayes.campaign.options.fit_options`' law keywords from the parsed arguments."""
    return {"law": getattr(args, "law", "linear"), "law_shape": getattr(args, "law_shape", None),
            "law_mesh": getattr(args, "law_mesh", "default"),
            "instron_strain": getattr(args, "instron_strain", INSTRON_STRAIN)}
