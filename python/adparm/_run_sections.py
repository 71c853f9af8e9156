"""The sections of the configuration that set the run: [extrapolation], [identifier], [sim] and
[diagnostics]."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._fields import (
    AUTO,
    Vector,
    boolean_value,
    choice_value,
    int_text,
    integer_value,
    is_number,
    scalar_value,
    setting,
    vector_value,
)

EXTRAPOLATION_MODES = ("fixed", "grid", "local")
#: The most extrapolation points a run may have. A point costs about 180 ns per RK4 step, so a
#: million of them take about 0.2 s per step: some 8 hours for the paper's 150 s at dt = 1 ms.
MAX_POINTS = 10**6
#: The largest sim.record_every: a run has at most 1e10 steps, so a larger value would change
#: nothing (only the first and the last step are recorded), and this one fits the core's integer.
MAX_RECORD_EVERY = 10**10


@dataclass(frozen=True)
class ExtrapolationConfig:
    """Bellman-error extrapolation: the critic and actor laws also average their terms over the
    HJB error at ``points`` extra states x (0: off, the paper; at most MAX_POINTS = 10^6, which
    already takes about 0.2 s per RK4 step). ``mode``: ``fixed`` (points drawn once, uniform in
    centre + [-box, box]), ``grid`` (m points per axis, points = m^4) or ``local`` (points redrawn
    every step, uniform in x(t) + centre + [-box, box]). ``box``: half-widths in x = [e1; e2],
    one number or 4; ``centre``: the box's centre in x, one number or 4 (0: symmetric about x =
    0, the paper's and the two-link default; a URDF arm's derived box spans each joint's range
    within its limits, :func:`adparm.rates.extrapolation_range`).
    ``seed`` (0 <= seed < 2^32) seeds MT19937, drawn in the order of NumPy's
    ``RandomState(seed).random_sample((points, 4))``."""

    points: int = setting(
        0,
        "Number of extra states at which the HJB error enters the critic and actor laws; 0 is off "
        "(the paper). See :doc:`/guide/extrapolation`.",
        core="extrapolation.points",
    )
    box: float | Vector = setting(
        1.0,
        "Half-widths of the sampling box in x = [e1; e2] (one number or 4).",
        via="extrapolation.box, one per state (box_vector)",
    )
    centre: float | Vector = setting(
        0.0,
        "Centre of the sampling box in x = [e1; e2] (one number or 4; the points are drawn in "
        "centre + [-box, box]).",
        via="extrapolation.centre, one per state (centre_vector)",
    )
    mode: str = setting(
        "fixed",
        "``fixed`` (drawn once in centre + [-box, box]), ``grid`` (m per axis, points = m^4) or "
        "``local`` (redrawn every step around x(t) + centre).",
        via="extrapolation.mode, an enum (ExtrapolationMode)",
    )
    seed: int = setting(
        0, "Seed of the draws (MT19937, as NumPy's RandomState).", core="extrapolation.seed"
    )

    def __post_init__(self) -> None:
        object.__setattr__(
            self,
            "points",
            integer_value(self.points, "extrapolation.points", minimum=0, maximum=MAX_POINTS),
        )
        if is_number(self.box):
            box: float | Vector = scalar_value(
                self.box, "extrapolation.box", minimum=0.0, strict=True
            )
        else:
            box = vector_value(self.box, "extrapolation.box", None)
            if min(box) <= 0.0:
                raise ValueError(f"extrapolation.box: half-widths must be > 0, got {list(box)}")
        object.__setattr__(self, "box", box)
        if is_number(self.centre):
            centre: float | Vector = scalar_value(self.centre, "extrapolation.centre")
        else:
            centre = vector_value(self.centre, "extrapolation.centre", None)
        object.__setattr__(self, "centre", centre)
        choice_value(self.mode, "extrapolation.mode", EXTRAPOLATION_MODES)
        object.__setattr__(self, "seed", integer_value(self.seed, "extrapolation.seed", minimum=0))
        if self.seed >= 2**32:
            raise ValueError(f"extrapolation.seed: must be < 2^32, got {int_text(self.seed)}")
        if self.mode == "grid":
            m = round(self.points**0.25)
            if m**4 != self.points:
                raise ValueError(
                    "extrapolation.points: grid mode needs m^4 points (1, 16, 81, 256, ...), "
                    f"got {self.points}"
                )

    def box_vector(self, joints: int = 2) -> np.ndarray:
        """The half-widths as a (2 joints,) array."""
        return np.broadcast_to(np.array(self.box, dtype=float), (2 * joints,)).copy()

    def centre_vector(self, joints: int = 2) -> np.ndarray:
        """The box's centre as a (2 joints,) array."""
        return np.broadcast_to(np.array(self.centre, dtype=float), (2 * joints,)).copy()

    def bounds(self, joints: int = 2) -> tuple[np.ndarray, np.ndarray]:
        """The sampling box's lower and upper corners in x, centre -+ box, each (2 joints,)."""
        box, centre = self.box_vector(joints), self.centre_vector(joints)
        return centre - box, centre + box


