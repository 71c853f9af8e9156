"""Configuration of a run: frozen dataclasses, one per TOML section, validated on construction.

Every field has the paper's value (Section 4 of the paper, corrected by ERRATA.md) or, where the
paper leaves a setting open, this project's documented choice. A key left out of a TOML file takes
that default; an unknown section or key is refused with a "did you mean" hint.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import numbers
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "ActorConfig",
    "Config",
    "ControlConfig",
    "CostConfig",
    "CriticConfig",
    "InitConfig",
    "ModelConfig",
    "PlantConfig",
    "ProbeConfig",
    "SimConfig",
    "TaskConfig",
    "load_config",
    "paper_config",
]

Vector = tuple[float, ...]
Matrix = tuple[tuple[float, ...], ...]


# --- field checks: each names the field ("section.key") and what it expects -------------------


def _scalar(value: Any, name: str, *, minimum: float | None = None, strict: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name}: expected a number, got {type(value).__name__} {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name}: must be finite, got {value}")
    if minimum is not None and (value <= minimum if strict else value < minimum):
        relation = ">" if strict else ">="
        raise ValueError(f"{name}: must be {relation} {minimum:g}, got {value:g}")
    return value


def _integer(value: Any, name: str, *, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name}: expected an integer, got {type(value).__name__} {value!r}")
    if int(value) < minimum:
        raise ValueError(f"{name}: must be >= {minimum}, got {int(value)}")
    return int(value)


def _array(value: Any, name: str, shape: tuple[int | None, ...]) -> np.ndarray:
    if isinstance(value, (str, bytes, Mapping)) or isinstance(value, bool):
        raise TypeError(f"{name}: expected an array of shape {_shape_text(shape)}, got {value!r}")
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise TypeError(
            f"{name}: expected an array of numbers of shape {_shape_text(shape)}, got {value!r}"
        ) from error
    if array.ndim != len(shape) or any(
        expected is not None and actual != expected
        for actual, expected in zip(array.shape, shape, strict=False)
    ):
        raise ValueError(f"{name}: expected shape {_shape_text(shape)}, got {tuple(array.shape)}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name}: must be finite, got {array.tolist()}")
    return array


def _shape_text(shape: tuple[int | None, ...]) -> str:
    return (
        "("
        + ", ".join("n" if s is None else str(s) for s in shape)
        + ("," if len(shape) == 1 else "")
        + ")"
    )


def _vector(value: Any, name: str, size: int | None) -> Vector:
    if isinstance(value, bool) or isinstance(value, numbers.Real):
        raise TypeError(f"{name}: expected a list of {size or 'n'} numbers, got {value!r}")
    return tuple(float(v) for v in _array(value, name, (size,)))


def _matrix(value: Any, name: str, rows: int | None, cols: int | None) -> Matrix:
    return tuple(tuple(float(v) for v in row) for row in _array(value, name, (rows, cols)))


def _symmetric_positive_definite(matrix: Matrix, name: str) -> None:
    array = np.array(matrix)
    if not np.allclose(array, array.T, rtol=1e-12, atol=1e-12):
        raise ValueError(f"{name}: must be symmetric, got {array.tolist()}")
    if np.linalg.eigvalsh(array).min() <= 0.0:
        raise ValueError(f"{name}: must be positive definite, got {array.tolist()}")


def _check_arm(p1: float, p2: float, p3: float, section: str) -> None:
    if p2 <= 0.0:
        raise ValueError(f"{section}.p2: must be > 0, got {p2:g}")
    if p1 * p2 - p2**2 - p3**2 <= 0.0:
        raise ValueError(
            f"{section}.p1, {section}.p2, {section}.p3: M(q) must be positive definite for every q "
            f"(need p1 p2 - p2^2 - p3^2 > 0, got {p1 * p2 - p2**2 - p3**2:g})"
        )


_ARM_KEYS = ("p1", "p2", "p3", "g1", "g2", "coulomb", "viscous")


# --- sections ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class PlantConfig:
    """The arm of eq. (1): M, C, G as in Section 4, F = coulomb sgn(dq) + viscous dq,
    tau_d = [disturbance[0] sin t, disturbance[1] cos t]."""

    p1: float = 5.0
    p2: float = 1.0
    p3: float = 1.0
    g1: float = 9.8 * 1.2
    g2: float = 9.8
    coulomb: float = -0.1  # as printed: F = -0.1 sgn(dq)
    viscous: float = 0.0  # not in the paper; 0 keeps its plant
    disturbance: Vector = (0.1, 0.1)

    def __post_init__(self) -> None:
        for key in _ARM_KEYS:
            object.__setattr__(self, key, _scalar(getattr(self, key), f"plant.{key}"))
        object.__setattr__(self, "disturbance", _vector(self.disturbance, "plant.disturbance", 2))
        _check_arm(self.p1, self.p2, self.p3, "plant")


@dataclass(frozen=True)
class ModelConfig:
    """The arm the controller believes (feedforward h of eq. 5 and f, g of eq. 9). A key left
    out (None) takes the plant's value, so the default is an exact model."""

    p1: float | None = None
    p2: float | None = None
    p3: float | None = None
    g1: float | None = None
    g2: float | None = None
    coulomb: float | None = None
    viscous: float | None = None

    def __post_init__(self) -> None:
        for key in _ARM_KEYS:
            value = getattr(self, key)
            if value is not None:
                object.__setattr__(self, key, _scalar(value, f"model.{key}"))

    def resolve(self, plant: PlantConfig) -> dict[str, float]:
        """The model's parameters with the plant's values filled in."""
        return {
            key: getattr(plant, key) if getattr(self, key) is None else getattr(self, key)
            for key in _ARM_KEYS
        }


