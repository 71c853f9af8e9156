"""The type stub python/adparm/_core.pyi is generated, not written: it is pybind11-stubgen's output
for the built extension, checked here, and mypy's stubtest finds no difference between the stub and
the module beyond pybind11's metaclass (which no stub can name).

After changing the binding (python/src/core_bindings.cpp), rebuild and regenerate the stub with
``python tests/test_core_stub.py --write``.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

STUB = Path(__file__).resolve().parents[1] / "python" / "adparm" / "_core.pyi"


def generate(folder: Path) -> str:
    """pybind11-stubgen's stub of the importable adparm._core, as text."""
    subprocess.run(
        [sys.executable, "-m", "pybind11_stubgen", "adparm._core", "-o", str(folder)],
        check=True,
        capture_output=True,
        text=True,
    )
    return (folder / "adparm" / "_core.pyi").read_text()


def test_checked_in_stub_is_the_generated_one(tmp_path):
    pytest.importorskip("pybind11_stubgen")
    generated = generate(tmp_path)
    assert STUB.read_text() == generated, (
        "python/adparm/_core.pyi differs from pybind11-stubgen's output for the built extension; "
        "regenerate it: python tests/test_core_stub.py --write"
    )


def test_stubtest_finds_only_pybind11_metaclasses():
    pytest.importorskip("mypy")
    completed = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "adparm._core", "--concise"],
        capture_output=True,
        text=True,
    )
    lines = completed.stdout.splitlines()
    errors = [line for line in lines if "metaclass differs" not in line]
    assert not errors, "\n".join(errors) + completed.stderr
    # stubtest names pybind11's metaclass on every class: no line at all means it checked nothing
    assert lines, f"stubtest checked nothing: {completed.stderr}"


if __name__ == "__main__":
    if sys.argv[1:] != ["--write"]:
        sys.exit("usage: python tests/test_core_stub.py --write")
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        STUB.write_text(generate(Path(folder)))
    print(f"wrote {STUB}")
