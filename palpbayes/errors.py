"""Exception hierarchy of palpbayes.

Every error raised on purpose by palpbayes derives from :class:`PalpbayesError`, so callers can
catch the package's errors without catching numpy's or Python's own.  Errors caused by the user's
input (a bad file, an impossible option) derive from :class:`InputError`; the command line maps
them to exit status 2 with one line on stderr.
"""

from __future__ import annotations

from os import PathLike

__all__ = [
    "PalpbayesError",
    "InputError",
    "DataFileError",
    "StreamError",
    "MissingExtraError",
    "GeometryError",
    "NoContactError",
    "FitError",
    "ConvergenceError",
    "ConvergenceWarning",
    "OutputExistsError",
]


class PalpbayesError(Exception):
    """Base class of every error palpbayes raises on purpose."""


class InputError(PalpbayesError, ValueError):
    """The user's input (a file, an option, a value) cannot be used as given."""


class DataFileError(InputError):
    """A data file cannot be read or fails validation.

    Parameters
    ----------
    path
        The offending file (or a description of the source when there is no file).
    problem
        What is wrong, naming the column or value.
    fix
        What the user can do about it.
    """

    def __init__(self, path: str | PathLike | None, problem: str, fix: str | None = None):
        self.path = None if path is None else str(path)
        self.problem = problem
        self.fix = fix
        where = f"{self.path}: " if self.path else ""
        msg = f"{where}{problem}"
        if fix:
            msg += f" ({fix})"
        super().__init__(msg)


class StreamError(InputError):
    """A line of a live sample stream (``palpbayes follow``) cannot be used.

    Parameters
    ----------
    source
        Where the line came from (``stdin``, ``tcp 127.0.0.1:5000``).
    line
        Its line number in the stream, counting from 1 (the header is line 1 of a CSV stream).
    problem
        What is wrong, naming the column or value.
    fix
        What the sender can do about it.
    """

    def __init__(self, source: str, line: int, problem: str, fix: str):
        self.source, self.line, self.problem, self.fix = source, line, problem, fix
        super().__init__(f"{source} line {line}: {problem} ({fix})")


class MissingExtraError(InputError):
    """Reading a file needs an optional extra that is not installed (``pip install
    'palpbayes[afm]'``, ``'palpbayes[ros]'``); the message says which."""


class GeometryError(InputError):
    """A tip geometry or material parameter is missing or outside its valid range."""


class NoContactError(InputError):
    """The trace never reaches the specimen surface, so no modulus can be fitted."""


class FitError(PalpbayesError):
    """A fit could not be carried out on otherwise valid data."""


class ConvergenceError(FitError):
    """A Bayesian fit failed its convergence checks and ``strict`` mode was requested."""


class OutputExistsError(InputError):
    """An output would overwrite existing results without ``--force``."""


class ConvergenceWarning(UserWarning):
    """A Bayesian fit failed its convergence checks (R-hat, ESS); its numbers are flagged."""