@dataclass(frozen=True)
class TaskConfig:
    """Initial joint state and set-point (rad, rad/s).

    dq0 = 0 is our choice (the paper is silent)."""

    q0: Vector = (0.1598, 0.2257)
    dq0: Vector = (0.0, 0.0)
    qd: Vector = (0.0, 0.0)

    def __post_init__(self) -> None:
        for key in ("q0", "dq0", "qd"):
            object.__setattr__(self, key, _vector(getattr(self, key), f"task.{key}", 2))


_PAPER_Q: Matrix = (
    (40.0, 2.0, -4.0, 4.0),
    (2.0, 40.0, 4.0, -6.0),
    (-4.0, 4.0, 4.0, 0.0),
    (4.0, -6.0, 0.0, 4.0),
)


@dataclass(frozen=True)
class CostConfig:
    """r(x, u) = x^T Q x + u^T R u (eqs. 10-11); Q (4x4) and R (2x2) symmetric positive definite."""

    Q: Matrix = _PAPER_Q
    R: Matrix = ((0.25, 0.0), (0.0, 0.25))

    def __post_init__(self) -> None:
        object.__setattr__(self, "Q", _matrix(self.Q, "cost.Q", 4, 4))
        object.__setattr__(self, "R", _matrix(self.R, "cost.R", 2, 2))
        _symmetric_positive_definite(self.Q, "cost.Q")
        _symmetric_positive_definite(self.R, "cost.R")


@dataclass(frozen=True)
class ControlConfig:
    """alpha1 of eq. (7) (the paper's "alpha") and the RISE gains of eqs. (27)-(28).

    The paper prints no RISE gains. Defaults: ks = 10, alpha2 = 1, beta1 = 0.5, which satisfies
    condition (29) for the paper's disturbance (|tau_d| <= 0.1, |dtau_d/dt| <= 0.1, so
    zeta1 + zeta2 / alpha2 = 0.2 < 0.5)."""

    alpha1: Matrix = ((15.6, 10.6), (10.6, 10.4))
    ks: float = 10.0
    alpha2: float = 1.0
    beta1: float = 0.5

    def __post_init__(self) -> None:
        object.__setattr__(self, "alpha1", _matrix(self.alpha1, "control.alpha1", 2, 2))
        for key in ("ks", "alpha2", "beta1"):
            object.__setattr__(
                self, key, _scalar(getattr(self, key), f"control.{key}", minimum=0.0)
            )


@dataclass(frozen=True)
class CriticConfig:
    """Normalised least squares of eqs. (23)-(24): gain eta_c, normalisation nu,
    Gamma(0) = gamma0 I, reset to gamma0 I when lambda_min(Gamma) < epsilon_T.

    Paper values except epsilon_T = 1e-6 (paper: 1e-3). With 1e-3 Gamma is reset every few tens
    of ms under strong excitation, each window is too short to inform the weakly excited e1
    direction, and the critic stalls 10-40 % off W*; see README, "Probing"."""

    eta_c: float = 800.0
    nu: float = 1.0
    gamma0: float = 100.0
    epsilon_T: float = 1e-6

    def __post_init__(self) -> None:
        for key in ("eta_c", "nu", "epsilon_T"):
            object.__setattr__(self, key, _scalar(getattr(self, key), f"critic.{key}", minimum=0.0))
        object.__setattr__(
            self, "gamma0", _scalar(self.gamma0, "critic.gamma0", minimum=0.0, strict=True)
        )
        if self.epsilon_T >= self.gamma0:
            raise ValueError(
                f"critic.epsilon_T: must be < critic.gamma0 = {self.gamma0:g}, "
                f"got {self.epsilon_T:g}"
            )


