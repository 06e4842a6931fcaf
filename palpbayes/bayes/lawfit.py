"""A fit with a hyperelastic law: the exact mixture's draws as chains, and what the row says.

:func:`exact_law_chains` draws from the mixture over a law's free shape parameters and base
(:mod:`palpbayes.bayes.lawmix`); a concrete law model needs nothing of its own (its shape
function is the twin's table, :mod:`palpbayes.twin.hyper_shape`, and either engine fits it).
:func:`law_columns` are the row's ``law``, ``law_params`` and ``E_instron_law_pa`` (with its
interval): what a compression test of the block would read at the Instron's nominal strain,
the chord from 0 to that strain of the law's uniaxial curve
(:func:`palpbayes.material.chord_modulus`) over the posterior draws (each with its shape,
its Poisson ratio and E0 with the budget):

* lubricated platens: the closed form, c(shape, nu) = chord/E0, per draw;
* bonded platens (with a specimen): the block's hyperelastic twin between bonded platens
  (:func:`palpbayes.twin.solve_hyper_compression`, under a second a solve) at the fitted
  model's shape for each node of nu, its stress over the lubricated one interpolated per draw;
  NaN with a note where the twin does not converge to that strain;
* ``--platens unknown``: the interval spans both, as ``E_instron_pa``'s.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import FitError, GeometryError, InputError
from ..fitdata import FitData, ModelSpec
from ..intervals import central, hull
from ..material import chord_modulus, compression_stress
from .exact import sampled_coordinates
from .lawmix import LawPosterior, law_posterior
from .layer_fit import layer_coordinates
from .likelihood import TraceLikelihood
from .priors import TracePrior
from .sampler import ChainResult
from .start import Mode

__all__ = ["check_law_model", "exact_law_chains", "law_columns", "law_notes", "instron_law_draws",
           "LAW_COLUMNS", "law_parameters_text", "law_columns_of"]

#: ``summary.csv`` columns of a law fit (empty or NaN under the linear law).
LAW_COLUMNS = ("law", "law_params", "instron_strain", "E_instron_law_pa",
               "E_instron_law_lo_pa", "E_instron_law_hi_pa")


def exact_law_chains(data: FitData, prior: TracePrior, rng: np.random.Generator,
                     shape: tuple[int, int]):
    """Independent draws of the exact mixture of a law (:mod:`.lawmix`), shaped as ``shape``
    = (chains, draws), without a log posterior (each draw's shape is its component's).

    Returns
    -------
    chains, modes, like, mixture, extra
        The chains, the surface modes of the most probable component, a likelihood of the
        fitted model (its baseline for the checks), the :class:`~.lawmix.LawPosterior`, and
        the draws of ``E``, ``nu`` and each free shape parameter (``law_<name>``) shaped as
        the chains.
    """
    mix = law_posterior(data, prior)
    n = shape[0] * shape[1]
    d = mix.draws(rng, n)
    if "bond" in prior.names:
        theta = layer_coordinates(d, prior, rng)
    else:
        theta = sampled_coordinates(d, prior.names)
    samples = np.column_stack([theta[k] for k in prior.names]).reshape(*shape, len(prior.names))
    best = mix.components[int(np.argmax(mix.weights))].post
    modes = [Mode(z_surf=z, beta=np.full(2, np.nan), rss=np.nan, loglik=np.nan,
                  cov=np.full((3, 3), np.nan), lag1=np.nan, weight=w) for z, w in best.modes()]
    zs = best.z_summary()
    like = TraceLikelihood(replace(data, model=mix.best()), prior.noise,
                           baseline=prior.baseline, z_ref=prior.z_ref, z_center=zs.mean,
                           z_scale=zs.sd)
    chains = ChainResult(samples=samples, log_prob=None, tau=np.ones(samples.shape[-1]),
                         n_steps=mix.n_nodes, burn=0, thin=1, acceptance=1.0,
                         hit_cap=not mix.complete)
    extra = {k: v.reshape(shape) for k, v in d.items()
             if k in ("E", "nu") or k.startswith("law_")}
    return chains, modes, like, mix, extra


def check_law_model(model: ModelSpec, engine: str) -> None:
    """Raise :class:`~palpbayes.errors.InputError` for free shape parameters with the emcee
    engine (it would have to sample them through the table's piecewise interpolation, whose
    kinks at the nodes and holes where a node failed the exact mixture integrates exactly),
    and :class:`~palpbayes.errors.FitError` naming the finite elements' failure when a
    concrete law model has no shape at its table's depths (a node that did not converge)."""
    law = model.law
    if law is not None and law.free and engine != "exact":
        raise InputError(f"--law {law.name} mixes over its free shape parameters "
                         f"({', '.join(law.free)}), which only the exact engine integrates: "
                         "give --engine exact, or fix them with --law-shape NAME=VALUE")
    if law is None or not model.is_concrete or law.mode != "twin":
        return
    if np.all(np.isfinite(model.shape(np.array([model.law.depth])))):
        return
    from ..twin.hyper_shape import law_table

    table = law_table(model.law, model.tip, model.nu, model.thickness, model.specimen,
                      model.bases[0])[0]
    raise FitError(f"the {model.law.law.title} twin of {model.describe()} did not converge "
                   f"at the fitted depths: {'; '.join(table.notes) or 'no curve'}")


