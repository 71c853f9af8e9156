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


def test_scaled_inertia_scales_m_and_g_and_is_the_model_scale_of_a_urdf_arm(tmp_path) -> None:
    # every link's mass and inertia times 1.2 (centres of mass kept): M(q) and G(q) 1.2 times the
    # original's in Pinocchio's Python bindings; one link alone by a mapping; the written file
    # works as model.urdf, with the base parameters model.scale gives (tests/test_model_error.py:
    # the same run)
    urdf = adparm.example_path("arms/planar_3link.urdf")
    scaled = adparm.urdf_with_scaled_inertia(urdf, 1.2, path=tmp_path / "m.urdf")
    original, heavier = (pinocchio.buildModelFromUrdf(str(p)) for p in (urdf, scaled))
    q = np.random.default_rng(3).uniform(-1.0, 1.0, original.nq)
    for model, factor in ((original, 1.0), (heavier, 1.2)):
        data = model.createData()
        M = pinocchio.crba(model, data, q)
        G = pinocchio.computeGeneralizedGravity(model, data, q)
        if factor == 1.0:
            M0, G0 = M.copy(), G.copy()
    np.testing.assert_allclose(M, 1.2 * M0, rtol=1e-12)
    np.testing.assert_allclose(G, 1.2 * G0, rtol=1e-12)
    one = adparm.urdf_with_scaled_inertia(urdf, {"link3": 2.0}, path=tmp_path / "one.urdf")
    import xml.etree.ElementTree as ET

    def link_masses(path):
        links = ET.parse(str(path)).getroot().findall("link")
        return {
            link.get("name"): float(link.find("inertial/mass").get("value"))
            for link in links
            if link.find("inertial") is not None
        }

    before, after = link_masses(urdf), link_masses(one)
    assert after == {
        name: mass * (2.0 if name == "link3" else 1.0) for name, mass in before.items()
    }
    by_key = adparm.Config.from_dict({"plant": {"urdf": str(urdf)}, "model": {"scale": 1.2}})
    config = adparm.Config.from_dict(
        {"plant": {"urdf": str(urdf)}, "model": {"urdf": str(scaled)}, "sim": {"T": 0.05}}
    )
    beta = adparm.base_parameters(config, "model")[:3]
    np.testing.assert_allclose(beta, 1.2 * adparm.base_parameters(config, "plant")[:3], rtol=1e-12)
    np.testing.assert_allclose(adparm.base_parameters(by_key, "model")[:3], beta, rtol=1e-12)
    assert adparm.simulate(config, diagnose=False).status == "finished"
    for scale, message in (
        (0.0, r"^scale: must be a finite number > 0"),
        ({"link9": 2.0}, r"^scale: .* has no link 'link9'"),
    ):
        with pytest.raises(ValueError, match=message):
            adparm.urdf_with_scaled_inertia(urdf, scale, path=tmp_path / "bad.urdf")
    assert not (tmp_path / "bad.urdf").exists()
