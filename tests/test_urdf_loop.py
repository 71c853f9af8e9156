"""URDF arms in the closed loop: [plant] urdf runs the paper's laws on the arm Pinocchio reads."""

from __future__ import annotations

import json
import os
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

import adparm
from adparm.cli import main

ROOT = Path(__file__).parent.parent
ARMS = ROOT / "examples" / "arms"
TWO_LINK = ARMS / "two_link.urdf"
PLANAR = ARMS / "planar_3link.urdf"
SPATIAL = ARMS / "spatial_3dof.urdf"
EXAMPLE = ROOT / "examples" / "planar_3link.toml"


def _planar(changes: dict | None = None, T: float = 2.0) -> adparm.Config:
    config = adparm.load_config(EXAMPLE)
    return config.updated({"sim": {"T": T}, **(changes or {})})


def _planar_quadratic(changes: dict | None = None, T: float = 2.0) -> adparm.Config:
    """The example with the quadratic basis (21 functions; no known W* on this arm)."""
    return _planar({"controller": {"basis": "quadratic"}, **(changes or {})}, T)


def test_two_link_urdf_gives_the_built_in_arm_s_recording() -> None:
    """The two-link arm written as a URDF (gravity 9.8, the paper's friction) runs the same loop
    as the built-in arm with the same quadratic basis, to round-off, over 3 s with probing."""
    built_in = adparm.paper_config().updated(
        {"controller": {"basis": "quadratic"}, "sim": {"T": 3.0}}
    )
    weights = built_in.initial_weights().tolist()
    init = {"critic_weights": weights, "actor_weights": weights}
    built_in = built_in.updated({"init": init})
    # every setting given, so that the URDF arm derives none of its own (rates.urdf_defaults)
    settings = built_in.to_dict()
    settings["plant"] = {
        key: value
        for key, value in settings["plant"].items()
        if key not in ("p1", "p2", "p3", "g1", "g2")
    }
    settings["plant"].update({"urdf": str(TWO_LINK), "gravity": [0.0, 0.0, -9.8]})
    urdf = adparm.Config.from_dict(settings)
    assert urdf.plant.urdf == str(TWO_LINK) and urdf.dof == 2
    a = adparm.simulate(built_in, diagnose=False)
    b = adparm.simulate(urdf, diagnose=False)
    assert a.status == b.status == "finished"
    assert a.t.shape == b.t.shape
    for name in ("q", "dq", "tau", "critic_weights", "actor_weights", "hjb_error"):
        x, y = getattr(a, name), getattr(b, name)
        scale = max(np.abs(x).max(), 1.0)
        assert np.abs(x - y).max() <= 1e-9 * scale, name
    # and not trivially: the plant's gravity reaches the run (with the model's unchanged; an
    # exact model would cancel it in the feedforward)
    other = adparm.simulate(
        urdf.updated(
            {"plant": {"gravity": [0.0, 0.0, -9.0]}, "model": {"gravity": [0.0, 0.0, -9.8]}}
        ),
        diagnose=False,
    )
    assert np.abs(other.q - a.q).max() > 1e-4


def test_planar_3link_goes_to_the_set_point_and_stays_bounded() -> None:
    config = _planar(T=10.0)
    assert config.dof == 3
    assert config.controller.basis == adparm.config.URDF_DEFAULT_BASIS
    assert np.shape(config.cost.Q) == (6, 6)
    result = adparm.simulate(config, diagnose=False)
    assert result.status == "finished"
    assert result.q.shape[1] == 3
    qd = np.array(config.task.qd)
    assert np.abs(result.q[0] - qd).max() > 0.3  # starts away
    assert np.abs(result.q[-1] - qd).max() < 1e-3  # and arrives
    assert np.all(np.isfinite(result.critic_weights))
    assert np.abs(result.critic_weights).max() < 1e3


