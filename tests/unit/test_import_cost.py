"""Start-up cost guard (issue 47): importing palpbayes and building the command line's parser
do not import the heavy implementation modules (the simulator, scipy.signal, arviz,
matplotlib, dask, distributed, xarray) -- which modules are loaded, never how long it takes."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys
import textwrap

import pytest

#: Loaded by none of the cases below.
NEVER = ("matplotlib", "arviz", "dask", "distributed", "xarray", "palpbayes.sim.trace",
         "palpbayes.sim.campaign", "palpbayes.paper", "palpbayes.bayes.fit", "palpbayes.api",
         "palpbayes.campaign.fitjob", "palpbayes.reporting", "palpbayes.plots", "palpbayes.maps")


def _loaded(code: str, names) -> list[str]:
    """Which of ``names`` (and their submodules) ``code`` leaves in sys.modules, run in a fresh
    interpreter."""
    script = textwrap.dedent(code) + textwrap.dedent(f"""
        import json, sys
        names = {tuple(names)!r}
        print(json.dumps(sorted(n for n in names
                                if any(m == n or m.startswith(n + ".") for m in sys.modules))))
        """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True, timeout=300)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_import_palpbayes_is_light():
    heavy = (*NEVER, "scipy.signal", "scipy.stats", "scipy.interpolate", "scipy.optimize",
             "pandas", "emcee", "palpbayes.bayes", "palpbayes.checks", "palpbayes.twin",
             "palpbayes.sim", "palpbayes.cli")
    assert _loaded("import palpbayes", heavy) == []


def test_fit_parser_and_help_are_light():
    """``palpbayes fit --help`` (the parser ``palpbayes fit ...`` builds) loads neither the
    fitting code nor the other subcommands."""
    heavy = (*NEVER, "scipy.signal", "palpbayes.rheology", "palpbayes.online",
             "palpbayes.checks.ppc", "palpbayes.compression", "palpbayes.cli.simulate",
             "palpbayes.cli.report", "palpbayes.cli.map")
    code = """
        import contextlib, io
        from palpbayes.cli import main
        with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):
            main(["fit", "--help"])
        """
    assert _loaded(code, heavy) == []


def test_whole_parser_is_light():
    """``palpbayes --help``: every subcommand's options, none of their implementations.
    (scipy.signal is checked for ``fit`` only: the parsers of ``replay`` and ``follow`` import
    palpbayes.online, whose estimator imports palpbayes.checks.run and the checks' modules.)"""
    code = """
        import palpbayes, palpbayes.cli
        palpbayes.cli.build_parser()
        """
    assert _loaded(code, NEVER) == []


def test_written_out_choices_match_their_home():
    """The parser's copies of choices whose home module is heavy."""
    from palpbayes.bayes.fit import ENGINES
    from palpbayes.cli import options, simulate
    from palpbayes.paper import PAPER_TIPS

    assert options.ENGINES == ENGINES
    assert simulate.PAPER_TIP_NAMES == tuple(sorted(PAPER_TIPS))


@pytest.mark.parametrize("package", ["palpbayes", "palpbayes.bayes", "palpbayes.checks",
                                     "palpbayes.sim", "palpbayes.twin"])
def test_lazy_packages_export_their_names(package):
    """Every public name of a lazily importing package resolves, is listed by dir(), and is
    the object of the module that defines it."""
    mod = importlib.import_module(package)
    names = list(mod.__all__)
    assert names and len(set(names)) == len(names)
    assert set(names) <= set(dir(mod))
    for name in names:
        value = getattr(mod, name)
        home = getattr(value, "__module__", None)
        if isinstance(home, str) and home.startswith(package + ".") and not isinstance(
                value, type(mod)):
            assert getattr(importlib.import_module(home), name, value) is value
    with pytest.raises(AttributeError):
        mod.no_such_name  # noqa: B018
