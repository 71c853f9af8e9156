"""adparm.Config: the configuration of a run, resolved for its arm and basis.

The schema (the sections, their fields, defaults, bounds and checks, and the checks between them
that need only values) is adparm._schema.ConfigSchema with the sections of adparm._sections and
adparm._arm_sections; it sits at the bottom of the package. Config subclasses it in the model
layer, where it can call down into the arm and the basis: a URDF arm's derived defaults
(adparm.rates.urdf_defaults), the basis' size and default initial weights, cost.input_bound =
"auto" (adparm.rates.auto_input_bound) and sim.dt = "auto".
Everything that builds a config (``Config()``, :meth:`Config.from_dict`, :meth:`Config.updated`,
:func:`load_config`, :func:`paper_config`) therefore returns a resolved one, and nothing below
imports this module: the model's functions take a config by its schema (docs/design.md).

Every field has the paper's value (Section 4 of the paper, with the corrections of the docs page
"The paper and its corrections") or, where the paper leaves a setting open, this project's
documented choice. A key left out of a TOML file takes that default; an unknown section or key is
refused with a "did you mean" hint.
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from ._arm_sections import (
    EXAMPLE_ROBOT_PREFIX,
    ModelConfig,
    PlantConfig,
    SampledTrajectory,
    SinusoidTrajectory,
    TaskConfig,
    plain_value,
)
from ._fields import (
    ARM_KEYS,
    AUTO,
    MAX_CONFIG_BYTES,
    MAX_FREQUENCIES,
    MAX_SAMPLES,
    MAX_SAMPLES_FILE_BYTES,
    deep_toml,
    read_text_file,
    toml_text,
)
from ._run_sections import EXTRAPOLATION_MODES, MAX_POINTS, MAX_RECORD_EVERY
from ._schema import ConfigSchema
from ._sections import (
    BASIS_KINDS,
    CONTROLLER_KINDS,
    EPSILON_T_EXTRAPOLATION,
    EPSILON_T_PROBING,
    EXPRESSION_FAMILIES,
    SECTIONS,
    URDF_DEFAULT_BASIS,
    URDF_REFUSED_BASES,
    ActorConfig,
    ControlConfig,
    ControllerConfig,
    CostConfig,
    CriticConfig,
    DiagnosticsConfig,
    ExtrapolationConfig,
    IdentifierConfig,
    InitConfig,
    ProbeConfig,
    SimConfig,
)
from .basis_family import BasisFamily, basis_for
from .desired import desired_state
from .joint_limits import limits_box
from .optimal import initial_error_state
from .rates import (
    EPSILON_T_URDF,
    auto_input_bound,
    auto_step,
    closed_loop_rates,
    urdf_defaults,
)

__all__ = [
    "ActorConfig",
    "Config",
    "ControlConfig",
    "ControllerConfig",
    "CostConfig",
    "CriticConfig",
    "DiagnosticsConfig",
    "ExtrapolationConfig",
    "IdentifierConfig",
    "InitConfig",
    "ModelConfig",
    "PlantConfig",
    "ProbeConfig",
    "SampledTrajectory",
    "SimConfig",
    "SinusoidTrajectory",
    "TaskConfig",
    "load_config",
    "paper_config",
]

#: Names kept importable from adparm.config (they live in the schema modules).
REEXPORTED = (
    AUTO,
    BASIS_KINDS,
    CONTROLLER_KINDS,
    EXPRESSION_FAMILIES,
    EXTRAPOLATION_MODES,
    MAX_FREQUENCIES,
    MAX_POINTS,
    MAX_RECORD_EVERY,
    MAX_SAMPLES,
    MAX_SAMPLES_FILE_BYTES,
    SECTIONS,
    URDF_DEFAULT_BASIS,
    URDF_REFUSED_BASES,
    tomllib,
)


@dataclass(frozen=True)
class Config(ConfigSchema):
    """A whole run: one frozen, checked section per TOML table.

    ``Config()`` and :func:`paper_config` are the paper's instance. Change it with
    :meth:`updated` (a copy), build one with :meth:`from_dict`, or read a TOML file with
    :func:`load_config`; :meth:`to_toml` writes one back. The docs page "Configuration
    reference" lists every field with its default and meaning.

    Attributes
    ----------
    plant, model : PlantConfig, ModelConfig
        The simulated arm and the arm the controller believes (default: the plant).
    task : TaskConfig
        Initial state and desired trajectory.
    cost : CostConfig
        Q and R of the cost (eqs. 10-11).
    control : ControlConfig
        alpha1 and the RISE gains.
    critic, actor, init : CriticConfig, ActorConfig, InitConfig
        The learning laws (eqs. 23-26) and the initial weights.
    probe : ProbeConfig
        The probing signal.
    controller : ControllerConfig
        Controller kind (adp, rise, pd, optimal) and basis.
    extrapolation : ExtrapolationConfig
        Bellman-error extrapolation points.
    identifier : IdentifierConfig
        The online identifier of the arm's base parameters (off by default).
    sim : SimConfig
        Horizon, step, recording and divergence bound.
    diagnostics : DiagnosticsConfig
        The tolerance of the verdict.

    Examples
    --------
    >>> import adparm
    >>> config = adparm.paper_config().updated({"critic": {"eta_c": 100.0}})
    >>> config.critic.eta_c, config.sim.T
    (100.0, 150.0)
    """

    def _check_basis(self) -> None:
        size = self.basis_size
        for key in ("critic_weights", "actor_weights"):
            value = getattr(self.init, key)
            if value is not None and len(value) != size:
                raise ValueError(
                    f"init.{key}: expected shape ({size},), one weight per function of "
                    f"controller.basis = {plain_value(self.controller.basis)!r}, "
                    f"got ({len(value)},)"
                )
        family = basis_for(self)
        if not family.finite_everywhere:
            self._check_basis_at_start(family)

    def _check_identifier(self) -> None:
        """An identifying URDF run estimates the model's masses and inertias on the model's
        kinematics: a model.urdf whose joints or link frames differ from the plant's cannot reach
        the plant. Told by the mass regressor dM/dpi, which depends on the kinematics alone, at
        three seeded positions within the joint limits."""
        if not self.identifier.enabled or self.plant.urdf is None or self.model.urdf is None:
            return
        from .urdf import config_arm

        plant, model = config_arm(self), config_arm(self, model=True)
        low, high = limits_box(plant)
        for q in np.random.default_rng(0).uniform(low, high, size=(3, self.dof)):
            ours, theirs = plant.mass_regressor(q), model.mass_regressor(q)
            scale = max(float(np.abs(ours).max()), 1.0)
            if ours.shape != theirs.shape or not np.allclose(
                ours, theirs, rtol=0, atol=1e-9 * scale
            ):
                raise ValueError(
                    "model.urdf: its kinematics (joint axes, link frames) differ from the plant's "
                    "(plant.urdf), and identifier.enabled estimates masses and inertias only, on "
                    "the model's kinematics: give a model.urdf with the plant's joints and frames "
                    "(e.g. adparm.urdf_with_scaled_inertia of the plant's URDF), or turn the "
                    "identifier off (a wrong model is then judged against its own W*)"
                )

    def _arm_defaults(self) -> tuple[dict[tuple[str, str], Any], dict[str, str]]:
        return urdf_defaults(self)

    def _check_basis_at_start(self, family: BasisFamily) -> None:
        """An expression basis and its d phi / dx must be finite at the initial state: sqrt or
        log of a negative value there ends the run at t = 0 (or leaves V(x(0)) undefined)."""
        problem = family.nonfinite(self, initial_error_state(self), desired_state(self, 0.0)[0])
        if problem is not None:
            raise ValueError(
                f"controller.basis: at the initial state (task.q0, task.qd), {problem}"
            )

    def _resolve_input_bound(self) -> None:
        """cost.input_bound = "auto" (given so, now or in the config this one was updated from):
        lambda from plant.torque_limits, the feedforward over the task and the probe
        (rates.auto_input_bound)."""
        if self.cost.input_bound != AUTO and "cost.input_bound" not in self._auto:
            return
        bound, reason = auto_input_bound(self)
        object.__setattr__(self, "cost", dataclasses.replace(self.cost, input_bound=bound))
        self._derived["cost.input_bound"] = reason

    def _resolve_step(self) -> None:
        """sim.dt = "auto" (a URDF arm's default, or given so): the largest 1, 2 or 5 x 10^k s
        with every fast rate of the closed loop inside RK4's stable region with margin
        (rates.auto_step), at most 1 ms."""
        auto = self.sim.dt == AUTO or (
            self.plant.urdf is not None and "sim.dt" not in self._explicit
        )
        if not auto:
            return
        dt = auto_step(closed_loop_rates(self), self.sim.T)
        object.__setattr__(self, "sim", dataclasses.replace(self.sim, dt=dt))
        self._derived["sim.dt"] = "auto: every fast rate of the closed loop * dt <= 0.6 * 2.785"

    def initial_weights(self, key: str = "critic_weights") -> np.ndarray:
        """init.critic_weights (or ``key = "actor_weights"``), or the basis' default when left
        out (InitConfig)."""
        value = getattr(self.init, key)
        if value is not None:
            return np.array(value, dtype=float)
        return self._default_initial_weights(key)

    def _default_initial_weights(self, key: str) -> np.ndarray:
        """The basis' default initial weights (InitConfig), whether or not init gives some."""
        return basis_for(self).initial_weights(self, key)

    @property
    def basis_size(self) -> int:
        """The number of functions of controller.basis on this arm (the length of the weights):
        the structured basis of a URDF arm has n (n + 1) / 2 + one per base inertial parameter
        of the believed model's URDF."""
        return basis_for(self).size(self)

    def left_out_values(self) -> dict[str, tuple[Any, str]]:
        """The value each setting that adparm resolves when it is left out takes for this
        config, and why, as {"section.key": (value, reason)}, whether or not the config gives
        it: critic.epsilon_T, init.critic_weights and init.actor_weights, probe.phases, a URDF
        plant's gravity, and the model's keys (the plant's values: an exact model). The
        settings of :attr:`derived` are in the config's fields already."""
        out: dict[str, tuple[Any, str]] = {}
        epsilon = EPSILON_T_EXTRAPOLATION if self.extrapolation.points > 0 else EPSILON_T_PROBING
        out["critic.epsilon_T"] = (
            epsilon,
            "with Bellman-error extrapolation (extrapolation.points > 0)"
            if self.extrapolation.points > 0
            else "learning from the probing signal alone (extrapolation.points = 0)",
        )
        if self.plant.urdf is not None and self.extrapolation.points > 0:
            out["critic.epsilon_T"] = (
                EPSILON_T_URDF,
                "a URDF arm with Bellman-error extrapolation (rates.EPSILON_T_URDF)",
            )
        for key in ("critic_weights", "actor_weights"):
            out[f"init.{key}"] = (
                self._default_initial_weights(key).tolist(),
                f"the default of controller.basis = {plain_value(self.controller.basis)!r}",
            )
        out["probe.phases"] = (
            self.probe.phase_matrix(self.dof).tolist(),
            "phase k rad for sinusoid k, on every joint",
        )
        exact = "the plant's (the controller's model is exact)"
        if self.plant.urdf is None:
            for key in ARM_KEYS:
                out[f"model.{key}"] = (plain_value(getattr(self.plant, key)), exact)
        else:
            out["plant.gravity"] = (list(self.plant.resolved_gravity), "the default gravity")
            for key, value in ModelConfig().resolve_urdf(self.plant).items():
                if value is not None:
                    out[f"model.{key}"] = (plain_value(value), exact)
        return out

    def to_toml(self, *, resolved: bool = False) -> str:
        """The config as TOML text that load_config reads back to an equal config: each section
        in turn, matrices one row per line.

        With ``resolved=True`` (the config.toml that adparm writes beside a run), also every
        setting left out that adparm resolved (:meth:`left_out_values`: critic.epsilon_T, the
        initial weights, the probe phases, the model), each after a ``# resolved:`` comment,
        and a ``# derived for this arm:`` comment above each setting of :attr:`derived`. A run
        of that file is the same run: every value it used is written."""
        data = self.to_dict()
        notes: dict[str, str] = {
            name: f"derived for this arm: {reason}" for name, reason in self._derived.items()
        }
        if resolved:
            for name, (value, reason) in self.left_out_values().items():
                section, key = name.split(".", 1)
                if key not in data[section]:
                    data[section][key] = value
                    notes[name] = f"resolved (left out): {reason}"
        return toml_text(data, notes)


def paper_config() -> Config:
    """The paper's instance (Section 4, corrected) with our documented open choices."""
    return Config()


def load_config(path: str | Path) -> Config:
    """Read a TOML file of sections [plant] [model] [task] [cost] [control] [critic] [actor]
    [init] [probe] [controller] [extrapolation] [identifier] [sim]; keys left out take the paper
    default. A relative ``task.qd.file`` is relative to the TOML file's folder."""
    path = Path(path)
    text = read_text_file(path, "config", MAX_CONFIG_BYTES)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"{path}: invalid TOML: {error}") from error
    except RecursionError:
        raise ValueError(f"{path}: {deep_toml(text)}") from None
    for section in ("plant", "model"):  # a relative URDF path is relative to the TOML file
        values = data.get(section)
        if (
            isinstance(values, Mapping)
            and isinstance(values.get("urdf"), str)
            and not values["urdf"].startswith(EXAMPLE_ROBOT_PREFIX)
        ):
            data[section]["urdf"] = str(path.parent / Path(values["urdf"]).expanduser())
    qd = data.get("task", {}).get("qd") if isinstance(data.get("task"), Mapping) else None
    if isinstance(qd, Mapping) and isinstance(qd.get("file"), str):
        data["task"]["qd"] = {**qd, "file": str(path.parent / Path(qd["file"]).expanduser())}
    return Config.from_dict(data)
