"""The units of a run's joints: rad and N m, or m and N on a prismatic joint of a URDF arm; and
an axis's or a norm's label when the joints' units differ."""

from __future__ import annotations

from typing import Any

from .urdf import config_arm

__all__ = ["effort_units", "norm_unit", "position_units", "unit_label"]


def position_units(config: Any) -> list[str]:
    """Per joint, the unit of its position: "rad", or "m" on a prismatic joint."""
    return _joint_units(config, "rad", "m")


def effort_units(config: Any) -> list[str]:
    """Per joint, the unit of its torque: "N m", or "N" (a force) on a prismatic joint."""
    return _joint_units(config, "N m", "N")


def _joint_units(config: Any, rotation: str, translation: str) -> list[str]:
    """Per joint, `translation` on a prismatic joint of a URDF arm, else `rotation`."""
    if config.plant.urdf is None:
        return [rotation] * config.dof
    kinds = config_arm(config).joint_types
    return [translation if kind == "prismatic" else rotation for kind in kinds]


def unit_label(units: list[str], suffix: str = "") -> str:
    """One axis's unit for joints of `units` (each followed by `suffix`, e.g. "/s"): "rad" when
    all agree, else the revolute joints' unit and the others named: "rad; m on joint 1"."""
    kinds = list(dict.fromkeys(units))
    if len(kinds) == 1:
        return kinds[0] + suffix
    main = next((kind for kind in kinds if kind in ("rad", "N m")), kinds[0])
    others = "; ".join(
        f"{kind}{suffix} on joint{'s' if units.count(kind) > 1 else ''} "
        + ", ".join(str(i + 1) for i, u in enumerate(units) if u == kind)
        for kind in kinds
        if kind != main
    )
    return f"{main}{suffix}; {others}"


def norm_unit(units: list[str]) -> str:
    """The unit after a norm over joints of `units`: "rad", or "(rad; m on joint 1)"."""
    label = unit_label(units)
    return f"({label})" if ";" in label else label