def _shape_values(model: ModelSpec, point: dict[str, float]) -> dict[str, float]:
    """Every shape parameter of ``model``'s law at the free parameters' ``point``."""
    values = {n: grid[0] for n, grid in model.law.nodes}
    values.update(point)
    return values


def _chord(model: ModelSpec, point: dict, nu: float, strain: float) -> float:
    law = model.law.law
    shape = _shape_values(model, point)
    nu = float(shape.get(law.nu_parameter, nu)) if law.nu_parameter else nu
    p = law.natural(1.0, shape, nu)
    return chord_modulus(law, p, 0.0, strain, nu) / law.E0(p, nu)


def instron_law_draws(E_total: np.ndarray, nu: np.ndarray, points: dict[str, np.ndarray],
                      model: ModelSpec, strain: float, nu_grid: np.ndarray) -> np.ndarray:
    """Draws [Pa] of the chord modulus from 0 to ``strain`` of the law's uniaxial curve
    between lubricated platens: each draw's E0 (``E_total``) times c(shape, nu) of its shape
    parameters (``points``: draws of each free one by name) and Poisson ratio ``nu``, c
    interpolated over ``nu_grid`` (a foam's nu is its shape's)."""
    E = np.ravel(E_total)
    nu = np.ravel(nu)
    names = sorted(points)
    keys = (np.column_stack([np.ravel(points[n]) for n in names]) if names
            else np.zeros((E.size, 0)))
    out = np.empty(E.size)
    grid = np.unique(np.asarray(nu_grid, dtype=float))
    for key in np.unique(keys, axis=0):
        rows = np.all(keys == key, axis=1) if names else np.ones(E.size, dtype=bool)
        point = dict(zip(names, (float(v) for v in key), strict=True))
        c = np.array([_chord(model, point, float(v), strain) for v in grid])
        out[rows] = E[rows] * (np.interp(nu[rows], grid, c) if grid.size > 1 else c[0])
    return out.reshape(np.shape(E_total))


def _bonded_ratio(model: ModelSpec, strain: float, nu_grid: np.ndarray
                  ) -> tuple[np.ndarray | None, str]:
    """(bonded/lubricated nominal stress at ``strain`` per node of ``nu_grid``, a note) of the
    fitted model's block: None without a specimen, or where the twin does not converge."""
    from ..twin import solve_hyper_compression

    block = model.specimen
    if block is None:
        return None, ""
    law = model.law.law
    shape = model.law.values()
    out = []
    for nu in nu_grid:
        nu = float(shape.get(law.nu_parameter, nu)) if law.nu_parameter else float(nu)
        p = law.natural(1.0, shape, nu)
        try:
            c = solve_hyper_compression(block.radius, block.height, law, p, nu, "bonded",
                                        np.array([strain]), model.law.resolution)
        except (FitError, GeometryError) as exc:
            return None, (f"E_instron_law is for lubricated platens: the block's twin between "
                          f"bonded platens did not converge to {100 * strain:g} % strain "
                          f"({str(exc).split(':')[0]})")
        out.append(float(c.stress[0] / compression_stress(law, p, np.array([strain]), nu)[0]))
    return np.array(out), ""


def law_parameters_text(mixture: LawPosterior | None, model: ModelSpec) -> str:
    """``law_params``: each shape parameter's value (fixed) or posterior median with its 90 %
    interval, and the probability of each finite-element node of a free one, e.g.
    ``'alpha_1 7.9 [6.1, 9.4] (p: -10 0, -1.25 0, 7.5 0.93, 16.25 0.07, 25 0); nu 0.1'``."""
    law = model.law
    parts = []
    summary = {} if mixture is None else mixture.parameter_summary()
    nodes = {} if mixture is None else mixture.node_weights()
    values = dict(law.point or ())
    for name, grid in law.nodes:
        if name in summary:
            med, lo, hi = summary[name]
            p = ", ".join(f"{x:.4g} {w:.2f}" for x, w in nodes.get(name, []))
            parts.append(f"{name} {med:.4g} [{lo:.4g}, {hi:.4g}] (p: {p})")
        else:
            parts.append(f"{name} {values.get(name, grid[0]):.4g}")
    return "; ".join(parts) or "none (no shape parameters)"


