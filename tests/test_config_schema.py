"""Each configuration field is declared once (adparm._fields.setting): its default, its meaning
and where the core takes it. Every field of every section declares either the core Settings
attribute it is copied to (metadata "core", e.g. "critic.eta_c") or how the core gets it instead
(metadata "via"); each declared copy reaches its core attribute; and a default the core also
states (its paper preset) is the same number in both."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

import adparm
from adparm import _core
from adparm._arm_sections import SampledTrajectory, SinusoidTrajectory
from adparm._sections import SECTIONS
from adparm.translate import core_settings


def schema_fields() -> list[tuple[str, dataclasses.Field[Any]]]:
    """(section, field) of every section and of the trajectories of [task.qd]."""
    found = [(name, field) for name, cls in SECTIONS.items() for field in dataclasses.fields(cls)]
    for cls in (SinusoidTrajectory, SampledTrajectory):
        found += [("task.qd", field) for field in dataclasses.fields(cls)]
    return found


COPIED = [
    (section, field.name, field.metadata["core"])
    for section, field in schema_fields()
    if field.metadata.get("core") is not None
]


def core_value(settings: Any, target: str) -> Any:
    for name in target.split("."):
        settings = getattr(settings, name)
    return settings


def schema_default(section: str, key: str) -> Any:
    config = adparm.Config()
    if section == "model":  # a key left out takes the plant's value
        return getattr(config.plant, key)
    return getattr(getattr(config, section), key)


def other_value(section: str, key: str) -> Any:
    """A valid value of section.key other than its default (and than any other field's)."""
    default = schema_default(section, key)
    if isinstance(default, bool):
        return not default
    if isinstance(default, int):
        return default + 3
    # scaled and shifted: a symmetric positive definite or Hurwitz matrix stays one
    return (np.asarray(default, dtype=float) * 1.25 + 0.5).tolist()


def test_every_field_says_what_the_core_takes() -> None:
    for section, field in schema_fields():
        name = f"{section}.{field.name}"
        assert field.metadata.get("doc"), f"{name}: no description (setting(default, doc))"
        core, via = field.metadata.get("core"), field.metadata.get("via")
        assert (core is None) != (via is None), (
            f"{name}: declare either core= (the core Settings attribute it is copied to) or "
            "via= (how the core gets it instead)"
        )
    assert len(COPIED) > 30


@pytest.mark.parametrize(
    ("section", "key", "target"), COPIED, ids=[".".join(c[:2]) for c in COPIED]
)
def test_a_copied_field_reaches_its_core_attribute(section: str, key: str, target: str) -> None:
    value = other_value(section, key)
    config = adparm.Config().updated({section: {key: value}})
    assert not np.array_equal(np.asarray(value), np.asarray(schema_default(section, key)))
    read = core_value(core_settings(config), target)
    np.testing.assert_array_equal(np.asarray(read), np.asarray(value), err_msg=target)
    # and back: the copy is the config's own value
    np.testing.assert_array_equal(
        np.asarray(read), np.asarray(getattr(getattr(config, section), key))
    )


def test_the_schema_and_the_core_state_the_same_defaults() -> None:
    core = _core.paper_settings()
    for section, key, target in COPIED:
        np.testing.assert_array_equal(
            np.asarray(core_value(core, target)),
            np.asarray(schema_default(section, key)),
            err_msg=f"{section}.{key} (core {target})",
        )
