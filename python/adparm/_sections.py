"""The sections of the configuration that set the controller and the run: [cost], [control],
[critic], [actor], [init], [probe], [controller], [extrapolation], [sim], [diagnostics], and
SECTIONS, every section's class by its TOML name."""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._arm_sections import ModelConfig, PlantConfig, TaskConfig, plain_value
from ._fields import (
    AUTO,
    MAX_FREQUENCIES,
    Matrix,
    Vector,
    boolean_value,
    check_hurwitz,
    choice_value,
    did_you_mean,
    gain_value,
    int_text,
    integer_value,
    is_number,
    matrix_value,
    ndim_of,
    scalar_value,
    square_matrix,
    symmetric_positive_definite,
    vector_value,
)

PAPER_Q: Matrix = (
    (40.0, 2.0, -4.0, 4.0),
    (2.0, 40.0, 4.0, -6.0),
    (-4.0, 4.0, 4.0, 0.0),
    (4.0, -6.0, 0.0, 4.0),
)


@dataclass(frozen=True)
class CostConfig:
    """r(x, u) = x^T Q x + u^T R u (eqs. 10-11); Q (4x4) and R (2x2) symmetric positive definite."""

    Q: Matrix = PAPER_Q
    R: Matrix = ((0.25, 0.0), (0.0, 0.25))

    def __post_init__(self) -> None:
        object.__setattr__(self, "Q", square_matrix(self.Q, "cost.Q"))
        object.__setattr__(self, "R", square_matrix(self.R, "cost.R"))
        object.__setattr__(self, "Q", symmetric_positive_definite(self.Q, "cost.Q"))
        object.__setattr__(self, "R", symmetric_positive_definite(self.R, "cost.R"))


@dataclass(frozen=True)
class ControlConfig:
    """alpha1 of eq. (7) (the paper's "alpha") and the RISE gains of eqs. (27)-(28).

    -alpha1 must be Hurwitz (every eigenvalue of alpha1 with a positive real part), else the
    error e1 of de1 = -alpha1 e1 + e2 grows; the conditions of the analytic optimum (Q > 0) imply
    it.

    The paper prints no RISE gains. Defaults: ks = 10, alpha2 = 1, beta1 = 0.5, which satisfies
    condition (29) for the paper's disturbance (``|tau_d| <= 0.1``, ``|dtau_d/dt| <= 0.1``, so
    zeta1 + zeta2 / alpha2 = 0.2 < 0.5)."""

    alpha1: Matrix = ((15.6, 10.6), (10.6, 10.4))
    ks: float = 10.0
    alpha2: float = 1.0
    beta1: float = 0.5

    def __post_init__(self) -> None:
        object.__setattr__(self, "alpha1", square_matrix(self.alpha1, "control.alpha1"))
        check_hurwitz(self.alpha1, "control.alpha1")
        for key in ("ks", "alpha2", "beta1"):
            object.__setattr__(
                self, key, scalar_value(getattr(self, key), f"control.{key}", minimum=0.0)
            )


#: The covariance-reset threshold used when critic.epsilon_T is left out (None).
EPSILON_T_PROBING = 1e-6  # learning from the probing signal alone (docs: paper corrections)
EPSILON_T_EXTRAPOLATION = 1e-3  # with Bellman-error extrapolation: the paper's printed value


@dataclass(frozen=True)
class CriticConfig:
    """Normalised least squares of eqs. (23)-(24): gain eta_c, normalisation nu,
    Gamma(0) = gamma0 I, reset to gamma0 I when lambda_min(Gamma) < epsilon_T.

    Paper values, except that epsilon_T (paper: 1e-3) left out (None) depends on where the
    excitation comes from (Config.resolved_epsilon_T):

    - 1e-6 when the critic learns from the probing signal alone (no extrapolation points). With
      1e-3, Gamma is reset every few tens of ms under strong probing, each window is too short to
      inform the weakly excited e1 direction, and the critic stalls 10-40 % off W* (docs: "The
      paper and its corrections").
    - the printed 1e-3 with Bellman-error extrapolation. There the information grows steadily, and
      frequent resets keep the least-squares gain alive while the target (the value of the moving
      actor) moves; with 1e-6 the gain decays and the critic can take minutes (docs: user guide,
      "Bellman-error extrapolation")."""

    eta_c: float = 800.0
    nu: float = 1.0
    gamma0: float = 100.0
    epsilon_T: float | None = None

    def __post_init__(self) -> None:
        for key in ("eta_c", "nu"):
            object.__setattr__(
                self, key, scalar_value(getattr(self, key), f"critic.{key}", minimum=0.0)
            )
        object.__setattr__(
            self, "gamma0", scalar_value(self.gamma0, "critic.gamma0", minimum=0.0, strict=True)
        )
        if self.epsilon_T is not None:
            epsilon_T = scalar_value(self.epsilon_T, "critic.epsilon_T", minimum=0.0)
            object.__setattr__(self, "epsilon_T", epsilon_T)


