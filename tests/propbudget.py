"""Example budgets of the property tests, scaled with the loaded Hypothesis profile.

``tests/conftest.py`` registers the profiles and loads one before the test modules are imported
(``deterministic`` by default, ``wide`` with ``HYPOTHESIS_PROFILE=wide``).  A test whose
``@settings`` gives a plain ``max_examples=25`` keeps 25 examples in every profile, so write::

    from propbudget import examples

    @settings(max_examples=examples(25), deadline=None)

25 examples in the default profile, 250 in ``wide`` (1,000 examples instead of 100).
"""

from __future__ import annotations

from hypothesis import settings

__all__ = ["examples"]

#: The profile the per-test budgets are stated for (tests/conftest.py registers it).
REFERENCE_PROFILE = "deterministic"


def examples(n: int) -> int:
    """``n`` examples in the reference profile, scaled by the loaded profile's max_examples."""
    reference = settings.get_profile(REFERENCE_PROFILE).max_examples
    return max(1, round(n * settings.default.max_examples / reference))
