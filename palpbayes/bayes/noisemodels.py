"""The likelihood's noise models, one registry (as :mod:`palpbayes.contact` has the tips).

Each model names the extra parameter it samples beside sigma and whether the exact engine
(:mod:`palpbayes.bayes.exact`, the online estimator and the maps' per-point fits, which
integrate E and z_surf on a grid) has it.  Every option, choice list and fallback reads this
table; a new model is a row here plus its log-likelihood in :mod:`palpbayes.bayes.likelihood`
(and in :mod:`palpbayes.bayes.exact` if the exact engine is to have it).

* ``gaussian``: white Gaussian noise of sd sigma (the paper's sensor, design.md §3).
* ``ar1``: Gaussian noise correlated from sample to sample, e_i = phi·e_(i−1) + eta_i, the
  conditional likelihood (Box & Jenkins 1976, §7.1); phi sampled on (−1, 1).
* ``student``: Student-t noise of scale sigma and nu_t degrees of freedom, log nu_t sampled
  (Lange, Little & Taylor 1989, J. Am. Stat. Assoc. 84:881): robust to spikes.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import InputError

__all__ = ["NoiseModel", "NOISE_REGISTRY", "NOISE_MODELS", "EXACT_NOISE_MODELS",
           "get_noise_model", "exact_noise"]


@dataclass(frozen=True)
class NoiseModel:
    """One noise model of the likelihood.

    Parameters
    ----------
    name
        Its option value (``--noise NAME``).
    extra
        The parameter sampled beside sigma (None: sigma alone).
    exact
        Whether the exact engine integrates it (else emcee alone samples it).
    description
        One line for help texts.
    """

    name: str
    extra: str | None
    exact: bool
    description: str


#: Every noise model, by name.
NOISE_REGISTRY: dict[str, NoiseModel] = {m.name: m for m in (
    NoiseModel("gaussian", None, True, "white Gaussian noise"),
    NoiseModel("ar1", "phi", True, "Gaussian noise correlated from sample to sample, AR(1)"),
    NoiseModel("student", "log_nu_t", False, "Student-t noise, robust to spikes"),
)}
#: Their names, in the order help texts list them.
NOISE_MODELS: tuple[str, ...] = tuple(NOISE_REGISTRY)
#: The names the exact engine has.
EXACT_NOISE_MODELS: tuple[str, ...] = tuple(n for n, m in NOISE_REGISTRY.items() if m.exact)


def get_noise_model(name: str) -> NoiseModel:
    """The registered model ``name``; :class:`~palpbayes.errors.InputError` naming the choices
    otherwise."""
    try:
        return NOISE_REGISTRY[name]
    except KeyError:
        raise InputError(f"unknown noise model {name!r}; use one of "
                         f"{', '.join(NOISE_MODELS)}") from None


def exact_noise(name: str) -> str:
    """The model the exact engine uses for ``name``: ``name`` itself when it has it, else
    ``gaussian`` (the start of an emcee run, or an alternative of the model form)."""
    return name if get_noise_model(name).exact else "gaussian"