@dataclass(frozen=True)
class ActorConfig:
    """Actor law (26): gains eta_a1, eta_a2 and the projection bound ||Wa|| <= weight_bound
    (the paper leaves the bound open; 100 is about 8 ||W*||).

    positive_e2 (default true; not in the paper): the projection also keeps the e2 block of the
    actor's value, e2^T P(cos q2) e2, positive definite with lambda_min(P) >= e2_margin at
    cos q2 = +-1 (hence at every q), for the paper and augmented bases. Without it, about one run
    in four with other probe phases or q(0) ends at the anti-stabilising solution of the HJB
    equation (the e2 block negated; docs/guide/truth.md). For the structured basis of a URDF
    arm the block is sum_b W_b M_b(q), kept positive definite at qd(0), q(0) and the joint
    positions of the extrapolation box (rates.check_positions). e2_margin is in the units of M
    (kg m^2); a URDF arm derives it (a tenth of lambda_min(M)) and weight_bound (10 ||W*||)."""

    eta_a1: float = 0.01
    eta_a2: float = 1.0
    weight_bound: float = 100.0
    positive_e2: bool = True
    e2_margin: float = 0.01

    def __post_init__(self) -> None:
        for key in ("eta_a1", "eta_a2", "e2_margin"):
            object.__setattr__(
                self, key, scalar_value(getattr(self, key), f"actor.{key}", minimum=0.0)
            )
        object.__setattr__(
            self, "positive_e2", boolean_value(self.positive_e2, "actor.positive_e2")
        )
        object.__setattr__(
            self,
            "weight_bound",
            scalar_value(self.weight_bound, "actor.weight_bound", minimum=0.0, strict=True),
        )


@dataclass(frozen=True)
class InitConfig:
    """Initial critic and actor weights (one per basis function, in the order of
    adparm.basis_names(config)); None (left out) takes the basis' default
    (Config.initial_weights):

    - paper and augmented bases: all ones (not printed in the paper). The initial actor
      must stabilise the model, and all-zero weights are inadmissible (omega = 0 at rest while the
      HJB error is x^T Q x > 0, so the critic diverges within milliseconds; simulate() then raises
      SimulationDiverged; docs: "The paper and its corrections").
    - structured basis: [1, 0, 1, p1, p2, p3], i.e. K = I for the e1 block and the inertia
      parameters of the believed model ([model], default the plant) for the e2 block. The actor's
      policy depends on the e2 block only (u_hat = -R^-1 M(q)^-1 M_w(q) e2 with M_w the inertia the
      weights describe), so these weights start at u_hat = -R^-1 e2, the optimal policy of the
      believed model; all-ones weights give an indefinite M_w on other arms and blow up."""

    critic_weights: Vector | None = None
    actor_weights: Vector | None = None

    def __post_init__(self) -> None:
        for key in ("critic_weights", "actor_weights"):
            if getattr(self, key) is not None:
                object.__setattr__(self, key, vector_value(getattr(self, key), f"init.{key}", None))