def test_model_mismatch_through_model_urdf_and_gravity_changes_the_run() -> None:
    exact = adparm.simulate(_planar(), diagnose=False)
    for model in (
        {"gravity": [0.0, 0.0, -9.0]},
        {"urdf": str(SPATIAL)},
        {"coulomb": [0.1, 0.2, 0.3]},
    ):
        mismatch = adparm.simulate(_planar({"model": model}), diagnose=False)
        assert mismatch.status == "finished"
        assert np.abs(mismatch.tau - exact.tau).max() > 1e-3, model
    # the model's terms are the model URDF's
    config = _planar({"model": {"urdf": str(SPATIAL), "gravity": [0.0, 0.0, -5.0]}})
    q, dq = np.array([0.1, 0.2, 0.3]), np.zeros(3)
    believed = adparm.arm_terms(config, q, dq, model=True)
    expected = adparm.UrdfArm(SPATIAL, gravity=[0.0, 0.0, -5.0], coulomb=-0.1).terms(q, dq)
    np.testing.assert_allclose(believed["M"], expected["M"], rtol=1e-14)
    np.testing.assert_allclose(believed["G"], expected["G"], rtol=1e-14)


def test_a_model_urdf_with_another_joint_count_is_refused() -> None:
    with pytest.raises(ValueError, match=r"model\.urdf: the model has n = 2 joints.*n = 3"):
        _planar({"model": {"urdf": str(TWO_LINK)}})


@pytest.mark.parametrize(
    ("section", "key", "value"),
    [
        ("task", "q0", [0.1, 0.2]),
        ("task", "qd", [0.1, 0.2, 0.3, 0.4]),
        ("cost", "Q", np.eye(4).tolist()),
        ("cost", "R", np.eye(2).tolist()),
        ("control", "alpha1", np.eye(2).tolist()),
        ("plant", "coulomb", [0.1, 0.2]),
        ("plant", "viscous", [0.1, 0.2, 0.3, 0.4]),
        ("plant", "disturbance", [0.1, 0.2]),
        ("model", "coulomb", [0.1, 0.2]),
        ("extrapolation", "box", [1.0] * 4),
        ("probe", "amplitude", [1.0, 2.0]),
    ],
)
def test_wrong_sizes_name_the_field_and_n(section: str, key: str, value: object) -> None:
    with pytest.raises(ValueError, match=rf"{section}\.{key}: .*n = 3"):
        _planar({section: {key: value}})


def test_wrong_initial_weights_name_the_basis_size() -> None:
    with pytest.raises(ValueError, match=r"init\.critic_weights: expected shape \(21,\)"):
        _planar_quadratic({"init": {"critic_weights": [1.0] * 8}})
    with pytest.raises(ValueError, match=r"init\.critic_weights: expected shape \(13,\)"):
        _planar({"init": {"critic_weights": [1.0] * 8}})  # the structured basis


def test_per_joint_friction_reaches_the_plant() -> None:
    config = _planar({"plant": {"coulomb": [0.1, 0.2, 0.3], "viscous": 0.5}})
    dq = np.array([1.0, -1.0, 2.0])
    F = adparm.arm_terms(config, np.zeros(3), dq)["F"]
    np.testing.assert_allclose(F, [0.1 + 0.5, -0.2 - 0.5, 0.3 + 1.0], rtol=1e-15)


@pytest.mark.parametrize("key", ["p1", "p2", "p3", "g1", "g2"])
def test_two_link_keys_with_a_urdf_are_refused(key: str) -> None:
    with pytest.raises(ValueError, match=rf"plant\.{key}: .*two-link"):
        adparm.Config.from_dict({"plant": {"urdf": str(PLANAR), key: 2.0}})
    # even at the two-link default, when given
    default = getattr(adparm.PlantConfig(), key)
    with pytest.raises(ValueError, match=rf"plant\.{key}"):
        adparm.Config.from_dict({"plant": {"urdf": str(PLANAR), key: default}})
    with pytest.raises(ValueError, match=rf"model\.{key}"):
        adparm.Config.from_dict({"plant": {"urdf": str(PLANAR)}, "model": {key: 2.0}})


@pytest.mark.parametrize("basis", ["paper", "augmented"])
def test_two_link_bases_with_a_urdf_are_refused(basis: str) -> None:
    with pytest.raises(ValueError, match=r"controller\.basis: .*two-link.*'structured'"):
        adparm.Config.from_dict({"plant": {"urdf": str(PLANAR)}, "controller": {"basis": basis}})


