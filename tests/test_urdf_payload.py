"""adparm.urdf_with_payload: the written URDF is the original arm plus a solid sphere fixed to a
link, checked with Pinocchio's Python bindings (an independent construction: the original model
with the same sphere appended to the link's joint by appendBodyToJoint), and bad arguments are
refused naming the argument."""

from __future__ import annotations

import numpy as np
import pytest

import adparm

from numpy_reference import pinocchio_configuration, pinocchio_model

pinocchio = pytest.importorskip("pinocchio")


@pytest.mark.parametrize(
    ("robot", "link", "offset"),
    [("ur5", "wrist_3_link", (0.0, 0.1, 0.0)), ("planar", "link2", (0.05, -0.02, 0.1))],
)
def test_the_payload_is_a_sphere_on_the_link(tmp_path, robot, link, offset) -> None:
    if robot == "ur5":
        urdf = adparm.example_robot_urdf("ur5")
    else:
        urdf = adparm.example_path("arms/planar_3link.urdf")
    mass, radius = 2.0, 0.03
    out = adparm.urdf_with_payload(
        urdf, link, mass, offset, path=tmp_path / "p.urdf", radius=radius
    )
    assert out == tmp_path / "p.urdf"
    written = pinocchio_model(out)
    # the reference: the original model, the sphere appended to the joint that moves `link`
    reference = pinocchio_model(urdf)
    frame = reference.frames[reference.getFrameId(link)]
    placement = frame.placement * pinocchio.SE3(np.eye(3), np.asarray(offset))
    sphere = pinocchio.Inertia(mass, np.zeros(3), np.eye(3) * 0.4 * mass * radius**2)
    reference.appendBodyToJoint(frame.parentJoint, sphere, placement)
    assert written.nv == reference.nv
    data, reference_data = written.createData(), reference.createData()
    total = sum(inertia.mass for inertia in pinocchio_model(urdf).inertias)
    assert sum(inertia.mass for inertia in written.inertias) == pytest.approx(total + mass)
    rng = np.random.default_rng(0)
    for _ in range(5):
        q = pinocchio_configuration(written, rng.uniform(-3.0, 3.0, written.nv))
        M = pinocchio.crba(written, data, q)
        M_reference = pinocchio.crba(reference, reference_data, q)
        np.testing.assert_allclose(M, M_reference, rtol=0, atol=1e-12 * np.abs(M).max())
        G = pinocchio.computeGeneralizedGravity(written, data, q)
        G_reference = pinocchio.computeGeneralizedGravity(reference, reference_data, q)
        np.testing.assert_allclose(G, G_reference, rtol=0, atol=1e-12 * np.abs(G).max())


def test_the_plant_with_a_payload_runs_against_the_original_model(tmp_path) -> None:
    urdf = adparm.example_path("arms/planar_3link.urdf")
    plant = adparm.urdf_with_payload(urdf, "link3", 0.5, (0.1, 0.0, 0.0), path=tmp_path / "p.urdf")
    config = adparm.load_config(adparm.example_path("planar_3link.toml")).updated(
        {"plant": {"urdf": str(plant)}, "model": {"urdf": str(urdf)}, "sim": {"T": 0.05}}
    )
    beta_plant = adparm.base_parameters(config, "plant")
    beta_model = adparm.base_parameters(config, "model")
    assert np.abs(beta_plant - beta_model).max() > 0.01  # the model does not know it
    assert adparm.simulate(config, diagnose=False).status == "finished"


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"link": "link7"}, r"^link: .* has no link 'link7'; did you mean 'link"),
        ({"mass": 0.0}, r"^mass: must be a finite number > 0 \(kg\)"),
        ({"mass": float("nan")}, r"^mass: "),
        ({"mass": "heavy"}, r"^mass: "),
        ({"radius": -0.01}, r"^radius: must be a finite number > 0 \(m\)"),
        ({"offset": (0.0, 0.1)}, r"^offset: must be three finite numbers"),
        ({"offset": (0.0, np.inf, 0.0)}, r"^offset: "),
    ],
)
def test_bad_arguments_are_refused_naming_them(tmp_path, arguments, message) -> None:
    call = {"link": "link3", "mass": 1.0, "offset": (0.0, 0.0, 0.0), **arguments}
    with pytest.raises(ValueError, match=message):
        adparm.urdf_with_payload(
            adparm.example_path("arms/planar_3link.urdf"), path=tmp_path / "p.urdf", **call
        )
    assert not (tmp_path / "p.urdf").exists()
