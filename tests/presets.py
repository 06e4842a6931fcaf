"""Sampler presets shared by the tests (import as ``from presets import FAST``).

``tests/`` is on ``sys.path`` because pytest imports ``tests/conftest.py`` with its folder
prepended (the default "prepend" import mode).  Each preset trades convergence for speed in a
stated way; the statistical tests that check convergence use the package defaults instead.
"""

from __future__ import annotations

from palpbayes.bayes import SamplerSettings

__all__ = ["TINY", "POOL_FAST", "FAST", "SHORT"]

#: Plumbing only: short chains (flagged as not converged, which the tables must show).
TINY = SamplerSettings(n_walkers=16, max_steps=300, min_steps=200, check_every=100,
                       progress=False)
#: Per-trace fits feeding a pooling test: long enough for stable medians, not for R-hat.
POOL_FAST = SamplerSettings(n_walkers=32, max_steps=600, min_steps=400, check_every=200,
                            progress=False)
#: Comparison and pooling tables: 500-1,000 steps, usually converged on paper-like traces.
FAST = SamplerSettings(n_walkers=32, max_steps=1000, min_steps=500, check_every=250,
                       progress=False)
#: The stiffening laws (40 walkers for up to 5 parameters).
SHORT = SamplerSettings(n_walkers=40, max_steps=3000, min_steps=1500, check_every=500,
                        progress=False)
