"""One specimen palpated at several speeds, pooled in a campaign run: ``rheology_pooled.csv``.

``palpbayes fit MANIFEST --rheology power-law`` fits every trace into ``DIR/rheology.csv``
(:mod:`~palpbayes.rheology.results`) and pools the power laws of the traces of one group into
one posterior of (E0*, alpha) (:func:`~palpbayes.rheology.pool.pool_rheology`): the apparent
modulus of a ramp scales as speed^alpha, so traces at several speeds pin alpha down.

**Groups** are manifest rows with the same ``material``, ``specimen`` and tip: the ``tip``
kind and every tip-size column (``radius_m``, ``half_angle_deg``, ``profile_c``,
``profile_n``; :data:`GROUP_COLUMNS`).  An empty ``specimen`` cell groups by material × tip.
The speed is not a key: repetitions at one speed pool too (they share E0* and alpha), and
each trace's speed is read from its fitted approach (the median of the block means' motion).
A group with two or more successfully fitted power-law traces gets one row; a group of one
manifest row gets none, and so does a group with fewer than two fits.  The table is written
when a manifest is fitted with the power law and a group pools, **not at all when none
does** (an empty table is not written); ``fit --rheology`` removes a previous run's table first
(:data:`~palpbayes.outputs.RHEOLOGY_OUTPUTS`).  **SLS fits are not pooled**: the speed
scaling is the power law's (an SLS's apparent modulus has no single exponent); with
``--rheology power-law,sls`` the power-law fits are pooled.

**Memory**: a group is pooled as soon as its last manifest row is fitted; until then each fit
is kept reduced to what the pooling reads (block means and motion, the grid's nodes, the draws
of E0* and alpha; not the raw samples, nor the node posteriors).  Groups with a failed trace
are pooled at the end.  Pool draws are seeded by ``seed`` + the group's position.

Columns of ``DIR/rheology_pooled.csv`` (:data:`POOLED_COLUMNS`): the group keys, ``n_traces``,
``n_speeds`` (speeds apart by more than 5 %), ``trace_ids`` and ``speeds_mm_min`` (``;``
separated, in manifest order), ``t0_s``, ``E0_star_pa`` with ``E0_star_lo_pa`` and
``E0_star_hi_pa`` (the central 90 % interval), ``alpha`` with ``alpha_lo`` and ``alpha_hi``,
``nu`` and ``E0_pa`` (``_lo``, ``_hi``: Young's, when the group's traces share nu),
``flag_codes`` (``;``), ``flag_level`` and ``notes`` (the flags in words, `` | ``),
``seconds`` [s] of the pooling, ``error`` (why a group could not be pooled).  The codes:
``trace_disagrees`` (a trace's own E0*, alpha far from the pooled ones), ``pool_at_edge`` (the
traces pull the pooled grid apart), ``trace_model_check`` (a pooled trace failed its own model
check), ``missing`` (a trace of the group was not fitted), ``one_speed`` (alpha from the holds
alone).

In Python::

    pools = SpeedPools(read_manifest(path))
    fit_traces(traces, rheology_options("power-law"), out, on_fit=pools.add)
    pooled = pools.finish(out)
"""

from __future__ import annotations

import os
import time as _time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd

from ..bayes.conjugate import NodePosterior
from ..contact import TIP_PARAMETERS, youngs_modulus
from ..errors import PalpbayesError
from ..flagcodes import POOLED_RHEOLOGY_CODES, listed_flag_columns
from ..io.atomic import write_csv_atomic
from ..outputs import RHEOLOGY_POOLED
from ..trace import IndentationTrace
from ..units import format_pressure_interval, interval_digits
from .cycle import CycleData
from .fit import RheologyFit
from .pool import pool_rheology

__all__ = ["RHEOLOGY_POOLED", "GROUP_COLUMNS", "POOLED_COLUMNS", "SPEED_TOLERANCE",
           "manifest_groups", "approach_speed", "SpeedPools", "pooled_lines"]