@dataclass(frozen=True)
class IdentifierConfig:
    """The online identifier of the arm's base inertial parameters beta (issue 25; not in the
    paper; :doc:`/guide/unknown-dynamics`). The believed model (``[model]``) is the initial
    estimate beta_hat(0); the controller then uses beta_hat wherever the model appears. Runs on
    every arm, basis and controller kind."""

    enabled: bool = setting(
        False,
        "Identify beta online (the Slotine-Li gradient term plus concurrent learning over a "
        "history stack of windows of the momentum equation). false: the controller believes "
        "``[model]`` throughout (the runs of adparm before the identifier, bit for bit).",
        core="identifier.enabled",
    )
    gain: float = setting(
        0.01,
        "Gamma = gain I of the adaptive law d beta_hat/dt = Gamma [Y_r^T e2 + k sum_j Y_j^T "
        "(b_j - Y_j beta_hat)] (> 0).",
        core="identifier.gain",
    )
    gradient_term: bool = setting(
        False,
        "Include the Slotine-Li gradient term Gamma Y_r^T e2 in the adaptive law. Off by "
        "default (not in the issue's law): e2 is driven by the probe and the ADP input as much as "
        "by the model error, and before the stack is informative the term alone drifts beta_hat "
        "(on a light random 4-joint chain it made M_hat's smallest eigenvalue 34 times the "
        "plant's, and the run diverged when the stack corrected it); off, beta_hat stays at the "
        "model until the stack is informative.",
        core="identifier.gradient_term",
    )
    concurrent_gain: float = setting(
        1e6,
        "k, the weight of the history stack's term in the adaptive law (>= 0; integrated "
        "implicitly, stable for any value).",
        core="identifier.concurrent_gain",
    )
    history_size: int = setting(
        20,
        "Samples (windows) the history stack holds; a new one replaces the stored sample whose "
        "replacement most increases the stack's minimum singular value.",
        core="identifier.history_size",
    )
    window: float = setting(
        0.2,
        "Length T (s) of each window of the measurable equation int tau dt = [M dq] + "
        "int (G + F - C^T dq) dt (> 0).",
        core="identifier.window",
    )
    singular_value_threshold: float = setting(
        0.01,
        "The stack's term is used only while its minimum singular value (over the identified "
        "parameters) is at least this (>= 0): the rank condition (and max_uncertainty).",
        core="identifier.singular_value_threshold",
    )
    max_uncertainty: float = setting(
        0.05,
        "The stack's term is used only while the predicted relative error of the stack's "
        "least-squares estimate, sqrt(r / (m - P) trace(S^-1)) / ||beta_s|| (r its residual "
        "over m equations, P parameters; defined from m >= 2 P), is at most this (> 0): an "
        "unmodelled torque such as the disturbance makes the stack's equations disagree, and "
        "its estimate is then not jumped to. Not in the issue.",
        core="identifier.max_uncertainty",
    )
    inertia: bool = setting(
        True,
        "Identify the inertial parameters (two-link: p1, p2, p3; URDF: the kinetic energy's base "
        "parameters, those of the structured basis).",
        core="identifier.inertia",
    )
    gravity: bool = setting(
        True,
        "Identify the gravity coefficients (two-link: g1, g2; URDF: the parameters gravity sees "
        "beyond the kinetic energy's, if any).",
        core="identifier.gravity",
    )
    friction: bool = setting(
        False,
        "Identify the friction coefficients (two-link: coulomb, viscous; URDF: both per "
        "joint); false: the model's.",
        core="identifier.friction",
    )

    stop_probe: bool = setting(
        True,
        "Switch the probing signal off for good once the history stack is informative and "
        "beta_hat has moved by at most tolerance over the last history_size windows: the probe "
        "slows the critic, and the stack keeps what it recorded. Only with extrapolation points "
        "(without them the probe is the critic's only excitation, and it stays). Not in the "
        "paper.",
        core="identifier.stop_probe",
    )
    tolerance: float = setting(
        0.01,
        "stop_probe's settled beta_hat: its change over the last history_size windows at most "
        "this fraction of its norm, over the identified parameters (> 0). The default is the 1 % "
        "to which beta_hat and the critic are judged.",
        core="identifier.tolerance",
    )

    def __post_init__(self) -> None:
        for name in ("enabled", "gradient_term", "inertia", "gravity", "friction", "stop_probe"):
            object.__setattr__(self, name, boolean_value(getattr(self, name), f"identifier.{name}"))
        object.__setattr__(
            self, "gain", scalar_value(self.gain, "identifier.gain", minimum=0.0, strict=True)
        )
        object.__setattr__(
            self,
            "concurrent_gain",
            scalar_value(self.concurrent_gain, "identifier.concurrent_gain", minimum=0.0),
        )
        object.__setattr__(
            self,
            "history_size",
            integer_value(self.history_size, "identifier.history_size", minimum=1, maximum=100000),
        )
        object.__setattr__(
            self, "window", scalar_value(self.window, "identifier.window", minimum=0.0, strict=True)
        )
        object.__setattr__(
            self,
            "singular_value_threshold",
            scalar_value(
                self.singular_value_threshold, "identifier.singular_value_threshold", minimum=0.0
            ),
        )
        object.__setattr__(
            self,
            "max_uncertainty",
            scalar_value(
                self.max_uncertainty, "identifier.max_uncertainty", minimum=0.0, strict=True
            ),
        )
        object.__setattr__(
            self,
            "tolerance",
            scalar_value(self.tolerance, "identifier.tolerance", minimum=0.0, strict=True),
        )
        if not (self.inertia or self.gravity or self.friction):
            raise ValueError(
                "identifier.inertia, identifier.gravity, identifier.friction: at least one group "
                "must be identified"
            )


