"""The Config -> core translation: core_settings(config) is the C++ core's Settings struct of a
run (and extrapolation_points, the core's points for it)."""

from __future__ import annotations

from typing import Any

import numpy as np

import adparm._core as _core

from ._fields import ARM_KEYS
from .basis_family import UrdfStructuredBasis, basis_for
from .config import Config
from .desired import trajectory_settings
from .rates import check_positions

__all__ = ["core_settings", "extrapolation_points", "urdf_settings"]


def core_settings(config: Config) -> _core.Settings:
    """The C++ core's Settings struct for ``config`` (passed whole to the core)."""
    if not isinstance(config, Config):
        raise TypeError(f"config: expected adparm.Config, got {type(config).__name__}")
    settings = _core.Settings()
    plant = _core.ArmParameters()
    model = _core.ArmParameters()
    if config.plant.urdf is None:
        for key in ARM_KEYS:
            setattr(plant, key, getattr(config.plant, key))
        for key, value in config.model.resolve(config.plant).items():
            setattr(model, key, value)
    settings.plant = plant
    settings.model = model
    if config.plant.urdf is not None:  # a URDF arm: the two-link parameters are not used
        settings.plant_urdf = urdf_settings(
            config.plant.urdf,
            config.plant.resolved_gravity,
            config.plant.coulomb,
            config.plant.viscous,
            config.plant.locked_joints,
        )
        settings.model_urdf = urdf_settings(**config.model.resolve_urdf(config.plant))
    settings.disturbance = np.array(config.plant.disturbance)

    task = _core.TaskSettings()
    task.q0 = np.array(config.task.q0)
    task.dq0 = np.array(config.task.dq0)
    task.qd = trajectory_settings(config)
    settings.task = task

    settings.Q = np.array(config.cost.Q)
    settings.R = np.array(config.cost.R)

    control = _core.ControlSettings()
    control.alpha1 = np.array(config.control.alpha1)
    rise = _core.RiseGains()
    rise.ks, rise.alpha2, rise.beta1 = (
        config.control.ks,
        config.control.alpha2,
        config.control.beta1,
    )
    control.rise = rise
    settings.control = control

    critic = _core.CriticSettings()
    for key in ("eta_c", "nu", "gamma0"):
        setattr(critic, key, getattr(config.critic, key))
    critic.epsilon_T = config.resolved_epsilon_T
    settings.critic = critic
    actor = _core.ActorSettings()
    for key in ("eta_a1", "eta_a2", "weight_bound", "positive_e2", "e2_margin"):
        setattr(actor, key, getattr(config.actor, key))
    if (
        config.actor.positive_e2
        and isinstance(basis_for(config), UrdfStructuredBasis)
        and config.controller.kind == "adp"
    ):  # where the structured basis keeps its e2 block positive (not in the paper)
        actor.e2_check_positions = np.asfortranarray(check_positions(config).T)
    settings.actor = actor

    controller = _core.ControllerSettings()
    controller.kind = getattr(_core.ControllerKind, config.controller.kind)
    controller.rise = config.controller.rise
    controller.kp = config.controller.gain_matrix("kp", config.dof)
    controller.kd = config.controller.gain_matrix("kd", config.dof)
    settings.controller = controller
    family = basis_for(config)
    settings.basis = getattr(_core.BasisKind, family.core_kind)
    program = family.core_program(config)
    if program is not None:
        settings.basis_program = program
    extrapolation = _core.ExtrapolationSettings()
    extrapolation.points = config.extrapolation.points
    extrapolation.box = config.extrapolation.box_vector(config.dof)
    extrapolation.mode = getattr(_core.ExtrapolationMode, config.extrapolation.mode)
    extrapolation.seed = config.extrapolation.seed
    settings.extrapolation = extrapolation

    settings.critic_weights = config.initial_weights("critic_weights")
    settings.actor_weights = config.initial_weights("actor_weights")

    probe = _core.ProbeSettings()
    probe.amplitude = config.probe.amplitude_matrix(config.dof)
    probe.until = config.probe.until
    probe.ramp = config.probe.ramp
    probe.frequencies = np.array(config.probe.frequencies)
    probe.phases = config.probe.phase_matrix(config.dof)
    settings.probe = probe

    sim = _core.SimSettings()
    for key in ("T", "dt", "record_every", "divergence_bound"):
        setattr(sim, key, getattr(config.sim, key))
    settings.sim = sim
    return settings


def urdf_settings(
    urdf: str,
    gravity: Any,
    coulomb: float | tuple[float, ...],
    viscous: float | tuple[float, ...],
    locked_joints: dict[str, float] | None = None,
) -> _core.UrdfArmSettings:
    """The core's description of a URDF arm (friction: one value per joint, or one for all;
    locked joints: {name: position} or None)."""
    arm = _core.UrdfArmSettings()
    arm.urdf = urdf
    arm.gravity = np.array(gravity, dtype=float)
    arm.coulomb = np.atleast_1d(np.array(coulomb, dtype=float))
    arm.viscous = np.atleast_1d(np.array(viscous, dtype=float))
    arm.locked_joints = [(name, float(value)) for name, value in (locked_joints or {}).items()]
    return arm


def extrapolation_points(config: Config) -> np.ndarray:
    """The extrapolation points (N, 2n) in x = [e1; e2] of a fixed or grid ``config.extrapolation``
    (for mode local: the offsets are drawn anew at each step, and this returns zeros)."""
    return np.array(_core.extrapolation_points(core_settings(config)))
