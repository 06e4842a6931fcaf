"""docs/api.md's examples run (doctest), so the page cannot go stale."""

from __future__ import annotations

import doctest
import warnings
from pathlib import Path

DOC = Path(__file__).resolve().parents[2] / "docs" / "api.md"


def test_api_page_examples_run():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # convergence and tqdm notes are not the subject
        result = doctest.testfile(str(DOC), module_relative=False, verbose=False,
                                  optionflags=doctest.ELLIPSIS)
    assert result.attempted >= 20
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed"