@dataclass(frozen=True)
class ActorConfig:
    """Actor law (26): gains eta_a1, eta_a2 and the projection bound ||Wa|| <= weight_bound
    (the paper leaves the bound open; 100 is about 8 ||W*||)."""

    eta_a1: float = 0.01
    eta_a2: float = 1.0
    weight_bound: float = 100.0

    def __post_init__(self) -> None:
        for key in ("eta_a1", "eta_a2"):
            object.__setattr__(self, key, _scalar(getattr(self, key), f"actor.{key}", minimum=0.0))
        object.__setattr__(
            self,
            "weight_bound",
            _scalar(self.weight_bound, "actor.weight_bound", minimum=0.0, strict=True),
        )


@dataclass(frozen=True)
class InitConfig:
    """Initial critic and actor weights (8 each, in the basis order of adparm.BASIS_NAMES).

    Not printed in the paper. All ones (ERRATA): the initial actor must stabilise the model, and
    all-zero weights are inadmissible (omega = 0 at rest while the HJB error is x^T Q x > 0, so the
    critic diverges within milliseconds; simulate() then raises SimulationDiverged)."""

    critic_weights: Vector = (1.0,) * 8
    actor_weights: Vector = (1.0,) * 8

    def __post_init__(self) -> None:
        for key in ("critic_weights", "actor_weights"):
            object.__setattr__(self, key, _vector(getattr(self, key), f"init.{key}", 8))


@dataclass(frozen=True)
class ProbeConfig:
    """Probing signal added to the applied input u (persistence of excitation, eq. 25):
    probe_j(t) = ramp(t) sum_k amplitude_jk sin(frequencies_k t + phases_jk) for t < until,
    ramp(t) = min(1, t / ramp).

    The paper says only that "a probing signal is added"; the design is ours (README, "Probing").
    amplitude is one number (both joints), a pair (per joint, every sinusoid) or a 2 x n matrix
    (per joint and sinusoid, N m). Default: 4 sinusoids at 1, 2.7, 5.3, 9.1 rad/s, each with the
    torque direction [71, 23] N m = 75 N m along M(qd) v_fast, where v_fast is the eigenvector of
    alpha1 with the larger eigenvalue (23.9 1/s): that mode of e1 is filtered hardest and is the
    critic's least excited direction. Phases k rad on both joints (None), so each sinusoid keeps
    that direction; until 100 s, no ramp; until = 0 turns probing off."""

    amplitude: Vector | Matrix = (71.0, 23.0)
    until: float = 100.0
    ramp: float = 0.0
    frequencies: Vector = (1.0, 2.7, 5.3, 9.1)
    phases: Matrix | None = None  # None: phase k rad for sinusoid k, on both joints

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "frequencies", _vector(self.frequencies, "probe.frequencies", None)
        )
        n = len(self.frequencies)
        amplitude = self.amplitude
        if isinstance(amplitude, numbers.Real) and not isinstance(amplitude, bool):
            amplitude = (amplitude, amplitude)
        if np.ndim(amplitude) == 2:
            amplitude = _matrix(amplitude, "probe.amplitude", 2, n)
        else:
            amplitude = _vector(amplitude, "probe.amplitude", 2)
        object.__setattr__(self, "amplitude", amplitude)
        object.__setattr__(self, "until", _scalar(self.until, "probe.until", minimum=0.0))
        object.__setattr__(self, "ramp", _scalar(self.ramp, "probe.ramp", minimum=0.0))
        if self.phases is not None:
            object.__setattr__(self, "phases", _matrix(self.phases, "probe.phases", 2, n))

    def amplitude_matrix(self) -> np.ndarray:
        """Amplitudes as a (2, n) array (one column per sinusoid)."""
        amplitude = np.array(self.amplitude, dtype=float)
        if amplitude.ndim == 1:
            amplitude = np.repeat(amplitude[:, None], len(self.frequencies), axis=1)
        return amplitude.reshape(2, len(self.frequencies))

    def phase_matrix(self) -> np.ndarray:
        """Phases as a (2, n) array, with the default filled in."""
        if self.phases is not None:
            return np.array(self.phases, dtype=float).reshape(2, len(self.frequencies))
        n = len(self.frequencies)
        return np.vstack([np.arange(n, dtype=float)] * 2)


@dataclass(frozen=True)
class SimConfig:
    """Fixed-step RK4: horizon T (s), step dt (s), record every record_every-th step, and the
    bound on |q|, |dq|, |Wc|, |Wa| beyond which a run stops as diverged. The paper prints no step;
    dt = 1 ms and T = 150 s (past its 110 s convergence claim) are our choices. If T is not a
    multiple of dt, the last step is shortened to end exactly at T."""

    T: float = 150.0
    dt: float = 1e-3
    record_every: int = 10
    divergence_bound: float = 1e6

    def __post_init__(self) -> None:
        object.__setattr__(self, "T", _scalar(self.T, "sim.T", minimum=0.0, strict=True))
        object.__setattr__(self, "dt", _scalar(self.dt, "sim.dt", minimum=0.0, strict=True))
        object.__setattr__(
            self, "record_every", _integer(self.record_every, "sim.record_every", minimum=1)
        )
        object.__setattr__(
            self,
            "divergence_bound",
            _scalar(self.divergence_bound, "sim.divergence_bound", minimum=0.0, strict=True),
        )
        if self.dt > self.T:
            raise ValueError(f"sim.dt: must be <= sim.T = {self.T:g}, got {self.dt:g}")
        if self.T / self.dt > 1e10:
            raise ValueError(f"sim.dt: T / dt = {self.T / self.dt:.3g} steps is more than 1e10")