@dataclass(frozen=True)
class SimConfig:
    """Fixed-step RK4: horizon T (s), step dt (s), record every record_every-th step, and the
    bound on ``|q|``, ``|dq|``, ``|Wc|``, ``|Wa|`` beyond which a run stops as diverged. The paper
    prints no step; dt = 1 ms and T = 150 s (past its 110 s convergence claim) are our choices. If T
    is not a multiple of dt, the last step is shortened to end exactly at T. At most 1e10 steps (T /
    dt); 1 <= record_every <= MAX_RECORD_EVERY = 10^10.

    ``dt = "auto"`` (the default of a URDF arm) picks the largest 1, 2 or 5 x 10^k s, at most 1 ms,
    at which every fast rate of the closed loop (RISE through M^-1, the initial policy, the error
    dynamics, the critic) times dt is at most 0.6 of RK4's stability limit 2.785; the config then
    holds that number. simulate() refuses an explicit dt beyond the limit, naming the term, its
    rate and a dt that works. A URDF arm's T defaults to 10 s."""

    T: float = setting(150.0, "Horizon (s).", core="sim.T")
    dt: float | str = setting(
        1e-3,
        'RK4 step (s), or ``"auto"``: the largest 1, 2 or 5 x 10^k s (at most 1 ms) at which '
        "every fast rate of the closed loop times dt is at most 0.6 of RK4's limit 2.785 (a URDF "
        "arm's default). An explicit step beyond the limit is refused before the run.",
        core="sim.dt",
    )
    record_every: int = setting(10, "Record every n-th step.", core="sim.record_every")
    divergence_bound: float = setting(
        1e6,
        "The run stops as diverged when ``|q|``, ``|dq|``, ``|Wc|`` or ``|Wa|`` exceeds this "
        "value, or a state or recorded output is not finite.",
        core="sim.divergence_bound",
    )

    def __post_init__(self) -> None:
        object.__setattr__(self, "T", scalar_value(self.T, "sim.T", minimum=0.0, strict=True))
        if not (isinstance(self.dt, str) and self.dt == AUTO):  # "auto": Config resolves it
            object.__setattr__(
                self, "dt", scalar_value(self.dt, "sim.dt", minimum=0.0, strict=True)
            )
        object.__setattr__(
            self,
            "record_every",
            integer_value(
                self.record_every, "sim.record_every", minimum=1, maximum=MAX_RECORD_EVERY
            ),
        )
        object.__setattr__(
            self,
            "divergence_bound",
            scalar_value(self.divergence_bound, "sim.divergence_bound", minimum=0.0, strict=True),
        )
        dt = self.dt
        if isinstance(dt, str):  # AUTO: resolved by the Config
            return
        if dt > self.T:
            raise ValueError(f"sim.dt: must be <= sim.T = {self.T:g}, got {dt:g}")
        if self.T / dt > 1e10:
            raise ValueError(f"sim.dt: sim.T / sim.dt = {self.T / dt:.3g} steps is more than 1e10")


@dataclass(frozen=True)
class DiagnosticsConfig:
    """What a run's verdict holds it to (adparm.truth.diagnose). ``tolerance``: "ok" needs the
    critic weights, the actor weights and the applied policy (``rms |u_hat - u*| / rms |u*|`` over
    the last 10 % of the run) each within this relative distance of the known optimum; also the
    band of the summary's "time within tolerance". 0 < tolerance < 1; default 1 %."""

    tolerance: float = setting(
        0.01,
        'Verdict "ok" needs the critic weights, the actor weights and the applied policy (``rms '
        "|u_hat - u*| / rms |u*|`` over the last 10 % of the run) each within this relative "
        "distance of a known optimum; also the band of the summary's time within tolerance.",
        via="not for the core: the verdict (adparm.truth)",
    )

    def __post_init__(self) -> None:
        tolerance = scalar_value(self.tolerance, "diagnostics.tolerance", minimum=0.0, strict=True)
        if tolerance >= 1.0:
            raise ValueError(f"diagnostics.tolerance: must be < 1, got {tolerance:g}")
        object.__setattr__(self, "tolerance", tolerance)
