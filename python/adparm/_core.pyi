"""Type stubs for adparm._core, the pybind11 binding of the C++ core (python/src/core_bindings.cpp).

Private: use the adparm package. Eigen members of the settings structs are copied on access, so
assign them whole (``task.q0 = [0.1, 0.2]``); they are returned as float64 arrays. Argument errors
in the core raise ValueError.
"""

from typing import Literal, TypeAlias

import numpy as np
from numpy.typing import ArrayLike, NDArray

_FloatArray: TypeAlias = NDArray[np.float64]

#: Size of the closed loop's state [q (2), dq (2), Wc (8), Wa (8), Gamma (64), nu (2), J (1)].
STATE_SIZE: int

# --- settings -----------------------------------------------------------------------------------

class ArmParameters:
    """Two-link arm constants p1 p2 p3 g1 g2 coulomb viscous."""

    p1: float
    p2: float
    p3: float
    g1: float
    g2: float
    coulomb: float
    viscous: float
    def __init__(self) -> None: ...

class RiseGains:
    """RISE gains ks, alpha2, beta1 (eqs. 27-28)."""

    ks: float
    alpha2: float
    beta1: float
    def __init__(self) -> None: ...

class CriticSettings:
    """eta_c, nu, gamma0, epsilon_T (eqs. 23-24)."""

    eta_c: float
    nu: float
    gamma0: float
    epsilon_T: float
    def __init__(self) -> None: ...

class ActorSettings:
    """eta_a1, eta_a2, weight_bound (eq. 26), positive_e2, e2_margin."""

    eta_a1: float
    eta_a2: float
    weight_bound: float
    positive_e2: bool
    e2_margin: float
    e2_check_positions: np.ndarray
    def __init__(self) -> None: ...

class ProbeSettings:
    """amplitude (2, n), until, ramp, frequencies (n,), phases (2, n)."""

    until: float
    ramp: float
    def __init__(self) -> None: ...
    @property
    def amplitude(self) -> _FloatArray:
        """(2, n) N m"""
    @amplitude.setter
    def amplitude(self, value: ArrayLike) -> None: ...
    @property
    def frequencies(self) -> _FloatArray:
        """(n,) rad/s"""
    @frequencies.setter
    def frequencies(self, value: ArrayLike) -> None: ...
    @property
    def phases(self) -> _FloatArray:
        """(2, n) rad"""
    @phases.setter
    def phases(self, value: ArrayLike) -> None: ...

class TrajectoryKind:
    constant: TrajectoryKind
    sinusoid: TrajectoryKind
    spline: TrajectoryKind

class TrajectorySettings:
    """kind, offset (2,); sinusoid: amplitude, frequency, phase (2, n); spline: breaks (n + 1,),
    coefficients (n, 8)."""

    kind: TrajectoryKind
    offset: _FloatArray
    amplitude: _FloatArray
    frequency: _FloatArray
    phase: _FloatArray
    breaks: _FloatArray
    coefficients: _FloatArray
    def __init__(self) -> None: ...

class TaskSettings:
    """q0 (2,), dq0 (2,), qd (TrajectorySettings)."""

    qd: TrajectorySettings

    def __init__(self) -> None: ...
    @property
    def q0(self) -> _FloatArray: ...
    @q0.setter
    def q0(self, value: ArrayLike) -> None: ...
    @property
    def dq0(self) -> _FloatArray: ...
    @dq0.setter
    def dq0(self, value: ArrayLike) -> None: ...

class ControlSettings:
    """alpha1 (2, 2) and the RISE gains."""

    rise: RiseGains
    def __init__(self) -> None: ...
    @property
    def alpha1(self) -> _FloatArray:
        """(2, 2)"""
    @alpha1.setter
    def alpha1(self, value: ArrayLike) -> None: ...

class ControllerKind:
    adp: ControllerKind
    rise: ControllerKind
    pd: ControllerKind
    optimal: ControllerKind

class ControllerSettings:
    """kind, rise, kp (2, 2), kd (2, 2)."""

    kind: ControllerKind
    rise: bool
    kp: _FloatArray
    kd: _FloatArray
    def __init__(self) -> None: ...

class BasisKind:
    paper: BasisKind
    augmented: BasisKind
    structured: BasisKind
    expression: BasisKind

class ExpressionProgram:
    """The compiled terms of an expression basis (adparm.bases.compile_terms): opcodes and one
    argument per opcode. Copied on access: assign the lists whole."""

    opcodes: list[int]
    arguments: list[float]
    def __init__(self) -> None: ...

class ExtrapolationMode:
    fixed: ExtrapolationMode
    grid: ExtrapolationMode
    local: ExtrapolationMode

