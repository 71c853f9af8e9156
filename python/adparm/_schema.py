"""The configuration's schema: ConfigSchema, the sections of a run together with the checks that
need only the values and the arm's joint count (the section classes and field checks are in
adparm._sections, adparm._arm_sections and adparm._fields).

ConfigSchema stands at the bottom of the package and imports nothing that knows the arm's
dynamics. :class:`adparm.Config` (adparm.config, the model layer) subclasses it and fills in its
hooks (``_arm_defaults``, ``_check_basis``, ``_resolve_input_bound``, ``_resolve_step``) with
what the arm and the basis derive: a URDF arm's defaults, the basis' size and initial weights,
cost.input_bound = "auto", sim.dt = "auto". The
functions of the model layer (adparm.optimal, adparm.rates, adparm.urdf) take a config as a
ConfigSchema and read the fields and properties it has."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ._arm_sections import (
    ModelConfig,
    PlantConfig,
    SampledTrajectory,
    SinusoidTrajectory,
    TaskConfig,
    check_urdf_arm,
    plain_value,
    urdf_info,
)
from ._fields import (
    AUTO,
    TWO_LINK_KEYS,
    check_arm,
    check_depth,
    check_keys,
    check_known,
    shape_text,
)
from ._sections import (
    BASIS_KINDS,
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

__all__ = ["ConfigSchema"]


@dataclass(frozen=True)
class ConfigSchema:
    """The sections of a run, checked against each other and the arm's joint count; the base of
    :class:`adparm.Config`, which derives what depends on the arm's dynamics and the basis.
    Build an adparm.Config, not this class."""

    plant: PlantConfig = field(default_factory=PlantConfig)
    model: ModelConfig = field(default_factory=ModelConfig)
    task: TaskConfig = field(default_factory=TaskConfig)
    cost: CostConfig = field(default_factory=CostConfig)
    control: ControlConfig = field(default_factory=ControlConfig)
    critic: CriticConfig = field(default_factory=CriticConfig)
    actor: ActorConfig = field(default_factory=ActorConfig)
    init: InitConfig = field(default_factory=InitConfig)
    probe: ProbeConfig = field(default_factory=ProbeConfig)
    controller: ControllerConfig = field(default_factory=ControllerConfig)
    extrapolation: ExtrapolationConfig = field(default_factory=ExtrapolationConfig)
    identifier: IdentifierConfig = field(default_factory=IdentifierConfig)
    sim: SimConfig = field(default_factory=SimConfig)
    diagnostics: DiagnosticsConfig = field(default_factory=DiagnosticsConfig)
    #: "section.key" of every setting given explicitly through from_dict/updated/load_config (a
    #: value "auto" is not explicit): a URDF arm derives the others (rates.urdf_defaults).
    _explicit: frozenset[str] = field(default=frozenset(), repr=False, compare=False)
    #: "section.key" of every setting given as "auto" whose value adparm.Config resolves and
    #: resolves again when the config is updated (cost.input_bound).
    _auto: frozenset[str] = field(default=frozenset(), repr=False, compare=False)

    def __post_init__(self) -> None:
        for name, cls in SECTIONS.items():
            if not isinstance(getattr(self, name), cls):
                raise TypeError(
                    f"{name}: expected {cls.__name__}, got {type(getattr(self, name)).__name__}"
                )
        if self.plant.urdf is not None and self.controller.basis == ControllerConfig.basis:
            # left at the two-link default: the URDF arm's default (from_dict refuses a
            # two-link basis set explicitly)
            controller = dataclasses.replace(self.controller, basis=URDF_DEFAULT_BASIS)
            object.__setattr__(self, "controller", controller)
        self._check_model()
        self._fit_to_arm()
        if self.plant.urdf is None:
            model = self.model.resolve(self.plant)
            check_arm(model["p1"], model["p2"], model["p3"], "model")
        self._check_basis()
        self._check_identifier()
        if self.resolved_epsilon_T >= self.critic.gamma0:
            raise ValueError(
                f"critic.epsilon_T: must be < critic.gamma0 = {self.critic.gamma0:g}, "
                f"got {self.resolved_epsilon_T:g}"
            )
        qd = self.task.qd
        if isinstance(qd, SampledTrajectory) and qd.t[-1] < self.sim.T * (1.0 - 1e-12):
            raise ValueError(
                f"task.qd: the samples end at t = {qd.t[-1]:g} s, before sim.T = {self.sim.T:g} s"
            )
        self._resolve_input_bound()
        self._resolve_step()

    def _check_basis(self) -> None:
        """The initial weights and the basis against the arm (adparm.Config)."""

    def _check_identifier(self) -> None:
        """An identifying run's model against the plant's kinematics (adparm.Config)."""

    def _arm_defaults(self) -> tuple[dict[tuple[str, str], Any], dict[str, str]]:
        """The settings a URDF arm derives, with their reasons (adparm.Config)."""
        return {}, {}

    def _resolve_input_bound(self) -> None:
        """cost.input_bound = "auto" (adparm.Config)."""

    def _resolve_step(self) -> None:
        """sim.dt = "auto" (adparm.Config)."""

    @property
    def explicit_keys(self) -> frozenset[str]:
        """The settings ("section.key") given explicitly; a URDF arm derives the others."""
        return self._explicit

    @property
    def derived(self) -> dict[str, str]:
        """The settings derived for this arm (left out of the config), each with its reason."""
        return dict(self._derived)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], base: ConfigSchema | None = None) -> Any:
        """Build a config from nested mappings ``{section: {key: value}}`` over ``base``
        (default: the paper's instance). Unknown sections and keys are refused."""
        if not isinstance(data, Mapping):
            raise TypeError(f"config: expected a mapping of sections, got {type(data).__name__}")
        if base is not None and not isinstance(base, ConfigSchema):
            raise TypeError(f"base: expected adparm.Config or None, got {type(base).__name__}")
        base = cls() if base is None else base
        sections = {}
        explicit = set(base._explicit)
        auto = set(base._auto)
        for section, values in data.items():
            check_known(
                section,
                list(SECTIONS),
                strings="config: section names must be strings",
                unknown="unknown config section [{name}]",
                listing=f"known sections: {', '.join(SECTIONS)}",
            )
            if not isinstance(values, Mapping):
                raise TypeError(
                    f"[{section}]: expected a table of keys, got {type(values).__name__}"
                )
            if section == "model" and "torque_limits" in values:
                raise ValueError(
                    "model.torque_limits: a torque limit belongs to the plant's actuators; set "
                    "plant.torque_limits (the controller has no limits of its own)"
                )
            check_keys(values, [f.name for f in dataclasses.fields(SECTIONS[section])], section)
            for key, value in values.items():
                check_depth(value, f"{section}.{key}")
                name = f"{section}.{key}"
                if isinstance(value, str) and value == AUTO:
                    explicit.discard(name)
                    auto.add(name)
                else:
                    explicit.add(name)
                    auto.discard(name)
            sections[section] = dataclasses.replace(getattr(base, section), **values)
        check_urdf_keys(data, sections.get("plant", base.plant))
        return dataclasses.replace(
            base, **sections, _explicit=frozenset(explicit), _auto=frozenset(auto)
        )

    def to_dict(self) -> dict[str, dict[str, Any]]:
        """Nested plain dict (lists for arrays, model keys left at the plant's value omitted)."""
        out: dict[str, dict[str, Any]] = {}
        for name in SECTIONS:
            section = {
                f.name: getattr(getattr(self, name), f.name)
                for f in dataclasses.fields(SECTIONS[name])
            }
            if name == "plant" and self.plant.urdf is not None:  # the URDF gives the arm
                section = {k: v for k, v in section.items() if k not in TWO_LINK_KEYS}
            out[name] = {
                key: plain_value(value) for key, value in section.items() if value is not None
            }
        return out

    def _check_model(self) -> None:
        """The model's keys against the plant's kind of arm (URDF or the two-link arm)."""
        if self.plant.urdf is None:
            for key in ("urdf", "gravity", "locked_joints"):
                if getattr(self.model, key) is not None:
                    raise ValueError(
                        f"model.{key}: only with a URDF plant (plant.urdf); the two-link model "
                        "takes model.p1 ... model.g2"
                    )
            check_urdf_arm(self.model, "model")
            return
        check_urdf_arm(dataclasses.replace(self.model, urdf=self.plant.urdf), "model")
        if self.model.urdf is not None or self.model.locked_joints is not None:
            believed = self.model.resolve_urdf(self.plant)
            name = "model.urdf" if self.model.urdf is not None else "model.locked_joints"
            n = self.dof
            n_model = urdf_info(believed["urdf"], name, believed["locked_joints"])[0]
            if n_model != n:
                raise ValueError(
                    f"{name}: the model has n = {n_model} joints, the plant (plant.urdf) "
                    f"n = {n}; the model must leave the plant's joints free"
                )
        refuse_two_link_basis(self.controller.basis)

    def _fit_to_arm(self) -> None:
        """A URDF arm (any joint count, two included) derives every setting the config leaves
        out from its believed model's inertia (rates.urdf_defaults; the two-link arm keeps the
        paper's); then every size is checked against n, naming the field and the expected
        shape."""
        object.__setattr__(self, "_derived", {})
        n = self.dof
        if self.plant.urdf is not None:
            # the sizes first (the derivation evaluates the arm at q0 and qd)
            self._replace_fields(
                {
                    name: value
                    for name, value in joint_defaults(n).items()
                    if ".".join(name) not in self._explicit
                }
            )
            check_sizes(self, n)
            values, reasons = self._arm_defaults()
            self._replace_fields(values)
            self._derived.update(reasons)
        elif n != 2:  # an n-joint stand-in without a URDF (tests): the n-joint defaults
            for (section, key), value in joint_defaults(n).items():
                current = getattr(self, section)
                if getattr(current, key) == getattr(SECTIONS[section](), key):
                    object.__setattr__(self, section, dataclasses.replace(current, **{key: value}))
        qd = self.task.qd
        if isinstance(qd, SinusoidTrajectory) and qd.offset is None:  # rest: 0 (URDF: derived)
            self._replace_fields({("task", "qd"): dataclasses.replace(qd, offset=(0.0,) * n)})
        check_sizes(self, n)

    def _replace_fields(self, values: Mapping[tuple[str, str], Any]) -> None:
        """Sets {(section, key): value}, each section's keys at once: its checks between keys
        (e.g. cost.Q's e2 block against cost.R with e2_cost = "logcosh") see the new values
        together, not a new Q beside the old R."""
        sections: dict[str, dict[str, Any]] = {}
        for (section, key), value in values.items():
            sections.setdefault(section, {})[key] = value
        for section, changes in sections.items():
            current = getattr(self, section)
            object.__setattr__(self, section, dataclasses.replace(current, **changes))

    @property
    def dof(self) -> int:
        """The joint count n of the plant: 2 for the built-in two-link arm, the URDF's
        revolute, continuous and prismatic joints for plant.urdf that plant.locked_joints leaves
        free."""
        if self.plant.urdf is None:
            return 2
        return urdf_info(self.plant.urdf, "plant.urdf", self.plant.locked_joints)[0]

    @property
    def resolved_epsilon_T(self) -> float:
        """critic.epsilon_T, or its default for this run when left out: 1e-6 when learning from
        the probing signal alone, the paper's 1e-3 with Bellman-error extrapolation."""
        if self.critic.epsilon_T is not None:
            return self.critic.epsilon_T
        return EPSILON_T_EXTRAPOLATION if self.extrapolation.points > 0 else EPSILON_T_PROBING

    def believing_the_plant(self) -> Any:
        """This config with the controller believing the plant (``[model]`` emptied) and every
        setting a URDF arm derived from the believed model (the cost, gains, dt ...) kept at this
        config's value: the run an identifying or model-off run is judged against is the same
        problem, not the one the plant's own defaults would pose."""
        frozen: dict[str, dict[str, Any]] = {}
        for key in self._derived:
            section, name = key.split(".")
            frozen.setdefault(section, {})[name] = getattr(getattr(self, section), name)
        fixed = self.updated(frozen) if frozen else self
        return dataclasses.replace(fixed, model=type(self.model)())

    def updated(self, changes: Mapping[str, Any]) -> Any:
        """A copy with ``changes`` (``{section: {key: value}}``) applied, e.g.
        ``config.updated({"critic": {"eta_c": 100}})``."""
        return type(self).from_dict(changes, base=self)


def check_urdf_keys(data: Mapping[str, Any], plant: PlantConfig) -> None:
    """With a URDF plant, refuses the two-link keys and bases given explicitly (even at their
    default values), naming the field."""
    if plant.urdf is None:
        return
    for section in ("plant", "model"):
        values = data.get(section, {})
        for key in TWO_LINK_KEYS:
            if key in values:
                raise ValueError(
                    f"{section}.{key}: a parameter of the built-in two-link arm; a URDF arm "
                    "(plant.urdf) takes its inertia and geometry from the URDF (leave "
                    f"{section}.{key} out)"
                )
    refuse_two_link_basis(data.get("controller", {}).get("basis"))


def refuse_two_link_basis(basis: Any) -> None:
    """A URDF arm refuses the two-link bases (ValueError naming controller.basis)."""
    if isinstance(basis, str) and basis in URDF_REFUSED_BASES:
        works = ", ".join(
            repr(b) for b in (*BASIS_KINDS, *EXPRESSION_FAMILIES) if b not in URDF_REFUSED_BASES
        )
        raise ValueError(
            f"controller.basis: {basis!r} is a basis of the built-in two-link arm; with "
            f"plant.urdf use {works} or a list of terms (default {URDF_DEFAULT_BASIS!r})"
        )


def joint_defaults(n: int) -> dict[tuple[str, str], Any]:
    """The defaults of the sized settings for an arm of n != 2 joints (the two-link arm keeps the
    paper's): tau_d amplitudes 0.1 and q0 = 0.1 rad on every joint, dq0 = 0, qd = 0; K = I,
    alpha1 = 2 I, R = I and Q = [[K alpha1 + alpha1^T K, -K], [-K, R^-1]] = [[4 I, -I], [-I, I]]
    (the exact-solution conditions: V* = e1^T e1 + e2^T M(q) e2 is exact); probe amplitude 1 N m
    on every joint and sinusoid."""
    eye = np.eye(n)
    Q = np.block([[4.0 * eye, -eye], [-eye, eye]])
    return {
        ("plant", "disturbance"): (0.1,) * n,
        ("task", "q0"): (0.1,) * n,
        ("task", "dq0"): (0.0,) * n,
        ("task", "qd"): (0.0,) * n,
        ("cost", "Q"): tuple(map(tuple, Q)),
        ("cost", "R"): tuple(map(tuple, eye)),
        ("control", "alpha1"): tuple(map(tuple, 2.0 * eye)),
        ("probe", "amplitude"): 1.0,
    }


def check_shape(value: Any, name: str, shape: tuple[int, ...], n: int) -> None:
    actual = np.shape(value)
    if actual != shape:
        raise ValueError(
            f"{name}: expected shape {shape_text(shape)}, got {shape_text(actual)} "
            f"(the arm has n = {n} joints)"
        )


def check_sizes(config: ConfigSchema, n: int) -> None:
    """Every sized setting against the joint count n (ValueError naming the field)."""
    check_shape(config.plant.disturbance, "plant.disturbance", (n,), n)
    if isinstance(config.plant.torque_limits, tuple):
        check_shape(config.plant.torque_limits, "plant.torque_limits", (n,), n)
    for section in ("plant", "model"):
        for key in ("coulomb", "viscous"):
            value = getattr(getattr(config, section), key)
            if isinstance(value, tuple):
                check_shape(value, f"{section}.{key}", (n,), n)
    check_shape(config.task.q0, "task.q0", (n,), n)
    check_shape(config.task.dq0, "task.dq0", (n,), n)
    qd = config.task.qd
    if isinstance(qd, SinusoidTrajectory):
        k = len(qd.amplitude[0])
        if qd.offset is not None:  # None: the rest position (a URDF arm's derived below)
            check_shape(qd.offset, "task.qd.offset", (n,), n)
        for key in ("amplitude", "frequency", "phase"):
            check_shape(getattr(qd, key), f"task.qd.{key}", (n, k), n)
    elif isinstance(qd, SampledTrajectory):
        check_shape(qd.q, "task.qd.q", (len(qd.t), n), n)
    else:
        check_shape(qd, "task.qd", (n,), n)
    check_shape(config.cost.Q, "cost.Q", (2 * n, 2 * n), n)
    check_shape(config.cost.R, "cost.R", (n, n), n)
    if isinstance(config.cost.input_bound, tuple):
        check_shape(config.cost.input_bound, "cost.input_bound", (n,), n)
    check_shape(config.control.alpha1, "control.alpha1", (n, n), n)
    k = len(config.probe.frequencies)
    amplitude = config.probe.amplitude
    if not isinstance(amplitude, float):
        shape = (n, k) if np.ndim(amplitude) == 2 else (n,)
        check_shape(amplitude, "probe.amplitude", shape, n)
    if config.probe.phases is not None:
        check_shape(config.probe.phases, "probe.phases", (n, k), n)
    for key in ("kp", "kd"):
        gain = getattr(config.controller, key)
        if not isinstance(gain, float):
            check_shape(gain, f"controller.{key}", (n, n), n)
    if not isinstance(config.extrapolation.box, float):
        check_shape(config.extrapolation.box, "extrapolation.box", (2 * n,), n)
    if not isinstance(config.extrapolation.centre, float):
        check_shape(config.extrapolation.centre, "extrapolation.centre", (2 * n,), n)
