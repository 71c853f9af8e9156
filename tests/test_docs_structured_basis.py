"""Every ```python block of docs/guide/structured-basis.md runs as written (in a temporary
folder where the repository's examples/ folder is available as examples/)."""

from __future__ import annotations

import os
import re
import runpy
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "guide" / "structured-basis.md"
BLOCKS = re.findall(r"```python\n(.*?)```", PAGE.read_text(), flags=re.DOTALL)


def test_the_page_has_python_blocks() -> None:
    assert len(BLOCKS) >= 3


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_python_block_runs(index: int, tmp_path: Path, monkeypatch, capsys) -> None:
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    script = tmp_path / f"block{index}.py"
    script.write_text(BLOCKS[index])
    monkeypatch.chdir(tmp_path)
    runpy.run_path(os.fspath(script), run_name="__main__")
    printed = capsys.readouterr().out
    assert "False" not in printed.split(), printed  # every printed check holds