class ExtrapolationSettings:
    """points, box (4,), mode, seed."""

    points: int
    box: _FloatArray
    mode: ExtrapolationMode
    seed: int
    def __init__(self) -> None: ...

class SimSettings:
    """T, dt, record_every, divergence_bound."""

    T: float
    dt: float
    record_every: int
    divergence_bound: float
    def __init__(self) -> None: ...

class UrdfArmSettings:
    """A URDF arm of the loop: urdf (path; empty: the two-link arm of ArmParameters), gravity
    (3,), coulomb and viscous (n values, 1 for every joint, or 0: none). Eigen members are copied
    on access: assign them whole."""

    urdf: str
    def __init__(self) -> None: ...
    @property
    def gravity(self) -> _FloatArray:
        """(3,)"""
    @gravity.setter
    def gravity(self, value: ArrayLike) -> None: ...
    @property
    def coulomb(self) -> _FloatArray:
        """(n,), (1,) or (0,)"""
    @coulomb.setter
    def coulomb(self, value: ArrayLike) -> None: ...
    @property
    def viscous(self) -> _FloatArray:
        """(n,), (1,) or (0,)"""
    @viscous.setter
    def viscous(self, value: ArrayLike) -> None: ...
    @property
    def locked_joints(self) -> list[tuple[str, float]]:
        """Joints held at a position: [(name, rad or m), ...]"""
    @locked_joints.setter
    def locked_joints(self, value: list[tuple[str, float]]) -> None: ...

class Settings:
    """All settings of one run. Eigen members are copied on access: assign them whole.
    Q (2n, 2n), R (n, n), disturbance (n,), critic_weights and actor_weights (K,) for n joints
    (2 for the two-link arm) and K basis functions. dynamic_sizes runs the two-link arm through
    the n-joint (dynamic-size) loop, a check of that loop."""

    plant: ArmParameters
    model: ArmParameters
    plant_urdf: UrdfArmSettings  # urdf not empty: a URDF arm (expression basis) replaces plant
    model_urdf: UrdfArmSettings  # its believed model; urdf empty: the plant (an exact model)
    task: TaskSettings
    control: ControlSettings
    critic: CriticSettings
    actor: ActorSettings
    controller: ControllerSettings
    basis: BasisKind
    basis_program: ExpressionProgram  # basis = expression (run on the dynamic-size loop)
    dynamic_sizes: bool
    extrapolation: ExtrapolationSettings
    probe: ProbeSettings
    sim: SimSettings
    def __init__(self) -> None: ...
    @property
    def disturbance(self) -> _FloatArray:
        """(n,)"""
    @disturbance.setter
    def disturbance(self, value: ArrayLike) -> None: ...
    @property
    def Q(self) -> _FloatArray:
        """(2n, 2n)"""
    @Q.setter
    def Q(self, value: ArrayLike) -> None: ...
    @property
    def R(self) -> _FloatArray:
        """(n, n)"""
    @R.setter
    def R(self, value: ArrayLike) -> None: ...
    @property
    def critic_weights(self) -> _FloatArray:
        """(8,)"""
    @critic_weights.setter
    def critic_weights(self, value: ArrayLike) -> None: ...
    @property
    def actor_weights(self) -> _FloatArray:
        """(8,)"""
    @actor_weights.setter
    def actor_weights(self, value: ArrayLike) -> None: ...

def paper_settings() -> Settings:
    """The C++ core's copy of the paper preset."""

# --- arm, basis, HJB ------------------------------------------------------------------------------

def arm_terms(parameters: ArmParameters, q: ArrayLike, dq: ArrayLike) -> dict[str, _FloatArray]:
    """Model terms at q (2,), dq (2,): dict of M, M_inv, C (2, 2) and G, F (2,)."""

def simulate_open_loop(
    parameters: ArmParameters,
    disturbance: ArrayLike,
    initial_state: ArrayLike,
    dt: float,
    steps: int,
    compensate_gravity: bool,
) -> _FloatArray:
    """RK4 of the arm alone under tau = G(q) (or 0) from [q; dq] (4,); rows (steps + 1, 4)."""

