"""The sections of the configuration that set the controller: [cost], [control], [critic],
[actor], [init], [probe], [controller], and SECTIONS, every section's class by its TOML name
(with those of adparm._arm_sections and adparm._run_sections)."""

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
    integer_value,
    is_number,
    matrix_value,
    ndim_of,
    scalar_value,
    setting,
    square_matrix,
    symmetric_positive_definite,
    vector_value,
)
from ._run_sections import DiagnosticsConfig, ExtrapolationConfig, IdentifierConfig, SimConfig

PAPER_Q: Matrix = (
    (40.0, 2.0, -4.0, 4.0),
    (2.0, 40.0, 4.0, -6.0),
    (-4.0, 4.0, 4.0, 0.0),
    (4.0, -6.0, 0.0, 4.0),
)


@dataclass(frozen=True)
class CostConfig:
    """r(x, u) = x^T Q x + u^T R u (eqs. 10-11); Q (4x4) and R (2x2) symmetric positive definite.

    With ``input_bound`` (not in the paper) u^T R u becomes the constrained-input cost U(u) and,
    with ``e2_cost = "logcosh"``, the e2 block of x^T Q x its ln cosh form
    (:doc:`/guide/constrained-input`)."""

    Q: Matrix = setting(
        PAPER_Q,
        "4 x 4 state weight of r = x^T Q x + u^T R u (eqs. 10-11), symmetric positive definite.",
        core="Q",
    )
    R: Matrix = setting(
        ((0.25, 0.0), (0.0, 0.25)),
        "2 x 2 input weight, symmetric positive definite (diagonal with ``input_bound``).",
        core="R",
    )
    input_bound: float | Vector | str | None = setting(
        None,
        "Bound lambda on the ADP input, ``|u_i| <= lambda_i`` (one number or one per joint, > 0; "
        "not in the paper): the input cost becomes U(u) = sum_i R_i [2 lambda_i u_i "
        "atanh(u_i / lambda_i) + lambda_i^2 ln(1 - u_i^2 / lambda_i^2)] and the policy "
        "u = -lambda tanh(D) (Abu-Khalaf & Lewis 2005; :doc:`/guide/constrained-input`). "
        'Needs a diagonal R. ``"auto"``: derived from ``plant.torque_limits``, lambda_i = '
        "(limit_i - max ``|h_i|`` over the desired trajectory - the disturbance's and the probe's "
        "amplitudes) / 2, a "
        "conservative heuristic (:doc:`/guide/constrained-input`). Left out: the quadratic "
        "u^T R u.",
        via="input_bound, one per joint (CostConfig.bound_vector)",
    )
    e2_cost: str = setting(
        "quadratic",
        "``quadratic`` (e2^T Q22 e2) or ``logcosh``: sum_i 2 lambda_i^2 R_i "
        "ln cosh(s_i e2_i / (R_i lambda_i)), s_i = sqrt(Q22_ii R_i), equal to e2^T Q22 e2 for "
        "small e2 and, with Q22 = s^2 R^-1, the cost for which V* = e1^T K e1 + s e2^T M(q) e2 "
        "solves the constrained HJB exactly (adparm.saturated_cost). ``logcosh`` needs "
        "``input_bound`` and a diagonal Q22.",
        via="e2_cost, an enum (E2Cost)",
    )

    def __post_init__(self) -> None:
        object.__setattr__(self, "Q", square_matrix(self.Q, "cost.Q"))
        object.__setattr__(self, "R", square_matrix(self.R, "cost.R"))
        object.__setattr__(self, "Q", symmetric_positive_definite(self.Q, "cost.Q"))
        object.__setattr__(self, "R", symmetric_positive_definite(self.R, "cost.R"))
        object.__setattr__(
            self, "e2_cost", choice_value(self.e2_cost, "cost.e2_cost", ("quadratic", "logcosh"))
        )
        if self.input_bound is None:
            if self.e2_cost == "logcosh":
                raise ValueError('cost.e2_cost: "logcosh" needs cost.input_bound')
            return
        if isinstance(self.input_bound, str):
            if self.input_bound != AUTO:
                raise ValueError(
                    f'cost.input_bound: expected a number > 0, one per joint, or "auto", got '
                    f"{self.input_bound!r}"
                )
            bound: float | Vector | str = AUTO  # adparm.Config resolves it
        elif is_number(self.input_bound):
            bound = scalar_value(self.input_bound, "cost.input_bound", minimum=0.0, strict=True)
        else:
            bound = vector_value(self.input_bound, "cost.input_bound", None)
            if min(bound) <= 0.0:
                raise ValueError(f"cost.input_bound: every bound must be > 0, got {list(bound)}")
        object.__setattr__(self, "input_bound", bound)
        R = np.array(self.R)
        if np.any(R != np.diag(np.diag(R))):
            raise ValueError(
                f"cost.R: must be diagonal with cost.input_bound (the bounded input cost is a sum "
                f"over the joints), got {R.tolist()}"
            )
        if self.e2_cost == "logcosh":
            n = len(self.R)
            Q22 = np.array(self.Q)[n:, n:]
            if np.any(Q22 != np.diag(np.diag(Q22))):
                raise ValueError(
                    'cost.Q: its e2 block Q22 must be diagonal with cost.e2_cost = "logcosh" '
                    f"(the ln cosh cost is a sum over the joints), got {Q22.tolist()}"
                )

    def bound_vector(self, joints: int = 2) -> np.ndarray:
        """lambda, one per joint; empty without an input bound."""
        if self.input_bound is None:
            return np.zeros(0)
        if self.input_bound == AUTO:
            raise ValueError(
                'cost.input_bound: "auto" is resolved by adparm.Config (from plant.torque_limits); '
                "this section was not"
            )
        return np.broadcast_to(np.array(self.input_bound, dtype=float), (joints,)).copy()


