"""The extension imports where its run path cannot find Pinocchio's libraries (adparm's own
cmeel.prefix missing: a --system-site-packages virtual environment whose libpinocchio lives in
the system's site-packages)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import adparm
from adparm._libraries import preload_pinocchio


def test_adparm_imports_without_its_own_cmeel_prefix(tmp_path: Path) -> None:
    installed = Path(adparm.__file__).resolve().parent
    copy = tmp_path / "site" / "adparm"
    shutil.copytree(installed, copy, ignore=shutil.ignore_patterns("__pycache__"))
    assert not (copy.parent / "cmeel.prefix").exists()
    code = (
        "import adparm\n"
        "from adparm import _libraries\n"
        "print(adparm.__file__)\n"
        "print(_libraries.preload_pinocchio.__module__)\n"
        "print(adparm.UrdfArm('examples/arms/planar_3link.urdf').dof)\n"
    )
    env = {**os.environ, "PYTHONPATH": str(copy.parent)}
    root = Path(__file__).resolve().parents[1]
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=root, env=env, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.split()
    assert lines[0].startswith(str(copy)) and lines[-1] == "3"


def test_nothing_is_loaded_where_the_run_path_finds_pinocchio() -> None:
    own = Path(adparm.__file__).resolve().parent.parent / "cmeel.prefix" / "lib"
    if (own / "libpinocchio_default.so").exists():
        assert preload_pinocchio() is None
    else:  # this environment is itself one whose run path misses: the folder it loads from
        folder = preload_pinocchio()
        assert folder is not None and (folder / "libpinocchio_default.so").exists()