@dataclass(frozen=True)
class ProbeConfig:
    """Probing signal added to the applied input u (persistence of excitation, eq. 25):
    probe_j(t) = ramp(t) sum_k amplitude_jk sin(frequencies_k t + phases_jk) for t < until,
    ramp(t) = min(1, t / ramp).

    The paper says only that "a probing signal is added"; the design is ours (docs: "The paper and
    its corrections", excitation). amplitude is one number (both joints), a pair (per joint, every
    sinusoid) or a 2 x n matrix (per joint and sinusoid, N m). Default: 4 sinusoids at 1, 2.7, 5.3,
    9.1 rad/s, each with the torque direction [71, 23] N m = 75 N m along M(qd) v_fast, where v_fast
    is the eigenvector of alpha1 with the larger eigenvalue (23.9 1/s): that mode of e1 is filtered
    hardest and is the critic's least excited direction. Phases k rad on both joints (None), so each
    sinusoid keeps that direction; until 100 s, no ramp; until = 0 turns probing off."""

    amplitude: Vector | Matrix = (71.0, 23.0)
    until: float = 100.0
    ramp: float = 0.0
    frequencies: Vector = (1.0, 2.7, 5.3, 9.1)
    phases: Matrix | None = None  # None: phase k rad for sinusoid k, on both joints

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "frequencies", vector_value(self.frequencies, "probe.frequencies", None)
        )
        n = len(self.frequencies)
        if n > MAX_FREQUENCIES:
            raise ValueError(
                f"probe.frequencies: at most {MAX_FREQUENCIES} sinusoids (each costs every step "
                f"of the run), got {n}"
            )
        amplitude = self.amplitude
        if is_number(amplitude):
            amplitude = scalar_value(amplitude, "probe.amplitude")  # every joint and sinusoid
        elif ndim_of(amplitude) == 2:
            amplitude = matrix_value(amplitude, "probe.amplitude", None, n)
        else:
            amplitude = vector_value(amplitude, "probe.amplitude", None)
        object.__setattr__(self, "amplitude", amplitude)
        object.__setattr__(self, "until", scalar_value(self.until, "probe.until", minimum=0.0))
        object.__setattr__(self, "ramp", scalar_value(self.ramp, "probe.ramp", minimum=0.0))
        if self.phases is not None:
            object.__setattr__(self, "phases", matrix_value(self.phases, "probe.phases", None, n))

    def amplitude_matrix(self, joints: int = 2) -> np.ndarray:
        """Amplitudes as a (joints, k) array (one column per sinusoid)."""
        k = len(self.frequencies)
        amplitude = np.array(self.amplitude, dtype=float)
        if amplitude.ndim == 0:
            return np.full((joints, k), float(amplitude))
        if amplitude.ndim == 1:
            amplitude = np.repeat(amplitude[:, None], k, axis=1)
        return amplitude.reshape(joints, k)

    def phase_matrix(self, joints: int = 2) -> np.ndarray:
        """Phases as a (joints, k) array, with the default filled in."""
        k = len(self.frequencies)
        if self.phases is not None:
            return np.array(self.phases, dtype=float).reshape(joints, k)
        return np.vstack([np.arange(k, dtype=float)] * joints)


CONTROLLER_KINDS = ("adp", "rise", "pd", "optimal")
BASIS_KINDS = ("augmented", "paper", "structured")
#: The basis of a URDF arm (plant.urdf) when controller.basis is left out.
URDF_DEFAULT_BASIS = "structured"
#: Built-in bases that a URDF arm refuses (written for the two-link arm).
URDF_REFUSED_BASES = ("augmented", "paper")
#: The number of functions of each built-in basis (the length of init.critic_weights and
#: actor_weights); an expression basis has one per term (ControllerConfig.basis_size).
BASIS_SIZES = {"augmented": 8, "paper": 8, "structured": 6}
#: Families that expand to terms (adparm.bases): a basis of these runs as an expression basis.
EXPRESSION_FAMILIES = ("quadratic", "polynomial")
IDENTIFIER = re.compile(r"^[A-Za-z_]+$")


