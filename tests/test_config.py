"""Configuration: the paper preset, TOML loading, and refusal of bad input naming the field."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import adparm
from adparm import _core
from adparm.simulation import core_settings


def test_python_preset_equals_the_cores_copy() -> None:
    ours = core_settings(adparm.paper_config())
    core = _core.paper_settings()
    for section, keys in {
        "plant": ("p1", "p2", "p3", "g1", "g2", "coulomb", "viscous"),
        "critic": ("eta_c", "nu", "gamma0", "epsilon_T"),
        "actor": ("eta_a1", "eta_a2", "weight_bound", "positive_e2", "e2_margin"),
        "sim": ("T", "dt", "record_every", "divergence_bound"),
    }.items():
        for key in keys:
            assert getattr(getattr(ours, section), key) == getattr(getattr(core, section), key), key
    for key in ("ks", "alpha2", "beta1"):
        assert getattr(ours.control.rise, key) == getattr(core.control.rise, key), key
    for name in ("Q", "R", "disturbance", "critic_weights", "actor_weights"):
        np.testing.assert_array_equal(getattr(ours, name), getattr(core, name), err_msg=name)
    np.testing.assert_array_equal(ours.control.alpha1, core.control.alpha1)
    for name in ("q0", "dq0"):
        np.testing.assert_array_equal(getattr(ours.task, name), getattr(core.task, name))
    assert ours.task.qd.kind == core.task.qd.kind == _core.TrajectoryKind.constant
    np.testing.assert_array_equal(ours.task.qd.offset, core.task.qd.offset)
    assert ours.basis == core.basis
    for key in ("kind", "rise", "kp", "kd"):
        np.testing.assert_array_equal(
            getattr(ours.controller, key), getattr(core.controller, key), err_msg=key
        )
    for key in ("points", "box", "mode", "seed"):
        np.testing.assert_array_equal(
            getattr(ours.extrapolation, key), getattr(core.extrapolation, key), err_msg=key
        )
    for name in ("amplitude", "until", "frequencies", "phases"):
        np.testing.assert_array_equal(getattr(ours.probe, name), getattr(core.probe, name))


def test_paper_values() -> None:
    c = adparm.paper_config()
    assert (c.plant.p1, c.plant.p2, c.plant.p3) == (5.0, 1.0, 1.0)
    assert c.plant.g1 == pytest.approx(11.76) and c.plant.g2 == 9.8
    assert c.plant.coulomb == -0.1 and c.plant.disturbance == (0.1, 0.1)
    assert c.task.q0 == (0.1598, 0.2257) and c.task.qd == (0.0, 0.0)
    assert c.cost.R == ((0.25, 0.0), (0.0, 0.25))
    assert c.control.alpha1 == ((15.6, 10.6), (10.6, 10.4))
    assert (c.critic.eta_c, c.critic.nu, c.critic.gamma0) == (800, 1, 100)
    assert c.critic.epsilon_T is None
    assert c.resolved_epsilon_T == 1e-6  # our deviation from the printed 1e-3 (docs/paper.md)
    assert c.updated({"extrapolation": {"points": 10}}).resolved_epsilon_T == 1e-3  # printed
    assert c.updated({"critic": {"epsilon_T": 0.5}}).resolved_epsilon_T == 0.5
    assert (c.controller.kind, c.controller.basis, c.controller.rise) == ("adp", "augmented", True)
    assert c.extrapolation.points == 0
    assert (c.actor.eta_a1, c.actor.eta_a2) == (0.01, 1.0)
    assert c == adparm.Config()


def test_config_is_frozen_and_hashable() -> None:
    c = adparm.paper_config()
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.critic.eta_c = 1.0  # type: ignore[misc]
    assert hash(c) == hash(adparm.paper_config())


def test_load_config_fills_missing_keys_with_paper_defaults(tmp_path) -> None:
    path = tmp_path / "run.toml"
    path.write_text(
        """
[critic]
eta_c = 200
epsilon_T = 1e-5

