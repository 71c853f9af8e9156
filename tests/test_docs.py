"""Every ```python block of README.md and of the documentation pages (docs/**/*.md) runs as
written: each file's blocks in order, in one namespace, in a fresh working directory in which the
repository's examples/ folder is available as examples/. Blocks in other languages (text, sh,
toml) are not run. The examples in the public docstrings run too (doctest)."""

from __future__ import annotations

import re
import shutil
import textwrap
from pathlib import Path

import matplotlib
import pytest

ROOT = Path(__file__).resolve().parent.parent
_SKIP = ("_build", "auto_examples", "generated")
FILES = [ROOT / "README.md"] + sorted(
    path
    for path in (ROOT / "docs").rglob("*.md")
    if not any(part in _SKIP for part in path.relative_to(ROOT / "docs").parts)
)
_FENCE = re.compile(r"^(?P<indent>\s*)(?P<fence>`{3,}|~{3,})\s*(?P<info>[^`\s]*)")


def python_blocks(text: str) -> list[tuple[int, str]]:
    """(first line number, code) of each fenced block whose info string is ``python``."""
    blocks: list[tuple[int, str]] = []
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        match = _FENCE.match(lines[i])
        if not match:
            i += 1
            continue
        fence, info = match["fence"], match["info"].strip("{}").lower()
        start = i + 1
        i = start
        while i < len(lines) and not lines[i].strip().startswith(fence):
            i += 1
        if info in ("python", "py"):
            blocks.append((start + 1, textwrap.dedent("\n".join(lines[start:i]))))
        i += 1
    return blocks


def test_the_block_parser_finds_python_blocks_only() -> None:
    text = "a\n```python\nx = 1\n```\n```sh\nls\n```\n  ```python\n  y = 2\n  ```\n"
    assert python_blocks(text) == [(3, "x = 1"), (9, "y = 2")]


def test_readme_and_docs_have_python_blocks() -> None:
    assert ROOT / "README.md" in WITH_CODE and ROOT / "docs" / "paper.md" in WITH_CODE
    assert sum(len(python_blocks(path.read_text())) for path in FILES) >= 10


WITH_CODE = [path for path in FILES if python_blocks(path.read_text())]


# Short documentation runs have not converged, and adparm says so: the ApproximationWarning a
# user sees when pasting them is expected here (every other warning is still an error).
_SHORT_RUNS_WARN = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")


@_SHORT_RUNS_WARN
@pytest.mark.parametrize("path", WITH_CODE, ids=[str(p.relative_to(ROOT)) for p in WITH_CODE])
def test_python_blocks_run(path: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    blocks = python_blocks(path.read_text())
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    matplotlib.use("Agg")
    namespace: dict = {"__name__": "__main__"}
    for line, code in blocks:
        compiled = compile(code, f"{path.relative_to(ROOT)}:{line}", "exec")
        exec(compiled, namespace)  # noqa: S102 - running the documentation is the test
    import matplotlib.pyplot as plt

    plt.close("all")


@_SHORT_RUNS_WARN
@pytest.mark.parametrize(
    "module",
    [
        "adparm.bases",
        "adparm.config",
        "adparm.optimal",
        "adparm.physical",
        "adparm.simulation",
        "adparm.urdf",
    ],
)
def test_docstring_examples_run(module: str) -> None:
    import doctest
    import importlib

    failures, tried = doctest.testmod(importlib.import_module(module))
    assert tried > 0 and failures == 0