@functools.lru_cache(maxsize=64)
def compiled_expression_basis(basis: tuple[str, ...], degree: int | None, joints: int) -> Any:
    """The compiled expression basis of controller.basis (parsed once per distinct basis);
    a ValueError names the field and the term."""
    from . import bases

    names = bases.variable_names(joints)
    known = BASIS_KINDS + EXPRESSION_FAMILIES
    for item in basis:
        name = item.strip()
        if IDENTIFIER.match(name) and name not in known and name not in names:
            raise ValueError(
                f"controller.basis: unknown basis {name!r} (known: {', '.join(known)}, or terms "
                f"such as 'x1^2' in {', '.join(names)})" + did_you_mean(name, known)
            )
    if name_in(basis, "structured"):
        raise ValueError(
            "controller.basis: 'structured' is a basis of its own; it cannot be combined with "
            "terms or families"
        )
    try:
        return bases.ExpressionBasis(list(basis), joints, degree=degree)
    except ValueError as error:
        text = str(error)
        if text.startswith("degree:"):
            raise ValueError(f"controller.{text}") from None
        text = text.removeprefix("basis: ")
        raise ValueError(f"controller.basis: {text}") from None


def name_in(basis: tuple[str, ...], name: str) -> bool:
    return any(item.strip() == name for item in basis)


EXTRAPOLATION_MODES = ("fixed", "grid", "local")
#: The largest controller.degree (adparm.bases.MAX_DEGREE; one joint reaches 128 functions at 22).
MAX_DEGREE = 20


