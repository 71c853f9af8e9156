"""Pinocchio's shared libraries, found when the extension's run path does not find them.

The extension ``adparm._core`` links Pinocchio's C++ library (``libpinocchio``, a cmeel
package) and the libraries it needs from the environment it is installed in: its run path is
``$ORIGIN/../cmeel.prefix/lib``. In a virtual environment made with ``--system-site-packages``
whose ``libpinocchio`` was already installed in the system's site-packages, pip does not install
it again, that folder does not exist and the import would fail ("libpinocchio_parsers.so: cannot
open shared object file"). Then the libraries are loaded first, by full path, from the first
``cmeel.prefix/lib`` on ``sys.path`` that has them; the extension's import finds them loaded.
"""

from __future__ import annotations

import ctypes
import sys
from pathlib import Path

#: The extension's direct dependencies in a cmeel prefix (their own dependencies are found by
#: their run paths, in the same folder).
NEEDED = (
    "libboost_serialization.so.*",
    "liburdfdom_model.so.*",
    "libpinocchio_default.so",
    "libpinocchio_parsers.so",
)


def preload_pinocchio() -> Path | None:
    """Loads Pinocchio's libraries from another cmeel prefix on sys.path when the extension's
    own (``<site-packages>/cmeel.prefix/lib``) is missing; returns the folder they were loaded
    from, or None when nothing had to be loaded (or nothing was found: the import then fails
    with the loader's own message)."""
    own = Path(__file__).resolve().parent.parent / "cmeel.prefix" / "lib"
    if (own / "libpinocchio_default.so").exists():
        return None
    for entry in sys.path:
        folder = Path(entry or ".") / "cmeel.prefix" / "lib"
        if not (folder / "libpinocchio_default.so").exists():
            continue
        for pattern in NEEDED:
            for path in sorted(folder.glob(pattern))[-1:]:  # the most specific name
                ctypes.CDLL(str(path), mode=ctypes.RTLD_GLOBAL)
        return folder
    return None


preload_pinocchio()  # at import, before anything imports adparm._core
