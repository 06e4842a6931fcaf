"""Shared test fixtures.

Data too large (or not ours) to keep in the repository lives in ``../shared/data`` beside the
repository checkout (``$PALPBAYES_SHARED/data`` when that variable is set).  Tests reach it only
through the :func:`shared_data` fixture, so that a missing folder skips the test on a
developer's machine but FAILS it on CI (``CI=true``), where a silent skip would hide that the
real-data tests never ran.

Hypothesis (the property tests in ``tests/unit``) runs under a settings profile loaded here,
before any test module is imported:

``deterministic`` (the default)
    ``derandomize=True``: the examples are a fixed function of each test (and of the
    Hypothesis version), so the default suite, locally and on CI, checks the same examples every
    run; a failure is a real regression, never the luck of the draw.  100 examples
    (Hypothesis' own default), no deadline (CI machines are slow and uneven), and a failing
    example is printed with its ``@reproduce_failure`` blob.
``wide`` (``HYPOTHESIS_PROFILE=wide pytest ...``)
    Random examples, 10 times as many, for a deliberate search; add what it finds to the test
    with ``@example(...)`` so the default run checks it from then on.

A test that sets its own ``max_examples`` states it as ``examples(n)``
(``from propbudget import examples``): n in the default profile, scaled with the profile's
count in ``wide``.  Per-test ``@settings`` must not set ``derandomize``, ``database`` or use
``@seed``, which would override the profile.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from pathlib import Path

# One BLAS/OpenMP thread per test process, set before anything imports numpy: the suite runs
# one worker per core (pytest-xdist), and BLAS threads on top of that only contend.
for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

# The specimen twin's tables (palpbayes.twin.cache) of this test run in a folder of its own,
# not the user's ~/.cache: every run starts without them, as CI does (xdist workers inherit the
# controller's folder).
_OWN_CACHE = os.path.join(__import__("tempfile").gettempdir(),
                          f"palpbayes-test-cache-{os.getpid()}")
os.environ.setdefault("PALPBAYES_CACHE_DIR", _OWN_CACHE)
# ... and without the tables the source ships for its example (data/twin-cache): the tests solve
# what they test (tests/unit/test_twin.py reads the shipped ones on purpose).
os.environ.setdefault("PALPBAYES_SHIPPED_TABLES", "off")

import pytest  # noqa: E402
from hypothesis import settings  # noqa: E402

#: Name of the Hypothesis profile used unless HYPOTHESIS_PROFILE names another one.
DEFAULT_HYPOTHESIS_PROFILE = "deterministic"
settings.register_profile(DEFAULT_HYPOTHESIS_PROFILE, derandomize=True, max_examples=100,
                          deadline=None, print_blob=True)
settings.register_profile("wide", derandomize=False, max_examples=1000, deadline=None,
                          print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE") or DEFAULT_HYPOTHESIS_PROFILE)

#: The shared folder: $PALPBAYES_SHARED, else ../shared beside the repository (as on CI).
SHARED = Path(os.environ.get("PALPBAYES_SHARED")
              or Path(__file__).resolve().parents[2] / "shared")
#: Data sets in the shared folder (phantom-compression/, afm-curves/, ...).
SHARED_DATA = SHARED / "data"


def on_ci() -> bool:
    """True when the environment variable ``CI`` is ``true`` (or ``1``/``yes``), as CI sets it."""
    return os.environ.get("CI", "").strip().lower() in ("true", "1", "yes")


def find_shared_data(path: str | os.PathLike, *, files: Iterable[str] = ()) -> Path:
    """``SHARED_DATA / path``, checked; skips (locally) or fails (on CI) when it is absent.

    The function behind the :func:`shared_data` fixture, for module-level helpers; see there.
    """
    target = SHARED_DATA / path
    missing = [p for p in (target, *(target / f for f in files)) if not p.exists()]
    if missing:
        where = ("$PALPBAYES_SHARED/data" if os.environ.get("PALPBAYES_SHARED")
                 else "../shared/data beside the repository; set PALPBAYES_SHARED to override")
        msg = (f"shared test data not found: {missing[0]} (looked in {where})")
        if on_ci():
            pytest.fail(f"{msg}; CI=true, so a missing data set is an error, not a skip: "
                        "check out the shared folder next to the repository", pytrace=False)
        pytest.skip(msg)
    return target


@pytest.fixture(scope="session")
def shared_data() -> Callable[..., Path]:
    """Path to a data set under ``../shared/data``: skip when absent, FAIL when absent on CI.

    The fixture returns a function ``shared_data(path, *, files=())``:

    path
        Relative to the shared data folder, e.g. ``"phantom-compression"`` or
        ``"afm-curves/some_curve.txt"``.  Returns the absolute :class:`~pathlib.Path`.
    files
        Names that must exist inside ``path`` too (e.g. ``["published_moduli.csv"]``), so an
        empty or partial checkout is treated as absent.

    When ``path`` (or one of ``files``) does not exist the test is *skipped* with a reason
    naming the missing path, or — when the environment variable ``CI`` is ``true`` — it
    *fails* with a message saying so, because on CI the data must be there.

    The shared folder is ``$PALPBAYES_SHARED/data`` when that variable is set, else
    ``../shared/data`` beside the repository checkout (``SHARED_DATA`` in this module).

    Usage (the fixture is session-scoped, so module- and session-scoped fixtures can use it)::

        def test_curves(shared_data):
            root = shared_data("afm-curves")
            ...

        @pytest.fixture(scope="module")
        def phantoms(shared_data):
            return shared_data("phantom-compression", files=["published_moduli.csv"])
    """
    return find_shared_data


@pytest.fixture(scope="session")
def spot3(shared_data) -> Path:
    """afmformats' real JPK force-distance curve ``fmt-jpk-fd_spot3-0192.jpk-force`` (approach
    and retract, 2000 points each; MIT), read from ``../shared/data/afm-files``."""
    return shared_data("afm-files/fmt-jpk-fd_spot3-0192.jpk-force")


def pytest_sessionfinish(session, exitstatus):
    """Remove this run's twin-table folder (the controller's, after its workers are done)."""
    import shutil

    if (os.environ.get("PYTEST_XDIST_WORKER") is None
            and os.environ.get("PALPBAYES_CACHE_DIR") == _OWN_CACHE):
        shutil.rmtree(_OWN_CACHE, ignore_errors=True)
