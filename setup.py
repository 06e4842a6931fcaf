"""The compiled core (docs/reference.md, "Speed"): the (trial surface × sample) loops of the
exact engine, the least squares and the checks, in Cython, built by pip at install with the
machine's C compiler (setuptools compiles the .pyx through Cython, a build requirement in
pyproject.toml).  Everything else about the package is in pyproject.toml."""

from setuptools import Extension, setup

setup(ext_modules=[Extension("palpbayes._kernels", ["palpbayes/_kernels.pyx"])])
