"""adparm.sweep: a parameter grid run in-process or on an executor (thread pool, dask)."""

from __future__ import annotations

import csv
import json
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import adparm
from adparm.sweep import SWEEP_METRICS, SWEEP_OPTIMAL_METRICS

# short learning runs have not converged, and adparm.simulate says so (tests/test_truth.py)
pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")

BASE = adparm.paper_config().updated({"sim": {"T": 1.0}})
GRID = {
    "critic.eta_c": [100.0, 800.0],
    "task.q0": [[0.1598, 0.2257], [0.5, -0.3]],
    "probe.amplitude": [[71.0, 23.0]],
}


def without_wall_time(table: adparm.SweepResult) -> list[dict]:
    return [{k: v for k, v in row.items() if k != "wall_time"} for row in table]


@pytest.fixture(scope="module")
def table() -> adparm.SweepResult:
    return adparm.sweep(BASE, GRID, threads=2)


def test_grid_points_are_every_combination_last_key_fastest() -> None:
    points = adparm.grid_points({"critic.eta_c": [1, 2, 3], "sim.dt": np.array([1e-3, 2e-3])})
    assert len(points) == 6
    assert points[0] == {"critic.eta_c": 1, "sim.dt": 1e-3}
    assert points[1] == {"critic.eta_c": 1, "sim.dt": 2e-3}
    assert points[-1] == {"critic.eta_c": 3, "sim.dt": 2e-3}


def test_rows_are_the_summaries_of_one_by_one_runs(table) -> None:
    assert len(table) == 4
    assert table.parameters == tuple(GRID)
    assert table.columns == (*GRID, *SWEEP_METRICS)
    for row, point in zip(table, adparm.grid_points(GRID), strict=True):
        config = BASE.updated(
            {
                "critic": {"eta_c": point["critic.eta_c"]},
                "task": {"q0": point["task.q0"]},
                "probe": {"amplitude": point["probe.amplitude"]},
            }
        )
        summary = adparm.simulate(config).summary()
        assert {k: row[k] for k in point} == point
        for name in SWEEP_METRICS:
            if name != "wall_time":
                assert row[name] == summary[name], name
        assert row["wall_time"] > 0.0


def test_columns_as_arrays(table) -> None:
    np.testing.assert_array_equal(table["critic.eta_c"], [100.0, 100.0, 800.0, 800.0])
    assert table["critic_relative_error"].dtype == float
    assert table["status"].tolist() == ["finished"] * 4
    assert table["task.q0"][1] == [0.5, -0.3]
    with pytest.raises(KeyError, match="did you mean 'critic_relative_error'"):
        table["critic_relative_eror"]


def test_thread_pool_executor_gives_the_same_rows(table) -> None:
    with ThreadPoolExecutor(max_workers=2) as pool:
        pooled = adparm.sweep(BASE, GRID, executor=pool)
    assert without_wall_time(pooled) == without_wall_time(table)


def test_dask_local_cluster_gives_the_same_rows(table) -> None:
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        on_dask = adparm.sweep(BASE, GRID, executor=client.get_executor())
    assert without_wall_time(on_dask) == without_wall_time(table)


def test_a_list_of_points_runs_as_given() -> None:
    """Monte Carlo: random initial positions, drawn once, reproducible from the seed."""
    draws = np.random.default_rng(7).uniform(-0.5, 0.5, size=(3, 2))
    points = [{"task.q0": q0, "critic.eta_c": 400.0} for q0 in draws]
    table = adparm.sweep(BASE, points, threads=2)
    assert table.parameters == ("task.q0", "critic.eta_c")
    assert table["task.q0"].tolist() == draws.tolist()
    for row, q0 in zip(table, draws, strict=True):
        config = BASE.updated({"task": {"q0": q0}, "critic": {"eta_c": 400.0}})
        assert (
            row["critic_relative_error"]
            == adparm.simulate(config).summary()["critic_relative_error"]
        )


def test_diverged_points_are_rows() -> None:
    grid = {"init.critic_weights": [[0.0] * 8], "init.actor_weights": [[0.0] * 8, [1.0] * 8]}
    table = adparm.sweep(BASE, grid, threads=1)
    assert table["status"].tolist() == ["diverged", "finished"]
    assert table["t_end"][0] < 0.1


