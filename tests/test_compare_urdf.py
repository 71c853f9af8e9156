"""bench/compare_urdf.py's interleaved comparison of `adparm_bench --urdf` builds (rounds and
pairs), on stand-in benches that print fixed times: the table's medians and per-round ratios,
the order of the runs, and the refusal of a run that allocated."""

from __future__ import annotations

import stat
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))

import compare_urdf  # noqa: E402

CASES = ["planar_3link quadratic 0", "ur5 structured 50"]


def stand_in(folder: Path, name: str, ns: list[float], heap: int = 0) -> str:
    """An executable that prints one bench=urdf_loop line per case, case i taking ns[i] per
    step, and appends its name to folder/order (the order the runs were made in)."""
    path = folder / name
    lines = [
        f"bench=urdf_loop arm={arm} dof=3 basis={basis} functions=21 points={points} steps=1000 "
        f"repeats=3 ns_per_step={t} heap_allocations={heap} status=finished"
        for (arm, basis, points), t in zip((c.split() for c in CASES), ns, strict=True)
    ]
    path.write_text(
        f"#!{sys.executable}\n"
        f"open({str(folder / 'order')!r}, 'a').write({name!r} + '\\n')\n"
        f"print({chr(10).join(lines)!r})\n"
    )
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    return str(path)


def test_rounds_prints_medians_and_ratios_against_the_last_build(tmp_path, capsys) -> None:
    builds = [
        stand_in(tmp_path, "base", [30000.0, 240000.0]),
        stand_in(tmp_path, "main", [20000.0, 120000.0]),
        stand_in(tmp_path, "this", [10000.0, 100000.0]),
    ]
    compare_urdf.rounds(builds, 4, "1")
    table = capsys.readouterr().out.splitlines()
    assert table[0] == f"| case | {' | '.join(builds)} | {builds[0]} / {builds[2]} | " + (
        f"{builds[1]} / {builds[2]} |"
    )
    assert table[2] == "| planar_3link/quadratic/N=0 | 30.0 | 20.0 | 10.0 | 3.00 | 2.00 |"
    assert table[3] == "| ur5/structured/N=50 | 240.0 | 120.0 | 100.0 | 2.40 | 1.20 |"
    # every build once a round: forwards, backwards, then rotated by one, forwards and backwards
    order = (tmp_path / "order").read_text().split()
    assert order == ["base", "main", "this", "this", "main", "base",
                     "main", "this", "base", "base", "this", "main"]  # fmt: skip


def test_pairs_alternate_the_two_builds(tmp_path, capsys) -> None:
    old = stand_in(tmp_path, "old", [20000.0, 200000.0])
    new = stand_in(tmp_path, "new", [10000.0, 100000.0])
    compare_urdf.pairs(old, new, 3, "1")
    out = capsys.readouterr().out
    assert "2.00 (2.00-2.00)" in out
    assert (tmp_path / "order").read_text().split() == ["old", "new", "new", "old", "old", "new"]


def test_a_run_that_allocates_is_refused(tmp_path) -> None:
    builds = [stand_in(tmp_path, "a", [1.0, 1.0]), stand_in(tmp_path, "b", [1.0, 1.0], heap=3)]
    with pytest.raises(SystemExit, match="3 heap allocations"):
        compare_urdf.rounds(builds, 1, "1")
