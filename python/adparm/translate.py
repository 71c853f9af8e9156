"""The Config -> core translation: core_settings(config) is the C++ core's Settings struct of a
run (and extrapolation_points, the core's points for it)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

import adparm._core as _core

from .basis_family import UrdfStructuredBasis, basis_for
from .config import Config
from .desired import trajectory_settings
from .rates import check_positions

__all__ = ["core_settings", "extrapolation_points", "urdf_settings"]


def core_settings(config: Config) -> _core.Settings:
    """The C++ core's Settings struct for ``config`` (passed whole to the core): every field that
    declares a core attribute (``metadata["core"]``, adparm._fields.setting) is copied to it, and
    the fields that say ``via`` are converted here."""
    if not isinstance(config, Config):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")
    settings = _core.Settings()
    two_link = config.plant.urdf is None
    for section in dataclasses.fields(config):
        if section.name.startswith("_"):  # Config._explicit: not a section
            continue
        values = getattr(config, section.name)
        if section.name == "model":  # a key left out takes the plant's value
            values = config.model.resolve(config.plant)
        for field in dataclasses.fields(getattr(config, section.name)):
            target = field.metadata["core"]
            if target is None or (not two_link and target.split(".")[0] in ("plant", "model")):
                continue  # a URDF arm: the two-link parameters are not used
            value = values[field.name] if isinstance(values, dict) else getattr(values, field.name)
            _set_attribute(settings, target.split("."), value)

    if config.plant.urdf is not None:  # not two_link
        settings.plant_urdf = urdf_settings(
            config.plant.urdf,
            config.plant.resolved_gravity,
            config.plant.coulomb,
            config.plant.viscous,
            config.plant.locked_joints,
        )
        settings.model_urdf = urdf_settings(**config.model.resolve_urdf(config.plant))
    settings.torque_limits = config.plant.limit_vector(config.dof)
    task = settings.task
    task.qd = trajectory_settings(config)
    settings.task = task

    critic = settings.critic
    critic.epsilon_T = config.resolved_epsilon_T
    settings.critic = critic
    if config.actor.positive_e2 and isinstance(basis_for(config), UrdfStructuredBasis):
        # where the structured basis keeps its e2 block positive (not in the paper); the core
        # builds the basis (and asks for them) whatever the controller's kind
        actor = settings.actor
        actor.e2_check_positions = np.asfortranarray(check_positions(config).T)
        settings.actor = actor

    controller = settings.controller
    controller.kind = getattr(_core.ControllerKind, config.controller.kind)
    controller.kp = config.controller.gain_matrix("kp", config.dof)
    controller.kd = config.controller.gain_matrix("kd", config.dof)
    settings.controller = controller
    family = basis_for(config)
    settings.basis = getattr(_core.BasisKind, family.core_kind)
    program = family.core_program(config)
    if program is not None:
        settings.basis_program = program
    settings.input_bound = config.cost.bound_vector(config.dof)
    settings.e2_cost = getattr(_core.E2Cost, config.cost.e2_cost)
    extrapolation = settings.extrapolation
    extrapolation.box = config.extrapolation.box_vector(config.dof)
    centre = config.extrapolation.centre_vector(config.dof)
    if np.any(centre != 0.0):  # the core's empty centre is 0
        extrapolation.centre = centre
    extrapolation.mode = getattr(_core.ExtrapolationMode, config.extrapolation.mode)
    settings.extrapolation = extrapolation

    settings.critic_weights = config.initial_weights("critic_weights")
    settings.actor_weights = config.initial_weights("actor_weights")

    probe = settings.probe
    probe.amplitude = config.probe.amplitude_matrix(config.dof)
    probe.phases = config.probe.phase_matrix(config.dof)
    settings.probe = probe
    return settings


def _set_attribute(settings: Any, path: list[str], value: Any) -> None:
    """settings.a.b.c = value for path [a, b, c] (a tuple as an array); each struct on the way is
    read, changed and assigned back (the core's arms are copies on access)."""
    if len(path) > 1:
        part = getattr(settings, path[0])
        _set_attribute(part, path[1:], value)
        setattr(settings, path[0], part)
    else:
        setattr(settings, path[0], np.array(value) if isinstance(value, tuple) else value)


def urdf_settings(
    urdf: str,
    gravity: Any,
    coulomb: float | tuple[float, ...],
    viscous: float | tuple[float, ...],
    locked_joints: dict[str, float] | None = None,
    scale: float | None = None,
) -> _core.UrdfArmSettings:
    """The core's description of a URDF arm (friction: one value per joint, or one for all;
    locked joints: {name: position} or None; scale: its links' masses and inertias times it,
    None: 1)."""
    arm = _core.UrdfArmSettings()
    arm.urdf = urdf
    arm.gravity = np.array(gravity, dtype=float)
    arm.coulomb = np.atleast_1d(np.array(coulomb, dtype=float))
    arm.viscous = np.atleast_1d(np.array(viscous, dtype=float))
    arm.locked_joints = [(name, float(value)) for name, value in (locked_joints or {}).items()]
    arm.inertia_scale = 1.0 if scale is None else float(scale)
    return arm


def extrapolation_points(config: Config) -> np.ndarray:
    """The extrapolation points (N, 2n) in x = [e1; e2] of a fixed or grid ``config.extrapolation``
    (for mode local: the offsets are drawn anew at each step, and this returns zeros)."""
    return np.array(_core.extrapolation_points(core_settings(config)))
