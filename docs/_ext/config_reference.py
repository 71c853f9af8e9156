"""Sphinx directive ``config-reference``: the table of every configuration field, generated
from adparm's config dataclasses (section, key and default come from the code; the meaning from
the field's ``metadata["doc"]``, written with the field in the schema: adparm._fields.setting).
A field without a description is a warning, so ``sphinx-build -W`` fails until the table is
complete."""

from __future__ import annotations

import dataclasses

from docutils import nodes
from docutils.parsers.rst import Directive
from docutils.statemachine import StringList
from sphinx.util import logging

import adparm

logger = logging.getLogger(__name__)

#: Defaults that are None in the dataclasses, as the run resolves them.
RESOLVED_DEFAULTS = {
    ("model", "*"): "the plant's value",
    ("model", "scale"): "1 (the model's keys as they are)",
    ("plant", "urdf"): "none (the built-in two-link arm)",
    ("plant", "gravity"): "[0, 0, -9.81] (with ``urdf``)",
    ("plant", "locked_joints"): "none (every joint free)",
    ("plant", "torque_limits"): "none on the two-link arm; the URDF's ``<limit effort>`` on a "
    "URDF arm",
    ("cost", "input_bound"): "none (the quadratic input cost u^T R u of eq. 10)",
    ("critic", "epsilon_T"): "1e-6; 1e-3 with extrapolation points",
    ("probe", "phases"): "k rad for sinusoid k, both joints",
    ("task.qd sinusoid", "phase"): "zeros",
    ("task.qd sinusoid", "offset"): "zeros",
    ("task.qd samples", "file"): "none",
    ("controller", "degree"): "none (only with the polynomial basis, where it must be set)",
    ("init", "*"): "the basis' default: all ones (paper, augmented); [1, 0, 1, p1, p2, p3] "
    "(structured: K = I and the believed model's inertia; on a URDF arm the model's base "
    "inertial parameters)",
}


def _format(value):
    if isinstance(value, tuple):
        return "[" + ", ".join(_format(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, float):
        return f"{value:.10g}"
    return str(value)


def _sections():
    config = adparm.Config()
    for section in dataclasses.fields(config):
        if not section.name.startswith("_"):  # Config._explicit: not a section
            yield section.name, getattr(config, section.name)
    yield "task.qd sinusoid", adparm.SinusoidTrajectory()
    yield "task.qd samples", adparm.SampledTrajectory(t=(0.0, 1.0), q=((0.0, 0.0), (0.0, 0.0)))


def _default(section, key, instance):
    field = next(f for f in dataclasses.fields(instance) if f.name == key)
    raw = field.default if field.default is not dataclasses.MISSING else field.default_factory()
    if raw is None:
        resolved = RESOLVED_DEFAULTS.get((section, key)) or RESOLVED_DEFAULTS.get((section, "*"))
        if resolved is None:
            logger.warning(f"config-reference: {section}.{key} defaults to None; say what it means")
            return "None"
        return resolved
    if section == "task.qd samples" and key in ("t", "q"):
        return "[]"
    return "``" + _format(getattr(instance, key) if section != "task.qd samples" else raw) + "``"


class ConfigReference(Directive):
    has_content = False

    def run(self):
        lines = []
        for section, instance in _sections():
            header = f"[{section.split()[0]}]" + (
                f' with kind = "{section.split()[1]}"' if " " in section else ""
            )
            lines += [f".. list-table:: {header}", "   :header-rows: 1", "   :widths: 18 22 60", ""]
            lines += ["   * - key", "     - default", "     - meaning"]
            for field in dataclasses.fields(instance):
                description = field.metadata.get("doc")
                if description is None:
                    logger.warning(
                        f"config-reference: {section}.{field.name} has no description (metadata "
                        '"doc" of its dataclasses.field, adparm._fields.setting)'
                    )
                    description = "(undocumented)"
                default = _default(section, field.name, instance)
                lines += [f"   * - ``{field.name}``", f"     - {default}", f"     - {description}"]
            lines.append("")
        holder = nodes.container()
        self.state.nested_parse(StringList(lines, source="config-reference"), 0, holder)
        return holder.children


def setup(app):
    app.add_directive("config-reference", ConfigReference)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