#: Manifest columns whose values define a group (one specimen, one tip).
GROUP_COLUMNS = ("material", "specimen", "tip", *(p.column for p in TIP_PARAMETERS.values()))
#: Relative difference above which two speeds count as two (``n_speeds``).
SPEED_TOLERANCE = 0.05
#: Columns of the pooled table, in order.
POOLED_COLUMNS = [
    *GROUP_COLUMNS, "n_traces", "n_speeds", "trace_ids", "speeds_mm_min", "t0_s",
    "E0_star_pa", "E0_star_lo_pa", "E0_star_hi_pa", "alpha", "alpha_lo", "alpha_hi",
    "nu", "E0_pa", "E0_lo_pa", "E0_hi_pa", "flag_codes", "flag_level", "notes", "seconds",
    "error",
]
def _cell(v):
    """A manifest cell as a hashable key part: None when empty, float or stripped text."""
    if v is None or (isinstance(v, float) and np.isnan(v)):
        return None
    if isinstance(v, str):
        return v.strip()
    return float(v)


def manifest_groups(manifest: pd.DataFrame) -> dict[tuple, list[str]]:
    """Group key (the values of :data:`GROUP_COLUMNS`, None when empty) -> trace ids, both in
    manifest order (a manifest as :func:`~palpbayes.io.manifest.read_manifest` returns it)."""
    groups: dict[tuple, list[str]] = {}
    for _, row in manifest.iterrows():
        key = tuple(_cell(row.get(c)) for c in GROUP_COLUMNS)
        groups.setdefault(key, []).append(str(row["trace_id"]))
    return groups


def approach_speed(data: CycleData) -> float:
    """[m/s] Downward tip speed of a fitted cycle's approach: the median over its block means
    of the model's motion (:attr:`~palpbayes.rheology.cycle.CycleData.speed`)."""
    return float(np.median(data.speed[data.segment == 0]))


def _slim(fit: RheologyFit) -> RheologyFit:
    """``fit`` reduced to what :func:`~palpbayes.rheology.pool.pool_rheology` reads: the raw
    samples cut to a 3-sample stub (its id kept), the node posteriors emptied, the draws of E0
    and alpha only."""
    tr = fit.data.trace
    seg = None if tr.segment is None else tr.segment[:3]
    stub = tr.replace(time=tr.time[:3], z=tr.z[:3], force=tr.force[:3], segment=seg,
                      metadata={})
    data = replace(fit.data, trace=stub)
    g, post = fit.grid, fit.grid.post
    empty = NodePosterior(post.logp[:0], post.beta[:0], post.scale[:0], post.S[:0], post.nu)
    grid = replace(g, data=data, post=empty, log_mass=g.log_mass[:0])
    return replace(fit, data=data, grid=grid,
                   draws={k: fit.draws[k] for k in ("E0", "alpha")})


@dataclass
class _Member:
    """What a group keeps of one fitted trace until it is pooled."""

    fit: RheologyFit
    speed: float
    model_ok: bool
    nu: float | None


def _n_speeds(speeds: list[float]) -> int:
    v = np.sort(np.asarray(speeds))
    return int(1 + np.count_nonzero(v[1:] > v[:-1] * (1.0 + SPEED_TOLERANCE)))