[cost]
R = [[0.2, 0.0], [0.0, 0.2]]
Q = [[40, 2, -4, 4], [2, 40, 4, -6], [-4, 4, 5, 0], [4, -6, 0, 5]]

[probe]
amplitude = 3.0
frequencies = [1.0, 2.0]

[sim]
T = 2.5
record_every = 5
"""
    )
    c = adparm.load_config(path)
    assert c.critic.eta_c == 200.0 and c.critic.epsilon_T == 1e-5
    assert c.critic.nu == 1.0 and c.critic.gamma0 == 100.0
    assert c.probe.amplitude == 3.0 and c.probe.phase_matrix().shape == (2, 2)
    np.testing.assert_array_equal(c.probe.amplitude_matrix(), np.full((2, 2), 3.0))
    assert c.sim.T == 2.5 and c.sim.dt == 1e-3 and c.sim.record_every == 5
    assert c.plant == adparm.PlantConfig()
    assert adparm.optimal_weights(c)[0] == 4.0


def test_round_trip_through_dict() -> None:
    c = adparm.paper_config().updated({"model": {"p1": 4.0}, "task": {"qd": [0.5, 0.0]}})
    d = c.to_dict()
    assert d["model"] == {"p1": 4.0}
    assert adparm.Config.from_dict(d) == c


@pytest.mark.parametrize(
    ("data", "error", "message"),
    [
        (
            {"critc": {}},
            ValueError,
            r"unknown config section \[critc\] \(did you mean 'critic'\?\)",
        ),
        ({"critic": {"eta": 1}}, ValueError, r"unknown key critic.eta \(did you mean 'eta_c'\?\)"),
        ({"critic": 3}, TypeError, r"\[critic\]: expected a table"),
        ({"critic": {"eta_c": "fast"}}, TypeError, "critic.eta_c: expected a number"),
        ({"critic": {"eta_c": True}}, TypeError, "critic.eta_c: expected a number"),
        ({"critic": {"eta_c": -1}}, ValueError, "critic.eta_c: must be >= 0"),
        ({"critic": {"gamma0": 0}}, ValueError, "critic.gamma0: must be > 0"),
        ({"critic": {"epsilon_T": 200}}, ValueError, "critic.epsilon_T: must be < critic.gamma0"),
        ({"sim": {"dt": 0}}, ValueError, "sim.dt: must be > 0"),
        ({"sim": {"T": float("nan")}}, ValueError, "sim.T: must be finite"),
        ({"sim": {"record_every": 0}}, ValueError, "sim.record_every: must be >= 1"),
        ({"sim": {"record_every": 2.5}}, TypeError, "sim.record_every: expected an integer"),
        ({"sim": {"dt": 2.0, "T": 1.0}}, ValueError, "sim.dt: must be <= sim.T"),
        ({"task": {"q0": [0.1]}}, ValueError, r"task.q0: expected shape \(2,\), got \(1,\)"),
        ({"task": {"q0": 0.1}}, TypeError, "task.q0: expected a list of n numbers"),
        ({"task": {"qd": [0.0, float("inf")]}}, ValueError, "task.qd: must be finite"),
        ({"cost": {"R": [[1, 0.5], [0, 1]]}}, ValueError, "cost.R: must be symmetric"),
        ({"cost": {"R": [[1, 0], [0, -1]]}}, ValueError, "cost.R: must be positive definite"),
        ({"cost": {"Q": np.zeros((4, 4))}}, ValueError, "cost.Q: must be positive definite"),
        ({"cost": {"Q": [[1, 0], [0, 4]]}}, ValueError, r"cost.Q: expected shape \(4, 4\)"),
        ({"cost": {"Q": [[1, 2], [3, 4]]}}, ValueError, r"cost.Q: must be symmetric"),
        (
            {"control": {"alpha1": [["a", 0], [0, 1]]}},
            TypeError,
            "control.alpha1: expected an array",
        ),
        ({"plant": {"p2": -1}}, ValueError, "plant.p2: must be > 0"),
        ({"plant": {"p1": 1.0}}, ValueError, "plant.p1, plant.p2, plant.p3: M"),
        ({"model": {"p3": 3.0}}, ValueError, "model.p1, model.p2, model.p3: M"),
        (
            {"init": {"critic_weights": [1, 2]}},
            ValueError,
            r"init.critic_weights: expected shape \(8,\)",
        ),
        ({"probe": {"phases": [[0, 0]]}}, ValueError, "probe.phases: expected shape"),
        ({"actor": {"weight_bound": 0}}, ValueError, "actor.weight_bound: must be > 0"),
        (
            {"controller": {"kind": "optimum"}},
            ValueError,
            r"controller.kind: expected one of adp, rise, pd, optimal, got 'optimum' "
            r"\(did you mean 'optimal'\?\)",
        ),
        ({"controller": {"kind": 1}}, TypeError, "controller.kind: expected one of"),
        ({"controller": {"basis": "pape"}}, ValueError, "did you mean 'paper'"),
        ({"controller": {"rise": "yes"}}, TypeError, "controller.rise: expected true or false"),
        (
            {"controller": {"kind": "rise", "rise": False}},
            ValueError,
            "controller.rise: kind = 'rise' is the RISE feedback alone",
        ),
        ({"controller": {"kp": [1, 2]}}, ValueError, r"controller.kp: expected shape \(n, n\)"),
        ({"controller": {"kd": np.eye(3)}}, ValueError, r"controller.kd: expected shape \(2, 2\)"),
        (
            {"task": {"q0": [0.1, 0.2, 0.3]}},
            ValueError,
            r"task.q0: .* \(the arm has n = 2 joints\)",
        ),
        ({"controller": {"kd": float("nan")}}, ValueError, "controller.kd: must be finite"),
        ({"extrapolation": {"points": -1}}, ValueError, "extrapolation.points: must be >= 0"),
        ({"extrapolation": {"points": 2.0}}, TypeError, "extrapolation.points: expected an int"),
        ({"extrapolation": {"box": 0}}, ValueError, "extrapolation.box: must be > 0"),
        ({"extrapolation": {"box": [1, 1, 0, 1]}}, ValueError, "extrapolation.box: half-widths"),
        ({"extrapolation": {"box": [1, 1]}}, ValueError, r"extrapolation.box: expected shape"),
        ({"extrapolation": {"mode": "random"}}, ValueError, "extrapolation.mode: expected one of"),
        ({"extrapolation": {"seed": 2**32}}, ValueError, "extrapolation.seed: must be < 2"),
        (
            {"extrapolation": {"mode": "grid", "points": 10}},
            ValueError,
            "extrapolation.points: grid mode needs m\\^4 points",
        ),
        ({"extrapolation": {"pts": 10}}, ValueError, "did you mean 'points'"),
        ({"task": {"qd": {"amplitude": [1, 1]}}}, ValueError, "task.qd.kind: expected one of"),
        ({"task": {"qd": {"kind": "sinusiod"}}}, ValueError, "did you mean 'sinusoid'"),
        (
            {"task": {"qd": {"kind": "sinusoid", "amplitud": [1, 1]}}},
            ValueError,
            r"unknown key task.qd.amplitud \(did you mean 'amplitude'\?\)",
        ),
        (
            {
                "task": {
                    "qd": {"kind": "sinusoid", "amplitude": [[1, 2], [3, 4]], "frequency": [1, 2]}
                }
            },
            ValueError,
            r"task.qd.frequency: expected 2 column",
        ),
        (
            {"task": {"qd": {"kind": "sinusoid", "phase": [0, float("nan")]}}},
            ValueError,
            "task.qd.phase: must be finite",
        ),
        (
            {"task": {"qd": {"kind": "samples", "t": [0, 1, 1], "q": [[0, 0]] * 3}}},
            ValueError,
            "task.qd.t: sample times must be strictly increasing",
        ),
        (
            {"task": {"qd": {"kind": "samples", "t": [1, 2], "q": [[0, 0]] * 2}}},
            ValueError,
            "task.qd.t: the first sample must be at t <= 0",
        ),
        (
            {"task": {"qd": {"kind": "samples", "t": [0, 2], "q": [[0, 0]] * 3}}},
            ValueError,
            r"task.qd.q: expected shape \(2, 2\)",
        ),
        (
            {"task": {"qd": {"kind": "samples", "t": [0, 2], "q": [[0, 0]] * 2}}},
            ValueError,
            r"task.qd: the samples end at t = 2 s, before sim.T = 150 s",
        ),
        (
            {"task": {"qd": {"kind": "samples", "file": "/nonexistent/qd.csv"}}},
            ValueError,
            "task.qd.file: cannot read",
        ),
        ({"critic": {"gamma0": 1e-7}}, ValueError, "critic.epsilon_T: must be < critic.gamma0"),
        # arrays hold real numbers only: no strings, bools, complex numbers, None or ragged rows
        ({"task": {"q0": ["1", 0.0]}}, TypeError, r"task.q0: expected an array of numbers .*str"),
        ({"task": {"q0": [True, 0.0]}}, TypeError, r"task.q0: expected an array .*holds bool"),
        ({"cost": {"R": [[1j, 0], [0, 1]]}}, TypeError, "cost.R: .*holds complex"),
        ({"plant": {"disturbance": [None, 0.1]}}, TypeError, "plant.disturbance: .*NoneType"),
        ({"init": {"actor_weights": np.ones(8, bool)}}, TypeError, "init.actor_weights: expected"),
        ({"cost": {"R": [[1, 0], [0]]}}, TypeError, "cost.R: expected an array of numbers"),
        ({"probe": {"amplitude": [[1, 2], [3]]}}, TypeError, "probe.amplitude: expected an array"),
        ({"task": {"qd": {"kind": "sinusoid", "amplitude": [[1], []]}}}, TypeError, "task.qd.amp"),
        # numbers beyond the float range are not finite (they raised OverflowError)
        ({"critic": {"eta_c": 10**400}}, ValueError, "critic.eta_c: must be finite"),
        ({"task": {"q0": [10**400, 0]}}, ValueError, "task.q0: must be finite"),
        ({"plant": {"p2": 1e200}}, ValueError, "plant.p1, plant.p2, plant.p3: M.*and finite"),
        ({"plant": {"p1": 1e200, "p2": 1e200}}, ValueError, r"plant.p1, .*got nan\)"),
        # integers with an upper bound
        ({"sim": {"record_every": 10**30}}, ValueError, "sim.record_every: must be <= 10_000_000"),
        ({"extrapolation": {"points": 10**6 + 1}}, ValueError, "extrapolation.points: must be <="),
        ({"sim": {"dt": 1e-12}}, ValueError, r"sim.dt: sim.T / sim.dt = 1.5e\+14 steps"),
        # names that are no strings
        ({1: {}}, TypeError, "config: section names must be strings, got int 1"),
        ({"sim": {None: 1}}, TypeError, r"\[sim\]: key names must be strings, got NoneType"),
        ({"task": {"qd": {"kind": "sinusoid", 2: 1}}}, TypeError, r"\[task.qd\]: key names"),
        ({"task": {"qd": {"kind": 0}}}, TypeError, "task.qd.kind: expected one of .*got 0"),
        # -alpha1 Hurwitz (de1 = -alpha1 e1 + e2 stable)
        ({"control": {"alpha1": [[1, 2], [2, 1]]}}, ValueError, "control.alpha1: every eigen"),
        ({"control": {"alpha1": [[0, 1], [-1, 0]]}}, ValueError, "control.alpha1: every eigen"),
        ({"control": {"alpha1": np.zeros((2, 2))}}, ValueError, "control.alpha1: every eigen"),
        (
            {"cost": {"Q": np.diag([1e300, 1e300, 1e300, -1e300])}},
            ValueError,
            "cost.Q: must be pos",
        ),
        ({"cost": {"R": [[1e300, 1e300], [0, 1e300]]}}, ValueError, "cost.R: must be symmetric"),
        # samples: a path the OS refuses, and splines that overflow
        (
            {"task": {"qd": {"kind": "samples", "file": "qd\0.csv"}}},
            ValueError,
            "task.qd.file: cannot read",
        ),
        (
            {"task": {"qd": {"kind": "samples", "t": [-1e308, 1e308], "q": [[0, 0], [1, 1]]}}},
            ValueError,
            "task.qd.t: the samples must span a finite time, got -1e[+]308 to 1e[+]308",
        ),
        (
            {
                "task": {
                    "qd": {
                        "kind": "samples",
                        "t": [0, 1e-300, 200],
                        "q": [[0, 0], [1e300, 0], [0, 0]],
                    }
                }
            },
            ValueError,
            "task.qd.q: the cubic spline through the samples overflows",
        ),
    ],
)
def test_bad_input_names_the_field(data, error, message) -> None:
    with pytest.raises(error, match=message):
        adparm.Config.from_dict(data)


def test_numpy_values_are_accepted() -> None:
    c = adparm.Config.from_dict(
        {
            "controller": {"rise": np.bool_(False), "kp": np.float32(2.0)},
            "sim": {"record_every": np.int64(3), "T": np.float64(2.0)},
            "task": {"q0": np.array([1, 2], dtype=np.int32)},
            "cost": {"R": np.eye(2, dtype=np.float32)},
        }
    )
    assert c.controller.rise is False and c.controller.kp == 2.0
    assert c.sim.record_every == 3 and type(c.sim.record_every) is int
    assert c.task.q0 == (1.0, 2.0) and c.cost.R == ((1.0, 0.0), (0.0, 1.0))


def test_from_dict_refuses_a_base_that_is_no_config() -> None:
    with pytest.raises(TypeError, match="base: expected adparm.Config or None, got dict"):
        adparm.Config.from_dict({}, base={})  # type: ignore[arg-type]


def _set_arm(settings, which: str, **values: float) -> None:
    # the settings' arms are copies on access (a std::variant in the core): assign them whole
    arm = getattr(settings, which)
    for key, value in values.items():
        setattr(arm, key, value)
    setattr(settings, which, arm)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        # what config refuses, the core refuses too (settings built directly)
        (lambda s: setattr(s, "Q", np.diag([1.0, 1.0, 1.0, -1.0])), "cost.Q: must be positive def"),
        (lambda s: setattr(s, "Q", np.diag([1.0, 1.0, 1.0, 0.0])), "cost.Q: must be positive def"),
        (lambda s: setattr(s, "R", np.zeros((2, 2))), "cost.R: must be positive definite"),
        (lambda s: setattr(s, "R", [[1e300, 1e300], [0, 1e300]]), "cost.R: must be symmetric"),
        (lambda s: setattr(s.control, "alpha1", [[1, 2], [2, 1]]), "control.alpha1: every eigen"),
        (lambda s: setattr(s.control, "alpha1", [[0, 1], [-1, 0]]), "control.alpha1: every eigen"),
        (lambda s: setattr(s.control, "alpha1", np.zeros((2, 2))), "control.alpha1: every eigen"),
        (lambda s: _set_arm(s, "plant", p2=1e200), "plant.p1, p2, p3: M.*and finite"),
        (lambda s: _set_arm(s, "model", p1=1e200, p2=1e200), "model.p1, p2"),
        (
            lambda s: setattr(s.extrapolation, "points", 10**6 + 1),
            "extrapolation.points: must be <=",
        ),
    ],
)
def test_core_refuses_what_config_refuses(change, message) -> None:
    settings = core_settings(adparm.paper_config())
    change(settings)
    with pytest.raises(ValueError, match=message):
        _core.Simulation(settings)
    # and Python refuses the same values before any C++ runs
    with pytest.raises(ValueError, match=message.split(":")[0].split(",")[0]):
        adparm.Config.from_dict(_python_changes(settings))


def _python_changes(settings: _core.Settings) -> dict:
    paper = core_settings(adparm.paper_config())
    changes: dict = {}
    for name in ("Q", "R"):
        if not np.array_equal(getattr(settings, name), getattr(paper, name)):
            changes["cost"] = {name: getattr(settings, name)}
    if not np.array_equal(settings.control.alpha1, paper.control.alpha1):
        changes["control"] = {"alpha1": settings.control.alpha1}
    for section in ("plant", "model"):
        for key in ("p1", "p2"):
            if getattr(getattr(settings, section), key) != getattr(getattr(paper, section), key):
                changes.setdefault(section, {})[key] = getattr(getattr(settings, section), key)
    if settings.extrapolation.points != paper.extrapolation.points:
        changes["extrapolation"] = {"points": settings.extrapolation.points}
    return changes


def test_load_config_reports_invalid_toml(tmp_path) -> None:
    path = tmp_path / "broken.toml"
    path.write_text("[critic\neta_c = 1\n")
    with pytest.raises(ValueError, match="invalid TOML"):
        adparm.load_config(path)


def test_load_config_refuses_unknown_keys_in_files(tmp_path) -> None:
    path = tmp_path / "typo.toml"
    path.write_text("[sim]\nrecord_evry = 3\n")
    with pytest.raises(ValueError, match="did you mean 'record_every'"):
        adparm.load_config(path)


def test_simulate_refuses_non_config() -> None:
    with pytest.raises(TypeError, match="config: expected adparm.Config"):
        adparm.simulate({"sim": {"T": 1}})  # type: ignore[arg-type]


def test_trajectories_round_trip_through_toml(tmp_path) -> None:
    sinusoid = adparm.paper_config().updated(
        {
            "task": {
                "qd": {
                    "kind": "sinusoid",
                    "amplitude": [[0.5, 0.1], [0.3, 0.0]],
                    "frequency": [[1.0, 3.0], [2.0, 1.0]],
                    "offset": [0.1, -0.2],
                }
            }
        }
    )
    assert sinusoid.task.qd.phase == ((0.0, 0.0), (0.0, 0.0))
    path = tmp_path / "sinusoid.toml"
    path.write_text(sinusoid.to_toml())
    assert adparm.load_config(path) == sinusoid

    samples = tmp_path / "data" / "qd.csv"
    samples.parent.mkdir()
    samples.write_text("t,qd1,qd2\n# a comment\n0,0,0\n1,0.5,0.2\n2,0.3,0.1\n3,0,0\n")
    (tmp_path / "data" / "run.toml").write_text(
        '[task.qd]\nkind = "samples"\nfile = "qd.csv"\n\n[sim]\nT = 3.0\n'
    )
    config = adparm.load_config(tmp_path / "data" / "run.toml")  # file relative to the TOML
    assert config.task.qd.t == (0.0, 1.0, 2.0, 3.0)
    assert config.task.qd.q[1] == (0.5, 0.2)
    written = tmp_path / "written.toml"
    written.write_text(config.to_toml())  # the samples inline, no file
    again = adparm.load_config(written)
    assert again.task.qd.file is None
    assert (again.task.qd.t, again.task.qd.q) == (config.task.qd.t, config.task.qd.q)


def test_sample_file_errors_name_the_line(tmp_path) -> None:
    path = tmp_path / "qd.csv"
    path.write_text("t,qd1,qd2\n0,0,0\n1,0.5\n")
    with pytest.raises(ValueError, match=r"task.qd.file: .*qd.csv:3: expected 3 columns"):
        adparm.SampledTrajectory(file=str(path))
    path.write_text("0,0,0\n1,x,0\n")
    with pytest.raises(ValueError, match=r"qd.csv:2: not numbers"):
        adparm.SampledTrajectory(file=str(path))
    with pytest.raises(ValueError, match="give either file or t and q"):
        adparm.SampledTrajectory(file=str(path), t=(0.0, 1.0), q=((0, 0), (0, 0)))