class UrdfArm:
    """A fixed-base serial arm from a URDF file, through Pinocchio (cpp/src/pinocchio_arm.cpp).
    gravity (3,), coulomb and viscous: one number or one per joint; locked_joints: joints held at
    a position (Pinocchio's reduced model). A URDF that cannot be read or parsed, without a free
    revolute/continuous/prismatic joint, with a floating or planar joint, or that fails a
    physical check raises ValueError naming the file (and the link); a problem with the locked
    joints (or a free mimic joint) raises ValueError starting "locked_joints: "."""

    def __init__(
        self,
        urdf_path: str,
        gravity: ArrayLike = ...,
        coulomb: float | ArrayLike = 0.0,
        viscous: float | ArrayLike = 0.0,
        locked_joints: list[tuple[str, float]] = ...,
    ) -> None: ...
    @staticmethod
    def from_xml(
        xml: str,
        gravity: ArrayLike = ...,
        coulomb: float | ArrayLike = 0.0,
        viscous: float | ArrayLike = 0.0,
        name: str = "<URDF string>",
        locked_joints: list[tuple[str, float]] = ...,
    ) -> UrdfArm:
        """The same from the URDF's XML text; name stands for the file in error messages."""
    @property
    def dof(self) -> int: ...
    @property
    def source(self) -> str: ...
    @property
    def joint_names(self) -> list[str]: ...
    @property
    def joint_types(self) -> list[str]: ...
    @property
    def locked_joints(self) -> list[tuple[str, float]]: ...
    @property
    def gravity(self) -> _FloatArray: ...
    @property
    def coulomb(self) -> _FloatArray: ...
    @property
    def viscous(self) -> _FloatArray: ...
    @property
    def limits(self) -> dict[str, _FloatArray]:
        """lower, upper (+-inf for a continuous joint), velocity, effort (n,)."""
    @property
    def inertial_parameters(self) -> _FloatArray:
        """pi (10 n,): per joint m, m c (3), I about the joint origin (xx, xy, yy, xz, yz, zz)."""
    def terms(self, q: ArrayLike, dq: ArrayLike) -> dict[str, _FloatArray]:
        """Model terms at q (n,), dq (n,): dict of M, M_inv, C (n, n) and G, F (n,)."""
    def mass_regressor(self, q: ArrayLike) -> _FloatArray:
        """M_k(q) for the inertial parameters, side by side: (n, n * 10 n), M_k in columns
        [k n, (k + 1) n)."""
    @property
    def inertial_parameter_names(self) -> list[str]:
        """ "m link1", "mc_x link1", ..., "I_zz linkn" (10 n)."""
    def base_parameters(
        self, samples: int = 100, seed: int = 0, tolerance: float = 1e-9
    ) -> tuple[_FloatArray, list[int], _FloatArray]:
        """(values (r,), columns (r,), combination (r, 10 n)): the base inertial parameters."""

class UrdfStructuredBasis:
    """The structured basis of a URDF arm: [e1_i e1_j (i <= j); e2^T M_b(q) e2 per base
    inertial parameter b] (pinocchio_structured_basis.hpp)."""

    def __init__(self, arm: UrdfArm) -> None: ...
    @property
    def size(self) -> int: ...
    @property
    def joints(self) -> int: ...
    @property
    def names(self) -> list[str]: ...
    @property
    def base_parameters(self) -> tuple[_FloatArray, list[int], _FloatArray]: ...
    def optimal_weights(
        self, K: ArrayLike, inertial_parameters: ArrayLike | None = None
    ) -> _FloatArray:
        """W* = [K_ii on squares, K_ij + K_ji on cross terms; base parameters] for K (n, n); the
        base parameters of inertial_parameters (10 n) of an arm of the same kinematics if
        given."""
    def evaluate_rows(
        self, x: ArrayLike, qd: ArrayLike, dqd: ArrayLike
    ) -> tuple[_FloatArray, _FloatArray, _FloatArray]:
        """At rows x (m, 2n), qd (m, n), dqd (m, n): phi (m, N), d phi / dx (m, N, 2n) and
        (d phi / d qd) dqd (m, N)."""

def desired_state(trajectory: TrajectorySettings, t: ArrayLike) -> _FloatArray:
    """The desired state of n joints at times t (m,): rows [qd (n), dqd (n), ddqd (n)]
    (m, 3 n)."""

def basis(
    kind: BasisKind, x: ArrayLike, qd: ArrayLike, dqd: ArrayLike
) -> tuple[_FloatArray, _FloatArray, _FloatArray]:
    """A basis of K functions at x (4,) and desired qd, dqd (2,): phi (K,), d phi / dx (K, 4)
    and (d phi / d qd) dqd (K,)."""

class ExpressionOp:
    """Opcodes of an ExpressionBasis program (cpp/include/adparm/expression_basis.hpp)."""

    constant: ExpressionOp
    variable: ExpressionOp
    add: ExpressionOp
    subtract: ExpressionOp
    multiply: ExpressionOp
    negate: ExpressionOp
    power: ExpressionOp
    sin: ExpressionOp
    cos: ExpressionOp
    tan: ExpressionOp
    exp: ExpressionOp
    log: ExpressionOp
    sqrt: ExpressionOp
    tanh: ExpressionOp
    store: ExpressionOp
    def __int__(self) -> int: ...