class SpeedPools:
    """The power-law fits of a manifest's traces, pooled per group (module docstring).

    Parameters
    ----------
    manifest
        The fitted manifest (:func:`~palpbayes.io.manifest.read_manifest`).
    seed
        Seeds the pooled draws (``seed`` + the group's position).

    Pass :meth:`add` as ``on_fit`` to :func:`~palpbayes.rheology.results.fit_traces`, then
    call :meth:`finish`.
    """

    def __init__(self, manifest: pd.DataFrame, *, seed: int = 0):
        self.groups = manifest_groups(manifest)
        self.seed = int(seed)
        self._key_of = {tid: key for key, ids in self.groups.items() if len(ids) >= 2
                        for tid in ids}
        self._kept: dict[tuple, dict[str, _Member]] = {}
        self._rows: dict[tuple, dict] = {}

    def add(self, trace: IndentationTrace, fit: RheologyFit) -> None:
        """Keep one fit (reduced); pool its group when this was its last trace.  Fits of
        another model, of a trace outside the manifest or alone in its group are ignored."""
        key = self._key_of.get(trace.trace_id)
        if fit.rheology != "power-law" or key is None or key in self._rows:
            return
        members = self._kept.setdefault(key, {})
        members[trace.trace_id] = _Member(_slim(fit), approach_speed(fit.data), fit.model_ok,
                                          fit.nu)
        if len(members) == len(self.groups[key]):
            self._pool(key)

    def _pool(self, key: tuple) -> None:
        kept = self._kept.pop(key)
        ids = [t for t in self.groups[key] if t in kept]
        members = [kept[t] for t in ids]
        speeds = [m.speed for m in members]
        nus = {m.nu for m in members}
        nu = nus.pop() if len(nus) == 1 else None
        row: dict = dict(zip(GROUP_COLUMNS, key, strict=True))
        row.update(n_traces=len(ids), n_speeds=_n_speeds(speeds), trace_ids=";".join(ids),
                   speeds_mm_min=";".join(f"{v * 6e4:.4g}" for v in speeds),
                   nu=np.nan if nu is None else nu, error="")
        start = _time.perf_counter()
        try:
            pooled = pool_rheology([m.fit for m in members],
                                    rng=self.seed + list(self.groups).index(key))
        except (PalpbayesError, np.linalg.LinAlgError) as exc:
            row.update(flag_codes="", flag_level="", notes="", error=f"not pooled: {exc}")
            self._rows[key] = row
            return
        table = pooled.table().set_index("parameter")
        row["t0_s"] = pooled.t0
        for name, col in (("E0*", "E0_star"), ("alpha", "alpha")):
            unit = "_pa" if name == "E0*" else ""
            med, lo, hi = (float(table.loc[name, c]) for c in ("median", "lo", "hi"))
            row.update({f"{col}{unit}": med, f"{col}_lo{unit}": lo, f"{col}_hi{unit}": hi})
        if nu is not None:
            row.update({f"E0{p}_pa": youngs_modulus(row[f"E0_star{p}_pa"], nu)
                        for p in ("", "_lo", "_hi")})
        flags = list(pooled.flags)
        flags += [f"{t}: its own model check failed (rheology.csv); the pooled power law "
                  "leans on a trace the model does not describe"
                  for t, m in zip(ids, members, strict=True) if not m.model_ok]
        missing = [t for t in self.groups[key] if t not in kept]
        if missing:
            flags.append(f"{', '.join(missing)} were not fitted (see rheology.csv): pooled "
                         f"{len(ids)} of {len(self.groups[key])} traces")
        if row["n_speeds"] == 1:
            flags.append("every trace at one speed: alpha rests on the holds' relaxation "
                         "alone")
        row.update(**listed_flag_columns(flags, POOLED_RHEOLOGY_CODES),
                   seconds=round(_time.perf_counter() - start, 3))
        self._rows[key] = row

    def finish(self, out: str | os.PathLike) -> pd.DataFrame:
        """Pool the groups still open (a trace failed) with two or more fits, write
        ``out/rheology_pooled.csv`` atomically when a group pools (no file when none does:
        an empty table is not written) and return the table, one row per pooled group in
        manifest order."""
        for key in list(self._kept):
            if len(self._kept[key]) >= 2:
                self._pool(key)
            else:
                del self._kept[key]
        rows = [self._rows[k] for k in self.groups if k in self._rows]
        table = pd.DataFrame(rows, columns=POOLED_COLUMNS)
        if not table.empty:
            out = Path(out)
            out.mkdir(parents=True, exist_ok=True)
            write_csv_atomic(table, out / RHEOLOGY_POOLED, index=False)
        return table


def _label(r) -> str:
    spec = r["specimen"] if isinstance(r["specimen"], str) else ""
    who = r["material"] if spec in ("", r["material"]) else f"{r['material']}/{spec}"
    return f"{who} x {r['tip']}"


def pooled_lines(table: pd.DataFrame) -> list[str]:
    """The console lines of a pooled table: a heading, then one line per group."""
    if table.empty:
        return ["no pooled power law: no specimen x tip of the manifest has two fitted "
                "power-law traces"]
    lines = ["pooled power law per specimen x tip (its traces at several speeds; medians "
             "[90 % intervals], E0* at t0):"]
    for _, r in table.iterrows():
        head = (f"  {_label(r)}: {r['n_traces']} traces at {r['speeds_mm_min'].replace(';', ', ')}"
                " mm/min")
        if isinstance(r["error"], str) and r["error"]:
            lines.append(f"{head}: {r['error']}")
            continue
        flags = (f"flagged: {r['flag_codes']} (notes in {RHEOLOGY_POOLED})"
                 if isinstance(r["flag_codes"], str) and r["flag_codes"] else "no flags")
        d = interval_digits(r["alpha_lo"], r["alpha_hi"])
        E0 = format_pressure_interval(r["E0_star_pa"], r["E0_star_lo_pa"], r["E0_star_hi_pa"])
        lines.append(f"{head}: E0* {E0}, alpha {r['alpha']:.{d}g} "
                     f"[{r['alpha_lo']:.{d}g}, {r['alpha_hi']:.{d}g}]; {flags}")
    return lines
