"""Optional dependencies of the readers: import them, or say which extra installs them.

ROS 2 bags need ``rosbags`` (extra ``ros``), AFM files need ``afmformats`` (extra ``afm``).
Neither is imported until a file of that kind is read, so ``import palpbayes`` and every other
reader work without them.

A missing extra is one line that gives the command for the installation at hand: palpbayes run
from a clone of its repository (the README's ``pip install -e . -c
requirements/constraints.txt``) gets the same command with the extra, with the clone's absolute
paths so that it works from any folder; the command for a palpbayes installed from a package
index follows in brackets (or comes first, when no clone is found).
"""

from __future__ import annotations

import importlib
import shlex
from pathlib import Path
from types import ModuleType

from ..errors import MissingExtraError

__all__ = ["EXTRAS", "CONSTRAINTS", "import_extra", "install_command", "source_root"]

#: Extra name -> (importable module, what pip installs).
EXTRAS = {"ros": ("rosbags", "rosbags"), "afm": ("afmformats", "afmformats")}

#: The pinned versions the README installs with, relative to the repository root.
CONSTRAINTS = "requirements/constraints.txt"


def source_root() -> Path | None:
    """The clone of the repository this palpbayes runs from (the folder holding
    ``pyproject.toml`` and :data:`CONSTRAINTS` above the package), None for an installed
    package."""
    root = Path(__file__).resolve().parents[2]
    if (root / "pyproject.toml").is_file() and (root / CONSTRAINTS).is_file():
        return root
    return None


def install_command(extra: str) -> str:
    """What installs ``extra``, for this installation, as :func:`import_extra` says it.

    Returns
    -------
    str
        From a clone: ``pip install -e '/path/palpbayes[afm]' -c
        /path/palpbayes/requirements/constraints.txt (a palpbayes installed from a package
        index: pip install 'palpbayes[afm]')``; otherwise ``pip install 'palpbayes[afm]' (a
        clone of the repository: pip install -e '.[afm]' -c requirements/constraints.txt in
        its root)``.
    """
    index = f"pip install {shlex.quote(f'palpbayes[{extra}]')}"
    root = source_root()
    if root is None:
        return (f"{index} (a clone of the repository: pip install -e "
                f"{shlex.quote(f'.[{extra}]')} -c {CONSTRAINTS} in its root)")
    return (f"pip install -e {shlex.quote(f'{root}[{extra}]')} -c "
            f"{shlex.quote(str(root / CONSTRAINTS))} (a palpbayes installed from a package "
            f"index: {index})")


def import_extra(extra: str, what: str, module: str | None = None) -> ModuleType:
    """Import the module behind an optional extra, or raise :class:`MissingExtraError`.

    Parameters
    ----------
    extra
        Name of the extra in pyproject.toml (``"ros"`` or ``"afm"``).
    what
        What needs it, for the message: ``"reading .jpk-force files"``.
    module
        A submodule to import instead of the top-level one (``"rosbags.rosbag2"``).

    Raises
    ------
    MissingExtraError
        One line: "reading .jpk-force files needs the optional extra afm (afmformats is not
        installed): " and :func:`install_command`.
    """
    top, _ = EXTRAS[extra]
    try:
        return importlib.import_module(module or top)
    except ImportError as exc:
        raise MissingExtraError(
            f"{what} needs the optional extra {extra} ({exc.name or top} is not installed): "
            f"{install_command(extra)}") from None
