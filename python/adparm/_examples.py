"""The repository's example files (examples/: configurations, URDF arms, trajectory samples),
installed with adparm in ``adparm/examples/`` so that a script needs no clone of the repository
and no path relative to one."""

from __future__ import annotations

from pathlib import Path

__all__ = ["example_path"]

_PACKAGE = Path(__file__).resolve().parent


def _folders() -> list[Path]:
    # installed: <site-packages>/adparm/examples; from a source tree (PYTHONPATH=python or an
    # editable install): the repository's examples/ beside python/
    return [_PACKAGE / "examples", _PACKAGE.parent.parent / "examples"]


def example_path(name: str = "") -> Path:
    """The path of an example file of adparm, e.g. ``example_path("planar_3link.toml")`` (a TOML
    file finds its URDF beside it: ``arms/planar_3link.urdf``), or with no name the folder.

    The files are the repository's ``examples/``, installed with the package; the gallery's
    scripts load them so that they run from any folder.

    Raises
    ------
    FileNotFoundError
        No such example (the message lists the ones there are).
    """
    if not isinstance(name, str):
        raise TypeError(f"name: expected a file name (str), got {type(name).__name__}")
    folder = next((f for f in _folders() if (f / "planar_3link.toml").is_file()), None)
    if folder is None:
        raise FileNotFoundError(
            "adparm's example files are missing: expected adparm/examples/ beside the package "
            f"({_PACKAGE}); reinstall adparm"
        )
    if not name:
        return folder
    path = (folder / name).resolve()
    if folder.resolve() not in path.parents or not path.is_file():
        known = sorted(
            str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file() and p.suffix
        )
        raise FileNotFoundError(f"example_path: no example {name!r}; there are: {', '.join(known)}")
    return path