def law_columns_of(cols: dict, widen: tuple[float, float] = (1.0, 1.0)) -> dict:
    """The row's law columns from a result's stored ones (the linear law's when empty), the
    ends of ``E_instron_law``'s interval widened as E's full interval is over its budget
    interval (``widen`` = (full lo / budget lo, full hi / budget hi), the model form's)."""
    out = {"law": "linear", "law_params": "", "instron_strain": math.nan,
           "E_instron_law_pa": math.nan, "E_instron_law_lo_pa": math.nan,
           "E_instron_law_hi_pa": math.nan}
    out.update({k: v for k, v in cols.items() if k in LAW_COLUMNS})
    out["E_instron_law_lo_pa"] *= widen[0]
    out["E_instron_law_hi_pa"] *= widen[1]
    return out


def law_columns(post: dict, data: FitData, best: ModelSpec, mixture: LawPosterior | None,
                E_total: np.ndarray, nu: np.ndarray, platens: str, nu_grid: np.ndarray
                ) -> tuple[dict, list[str]]:
    """The row's law columns (:data:`LAW_COLUMNS`, module docstring) and notes; empty
    columns under the linear law.  ``E_total`` [Pa] and ``nu`` are the budget's draws (a
    foam's nu its posterior's), ``nu_grid`` the budget's nodes of nu, ``platens`` as
    ``E_instron_pa``'s."""
    model = data.model
    if model.law is None:
        return law_columns_of({}), []
    strain = model.law.instron_strain
    points = {n: post[f"law_{n}"] for n in model.law.free if f"law_{n}" in post}
    if len(points) < len(model.law.free):  # a concrete fit: the best model's point
        points = {n: np.full(np.shape(E_total), v) for n, v in (best.law.point or ())}
    lub = instron_law_draws(E_total, nu, points, best, strain, nu_grid)
    ratio, note = (None, "") if platens == "lubricated" else _bonded_ratio(
        best, strain, np.unique(np.asarray(nu_grid, dtype=float)))
    notes = [note] if note else []
    if ratio is None:
        lo, hi = central(lub)
        mid = float(np.median(lub))
        used = "lubricated"
    else:
        grid = np.unique(np.asarray(nu_grid, dtype=float))
        bond = lub * (np.interp(np.ravel(nu), grid, ratio).reshape(np.shape(lub))
                      if grid.size > 1 else ratio[0])
        used = platens
        if platens == "lubricated":
            pool, (lo, hi) = lub, central(lub)
        elif platens == "bonded":
            pool, (lo, hi) = bond, central(bond)
        else:
            pool = np.concatenate([np.ravel(lub), np.ravel(bond)])
            lo, hi = central(lub)[0], central(bond)[1]
        mid = float(np.median(pool))
    lo, hi = hull((float(lo), float(hi)), (mid, mid))
    if used != platens and platens != "lubricated" and not note:
        notes.append("E_instron_law is for lubricated platens: bonded ones need the block "
                     "(--specimen)")
    cols = {"law": model.law.name, "law_params": law_parameters_text(mixture, model),
            "instron_strain": strain, "E_instron_law_pa": mid, "E_instron_law_lo_pa": lo,
            "E_instron_law_hi_pa": hi}
    return cols, notes


def law_notes(mixture: LawPosterior | None, data: FitData, best: ModelSpec) -> list[str]:
    """What a law fit says besides its numbers: the geometry the law was solved on, nodes
    that did not converge, a free parameter piled at a bound.  No '; ' inside a note."""
    model = data.model
    if model.law is None:
        return []
    notes = []
    if not model.has_layer:
        notes.append(f"the {model.law.law.title} law on a half-space: its twin is a bonded "
                     "cylinder 40 contact radii deep and 160 wide with the bottom effect "
                     "divided out (docs/reference.md, Finite strain in the fits)")
    elif model.specimen is None:
        notes.append(f"the {model.law.law.title} law on a layer of the known thickness: its "
                     "twin is a cylinder of that height at least 10 contact radii and 4 "
                     "heights wide")
    if mixture is None:
        return notes
    if mixture.failed:
        notes.append(f"the {model.law.law.title} twin did not converge at "
                     f"{len(mixture.failed)} shape point(s) (e.g. {mixture.failed[0]}), which "
                     "carry no weight")
    for name, nodes in mixture.node_weights().items():
        if nodes[0][1] > 0.5 or nodes[-1][1] > 0.5:
            edge = nodes[0] if nodes[0][1] > 0.5 else nodes[-1]
            notes.append(f"{name}'s posterior piles at the end of its range ({edge[0]:g}, p "
                         f"{edge[1]:.2f}): the data want a value beyond it")
    return notes