def test_table_values_of_any_kind_are_written_as_json(tmp_path) -> None:
    """Grid values that are tables (a task.qd trajectory), arrays or NumPy numbers."""
    sinusoid = {"kind": "sinusoid", "amplitude": [0.1, 0.0], "frequency": [1.0, 1.0]}
    samples = {"kind": "samples", "t": np.array([0.0, 1.0]), "q": np.array([[0, 0], [0.1, 0.1]])}
    grid = {"task.qd": [sinusoid, samples], "critic.eta_c": np.array([100, 800])}
    base = BASE.updated({"sim": {"T": 0.05}})
    table = adparm.sweep(base, grid, threads=2)
    assert table["critic.eta_c"].dtype == float
    assert type(table.rows[0]["critic.eta_c"]) is int
    data = json.loads(table.save(tmp_path / "qd.json").read_text())
    assert data["rows"][0]["task.qd"] == sinusoid
    assert data["rows"][2]["task.qd"]["q"] == [[0, 0], [0.1, 0.1]]
    with table.save(tmp_path / "qd.csv").open() as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == 4
    assert json.loads(rows[0]["task.qd"]) == sinusoid
    assert json.loads(rows[3]["task.qd"])["t"] == [0.0, 1.0]
    assert '{"kind": "sinusoid"' in table.to_markdown()


def test_save_and_export(table, tmp_path) -> None:
    lines = table.save(tmp_path / "sweep.csv").read_text().splitlines()
    assert lines[0].split(",")[:4] == ["critic.eta_c", "task.q0", "probe.amplitude", "status"]
    assert len(lines) == 5 and '"[0.5, -0.3]"' in lines[2]
    data = json.loads(table.save(tmp_path / "sweep.json").read_text())
    assert data["columns"] == list(table.columns)
    assert data["rows"][1]["task.q0"] == [0.5, -0.3]
    assert "| critic.eta_c |" in table.save(tmp_path / "sweep.md").read_text()
    frame = table.to_dataframe()
    assert list(frame.columns) == list(table.columns) and len(frame) == 4
    with pytest.raises(ValueError, match=r"path: expected a .csv, .json or .md file"):
        table.save(tmp_path / "sweep.txt")


@pytest.mark.parametrize(
    ("grid", "error", "match"),
    [
        (5, TypeError, "grid: expected a mapping .* or a list of points"),
        ([("critic.eta_c", [1])], TypeError, r"grid\[0\]: expected a point"),
        ([], ValueError, "grid: expected at least one point"),
        ([{"task.q0": [0.1, 0.2]}, {"task.q": [0.1, 0.2]}], ValueError, r"grid\[1\]\['task.q'\]"),
        ([{"task.q0": [0.1, 0.2]}, {"task.dq0": [0, 0]}], ValueError, "the same keys as grid"),
        ({}, ValueError, "grid: expected at least one"),
        ({"eta_c": [1]}, ValueError, "must be 'section.key'"),
        ({"critc.eta_c": [1]}, ValueError, "did you mean 'critic'"),
        (
            {"critic.eta": [1]},
            ValueError,
            r"unknown key 'eta' in \[critic\] \(did you mean 'eta_c'",
        ),
        ({"critic.eta_c": 800}, TypeError, "expected a list of values to try, got int"),
        ({"critic.eta_c": "800"}, TypeError, "expected a list of values to try, got str"),
        ({"critic.eta_c": []}, ValueError, "expected at least one value"),
        (
            {"critic.eta_c": [800, -1]},
            ValueError,
            r"grid point \{'critic.eta_c': -1\}: critic.eta_c",
        ),
        ({"task.q0": [[0.1]]}, ValueError, "task.q0"),
        ({"critic.eta_c": np.array(5.0)}, TypeError, "got a 0-d array"),
        ({"init.critic_weights": [[1.0] * 8, "ones"]}, TypeError, r"grid point .*critic_weights"),
    ],
)
def test_bad_grids_are_refused_before_anything_runs(grid, error, match) -> None:
    with pytest.raises(error, match=match):
        adparm.sweep(BASE, grid)


def test_bad_arguments_are_refused() -> None:
    with pytest.raises(TypeError, match="base_config: expected adparm.Config"):
        adparm.sweep({"critic": {}}, GRID)
    with pytest.raises(TypeError, match="executor: expected a concurrent.futures-style"):
        adparm.sweep(BASE, GRID, executor=object())
    with pytest.raises(ValueError, match="tolerance"):
        adparm.sweep(BASE, GRID, tolerance=2.0)
    with pytest.raises(ValueError, match="threads"):
        adparm.sweep(BASE, GRID, threads=0)


