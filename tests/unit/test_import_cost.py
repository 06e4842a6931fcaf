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
    fitting code nor the other subcommands, nor emcee (which imports scipy.stats) for the
    sampler's settings."""
    heavy = (*NEVER, "scipy.signal", "scipy.stats", "emcee", "palpbayes.rheology",
             "palpbayes.online", "palpbayes.checks.ppc", "palpbayes.compression",
             "palpbayes.cli.simulate", "palpbayes.cli.report", "palpbayes.cli.map")
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


#: Loaded by no fit (issue 59): full arviz imports matplotlib; xarray's netCDF writer and its
#: ``Variable`` look up dask's arrays and scheduler (dask.array, distributed) when dask is
#: installed.  The fit's R-hat and ESS come from arviz-stats, its file from h5netcdf.
FIT_NEVER = ("matplotlib", "arviz", "dask", "distributed", "palpbayes.plots",
             "palpbayes.reporting")


@pytest.fixture(scope="module")
def light_trace(tmp_path_factory):
    """A simulated sphere press (Hertz, 120 kPa), written as palpbayes writes a trace."""
    import palpbayes as pb

    tr = pb.simulate_trace(120e3, pb.Tip("sphere", radius=0.01), nu=0.45, rng=6, depth=2e-3,
                           trace_id="light")
    return pb.write_trace(tr, tmp_path_factory.mktemp("light") / "light.csv")


@pytest.mark.parametrize("engine", ["emcee", "exact"])
def test_a_fit_on_the_command_line_imports_no_plotting_nor_dask(light_trace, tmp_path, engine):
    """``palpbayes fit TRACE`` (either engine) writes its posterior file and summary without
    importing matplotlib, arviz, dask or distributed; the file opens in arviz."""
    out = tmp_path / "out"
    code = f"""
        import contextlib, io
        from palpbayes.cli import main
        with contextlib.redirect_stdout(io.StringIO()):
            status = main(["fit", {str(light_trace)!r}, "--tip", "sphere", "--radius", "0.01",
                           "--nu", "0.45", "--engine", {engine!r}, "--out", {str(out)!r},
                           "--no-progress"])
        assert status == 0, status
        """
    assert _loaded(code, FIT_NEVER) == []
    from palpbayes.bayes.diagnostics import import_arviz

    idata = import_arviz().from_netcdf(str(out / "posterior" / "light.nc"))
    assert idata.posterior.attrs["engine"] == engine and "lp" in idata.sample_stats


def test_pb_fit_and_save_import_no_plotting_nor_dask(light_trace, tmp_path):
    """``pb.fit`` and ``Fit.save`` neither; ``Fit.posterior`` (the arviz InferenceData, made on
    first use) imports arviz."""
    code = (f"import palpbayes as pb\n"
            f"f = pb.fit({str(light_trace)!r}, tip='sphere', radius=0.01, nu=0.45, "
            f"engine='exact')\n"
            f"f.save({str(tmp_path / 'out')!r})\n"
            "assert f.bayes.converged and repr(f.bayes).startswith(\"BayesResult('light'\")\n")
    assert _loaded(code, FIT_NEVER) == []
    assert _loaded(code + "f.posterior.posterior\n", ("arviz",)) == ["arviz"]
