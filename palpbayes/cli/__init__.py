"""The ``palpbayes`` command (docs/design.md §7).

Each subcommand lives in its own module with ``register(subparsers)`` and ``run(args) -> int``.
Exit status: 0 on success, 2 on bad input (one clear line on stderr), 1 otherwise.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings

from .. import __version__
from ..errors import InputError, PalpbayesError
from ..threads import one_blas_thread

__all__ = ["main", "build_parser", "SUBCOMMANDS"]

#: Subcommand modules, in the order ``--help`` lists them.
SUBCOMMANDS = ("simulate", "fit", "groundtruth", "compare", "report", "replay", "follow",
               "inspect", "map", "next")


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose usage errors exit with status 2 and one line on stderr."""

    def error(self, message: str) -> None:  # noqa: D401
        self.exit(2, f"palpbayes: error: {message} (see 'palpbayes --help')\n")


def build_parser(commands: tuple[str, ...] = SUBCOMMANDS) -> argparse.ArgumentParser:
    """The ``palpbayes`` parser with the subcommands ``commands`` (default: all of them)."""
    parser = _Parser(
        prog="palpbayes",
        description="Elastic modulus with an honest uncertainty from robotic palpation data.",
    )
    parser.add_argument("--version", action="version", version=f"palpbayes {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name in commands:
        try:
            module = importlib.import_module(f".{name}", __name__)
        except ModuleNotFoundError as exc:  # a subcommand not built yet in this checkout
            if exc.name != f"{__name__}.{name}":
                raise
            continue
        module.register(sub)
        sub.choices[name].set_defaults(func=module.run)
    return parser


def _parser_for(argv: list[str]) -> argparse.ArgumentParser:
    """The parser for ``argv``: with a subcommand first, only that subcommand's (the other
    subcommands' modules are not imported: ``palpbayes fit ...`` parses, helps and fails
    exactly as with all of them); else the whole parser (``--help``, ``--version``, a typo)."""
    if argv and argv[0] in SUBCOMMANDS:
        return build_parser((argv[0],))
    return build_parser()


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``palpbayes`` console script; returns the exit status."""
    if argv is None:
        argv = sys.argv[1:]
    parser = _parser_for(argv)
    args = parser.parse_args(argv)
    if not getattr(args, "command", None):
        parser.print_help()
        return 2
    one_blas_thread()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            return int(args.func(args) or 0)
    except InputError as exc:
        print(f"palpbayes {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except PalpbayesError as exc:
        print(f"palpbayes {args.command}: failed: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"palpbayes {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
