"""Each URDF file is parsed once per simulate() and once per batch (issue 23): counted by the
core (``adparm._core.urdf_parse_count``, every URDF text the C++ core parses, including those
Python's ``UrdfArm`` asks it for) and by Python (``adparm.urdf.parse_count``, every file
``UrdfArm`` reads). Each test reads a fresh copy of the example arm, so no cache of an earlier
test answers for it."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

import adparm
from adparm import _core
from adparm import urdf as adparm_urdf

ARM = Path(adparm.example_path("planar_3link.toml")).parent / "arms" / "planar_3link.urdf"


@pytest.fixture(scope="module")
def example() -> adparm.Config:
    return adparm.load_config(adparm.example_path("planar_3link.toml"))


def fresh_config(example: adparm.Config, tmp_path: Path, **sections: dict) -> adparm.Config:
    """The planar 3-link example (structured basis) on a copy of its URDF, 0.05 s long."""
    urdf = tmp_path / "arm.urdf"
    shutil.copy(ARM, urdf)
    return example.updated({"plant": {"urdf": str(urdf)}, "sim": {"T": 0.05}, **sections})


def counts() -> tuple[int, int]:
    return adparm_urdf.parse_count(), _core.urdf_parse_count()


def run(config: adparm.Config) -> adparm.SimulationResult:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", adparm.ApproximationWarning)
        return adparm.simulate(config)


def run_batch(configs: list[adparm.Config]) -> list[adparm.SimulationResult]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", adparm.ApproximationWarning)
        return adparm.simulate_batch(configs, threads=2)


def test_one_simulate_parses_the_urdf_once_in_python_and_once_in_the_core(
    example, tmp_path
) -> None:
    """Building the config reads the file once (Python's arm: its checks, defaults, basis size,
    initial weights; the config's friction shares that parse); the run reads it once more in
    the core, for its plant, its model and its structured basis together."""
    python_before, core_before = counts()
    config = fresh_config(example, tmp_path)
    python_config, core_config = counts()
    assert python_config - python_before == 1
    assert core_config - core_before == 1  # Python's UrdfArm is the core's parse
    result = run(config)
    python_after, core_after = counts()
    assert python_after == python_config
    assert core_after - core_config == 1
    assert result.status == "finished"


def test_a_model_differing_in_forces_shares_the_plants_parse(example, tmp_path) -> None:
    """A believed model of the plant's file with other gravity and friction is the plant's parse
    with those: still one parse per run, in Python and in the core."""
    config = fresh_config(
        example, tmp_path, model={"gravity": [0.0, 0.0, -9.7], "coulomb": 0.0, "viscous": 0.05}
    )
    _, core_before = counts()
    run(config)
    assert counts()[1] - core_before == 1


def test_a_batch_of_four_runs_of_one_urdf_parses_it_once(example, tmp_path) -> None:
    """Four runs of one file in a batch (two threads) share one parse, and each equals its run
    alone bit for bit (a shared const model, a Data per run)."""
    base = fresh_config(example, tmp_path)
    configs = [base.updated({"task": {"q0": [0.3 + 0.05 * i, -0.4, 0.2]}}) for i in range(4)]
    python_before, core_before = counts()
    results = run_batch(configs)
    assert counts() == (python_before, core_before + 1)
    for config, result in zip(configs, results, strict=True):
        alone = run(config)
        for name in ("q", "dq", "critic_weights", "actor_weights", "cost", "hjb_error"):
            np.testing.assert_array_equal(getattr(result, name), getattr(alone, name), name)


def test_with_gravity_and_friction_shares_the_parse_and_equals_a_fresh_read(tmp_path) -> None:
    """UrdfArm.with_gravity_and_friction reads nothing and gives the terms of an arm read with
    that gravity and friction, bit for bit."""
    urdf = tmp_path / "arm.urdf"
    shutil.copy(ARM, urdf)
    arm = adparm.UrdfArm(urdf)
    before = counts()
    forces = {"gravity": [0.0, -9.81, 0.0], "coulomb": [0.1, 0.2, 0.3], "viscous": 0.05}
    rubbing = arm.with_gravity_and_friction(**forces)
    assert counts() == before
    read = adparm.UrdfArm(urdf, **forces)
    q, dq = np.array([0.1, -0.2, 0.3]), np.array([0.4, -0.5, 0.6])
    for name, value in read.terms(q, dq).items():
        np.testing.assert_array_equal(rubbing.terms(q, dq)[name], value, name)
    np.testing.assert_array_equal(arm.coulomb, np.zeros(3))  # the original is unchanged
    np.testing.assert_array_equal(arm.gravity, [0.0, 0.0, -9.81])
    with pytest.raises(ValueError, match="coulomb"):
        arm.with_gravity_and_friction(coulomb=[0.1, 0.2])


def test_a_changed_file_is_read_again(example, tmp_path) -> None:
    """The parses are kept per version of the file (its modification time and size): a file
    rewritten between two runs is read again, on both sides."""
    config = fresh_config(example, tmp_path)
    run(config)
    urdf = Path(config.plant.urdf)
    urdf.write_text(urdf.read_text() + "\n<!-- changed -->\n")
    python_before, core_before = counts()
    changed = adparm.Config.from_dict(config.to_dict())
    run(changed)
    python_after, core_after = counts()
    assert python_after - python_before == 1
    assert core_after - core_before == 2  # Python's arm, and the run's