@dataclass(frozen=True)
class ControlConfig:
    """alpha1 of eq. (7) (the paper's "alpha") and the RISE gains of eqs. (27)-(28).

    -alpha1 must be Hurwitz (every eigenvalue of alpha1 with a positive real part), else the
    error e1 of de1 = -alpha1 e1 + e2 grows; the conditions of the analytic optimum (Q > 0) imply
    it.

    The paper prints no RISE gains. Defaults: ks = 10, alpha2 = 1, beta1 = 0.5, which satisfies
    condition (29) for the paper's disturbance (``|tau_d| <= 0.1``, ``|dtau_d/dt| <= 0.1``, so
    zeta1 + zeta2 / alpha2 = 0.2 < 0.5)."""

    alpha1: Matrix = setting(
        ((15.6, 10.6), (10.6, 10.4)),
        "Gain in e2 = de1 + alpha1 e1 (the paper's alpha); -alpha1 must be Hurwitz.",
        core="control.alpha1",
    )
    ks: float = setting(
        10.0,
        "RISE gain (eqs. 27-28); the feedback acts with ks + 1, so ks > -1 (the paper's proofs "
        "take ks >= 0: below 0 is a deviation, for arms so light that a gain of 1 is stiff; "
        "see :doc:`/guide/urdf-arms`). Not printed in the paper.",
        core="control.rise.ks",
    )
    alpha2: float = setting(1.0, "RISE gain. Not printed in the paper.", core="control.rise.alpha2")
    beta1: float = setting(
        0.5,
        "RISE gain; condition (29) bounds it from below (0.1 + 0.1/alpha2 = 0.2 < 0.5 here).",
        core="control.rise.beta1",
    )
    anti_windup: bool = setting(
        True,
        "Not in the paper: while a joint's torque is clipped at its limit "
        "(``plant.torque_limits``), RISE's integral nu stops integrating in the direction that "
        "pushes the torque further into the limit (conditional integration); false lets it wind "
        "up. Does nothing without limits. See :doc:`/guide/torque-limits`.",
        core="control.anti_windup",
    )

    def __post_init__(self) -> None:
        object.__setattr__(self, "alpha1", square_matrix(self.alpha1, "control.alpha1"))
        check_hurwitz(self.alpha1, "control.alpha1")
        # ks > -1, not >= 0 as in the paper: only the gain ks + 1 (> 0) enters eqs. (27)-(28)
        object.__setattr__(
            self, "ks", scalar_value(self.ks, "control.ks", minimum=-1.0, strict=True)
        )
        for key in ("alpha2", "beta1"):
            object.__setattr__(
                self, key, scalar_value(getattr(self, key), f"control.{key}", minimum=0.0)
            )
        object.__setattr__(
            self, "anti_windup", boolean_value(self.anti_windup, "control.anti_windup")
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

    eta_c: float = setting(800.0, "Critic gain (eq. 23).", core="critic.eta_c")
    nu: float = setting(
        1.0, "Normalisation 1 + nu omega^T Gamma omega (eq. 24, corrected).", core="critic.nu"
    )
    gamma0: float = setting(
        100.0, "Gamma(0) = gamma0 I; Gamma is reset to this value.", core="critic.gamma0"
    )
    epsilon_T: float | None = setting(
        None,
        "Reset Gamma when its smallest eigenvalue falls below epsilon_T (< gamma0). See "
        ":doc:`/paper`.",
        via="critic.epsilon_T, resolved (Config.resolved_epsilon_T)",
    )

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

    eta_a1: float = setting(
        0.01, "Actor gain on the HJB-error gradient (eq. 26).", core="actor.eta_a1"
    )
    eta_a2: float = setting(1.0, "Actor gain pulling Wa towards Wc (eq. 26).", core="actor.eta_a2")
    weight_bound: float = setting(
        100.0,
        "The projection keeps ||Wa|| <= weight_bound (the paper's proj{} has no printed bound).",
        core="actor.weight_bound",
    )
    positive_e2: bool = setting(
        True,
        "Not in the paper: the projection also keeps the e2 block of the actor's (and critic's) "
        "value positive definite at cos q2 = +-1 (the structured basis of a URDF arm: at qd(0), "
        "q(0) and the joint positions of the extrapolation box), which keeps learning away from "
        "the anti-stabilising HJB solution (see the truth guide).",
        core="actor.positive_e2",
    )
    e2_margin: float = setting(
        0.01,
        "The smallest eigenvalue the e2 block keeps when positive_e2 is on (units of M).",
        core="actor.e2_margin",
    )

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

    critic_weights: Vector | None = setting(
        None,
        "Wc(0), in the order of ``adparm.basis_names(config)``. Zero is inadmissible "
        "(:doc:`/paper`).",
        via="critic_weights, resolved (Config.initial_weights)",
    )
    actor_weights: Vector | None = setting(
        None,
        "Wa(0); it must stabilise the model.",
        via="actor_weights, resolved (Config.initial_weights)",
    )

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

    amplitude: Vector | Matrix = setting(
        (71.0, 23.0),
        "Probing torque probe_j = ramp(t) sum_k amplitude_jk sin(frequencies_k t + phases_jk), N "
        "m: one number (both joints), a pair (per joint) or a 2 x n matrix (per joint and "
        "sinusoid). See :doc:`/paper` (excitation).",
        via="probe.amplitude, a joints x k matrix (amplitude_matrix)",
    )
    until: float = setting(
        100.0, "Probing stops at this time (s); 0 turns it off.", core="probe.until"
    )
    ramp: float = setting(
        0.0, "Linear fade-in time (s); 0 starts at full amplitude.", core="probe.ramp"
    )
    frequencies: Vector = setting(
        (1.0, 2.7, 5.3, 9.1), "rad/s, one per sinusoid.", core="probe.frequencies"
    )
    # None: phase k rad for sinusoid k, on both joints
    phases: Matrix | None = setting(
        None,
        "2 x n (rad). Equal phases on both joints keep each sinusoid along one torque direction.",
        via="probe.phases, a joints x k matrix (phase_matrix)",
    )

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


#: The largest controller.degree (adparm.bases.MAX_DEGREE; one joint reaches 128 functions at 22).
MAX_DEGREE = 20


@dataclass(frozen=True)
class ControllerConfig:
    """Which input u the loop applies (tau = h_hat + mu - u, mu the RISE term):
    ``adp`` u = u_hat + probe (the paper; critic and actor learn), ``rise`` u = 0,
    ``pd`` u = -(kp e1 + kd de1), ``optimal`` u = -R^-1 e2 (the exact optimal policy).
    Only adp learns and probes. ``rise = false`` drops the RISE term mu (not with kind rise).
    kp, kd: a number (times I) or an n x n matrix, pd only (two-link 50, 10; URDF: derived).

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

    kind: str = setting(
        "adp",
        "``adp`` (u = u_hat + probe; learns), ``rise`` (u = 0), ``pd`` (u = -(kp e1 + kd de1)) or "
        "``optimal`` (u* = -R^-1 e2). See :doc:`/guide/baselines`.",
        via="controller.kind, an enum (ControllerKind)",
    )
    basis: str | tuple[str, ...] = setting(
        "augmented",
        "``augmented`` (the paper's functions with cos q2 = cos(qd2 - x2), exact for any qd), "
        "``paper`` (the printed phi(x)), ``structured`` (e1 monomials and e2^T M_k(q) e2, "
        ":doc:`/guide/structured-basis`), ``quadratic``, ``polynomial`` (with ``degree``), or a "
        'list of terms and families such as ``["quadratic", "x3^2*cos(q2)"]`` '
        "(:doc:`/guide/bases`). See also :doc:`/guide/tracking`. A URDF arm takes its own "
        "``structured`` basis by default (e1 products and e2^T M_b(q) e2 per base inertial "
        "parameter, :doc:`/guide/urdf-arms`) and refuses ``paper`` and ``augmented``.",
        via="basis and basis_program (basis_family)",
    )
    degree: int | None = setting(
        None,
        "The highest (even) degree of the ``polynomial`` basis; only with ``basis = "
        '"polynomial"``.',
        via="basis_program (basis_family)",
    )
    rise: bool = setting(
        True,
        'Add the RISE term mu (eqs. 27-28); must be true with ``kind = "rise"``.',
        core="controller.rise",
    )
    kp: float | Matrix = setting(
        50.0,
        "PD gain (a number times I, or n x n), ``pd`` only; a URDF arm's: 5 kd (derived).",
        via="controller.kp, a matrix (gain_matrix)",
    )
    kd: float | Matrix = setting(
        10.0, "PD gain on de1, ``pd`` only; URDF: diag(10 M_ii(qd))", via="controller.kd, matrix"
    )

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
    "identifier": IdentifierConfig,
    "sim": SimConfig,
    "diagnostics": DiagnosticsConfig,
}