def test_gravity_and_model_urdf_need_a_urdf_plant() -> None:
    with pytest.raises(ValueError, match=r"plant\.gravity: only with plant\.urdf"):
        adparm.Config.from_dict({"plant": {"gravity": [0.0, 0.0, -9.81]}})
    with pytest.raises(ValueError, match=r"model\.urdf: only with a URDF plant"):
        adparm.Config.from_dict({"model": {"urdf": str(PLANAR)}})
    with pytest.raises(ValueError, match=r"plant\.coulomb: one number for the built-in"):
        adparm.Config.from_dict({"plant": {"coulomb": [0.1, 0.1]}})
    with pytest.raises(ValueError, match=r"plant\.gravity: expected shape \(3,\)"):
        adparm.Config.from_dict({"plant": {"urdf": str(PLANAR), "gravity": [0.0, -9.81]}})


FLOATING = """<robot name="floating">
  <link name="world"/>
  <link name="body"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1"
    iyz="0" izz="1"/></inertial></link>
  <joint name="free" type="floating"><parent link="world"/><child link="body"/></joint>
</robot>"""

FIXED_ONLY = """<robot name="statue">
  <link name="world"/>
  <link name="body"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1"
    iyz="0" izz="1"/></inertial></link>
  <joint name="weld" type="fixed"><parent link="world"/><child link="body"/></joint>
</robot>"""


@pytest.mark.parametrize(
    ("text", "problem"),
    [("<robot name='x'><link", ""), (FLOATING, "floating"), (FIXED_ONLY, "")],
    ids=["unparsable", "floating", "no actuated joint"],
)
def test_bad_urdfs_are_refused_naming_plant_urdf(tmp_path: Path, text: str, problem: str) -> None:
    path = tmp_path / "bad.urdf"
    path.write_text(text)
    with pytest.raises(ValueError, match=r"plant\.urdf: .*bad\.urdf.*" + problem) as error:
        adparm.Config.from_dict({"plant": {"urdf": str(path)}})
    assert "plant.urdf" in str(error.value)
    with pytest.raises(ValueError, match=r"plant\.urdf: no URDF file"):
        adparm.Config.from_dict({"plant": {"urdf": str(tmp_path / "missing.urdf")}})


def test_a_relative_urdf_path_is_relative_to_the_toml_file(tmp_path: Path, monkeypatch) -> None:
    folder = tmp_path / "project"
    (folder / "arms").mkdir(parents=True)
    shutil.copy(PLANAR, folder / "arms" / "mine.urdf")
    (folder / "run.toml").write_text('[plant]\nurdf = "arms/mine.urdf"\n')
    monkeypatch.chdir(tmp_path)  # not the TOML file's folder
    config = adparm.load_config(folder / "run.toml")
    assert config.plant.urdf == str(folder / "arms" / "mine.urdf")
    assert config.dof == 3
    # from a dict: relative to the current directory, stored absolute
    monkeypatch.chdir(folder)
    from_dict = adparm.Config.from_dict({"plant": {"urdf": "arms/mine.urdf"}})
    assert from_dict.plant.urdf == os.path.abspath(folder / "arms" / "mine.urdf")
    # and the TOML it writes reads back to the same config
    assert adparm.Config.from_dict(_toml_roundtrip(from_dict)) == from_dict


def _toml_roundtrip(config: adparm.Config) -> dict:
    import tomllib

    return tomllib.loads(config.to_toml())