_SECTIONS: dict[str, type] = {
    "plant": PlantConfig,
    "model": ModelConfig,
    "task": TaskConfig,
    "cost": CostConfig,
    "control": ControlConfig,
    "critic": CriticConfig,
    "actor": ActorConfig,
    "init": InitConfig,
    "probe": ProbeConfig,
    "sim": SimConfig,
}


def _hint(name: str, choices: list[str]) -> str:
    close = difflib.get_close_matches(name, choices, n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


@dataclass(frozen=True)
class Config:
    """A whole run. ``Config()`` and :func:`paper_config` are the paper's instance."""

    plant: PlantConfig = field(default_factory=PlantConfig)
    model: ModelConfig = field(default_factory=ModelConfig)
    task: TaskConfig = field(default_factory=TaskConfig)
    cost: CostConfig = field(default_factory=CostConfig)
    control: ControlConfig = field(default_factory=ControlConfig)
    critic: CriticConfig = field(default_factory=CriticConfig)
    actor: ActorConfig = field(default_factory=ActorConfig)
    init: InitConfig = field(default_factory=InitConfig)
    probe: ProbeConfig = field(default_factory=ProbeConfig)
    sim: SimConfig = field(default_factory=SimConfig)

    def __post_init__(self) -> None:
        for name, cls in _SECTIONS.items():
            if not isinstance(getattr(self, name), cls):
                raise TypeError(
                    f"{name}: expected {cls.__name__}, got {type(getattr(self, name)).__name__}"
                )
        model = self.model.resolve(self.plant)
        _check_arm(model["p1"], model["p2"], model["p3"], "model")

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], base: Config | None = None) -> Config:
        """Build a config from nested mappings ``{section: {key: value}}`` over ``base``
        (default: the paper's instance). Unknown sections and keys are refused."""
        if not isinstance(data, Mapping):
            raise TypeError(f"config: expected a mapping of sections, got {type(data).__name__}")
        base = cls() if base is None else base
        sections = {}
        for section, values in data.items():
            if section not in _SECTIONS:
                raise ValueError(
                    f"unknown config section [{section}]{_hint(section, list(_SECTIONS))}; "
                    f"known sections: {', '.join(_SECTIONS)}"
                )
            if not isinstance(values, Mapping):
                raise TypeError(
                    f"[{section}]: expected a table of keys, got {type(values).__name__}"
                )
            keys = [f.name for f in dataclasses.fields(_SECTIONS[section])]
            for key in values:
                if key not in keys:
                    raise ValueError(
                        f"unknown key {section}.{key}{_hint(key, keys)}; "
                        f"known keys of [{section}]: {', '.join(keys)}"
                    )
            sections[section] = dataclasses.replace(getattr(base, section), **values)
        return dataclasses.replace(base, **sections)

    def to_dict(self) -> dict[str, dict[str, Any]]:
        """Nested plain dict (lists for arrays, model keys left at the plant's value omitted)."""
        out: dict[str, dict[str, Any]] = {}
        for name in _SECTIONS:
            section = dataclasses.asdict(getattr(self, name))
            out[name] = {key: _plain(value) for key, value in section.items() if value is not None}
        return out

    def to_toml(self) -> str:
        """The config as TOML text that load_config reads back to an equal config."""
        import tomli_w

        return tomli_w.dumps(self.to_dict())

    def updated(self, changes: Mapping[str, Any]) -> Config:
        """A copy with ``changes`` (``{section: {key: value}}``) applied, e.g.
        ``config.updated({"critic": {"eta_c": 100}})``."""
        return Config.from_dict(changes, base=self)


def _plain(value: Any) -> Any:
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def paper_config() -> Config:
    """The paper's instance (Section 4, ERRATA-corrected) with our documented open choices."""
    return Config()


def load_config(path: str | Path) -> Config:
    """Read a TOML file of sections [plant] [model] [task] [cost] [control] [critic] [actor]
    [init] [probe] [sim]; keys left out take the paper default."""
    path = Path(path)
    try:
        with path.open("rb") as stream:
            data = tomllib.load(stream)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"{path}: invalid TOML: {error}") from error
    return Config.from_dict(data)