def test_cli_sweep_writes_the_table(tmp_path, capsys) -> None:
    from adparm.cli import main

    out = tmp_path / "runs" / "sweep.json"
    argv = ["sweep", "--grid", "critic.eta_c=100,800", "--grid", "task.q0=[0.1,0.2],[0.5,-0.3]"]
    assert main([*argv, "--T", "0.5", "--threads", "2", "--out", str(out), "--no-progress"]) == 0
    rows = json.loads(out.read_text())["rows"]
    assert all(r["t_end"] == 0.5 for r in rows)
    capsys.readouterr()
    argv_dt = [*argv, "--T", "0.2", "--dt", "2e-3", "--out", str(out), "--no-progress"]
    assert main(argv_dt) == 0
    rows_dt = json.loads(out.read_text())["rows"]
    assert all(r["t_end"] == 0.2 for r in rows_dt)
    capsys.readouterr()
    assert main([*argv, "--dt=-1e-3", "--out", str(out), "--no-progress"]) == 2
    assert "sim.dt" in capsys.readouterr().err
    assert main([*argv, "--T", "0.5", "--threads", "2", "--out", str(out), "--no-progress"]) == 0
    rows = json.loads(out.read_text())["rows"]
    assert [(r["critic.eta_c"], r["task.q0"]) for r in rows] == [
        (100, [0.1, 0.2]),
        (100, [0.5, -0.3]),
        (800, [0.1, 0.2]),
        (800, [0.5, -0.3]),
    ]
    assert all(r["t_end"] == 0.5 for r in rows)
    assert "| critic.eta_c | task.q0 |" in capsys.readouterr().out


def test_unreadable_trajectory_file_is_a_value_error_naming_the_point(tmp_path) -> None:
    binary = tmp_path / "qd.csv"
    binary.write_bytes(bytes(range(256)))
    with pytest.raises(ValueError, match=r"grid point .*task.qd"):
        adparm.sweep(BASE, {"task.qd": [{"kind": "samples", "file": str(binary)}]})


def test_cli_sweep_reports_bad_grids(capsys, tmp_path, monkeypatch) -> None:
    from adparm.cli import main

    monkeypatch.chdir(tmp_path)  # the default --out is ./sweep.csv (its folder gets the lock file)

    assert main(["sweep", "--grid", "critic.eta=1,2"]) == 2
    assert "did you mean 'eta_c'" in capsys.readouterr().err
    assert main(["sweep", "--grid", "critic.eta_c=1", "--grid", "critic.eta_c=2,3"]) == 2
    assert "critic.eta_c given more than once" in capsys.readouterr().err
    assert main(["sweep", "--grid", "critic.eta_c=1", "--out", "sweep.txt"]) == 2
    assert "--out: expected a .csv, .json or .md file" in capsys.readouterr().err
    for bad in ("critic.eta_c", "critic.eta_c=[1"):
        with pytest.raises(SystemExit):
            main(["sweep", "--grid", bad])
        assert "argument --grid" in capsys.readouterr().err


def test_cli_sweep_exit_status_1_when_a_run_diverges(tmp_path, capsys) -> None:
    from adparm.cli import main

    grid = ["--grid", "init.actor_weights=[0,0,0,0,0,0,0,0],[1,1,1,1,1,1,1,1]"]
    argv = ["sweep", *grid, "--grid", "init.critic_weights=[0,0,0,0,0,0,0,0]", "--T", "0.2"]
    assert main([*argv, "--out", str(tmp_path / "s.csv"), "--no-progress"]) == 1
    captured = capsys.readouterr()
    assert "1 of 2 runs diverged" in captured.err and "| diverged |" in captured.out
    lines = (tmp_path / "s.csv").read_text().splitlines()
    assert sum("diverged" in line for line in lines) == 1  # its status and verdict


def test_rows_carry_J_over_J_star_on_request() -> None:
    """optimal_cost=True adds compare's J, J* (with the plant's torque limits) and J / J* - 1 to
    each row, the same numbers compare's machinery gives for that run; a bad value is refused."""
    from adparm.comparison import applied_cost, run_optimal_cost

    base = adparm.paper_config().updated(
        {"sim": {"T": 1.0}, "plant": {"torque_limits": [60.0, 25.0]}, "probe": {"until": 0.0}}
    )
    table = adparm.sweep(base, {"cost.input_bound": [5.0, 20.0]}, optimal_cost=True)
    assert table.columns[-3:] == SWEEP_OPTIMAL_METRICS
    config = base.updated({"cost": {"input_bound": 5.0}})
    J = applied_cost(adparm.simulate(config))[0]
    J_star = run_optimal_cost(config)[0]
    row = table.rows[0]
    assert row["applied_cost"] == pytest.approx(J, rel=1e-12)
    assert row["optimal_cost"] == pytest.approx(float(J_star), rel=1e-9)
    assert row["cost_vs_optimal_cost"] == pytest.approx(J / J_star - 1.0, rel=1e-9)
    assert all(r["cost_vs_optimal_cost"] > 0.0 for r in table)  # J* bounds every J
    with pytest.raises(TypeError, match="optimal_cost: expected True, False or a dict"):
        adparm.sweep(base, {"cost.input_bound": [5.0]}, optimal_cost="yes")