def test_arm_terms_equal_pinocchio_s_python_bindings(rng) -> None:
    pin = pytest.importorskip("pinocchio")
    gravity = np.array([0.3, -0.2, -9.7])
    config = adparm.Config.from_dict(
        {
            "plant": {
                "urdf": str(SPATIAL),
                "gravity": gravity.tolist(),
                "coulomb": [0.1, 0.2, 0.3],
                "viscous": 0.05,
            }
        }
    )
    model = pin.buildModelFromUrdf(str(SPATIAL))
    model.gravity.linear = gravity
    data = model.createData()
    for _ in range(3):
        q, dq = rng.uniform(-1.5, 1.5, 3), rng.uniform(-2.0, 2.0, 3)
        terms = adparm.arm_terms(config, q, dq)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        C = pin.computeCoriolisMatrix(model, data, q, dq)
        G = pin.computeGeneralizedGravity(model, data, q)
        F = np.array([0.1, 0.2, 0.3]) * np.sign(dq) + 0.05 * dq
        np.testing.assert_allclose(terms["M"], M, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(terms["C"], C, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(terms["G"], G, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(terms["F"], F, rtol=1e-15)


def test_basis_and_names_of_an_n_joint_expression_basis(rng) -> None:
    config = _planar_quadratic()
    names = adparm.basis_names(config)
    assert len(names) == 21 and "x6^2" in names
    x = rng.uniform(-1.0, 1.0, (5, 6))
    phi, jacobian = adparm.basis(config, x)
    assert phi.shape == (5, 21) and jacobian.shape == (5, 21, 6)
    i = names.index("x6^2")
    np.testing.assert_allclose(phi[:, i], x[:, 5] ** 2, rtol=1e-15)
    np.testing.assert_allclose(jacobian[:, i, 5], 2.0 * x[:, 5], rtol=1e-15)
    # the HJB error of the initial weights, at states of 2n = 6 entries
    W = config.initial_weights()
    residual = adparm.hjb_residual(config, x, W, W)
    assert residual.shape == (5,) and np.all(np.isfinite(residual))
    with pytest.raises(ValueError, match=r"x: expected shape \(\.\.\., 6\)"):
        adparm.hjb_residual(config, x[:, :4], W, W)


def test_diagnostics_say_the_optimum_is_not_known() -> None:
    with warnings.catch_warnings():  # a quadratic basis cannot represent V* on this arm
        warnings.simplefilter("ignore", adparm.ApproximationWarning)
        result = adparm.simulate(_planar_quadratic(T=3.0))
    diagnostics = result.diagnostics
    assert diagnostics["critic_relative_error"] is None
    assert "optimum is not known" in diagnostics["verdict"]
    assert diagnostics["value_yardstick"] == "LQR"
    assert np.isfinite(diagnostics["hjb_residual_explored"])
    summary = result.summary()
    assert "optimum is not known" in summary["verdict"]
    with pytest.raises(ValueError, match="no known W\\* for an expression basis on a URDF arm"):
        adparm.optimal_weights(result.config)


def test_cli_runs_a_urdf_config_and_writes_its_outputs(tmp_path: Path, capsys) -> None:
    config = tmp_path / "arm.toml"
    text = EXAMPLE.read_text().replace(
        'urdf = "arms/planar_3link.urdf"', f"urdf = {json.dumps(str(PLANAR))}"
    )
    text = text.replace("[task]", '[controller]\nbasis = "quadratic"\n\n[task]')
    config.write_text(text.replace("T = 20.0", "T = 1.0"))
    out = tmp_path / "out"
    assert main(["run", str(config), "--out", str(out), "--no-progress"]) == 0
    written = {p.name for p in out.iterdir()}
    assert {"summary.json", "fig4_errors.png", "fig2_critic_weights.png"} <= written
    summary = json.loads((out / "summary.json").read_text())
    assert len(summary["basis"]) == 21 and len(summary["final_e1"]) == 3
    assert adparm.load_config(out / "config.toml").plant.urdf == str(PLANAR)
    loaded = adparm.load_result(out / "result.csv")
    assert loaded.q.shape[1] == 3
    np.testing.assert_array_equal(loaded.q, adparm.load_result(out / "result.npz").q)
    assert "optimum is not known" in capsys.readouterr().err


def test_batch_of_urdf_runs_equals_single_runs() -> None:
    configs = [_planar(T=0.5), _planar({"task": {"q0": [0.0, 0.1, 0.2]}}, T=0.5)]
    batch = adparm.simulate_batch(configs, threads=2)
    for config, result in zip(configs, batch, strict=True):
        single = adparm.simulate(config, diagnose=False)
        np.testing.assert_array_equal(result.q, single.q)
        np.testing.assert_array_equal(result.critic_weights, single.critic_weights)


def test_compare_and_sweep_run_a_urdf_config() -> None:
    config = _planar_quadratic(T=1.0)
    with warnings.catch_warnings():  # the quadratic basis on this arm (diagnosed in the rows)
        warnings.simplefilter("ignore", adparm.ApproximationWarning)
        comparison = adparm.compare(config, ["adp", "rise", "optimal"])
        swept = adparm.sweep(config, {"critic.eta_c": [400.0, 800.0]}, threads=1)
    best = comparison.optimal_cost  # J* of the URDF arm over sim.T: a lower bound of every J
    assert best is not None and best.horizon == 1.0 and not best.terminal
    assert min(row["cost_vs_optimal_cost"] for row in comparison.rows) >= -2 * best.error
    assert {r.status for r in comparison.results.values()} == {"finished"}
    assert all(r.q.shape[1] == 3 for r in comparison.results.values())
    figure = comparison.plot()
    assert len(figure.axes) == 2 * 6  # e1 and tau of each of the 3 joints, two columns
    assert [row["status"] for row in swept.rows] == ["finished", "finished"]
    assert all("optimum is not known" in row["verdict"] for row in swept.rows)
    assert comparison.post_run_errors == ()


def test_the_core_checks_a_urdf_run_naming_the_field() -> None:
    from adparm import _core
    from adparm.simulation import core_settings

    def settings() -> _core.Settings:
        return core_settings(_planar(T=0.1))

    assert _core.Simulation(settings()).steps == 100
    s = settings()
    s.basis = _core.BasisKind.augmented
    with pytest.raises(ValueError, match=r"controller\.basis: .*URDF"):
        _core.Simulation(s)
    s = settings()
    model = s.model_urdf
    model.urdf = str(TWO_LINK)
    s.model_urdf = model
    with pytest.raises(ValueError, match=r"model\.urdf: the model has 2 joints"):
        _core.Simulation(s)
    s = settings()
    task = s.task
    task.q0 = np.zeros(2)
    s.task = task
    with pytest.raises(ValueError, match=r"task\.q0"):
        _core.Simulation(s)
    s = settings()
    plant = s.plant_urdf
    plant.coulomb = np.zeros(2)
    s.plant_urdf = plant
    with pytest.raises(ValueError, match=r"plant\.urdf: .*coulomb"):
        _core.Simulation(s)


def test_a_six_joint_arm_runs_and_plots_one_line_per_joint() -> None:
    try:
        ur5 = adparm.example_robot_urdf("ur5")
    except ModuleNotFoundError:  # pragma: no cover - example-robot-data is in the test extra
        pytest.skip("example-robot-data is not installed")
    config = adparm.Config.from_dict(
        {
            "plant": {"urdf": str(ur5)},
            "task": {
                "q0": [0.1, -1.2, 1.0, -0.5, 0.3, 0.2],
                "qd": [0.3, -1.0, 0.8, -0.3, 0.5, 0.0],
            },
            "controller": {"basis": "quadratic"},
            "sim": {"T": 0.3},
        }
    )
    assert config.dof == 6 and len(adparm.basis_names(config)) == 78
    result = adparm.simulate(config, diagnose=False)
    assert result.status == "finished" and result.q.shape[1] == 6
    # the error shrinks from the start (RISE and the actor's initial policy on the exact model)
    assert np.linalg.norm(result.e1[-1]) < np.linalg.norm(result.e1[0])
    figures = result.plot()
    errors = figures["fig4_errors"].axes[0]
    assert len(errors.get_lines()) >= 6
    assert [t.get_text() for t in errors.get_legend().get_texts()][:6] == [
        f"$q_{j}$" for j in range(1, 7)
    ]


@pytest.mark.parametrize("kind", ["rise", "pd", "optimal"])
def test_every_controller_kind_runs_a_urdf_arm_with_the_structured_basis(kind: str) -> None:
    """The core builds the structured basis (with its e2 check positions) for every controller,
    not only the learning one."""
    config = _planar({"controller": {"kind": kind}}, T=0.2)
    assert config.controller.basis == "structured"
    result = adparm.simulate(config, diagnose=False)
    assert result.status == "finished"