@dataclass(frozen=True)
class ControllerConfig:
    """Which input u the loop applies (tau = h_hat + mu - u, mu the RISE term):
    ``adp`` u = u_hat + probe (the paper; critic and actor learn), ``rise`` u = 0,
    ``pd`` u = -(kp e1 + kd de1), ``optimal`` u = -R^-1 e2 (the exact optimal policy).
    Only adp learns and probes. ``rise = false`` drops the RISE term mu (not with kind rise).
    kp, kd: a number (times I) or a 2 x 2 matrix, used by pd only (our choice 50 and 10).

    basis: the critic/actor basis. ``augmented`` (default) is the paper's 8 functions over the
    augmented state [x; qd] with cos x2 replaced by cos(qd2 - x2) = cos q2: identical to the
    paper's basis while qd2 = 0 (the paper's task), and exact for V* = x^T blockdiag(K, M(q)) x
    with the same W* for any qd(t). ``paper`` is the printed phi(x), exact only for qd2 = 0.
    ``structured`` has 6 functions, [e1_1^2, e1_1 e1_2, e1_2^2, e2^T M_k(q) e2 (k = 1..3)] with
    M(q) = p1 M1 + p2 M2 + p3 M3: exact for any qd(t) with W* = [K11, 2 K12, K22, p1, p2, p3], so
    the critic learns the arm's inertia parameters (docs, "The structured basis").
    ``quadratic`` (every x_i x_j, i <= j: 10 functions), ``polynomial`` with ``degree`` (even,
    >= 2: every monomial of even degree up to it) and a list of terms and families (e.g.
    ``["quadratic", "x3^2*cos(q2)"]``) are expression bases (adparm.bases; docs, "Bases"): parsed
    once, evaluated by the C++ core with exact Jacobians on its dynamic-size loop."""

    kind: str = "adp"
    basis: str | tuple[str, ...] = "augmented"
    degree: int | None = None
    rise: bool = True
    kp: float | Matrix = 50.0
    kd: float | Matrix = 10.0

    def __post_init__(self) -> None:
        choice_value(self.kind, "controller.kind", CONTROLLER_KINDS)
        basis = self.basis
        if isinstance(basis, (list, tuple)):
            if not basis:
                raise ValueError("controller.basis: needs at least one term or family")
            if not all(isinstance(item, str) for item in basis):
                bad = next(item for item in basis if not isinstance(item, str))
                raise ValueError(f"controller.basis: each entry must be a string, got {bad!r}")
            basis = tuple(basis)
        elif not isinstance(basis, str):
            raise ValueError(
                f"controller.basis: expected a basis name or a list of terms, got {basis!r}"
            )
        object.__setattr__(self, "basis", basis)
        if self.degree is not None:
            object.__setattr__(
                self,
                "degree",
                integer_value(self.degree, "controller.degree", minimum=2, maximum=MAX_DEGREE),
            )
            if self.degree % 2:
                raise ValueError(
                    "controller.degree: must be even (a value function has even degree), "
                    f"got {self.degree}"
                )
            if not name_in(self.terms_spec, "polynomial"):
                raise ValueError(
                    "controller.degree: only with the 'polynomial' basis (controller.basis = "
                    f"{plain_value(self.basis)!r})"
                )
        # an expression basis is parsed and checked by Config, for the arm's n joints (errors
        # name the field and the term)
        object.__setattr__(self, "rise", boolean_value(self.rise, "controller.rise"))
        if self.kind == "rise" and not self.rise:
            raise ValueError(
                "controller.rise: kind = 'rise' is the RISE feedback alone, so rise must be true"
            )
        for key in ("kp", "kd"):
            object.__setattr__(self, key, gain_value(getattr(self, key), f"controller.{key}"))

    @property
    def terms_spec(self) -> tuple[str, ...]:
        """controller.basis as a tuple of names and terms."""
        return (self.basis,) if isinstance(self.basis, str) else self.basis

    @property
    def is_expression(self) -> bool:
        """Whether the basis is an expression basis (anything but one built-in basis name)."""
        return not (isinstance(self.basis, str) and self.basis in BASIS_KINDS)

    def expression_basis(self, joints: int = 2) -> Any:
        """The compiled adparm.bases.ExpressionBasis of an expression basis (cached)."""
        if not self.is_expression:
            raise ValueError(f"controller.basis: {self.basis!r} is not an expression basis")
        return compiled_expression_basis(self.terms_spec, self.degree, joints)

    def basis_size(self, joints: int = 2) -> int:
        """The number of basis functions K."""
        if self.is_expression:
            return self.expression_basis(joints).size
        return BASIS_SIZES[self.basis]

    def gain_matrix(self, key: str, joints: int = 2) -> np.ndarray:
        """kp or kd as a (joints x joints) array."""
        value = getattr(self, key)
        return value * np.eye(joints) if isinstance(value, float) else np.array(value)


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
    [-box, box]), ``grid`` (m points per axis, points = m^4) or ``local`` (points redrawn every
    step, uniform in x(t) + [-box, box]). ``box``: half-widths in x = [e1; e2], one number or 4.
    ``seed`` (0 <= seed < 2^32) seeds MT19937, drawn in the order of NumPy's
    ``RandomState(seed).random_sample((points, 4))``."""

    points: int = 0
    box: float | Vector = 1.0
    mode: str = "fixed"
    seed: int = 0

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

    T: float = 150.0
    dt: float | str = 1e-3
    record_every: int = 10
    divergence_bound: float = 1e6

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
        if self.dt == AUTO:
            return
        if self.dt > self.T:
            raise ValueError(f"sim.dt: must be <= sim.T = {self.T:g}, got {self.dt:g}")
        if self.T / self.dt > 1e10:
            raise ValueError(
                f"sim.dt: sim.T / sim.dt = {self.T / self.dt:.3g} steps is more than 1e10"
            )


@dataclass(frozen=True)
class DiagnosticsConfig:
    """What a run's verdict holds it to (adparm.truth.diagnose). ``tolerance``: "ok" needs the
    critic weights, the actor weights and the applied policy (``rms |u_hat - u*| / rms |u*|`` over
    the last 10 % of the run) each within this relative distance of the known optimum; also the
    band of the summary's "time within tolerance". 0 < tolerance < 1; default 1 %."""

    tolerance: float = 0.01

    def __post_init__(self) -> None:
        tolerance = scalar_value(self.tolerance, "diagnostics.tolerance", minimum=0.0, strict=True)
        if tolerance >= 1.0:
            raise ValueError(f"diagnostics.tolerance: must be < 1, got {tolerance:g}")
        object.__setattr__(self, "tolerance", tolerance)


SECTIONS: dict[str, type] = {
    "plant": PlantConfig,
    "model": ModelConfig,
    "task": TaskConfig,
    "cost": CostConfig,
    "control": ControlConfig,
    "critic": CriticConfig,
    "actor": ActorConfig,
    "init": InitConfig,
    "probe": ProbeConfig,
    "controller": ControllerConfig,
    "extrapolation": ExtrapolationConfig,
    "sim": SimConfig,
    "diagnostics": DiagnosticsConfig,
}