class ExpressionBasis:
    """A basis compiled from a postfix program over z = [x (2n); qd (n)]
    (cpp/include/adparm/expression_basis.hpp)."""

    def __init__(self, joints: int, opcodes: list[int], arguments: list[float]) -> None: ...
    def __len__(self) -> int: ...
    @property
    def size(self) -> int: ...
    @property
    def joints(self) -> int: ...
    @property
    def state_dim(self) -> int: ...
    @property
    def stack_depth(self) -> int: ...
    def evaluate(
        self, x: ArrayLike, qd: ArrayLike, dqd: ArrayLike
    ) -> tuple[_FloatArray, _FloatArray, _FloatArray, _FloatArray]:
        """At x (2n,), qd (n,), dqd (n,): phi (N,), d phi / dx (N, 2n), (d phi / d qd) dqd (N,)
        and d phi / d qd (N, n)."""
    def evaluate_rows(
        self, x: ArrayLike, qd: ArrayLike, dqd: ArrayLike
    ) -> tuple[_FloatArray, _FloatArray, _FloatArray]:
        """Row by row, x (m, 2n), qd and dqd (m, n): phi (m, N), d phi / dx (m, N, 2n) and
        (d phi / d qd) dqd (m, N)."""

def hjb_residual(
    settings: Settings,
    x: ArrayLike,
    critic_weights: ArrayLike,
    actor_weights: ArrayLike,
    t: float,
) -> _FloatArray:
    """HJB error of eq. (21) at each row of x (m, 2n) for weights (K,), with the desired state at
    time t; returns (m,)."""

# --- closed loop ----------------------------------------------------------------------------------

def closed_loop_derivative(
    settings: Settings, t: float, state: ArrayLike
) -> tuple[_FloatArray, dict[str, _FloatArray | float]]:
    """Right-hand side at t of state (87,) = [q, dq, Wc (8), Wa (8), Gamma (64, column-major),
    nu (2), J]; local extrapolation points are drawn around this state first. Returns
    (rate (87,), outputs dict of qd, e1, e2, tau, u, u_hat, mu, probe (2,) and hjb_error
    (float))."""

def initial_state(settings: Settings) -> _FloatArray:
    """The closed loop's initial state (87,)."""

def extrapolation_points(settings: Settings) -> _FloatArray:
    """The fixed or grid extrapolation points (N, 2n) in x (zeros for mode local)."""

class Simulation:
    """The closed-loop run (basis from settings.basis); advance(n) takes up to n RK4 steps."""

    def __init__(self, settings: Settings) -> None: ...
    def advance(self, max_steps: int) -> int:
        """Take at most max_steps steps (GIL released); returns the number taken."""
    @property
    def status(self) -> Literal["running", "finished", "diverged"]: ...
    @property
    def steps(self) -> int:
        """Total number of steps of the run."""
    @property
    def step(self) -> int:
        """Steps taken so far."""
    @property
    def divergence_time(self) -> float:
        """Time of divergence (s), NaN unless status is "diverged"."""
    @property
    def reset_times(self) -> list[float]:
        """Times (s) of the covariance resets so far."""
    @property
    def state(self) -> _FloatArray:
        """Current closed-loop state (87,); after divergence, the last finite state (that of
        the last recorded row), while ``step`` counts the diverging step too."""
    def recording(self) -> dict[str, _FloatArray]:
        """Recorded rows so far: dict of arrays t, hjb_error, cost (n,), q ... (n, 2),
        weights (n, 8)."""

class Batch:
    """Independent runs on a pool of C++ worker threads that take runs from a shared queue and
    run each to its end (no barrier between threads); the caller polls with wait() and takes
    each run as it ends. Not for use from several Python threads at once."""

    def __init__(self, settings: list[Settings]) -> None:
        """Checks every run's settings (ValueError naming settings[i])."""
    def __len__(self) -> int: ...
    def start(self, threads: int, window: int = ...) -> None:
        """Start min(threads, len) workers; at most `window` runs are built and not yet
        taken at any time."""
    def wait(self, seconds: float) -> list[int]:
        """Wait up to `seconds` (GIL released) for a run to end; the indices of the runs that
        ended since the last call. Re-raises an error a worker met."""
    @property
    def done(self) -> bool:
        """Every run ended (or the batch was stopped) and every ending was reported."""
    def stop(self) -> None:
        """Stop every worker within one step of its run and join them (GIL released)."""
    @property
    def steps_done(self) -> int:
        """Steps taken so far by all runs (readable while the workers run)."""
    @property
    def total_steps(self) -> int: ...
    def take(self, index: int) -> Simulation:
        """Hand run `index` over: ended, stopped part-way, or built now if it never started
        (RuntimeError if it is still running or already taken)."""
    def seconds(self, index: int) -> float:
        """Wall time spent building and advancing run `index`, s."""
