"""Optional dependencies of the readers: import them, or say which extra installs them.

ROS 2 bags need ``rosbags`` (extra ``ros``), AFM files need ``afmformats`` (extra ``afm``).
Neither is imported until a file of that kind is read, so ``import palpbayes`` and every other
reader work without them.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from ..errors import MissingExtraError

__all__ = ["EXTRAS", "import_extra"]

#: Extra name -> (importable module, what pip installs).
EXTRAS = {"ros": ("rosbags", "rosbags"), "afm": ("afmformats", "afmformats")}


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
        "reading .jpk-force files needs the optional extra: pip install 'palpbayes[afm]'".
    """
    top, _ = EXTRAS[extra]
    try:
        return importlib.import_module(module or top)
    except ImportError as exc:
        raise MissingExtraError(
            f"{what} needs the optional extra: pip install 'palpbayes[{extra}]' "
            f"({exc.name or top} is not installed)") from None