def test_a_lambda_sweep_on_the_ur5_carries_saturation_and_J_over_J_star() -> None:
    """The issue's test: a sweep over lambda on the UR5 (its URDF torque limits, the exact
    saturated family of examples/ur5.toml, a 0.3 s horizon; J* with 20 intervals to keep it to
    seconds) runs, and its rows carry the saturated time per joint and J / J* - 1 >= 0."""
    n = 6
    base = adparm.load_config(
        Path(__file__).resolve().parents[1] / "examples" / "ur5.toml"
    ).updated({"sim": {"T": 0.3}, "extrapolation": {"points": 60}})
    K = np.diag([2.0, 1.5, 1.0, 0.8, 0.5, 0.3])
    points = [
        {"cost." + key: value for key, value in cost.items()}
        for cost in (
            adparm.saturated_cost(K, 2.0 * np.eye(n), np.eye(n), bound) for bound in (0.12, 1.0)
        )
    ]
    table = adparm.sweep(base, points, optimal_cost={"intervals": 20, "max_intervals": 20})
    assert len(table) == 2
    for row in table:
        assert row["status"] == "finished" and row["post_run_errors"] == []
        assert len(row["saturated_time"]) == n
        assert row["optimal_cost"] > 0.0
        assert 0.0 <= row["cost_vs_optimal_cost"] < 10.0


def test_a_sweep_solves_each_J_star_problem_once(monkeypatch) -> None:
    """Rows that differ only in settings J* does not depend on (a learning gain, cost.input_bound:
    J charges the quadratic cost) share one IPOPT solve, with equal J*; rows with another x(0)
    solve their own; outside a sweep every call solves (no cache)."""
    import adparm.truth as truth
    from adparm.comparison import run_optimal_cost

    real, calls = truth.optimal_cost, []

    def counting(config, **options):
        calls.append(tuple(config.task.q0))
        return real(config, **options)

    monkeypatch.setattr(truth, "optimal_cost", counting)
    base = adparm.paper_config().updated({"sim": {"T": 0.3}, "probe": {"until": 0.0}})
    options = {"intervals": 20, "max_intervals": 20}
    grid = {"actor.eta_a2": [0.5, 1.0], "cost.input_bound": [5.0, 20.0]}
    table = adparm.sweep(base, grid, optimal_cost=options, threads=2)
    assert len(table) == 4 and len(calls) == 1
    assert len({row["optimal_cost"] for row in table}) == 1
    assert table.rows[0]["optimal_cost"] == pytest.approx(run_optimal_cost(base, **options)[0])
    calls.clear()
    with ThreadPoolExecutor(2) as executor:  # a thread executor shares the sweep's cache
        table = adparm.sweep(base, grid, optimal_cost=options, executor=executor)
    assert len(calls) == 1
    calls.clear()
    q0 = [[0.3, 0.5], [0.2, 0.4]]
    table = adparm.sweep(
        base, {"task.q0": q0, "critic.eta_c": [100.0, 800.0]}, optimal_cost=options
    )
    assert len(calls) == 2 and len({row["optimal_cost"] for row in table}) == 2
    calls.clear()
    run_optimal_cost(base, **options)
    run_optimal_cost(base, **options)
    assert len(calls) == 2


def test_a_verdict_with_norms_stays_in_its_markdown_cell() -> None:
    # "critic ||Wc - W*|| / ||W*||" in a verdict split the sweep table's row into extra columns;
    # the cell escapes "|" and a Markdown parser (markdown-it, with tables) reads it back whole
    from markdown_it import MarkdownIt

    from adparm.table import rows_markdown

    verdict = "ended away from the known W*: critic ||Wc - W*|| / ||W*|| = 0.016"
    text = rows_markdown(["controller", "verdict"], [{"controller": "adp", "verdict": verdict}])
    tokens = MarkdownIt("commonmark").enable("table").parse(text)
    cells = [t.children[0].content for t in tokens if t.type == "inline"]
    assert cells == ["controller", "verdict", "adp", verdict]
