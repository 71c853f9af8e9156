"""Model errors written as URDFs (guide: Unknown dynamics): a payload added to an arm
(urdf_with_payload, the plant of a run whose model does not know what the arm carries) and links'
masses and inertias scaled (urdf_with_scaled_inertia, a model whose inertia is off). Each writes a
new URDF; the original is not changed."""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ._files import write_text
from .term_checks import did_you_mean

__all__ = ["urdf_with_payload", "urdf_with_scaled_inertia"]


def urdf_with_payload(
    urdf: str | os.PathLike[str],
    link: str,
    mass: float,
    offset: ArrayLike = (0.0, 0.0, 0.0),
    *,
    path: str | os.PathLike[str],
    radius: float = 0.02,
) -> Path:
    """Write the URDF at ``urdf`` with a payload fixed to ``link`` to ``path`` (atomically) and
    return ``path``.

    The payload is a solid sphere of ``mass`` kg and ``radius`` m (inertia 2/5 m r^2 about its
    centre) whose centre sits at ``offset`` (m, in ``link``'s frame): a new link and a fixed
    joint, which Pinocchio merges into the body that moves ``link``, so the arm keeps its joints
    and only its inertial parameters change. Use it as ``[plant] urdf`` with the original as
    ``[model] urdf``: a model that does not know the payload (``[identifier] enabled = true``
    identifies it). Raises ValueError naming the argument: an unknown link (with the closest
    name), a mass or radius not > 0, an offset that is not three finite numbers."""
    mass, radius = _positive(mass, "mass", "kg"), _positive(radius, "radius", "m")
    xyz = np.asarray(offset, dtype=float)
    if xyz.shape != (3,) or not np.all(np.isfinite(xyz)):
        raise ValueError(f"offset: must be three finite numbers (m), got {offset!r}")
    tree = ET.parse(os.fspath(urdf))
    root = tree.getroot()
    links = [element.get("name", "") for element in root.findall("link")]
    if link not in links:
        raise ValueError(f"link: {urdf} has no link {link!r}{did_you_mean(link, links)}")
    joints = [element.get("name", "") for element in root.findall("joint")]
    name = "payload"
    while name in links or f"{name}_joint" in joints:  # names the URDF does not use yet
        name += "_"
    inertia = repr(2.0 / 5.0 * mass * radius**2)
    payload = ET.SubElement(root, "link", name=name)
    inertial = ET.SubElement(payload, "inertial")
    ET.SubElement(inertial, "origin", xyz="0 0 0", rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=repr(mass))
    ET.SubElement(
        inertial, "inertia", ixx=inertia, iyy=inertia, izz=inertia, ixy="0", ixz="0", iyz="0"
    )
    joint = ET.SubElement(root, "joint", name=f"{name}_joint", type="fixed")
    ET.SubElement(joint, "parent", link=link)
    ET.SubElement(joint, "child", link=name)
    ET.SubElement(joint, "origin", xyz=" ".join(repr(float(x)) for x in xyz), rpy="0 0 0")
    return write_text(path, ET.tostring(root, encoding="unicode", xml_declaration=True))


def urdf_with_scaled_inertia(
    urdf: str | os.PathLike[str],
    scale: float | Mapping[str, float],
    *,
    path: str | os.PathLike[str],
) -> Path:
    """Write the URDF at ``urdf`` with its links' masses and inertias multiplied by ``scale`` (a
    number: every link; a mapping {link name: factor}: those links) to ``path`` (atomically) and
    return ``path``; the centres of mass stay where they are, so M(q) and G(q) of the arm are
    ``scale`` times the original's. Use it as ``[model] urdf``: a model whose inertia is off (a
    single factor is what ``[model] scale`` gives without a file). Raises ValueError naming the
    argument: a factor not > 0, an unknown link (with the closest name) or one without
    ``<inertial>``."""
    tree = ET.parse(os.fspath(urdf))
    links = {element.get("name", ""): element for element in tree.getroot().findall("link")}
    if isinstance(scale, Mapping):
        factors = {name: _positive(value, f"scale[{name!r}]", "") for name, value in scale.items()}
        for name in factors:
            if name not in links:
                raise ValueError(f"scale: {urdf} has no link {name!r}{did_you_mean(name, links)}")
            if links[name].find("inertial") is None:
                raise ValueError(f"scale: link {name!r} of {urdf} has no <inertial>")
    else:
        factor = _positive(scale, "scale", "")
        factors = {
            name: factor for name, link in links.items() if link.find("inertial") is not None
        }
    for name, factor in factors.items():
        inertial = links[name].find("inertial")
        for tag in ("mass", "inertia"):
            element = inertial.find(tag) if inertial is not None else None
            for key, value in element.attrib.items() if element is not None else ():
                element.set(key, repr(float(value) * factor))
    return write_text(path, ET.tostring(tree.getroot(), encoding="unicode", xml_declaration=True))


def _positive(value: object, name: str, unit: str) -> float:
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        number = math.nan
    if isinstance(value, bool) or not (math.isfinite(number) and number > 0.0):
        raise ValueError(
            f"{name}: must be a finite number > 0{f' ({unit})' if unit else ''}, got {value!r}"
        )
    return number
