"""The groups of a fit's arviz InferenceData as numpy arrays: built without arviz or xarray,
turned into an ``InferenceData`` on first use, written to netCDF in arviz's layout.

A fit (``palpbayes fit``, :func:`palpbayes.fit`) needs its draws as numpy arrays, their
diagnostics (:mod:`palpbayes.bayes.diagnostics`) and a posterior file; building an arviz
``InferenceData`` on the way imported arviz (and with it matplotlib), and xarray's
``Variable``, then ``to_netcdf``, imported dask.array and distributed (xarray looks for dask
arrays and dask's scheduler whenever dask is installed): ~2-3 s of a fit of one curve
(issue 59).  :class:`PosteriorData` holds what ``az.from_dict`` took — the groups' arrays,
each group's own attributes, the InferenceData's — and

* :meth:`PosteriorData.to_inference_data` makes the same ``InferenceData`` as before (arviz's
  ``from_dict``, then each group's attributes), when a user asks for it
  (:attr:`palpbayes.bayes.BayesResult.idata`, :attr:`palpbayes.Fit.posterior`);
* :meth:`PosteriorData.to_netcdf` writes the file ``InferenceData.to_netcdf(engine=
  "h5netcdf")`` wrote, with h5netcdf directly: the InferenceData's attributes on the root
  group, one netCDF group per arviz group with its attributes (``created_at``,
  ``arviz_version``, then the group's own; arviz 0.2x copies the InferenceData's attributes
  onto ``observed_data`` and ``constant_data``), dimension coordinates ``chain``, ``draw``
  (sample groups) and ``<name>_dim_<i>`` (int64, 0-based), float variables with
  ``_FillValue`` NaN, every numeric variable gzip-compressed.  ``arviz.from_netcdf`` reads it
  back identical (``tests/unit/test_posterior_data.py``).
"""

from __future__ import annotations

import datetime
import os
import warnings
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.atomic import write_with

__all__ = ["Group", "PosteriorData", "SAMPLE_GROUPS", "DATA_GROUPS"]

#: Groups whose variables have the dimensions (chain, draw, ...).
SAMPLE_GROUPS = ("posterior", "sample_stats")
#: Groups of data, each axis a dimension of its own (``<name>_dim_<i>``).
DATA_GROUPS = ("observed_data", "constant_data")


@dataclass
class Group(Mapping):
    """One group: variable name -> numpy array, and the group's own attributes (those it has
    besides arviz's ``created_at`` and ``arviz_version``).  Reads like an xarray Dataset for
    what a fit needs: ``group[name]``, ``name in group``, ``group.attrs``."""

    data: dict[str, np.ndarray]
    attrs: dict = field(default_factory=dict)

    def __getitem__(self, name: str) -> np.ndarray:
        return self.data[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self.data)

    def __len__(self) -> int:
        return len(self.data)


def _arviz_version() -> str:
    """The installed arviz's version, without importing arviz."""
    try:
        return metadata.version("arviz")
    except metadata.PackageNotFoundError:  # pragma: no cover - arviz is a dependency
        return "unknown"


