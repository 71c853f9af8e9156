"""Checks of a URDF's text before the core reads it: a xacro file (not yet expanded), and
<inertial> numbers urdfdom would read as a massless link (urdf.UrdfArm calls them)."""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ElementTree

__all__ = ["check_inertial_text"]


#: The attributes of an <inertial> element that urdfdom reads as numbers.
_INERTIAL_NUMBERS = {
    "mass": ("value",),
    "inertia": ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"),
}


#: A xacro file: urdfdom would read its ${...} as text (a link without mass) or not at all.
_XACRO = (
    "URDF {path} is a xacro file (xacro: elements or ${{...}} expressions), not a URDF: expand it "
    "first (`pip install xacro`, then `xacro {path} > arm.urdf`) and give the arm.urdf it writes"
)


def check_inertial_text(path: str | os.PathLike[str]) -> None:
    """Refuses (ValueError naming the file and the link) an <inertial> element whose numbers do
    not read as finite floats: urdfdom prints a warning (e.g. "mass [2,0] is not a float") and
    goes on with a massless link. Only the text of <mass value> and <inertia ixx ...> and of the
    inertial <origin xyz rpy> is read here; the core checks the values (mass, inertia). A xacro
    file (xacro: elements, ${...} expressions, or a .xacro that does not parse) is refused first,
    saying to expand it."""
    try:
        root = ElementTree.parse(path).getroot()
    except (OSError, ElementTree.ParseError):
        if str(path).endswith(".xacro"):  # xacro:... without its namespace declared
            raise ValueError(_XACRO.format(path=path)) from None
        return  # the core refuses what it cannot read or parse, with its own reason
    if any(
        element.tag.startswith("{http://www.ros.org/wiki/xacro}")
        or any("${" in value for value in element.attrib.values())
        for element in root.iter()
    ):
        raise ValueError(_XACRO.format(path=path))
    for link in root.iter("link"):
        for inertial in link.findall("inertial"):
            name = link.get("name", "?")
            checks = [
                (inertial.find(tag), tag, attributes)
                for tag, attributes in _INERTIAL_NUMBERS.items()
            ]
            checks.append((inertial.find("origin"), "origin", ()))
            for element, tag, attributes in checks:
                if element is None:
                    continue
                for attribute in attributes:
                    text = element.get(attribute)
                    if text is None or not _is_float(text):
                        raise ValueError(
                            f"URDF {path}: link {name!r}: <{tag} {attribute}={text!r}> in its "
                            "<inertial> is not a number (urdfdom would read the link as "
                            "massless)"
                        )
                if tag == "origin":
                    for attribute in ("xyz", "rpy"):
                        text = element.get(attribute)
                        if text is not None and not all(_is_float(t) for t in text.split()):
                            raise ValueError(
                                f"URDF {path}: link {name!r}: <origin {attribute}={text!r}> in "
                                "its <inertial> is not three numbers"
                            )


def _is_float(text: str) -> bool:
    try:
        return math.isfinite(float(text.strip()))
    except ValueError:
        return False