@dataclass
class PosteriorData:
    """A fit's InferenceData as numpy arrays (module docstring).

    Attributes
    ----------
    posterior
        The draws, each (chain, draw, ...).
    sample_stats
        ``lp``, the log posterior (chain, draw), or None.
    observed_data, constant_data
        The fitted force and heights, or None.
    attrs
        The InferenceData's attributes (``az.from_dict(attrs=...)``).
    created_at
        ISO time (UTC) the draws were made: each group's ``created_at``.
    """

    posterior: Group
    sample_stats: Group | None = None
    observed_data: Group | None = None
    constant_data: Group | None = None
    attrs: dict = field(default_factory=dict)
    created_at: str = field(
        default_factory=lambda: datetime.datetime.now(datetime.UTC).isoformat())

    @classmethod
    def from_dicts(cls, posterior: dict[str, np.ndarray],
                   sample_stats: dict[str, np.ndarray] | None = None,
                   observed_data: dict[str, np.ndarray] | None = None,
                   constant_data: dict[str, np.ndarray] | None = None,
                   attrs: dict | None = None) -> PosteriorData:
        """The groups from dictionaries of arrays, as ``az.from_dict`` takes them.

        Raises
        ------
        InputError
            A sample group's variable has fewer than two axes (chain, draw).
        """
        def group(d: dict | None) -> Group | None:
            return None if d is None else Group({k: np.asarray(v) for k, v in d.items()})

        out = cls(posterior=group(posterior), sample_stats=group(sample_stats),
                  observed_data=group(observed_data), constant_data=group(constant_data),
                  attrs=dict(attrs or {}))
        for name in SAMPLE_GROUPS:
            for var, x in (getattr(out, name) or {}).items():
                if x.ndim < 2:
                    raise InputError(f"{name}.{var}: draws need the axes (chain, draw, ...), "
                                     f"got shape {x.shape}")
        return out

    def group_names(self) -> list[str]:
        """The groups present, in arviz's order."""
        return [g for g in (*SAMPLE_GROUPS, *DATA_GROUPS) if getattr(self, g) is not None]

    def group_attrs(self, name: str) -> dict:
        """All the attributes of the group ``name`` as arviz 0.2x's ``from_dict`` gives them
        (``created_at``, ``arviz_version``, the InferenceData's for a data group), then the
        group's own."""
        out = {"created_at": self.created_at, "arviz_version": _arviz_version()}
        if name in DATA_GROUPS:
            out.update(self.attrs)
        out.update(getattr(self, name).attrs)
        return out

    # ----------------------------------------------------------------- arviz
    def to_inference_data(self):
        """The arviz ``InferenceData`` (``az.from_dict``, then each group's attributes;
        imports arviz)."""
        from .diagnostics import import_arviz

        az = import_arviz()
        groups = {g: dict(getattr(self, g).data) for g in self.group_names()}
        with warnings.catch_warnings():
            # heavy thinning of a short chain can leave fewer draws than walkers: fine for us
            warnings.filterwarnings("ignore", message="More chains", category=UserWarning)
            idata = az.from_dict(**groups, attrs=dict(self.attrs))
        for g in self.group_names():
            ds = getattr(idata, g)
            ds.attrs["created_at"] = self.created_at
            ds.attrs.update(getattr(self, g).attrs)
        return idata

    # ----------------------------------------------------------------- netCDF
    def to_netcdf(self, path: str | os.PathLike) -> Path:
        """Write the groups in the layout of ``InferenceData.to_netcdf`` (h5netcdf engine,
        compressed) atomically; return the path.  Imports h5netcdf, not arviz, xarray or
        dask."""
        return write_with(self._write, path, suffix=".nc")

    def _write(self, path: Path) -> None:
        import h5netcdf

        with h5netcdf.File(str(path), "w") as f:
            for key, value in self.attrs.items():
                f.attrs[key] = value
            for name in self.group_names():
                _write_group(f.create_group(name), getattr(self, name),
                             self.group_attrs(name), name in SAMPLE_GROUPS)


def _dims(name: str, shape: tuple[int, ...], sample: bool) -> tuple[str, ...]:
    """arviz's dimension names: (chain, draw, <name>_dim_0, ...) or (<name>_dim_0, ...)."""
    lead = ("chain", "draw") if sample else ()
    return lead + tuple(f"{name}_dim_{i}" for i in range(len(shape) - len(lead)))


def _write_group(g, group: Group, attrs: dict, sample: bool) -> None:
    """One arviz group into the h5netcdf group ``g`` (as xarray writes a Dataset)."""
    for key, value in attrs.items():
        g.attrs[key] = value
    dims: dict[str, int] = {}
    for name, x in group.items():
        dims.update(zip(_dims(name, x.shape, sample), x.shape, strict=True))
    g.dimensions = dims
    for dim, size in dims.items():  # the dimension coordinates 0, 1, ...
        g.create_variable(dim, (dim,), data=np.arange(size, dtype=np.int64),
                          compression="gzip")
    for name, x in group.items():
        floating = x.dtype.kind == "f"
        g.create_variable(name, _dims(name, x.shape, sample), data=x,
                          fillvalue=np.nan if floating else None,
                          compression="gzip" if x.dtype.kind in "biufcS" else None)
