"""
adparm's C++ core (private; use the adparm package).
"""
from __future__ import annotations
import collections.abc
import numpy
import numpy.typing
import typing
__all__: list = ['ArmParameters', 'RiseGains', 'CriticSettings', 'ActorSettings', 'ProbeSettings', 'TrajectoryKind', 'TrajectorySettings', 'TaskSettings', 'ControlSettings', 'ControllerKind', 'ControllerSettings', 'E2Cost', 'BasisKind', 'ExpressionProgram', 'ExtrapolationMode', 'ExtrapolationSettings', 'IdentifierSettings', 'SimSettings', 'UrdfArmSettings', 'Settings', 'paper_settings', 'arm_terms', 'two_link_regressors', 'simulate_open_loop', 'urdf_parse_count', 'UrdfArm', 'UrdfStructuredBasis', 'desired_state', 'basis', 'ExpressionOp', 'ExpressionBasis', 'hjb_residual', 'hjb_evaluation', 'STATE_SIZE', 'closed_loop_derivative', 'initial_state', 'extrapolation_points', 'RECORDED_SERIES', 'Simulation', 'Batch']
class ArmParameters:
    """
    Two-link arm constants p1 p2 p3 g1 g2 coulomb viscous.
    """
    def __init__(self) -> None:
        ...
    @property
    def coulomb(self) -> float:
        ...
    @coulomb.setter
    def coulomb(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def g1(self) -> float:
        ...
    @g1.setter
    def g1(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def g2(self) -> float:
        ...
    @g2.setter
    def g2(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def p1(self) -> float:
        ...
    @p1.setter
    def p1(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def p2(self) -> float:
        ...
    @p2.setter
    def p2(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def p3(self) -> float:
        ...
    @p3.setter
    def p3(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def viscous(self) -> float:
        ...
    @viscous.setter
    def viscous(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class RiseGains:
    """
    RISE gains ks, alpha2, beta1 (eqs. 27-28).
    """
    def __init__(self) -> None:
        ...
    @property
    def alpha2(self) -> float:
        ...
    @alpha2.setter
    def alpha2(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def beta1(self) -> float:
        ...
    @beta1.setter
    def beta1(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def ks(self) -> float:
        ...
    @ks.setter
    def ks(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class CriticSettings:
    """
    eta_c, nu, gamma0, epsilon_T (eqs. 23-24).
    """
    def __init__(self) -> None:
        ...
    @property
    def epsilon_T(self) -> float:
        ...
    @epsilon_T.setter
    def epsilon_T(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def eta_c(self) -> float:
        ...
    @eta_c.setter
    def eta_c(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def gamma0(self) -> float:
        ...
    @gamma0.setter
    def gamma0(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def nu(self) -> float:
        ...
    @nu.setter
    def nu(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class ActorSettings:
    """
    eta_a1, eta_a2, weight_bound (eq. 26), positive_e2, e2_margin.
    """
    positive_e2: bool
    def __init__(self) -> None:
        ...
    @property
    def e2_check_positions(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @e2_check_positions.setter
    def e2_check_positions(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> None:
        ...
    @property
    def e2_margin(self) -> float:
        ...
    @e2_margin.setter
    def e2_margin(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def eta_a1(self) -> float:
        ...
    @eta_a1.setter
    def eta_a1(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def eta_a2(self) -> float:
        ...
    @eta_a2.setter
    def eta_a2(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def weight_bound(self) -> float:
        ...
    @weight_bound.setter
    def weight_bound(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class ProbeSettings:
    """
    amplitude (n, k), until, ramp, frequencies (k,), phases (n, k) for n joints and k sinusoids.
    """
    def __init__(self) -> None:
        ...
    @property
    def amplitude(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @amplitude.setter
    def amplitude(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> None:
        ...
    @property
    def frequencies(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @frequencies.setter
    def frequencies(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def phases(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @phases.setter
    def phases(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> None:
        ...
    @property
    def ramp(self) -> float:
        ...
    @ramp.setter
    def ramp(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def until(self) -> float:
        ...
    @until.setter
    def until(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class TrajectoryKind:
    """
    Members:
    
      constant
    
      sinusoid
    
      spline
    """
    __members__: typing.ClassVar[dict[str, TrajectoryKind]]
    constant: typing.ClassVar[TrajectoryKind]
    sinusoid: typing.ClassVar[TrajectoryKind]
    spline: typing.ClassVar[TrajectoryKind]
    @typing.overload
    def __eq__(self, other: TrajectoryKind) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: TrajectoryKind) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class TrajectorySettings:
    """
    kind, offset (n,); sinusoid: amplitude, frequency, phase (n, k); spline: breaks (m + 1,), coefficients (m, 4 n).
    """
    kind: TrajectoryKind
    def __init__(self) -> None:
        ...
    @property
    def amplitude(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @amplitude.setter
    def amplitude(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> None:
        ...
    @property
    def breaks(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @breaks.setter
    def breaks(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def coefficients(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @coefficients.setter
    def coefficients(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> None:
        ...
    @property
    def frequency(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @frequency.setter
    def frequency(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> None:
        ...
    @property
    def offset(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @offset.setter
    def offset(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def phase(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @phase.setter
    def phase(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> None:
        ...
class TaskSettings:
    """
    q0 (n,), dq0 (n,), qd (TrajectorySettings).
    """
    qd: TrajectorySettings
    def __init__(self) -> None:
        ...
    @property
    def dq0(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @dq0.setter
    def dq0(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def q0(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @q0.setter
    def q0(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
class ControlSettings:
    """
    alpha1 (n, n), the RISE gains and anti_windup.
    """
    anti_windup: bool
    rise: RiseGains
    def __init__(self) -> None:
        ...
    @property
    def alpha1(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @alpha1.setter
    def alpha1(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> None:
        ...
class ControllerKind:
    """
    Members:
    
      adp
    
      rise
    
      pd
    
      optimal
    """
    __members__: typing.ClassVar[dict[str, ControllerKind]]
    adp: typing.ClassVar[ControllerKind]
    optimal: typing.ClassVar[ControllerKind]
    pd: typing.ClassVar[ControllerKind]
    rise: typing.ClassVar[ControllerKind]
    @typing.overload
    def __eq__(self, other: ControllerKind) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: ControllerKind) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class ControllerSettings:
    """
    kind, rise, kp (n, n), kd (n, n).
    """
    kind: ControllerKind
    rise: bool
    def __init__(self) -> None:
        ...
    @property
    def kd(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @kd.setter
    def kd(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> None:
        ...
    @property
    def kp(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @kp.setter
    def kp(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> None:
        ...
class E2Cost:
    """
    Members:
    
      quadratic
    
      logcosh
    """
    __members__: typing.ClassVar[dict[str, E2Cost]]
    logcosh: typing.ClassVar[E2Cost]
    quadratic: typing.ClassVar[E2Cost]
    @typing.overload
    def __eq__(self, other: E2Cost) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: E2Cost) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class BasisKind:
    """
    Members:
    
      paper
    
      augmented
    
      structured
    
      expression
    """
    __members__: typing.ClassVar[dict[str, BasisKind]]
    augmented: typing.ClassVar[BasisKind]
    expression: typing.ClassVar[BasisKind]
    paper: typing.ClassVar[BasisKind]
    structured: typing.ClassVar[BasisKind]
    @typing.overload
    def __eq__(self, other: BasisKind) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: BasisKind) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class ExpressionProgram:
    """
    The compiled terms of an expression basis: opcodes and one argument per opcode (adparm.bases.compile_terms).
    """
    def __init__(self) -> None:
        ...
    @property
    def arguments(self) -> list[float]:
        ...
    @arguments.setter
    def arguments(self, arg0: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex]) -> None:
        ...
    @property
    def opcodes(self) -> list[int]:
        ...
    @opcodes.setter
    def opcodes(self, arg0: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex]) -> None:
        ...
class ExtrapolationMode:
    """
    Members:
    
      fixed
    
      grid
    
      local
    """
    __members__: typing.ClassVar[dict[str, ExtrapolationMode]]
    fixed: typing.ClassVar[ExtrapolationMode]
    grid: typing.ClassVar[ExtrapolationMode]
    local: typing.ClassVar[ExtrapolationMode]
    @typing.overload
    def __eq__(self, other: ExtrapolationMode) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: ExtrapolationMode) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class ExtrapolationSettings:
    """
    points, box (2 n,), centre (2 n,; empty: 0), mode, seed.
    """
    mode: ExtrapolationMode
    def __init__(self) -> None:
        ...
    @property
    def box(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @box.setter
    def box(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def centre(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @centre.setter
    def centre(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def points(self) -> int:
        ...
    @points.setter
    def points(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def seed(self) -> int:
        ...
    @seed.setter
    def seed(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class IdentifierSettings:
    """
    The online identifier of beta (identifier.hpp): enabled, gain, gradient_term, concurrent_gain, history_size, window, singular_value_threshold, max_uncertainty, inertia, gravity, friction, stop_probe, tolerance.
    """
    enabled: bool
    friction: bool
    gradient_term: bool
    gravity: bool
    inertia: bool
    stop_probe: bool
    def __init__(self) -> None:
        ...
    @property
    def concurrent_gain(self) -> float:
        ...
    @concurrent_gain.setter
    def concurrent_gain(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def gain(self) -> float:
        ...
    @gain.setter
    def gain(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def history_size(self) -> int:
        ...
    @history_size.setter
    def history_size(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def max_uncertainty(self) -> float:
        ...
    @max_uncertainty.setter
    def max_uncertainty(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def singular_value_threshold(self) -> float:
        ...
    @singular_value_threshold.setter
    def singular_value_threshold(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def tolerance(self) -> float:
        ...
    @tolerance.setter
    def tolerance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def window(self) -> float:
        ...
    @window.setter
    def window(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class SimSettings:
    """
    T, dt, record_every, divergence_bound.
    """
    def __init__(self) -> None:
        ...
    @property
    def T(self) -> float:
        ...
    @T.setter
    def T(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def divergence_bound(self) -> float:
        ...
    @divergence_bound.setter
    def divergence_bound(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def dt(self) -> float:
        ...
    @dt.setter
    def dt(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def record_every(self) -> int:
        ...
    @record_every.setter
    def record_every(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class UrdfArmSettings:
    """
    A URDF arm of the loop: urdf (path; empty: the two-link arm), gravity (3,), coulomb and viscous (n, 1 or 0 values), locked_joints ([(name, position), ...]), inertia_scale (every link's mass and inertia times it: M, C and G times it; 1: as the URDF).
    """
    urdf: str
    def __init__(self) -> None:
        ...
    @property
    def coulomb(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @coulomb.setter
    def coulomb(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def gravity(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]:
        ...
    @gravity.setter
    def gravity(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"]) -> None:
        ...
    @property
    def inertia_scale(self) -> float:
        ...
    @inertia_scale.setter
    def inertia_scale(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def locked_joints(self) -> list[tuple[str, float]]:
        ...
    @locked_joints.setter
    def locked_joints(self, arg0: collections.abc.Sequence[tuple[str, typing.SupportsFloat | typing.SupportsIndex]]) -> None:
        ...
    @property
    def viscous(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @viscous.setter
    def viscous(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
class Settings:
    """
    All settings of one run. Eigen members and the arms (plant, model, plant_urdf, model_urdf) are copied on access: assign them whole. Q (2 n, 2 n), R (n, n), disturbance (n,), torque_limits (n, or empty: none), critic_weights and actor_weights (K,); n = 2 joints for the two-link arm, K the basis size. dynamic_sizes runs the two-link arm through the n-joint (dynamic-size) loop.
    """
    actor: ActorSettings
    basis: BasisKind
    basis_program: ExpressionProgram
    control: ControlSettings
    controller: ControllerSettings
    critic: CriticSettings
    dynamic_sizes: bool
    e2_cost: E2Cost
    extrapolation: ExtrapolationSettings
    identifier: IdentifierSettings
    probe: ProbeSettings
    sim: SimSettings
    task: TaskSettings
    def __init__(self) -> None:
        ...
    @property
    def Q(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @Q.setter
    def Q(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> None:
        ...
    @property
    def R(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        ...
    @R.setter
    def R(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> None:
        ...
    @property
    def actor_weights(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @actor_weights.setter
    def actor_weights(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def critic_weights(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @critic_weights.setter
    def critic_weights(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def disturbance(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @disturbance.setter
    def disturbance(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def input_bound(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @input_bound.setter
    def input_bound(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
    @property
    def is_urdf(self) -> bool:
        """
        Whether the arm is a URDF arm (plant_urdf) rather than the two-link arm.
        """
    @property
    def model(self) -> typing.Any:
        """
        The parameters of the two-link arm the controller believes.
        """
    @model.setter
    def model(self, arg1: ArmParameters) -> None:
        ...
    @property
    def model_urdf(self) -> typing.Any:
        """
        The URDF arm's believed model (urdf empty: the plant, an exact model); assign plant_urdf first.
        """
    @model_urdf.setter
    def model_urdf(self, arg1: UrdfArmSettings) -> None:
        ...
    @property
    def plant(self) -> typing.Any:
        """
        The two-link arm's parameters (the default arm; assigning plant_urdf makes the arm a URDF arm, whose plant and model are default ArmParameters here).
        """
    @plant.setter
    def plant(self, arg1: ArmParameters) -> None:
        ...
    @property
    def plant_urdf(self) -> typing.Any:
        """
        A URDF plant: assigning one with a path makes the arm a URDF arm (one with an empty path, the two-link arm); urdf empty when the arm is the two-link arm.
        """
    @plant_urdf.setter
    def plant_urdf(self, arg1: UrdfArmSettings) -> None:
        ...
    @property
    def torque_limits(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @torque_limits.setter
    def torque_limits(self, arg0: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> None:
        ...
class UrdfArm:
    """
    A fixed-base serial arm from a URDF file, through Pinocchio. gravity (3,), coulomb and viscous: one number or one per joint.
    """
    @staticmethod
    def from_xml(xml: str, gravity: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"] = ..., coulomb: typing.SupportsFloat | typing.SupportsIndex | typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] = 0.0, viscous: typing.SupportsFloat | typing.SupportsIndex | typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] = 0.0, name: str = '<URDF string>', locked_joints: collections.abc.Sequence[tuple[str, typing.SupportsFloat | typing.SupportsIndex]] = []) -> UrdfArm:
        """
        The same from the URDF's XML text; name stands for the file in error messages.
        """
    def __init__(self, urdf_path: str, gravity: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"] = ..., coulomb: typing.SupportsFloat | typing.SupportsIndex | typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] = 0.0, viscous: typing.SupportsFloat | typing.SupportsIndex | typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] = 0.0, locked_joints: collections.abc.Sequence[tuple[str, typing.SupportsFloat | typing.SupportsIndex]] = []) -> None:
        ...
    def base_parameters(self, samples: typing.SupportsInt | typing.SupportsIndex = 100, seed: typing.SupportsInt | typing.SupportsIndex = 0, tolerance: typing.SupportsFloat | typing.SupportsIndex = 1e-09) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"], list[int], typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]]:
        """
        (values (r,), columns (r,), combination (r, 10 n)): the base inertial parameters (pinocchio_structured_basis.hpp).
        """
    def identifier_parameters(self) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"], list[str], list[str]]:
        """
        (values (P,), names, groups): the online identifier's base parameters beta = [kinetic (the structured basis'); gravity's beyond them; coulomb; viscous] (urdf_regressor.hpp), each group 'inertia', 'gravity' or 'friction'.
        """
    def identifier_regressors(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], ddq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], dq_r: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], ddq_r: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> dict:
        """
        The online identifier's regressors (n, P) in identifier_parameters()' beta (urdf_regressor.hpp): Y (M ddq + C dq + G + F), Y_r (M ddq_r + C(q, dq) dq_r + G + F), Y_M (M dq) and Y_N (G + F - C^T dq).
        """
    def mass_regressor(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
        """
        M_k(q) for the inertial parameters, side by side: (n, n * 10 n), M_k in columns [k n, (k + 1) n).
        """
    def terms(self, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> dict:
        """
        Model terms at q (n,), dq (n,): dict of M, M_inv, C (n, n) and G, F (n,).
        """
    def with_gravity_and_friction(self, gravity: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"] = ..., coulomb: typing.SupportsFloat | typing.SupportsIndex | typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] = 0.0, viscous: typing.SupportsFloat | typing.SupportsIndex | typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] = 0.0) -> UrdfArm:
        """
        The arm the constructor would read with this gravity and friction, without reading the URDF again (the parsed model is shared or copied).
        """
    def with_inertia_scaled(self, scale: typing.SupportsFloat | typing.SupportsIndex) -> UrdfArm:
        """
        This arm with every link's mass and inertia times scale > 0: M, C and G times scale, friction and kinematics unchanged (1: this arm).
        """
    @property
    def coulomb(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @property
    def dof(self) -> int:
        ...
    @property
    def gravity(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]:
        ...
    @property
    def inertial_parameter_names(self) -> list[str]:
        ...
    @property
    def inertial_parameters(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @property
    def joint_names(self) -> list[str]:
        ...
    @property
    def joint_types(self) -> list[str]:
        ...
    @property
    def limits(self) -> dict:
        ...
    @property
    def locked_joints(self) -> list[tuple[str, float]]:
        ...
    @property
    def source(self) -> str:
        ...
    @property
    def viscous(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
class UrdfStructuredBasis:
    """
    The structured basis of a URDF arm: [e1_i e1_j (i <= j); e2^T M_b(q) e2 per base inertial parameter b] (pinocchio_structured_basis.hpp).
    """
    def __init__(self, arm: UrdfArm) -> None:
        ...
    def evaluate_rows(self, x: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"], qd: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"], dqd: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> tuple[numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64]]:
        """
        At rows x (m, 2n), qd (m, n), dqd (m, n): phi (m, N), d phi / dx (m, N, 2n) and (d phi / d qd) dqd (m, N).
        """
    def optimal_weights(self, K: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"], inertial_parameters: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"] | None = None) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        """
        W* = [K_ii on squares, K_ij + K_ji on cross terms; base parameters] for K (n, n); the base parameters of inertial_parameters (10 n) of an arm of the same kinematics if given.
        """
    @property
    def base_parameters(self) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"], list[int], typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]]:
        ...
    @property
    def joints(self) -> int:
        ...
    @property
    def names(self) -> list[str]:
        ...
    @property
    def size(self) -> int:
        ...
class ExpressionOp:
    """
    Members:
    
      constant
    
      variable
    
      add
    
      subtract
    
      multiply
    
      negate
    
      power
    
      sin
    
      cos
    
      tan
    
      exp
    
      log
    
      sqrt
    
      tanh
    
      store
    """
    __members__: typing.ClassVar[dict[str, ExpressionOp]]
    add: typing.ClassVar[ExpressionOp]
    constant: typing.ClassVar[ExpressionOp]
    cos: typing.ClassVar[ExpressionOp]
    exp: typing.ClassVar[ExpressionOp]
    log: typing.ClassVar[ExpressionOp]
    multiply: typing.ClassVar[ExpressionOp]
    negate: typing.ClassVar[ExpressionOp]
    power: typing.ClassVar[ExpressionOp]
    sin: typing.ClassVar[ExpressionOp]
    sqrt: typing.ClassVar[ExpressionOp]
    store: typing.ClassVar[ExpressionOp]
    subtract: typing.ClassVar[ExpressionOp]
    tan: typing.ClassVar[ExpressionOp]
    tanh: typing.ClassVar[ExpressionOp]
    variable: typing.ClassVar[ExpressionOp]
    @typing.overload
    def __eq__(self, other: ExpressionOp) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: ExpressionOp) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class ExpressionBasis:
    """
    A basis compiled from a postfix program over z = [x (2n); qd (n)] (cpp/include/adparm/expression_basis.hpp).
    """
    def __init__(self, joints: typing.SupportsInt | typing.SupportsIndex, opcodes: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex], arguments: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex]) -> None:
        ...
    def __len__(self) -> int:
        ...
    def evaluate(self, x: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], qd: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], dqd: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"], typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"], typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"], typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]]:
        """
        At x (2n,), qd (n,), dqd (n,): phi (N,), d phi / dx (N, 2n), (d phi / d qd) dqd (N,) and d phi / d qd (N, n).
        """
    def evaluate_rows(self, x: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"], qd: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"], dqd: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"]) -> tuple[numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64]]:
        """
        Row by row, x (m, 2n), qd and dqd (m, n): phi (m, N), d phi / dx (m, N, 2n) and (d phi / d qd) dqd (m, N).
        """
    @property
    def joints(self) -> int:
        ...
    @property
    def size(self) -> int:
        ...
    @property
    def stack_depth(self) -> int:
        ...
    @property
    def state_dim(self) -> int:
        ...
class Simulation:
    """
    The closed-loop run (basis from settings.basis); advance(n) takes up to n RK4 steps.
    """
    def __init__(self, settings: Settings) -> None:
        ...
    def advance(self, max_steps: typing.SupportsInt | typing.SupportsIndex) -> int:
        ...
    def recording(self) -> dict:
        """
        Recorded rows so far: dict of arrays t, hjb_error, cost (n,), q ... (n, 2), weights (n, 8).
        """
    @property
    def divergence_time(self) -> float:
        ...
    @property
    def reset_times(self) -> list[float]:
        ...
    @property
    def saturated_time(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        """
        Per joint, the time (s) its commanded torque lay beyond its limit (plant.torque_limits), counted per step from the step's start.
        """
    @property
    def state(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
        ...
    @property
    def status(self) -> str:
        ...
    @property
    def step(self) -> int:
        ...
    @property
    def steps(self) -> int:
        ...
class Batch:
    """
    Independent runs on a pool of C++ threads that take runs from a shared queue and run each to the end; the caller polls with wait().
    """
    def __init__(self, settings: collections.abc.Sequence[Settings], window: typing.SupportsInt | typing.SupportsIndex = 18446744073709551615) -> None:
        """
        Builds (checks) every run; at most `window` runs are built and not yet taken.
        """
    def __len__(self) -> int:
        ...
    def seconds(self, index: typing.SupportsInt | typing.SupportsIndex) -> float:
        """
        Wall time spent building and advancing run `index`, s.
        """
    def start(self, threads: typing.SupportsInt | typing.SupportsIndex) -> None:
        """
        Starts the workers.
        """
    def stop(self) -> None:
        """
        Stops every worker within one step and joins them.
        """
    def take(self, index: typing.SupportsInt | typing.SupportsIndex) -> Simulation:
        """
        Hands run `index` over (ended, stopped part-way, or built now if never started).
        """
    def wait(self, seconds: typing.SupportsFloat | typing.SupportsIndex) -> list[int]:
        """
        Waits up to `seconds` for a run to end; returns the indices of the runs that ended since the last call.
        """
    @property
    def done(self) -> bool:
        ...
    @property
    def steps_done(self) -> int:
        ...
    @property
    def total_steps(self) -> int:
        ...
def arm_terms(parameters: ArmParameters, q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[2, 1]"], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[2, 1]"]) -> dict:
    """
    Model terms at q (2,), dq (2,): dict of M, M_inv, C (2, 2) and G, F (2,).
    """
def basis(kind: BasisKind, x: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[4, 1]"], qd: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[2, 1]"], dqd: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[2, 1]"]) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"], typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"], typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]]:
    """
    A basis of K functions at x (4,) and desired qd, dqd (2,): phi (K,), d phi / dx (K, 4) and (d phi / d qd) dqd (K,).
    """
def closed_loop_derivative(settings: Settings, t: typing.SupportsFloat | typing.SupportsIndex, state: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"], dict]:
    """
    Right-hand side at t of state (S,) = [q, dq, Wc (K), Wa (K), Gamma (K^2, column-major), nu (2), J] (S = 87 for the 8-function bases, 55 for the structured basis, 2 K + K^2 + 7 for an expression basis of K functions); local extrapolation points are drawn around this state first. Returns (rate (S,), outputs dict).
    """
def desired_state(trajectory: TrajectorySettings, t: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
    """
    The desired state of n joints at times t (m,): rows [qd (n), dqd (n), ddqd (n)] (m, 3 n).
    """
def extrapolation_points(settings: Settings) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]:
    """
    The fixed or grid extrapolation points (N, 2 n) in x (zeros for mode local, whose points are drawn around the state at each step).
    """
def hjb_evaluation(settings: Settings, x: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"], critic_weights: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], actor_weights: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], t: typing.SupportsFloat | typing.SupportsIndex) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"], typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, n]"]]:
    """
    hjb_residual's HJB error (m,) and each row's omega = (dphi/dx) (f + g u_hat) + (dphi/dqd) dqd (m, K), the regressor of eqs. (21)-(26): d eps / d Wc, and d eps / d W at Wc = Wa = W (u_hat minimises U(u) + W^T B u).
    """
def hjb_residual(settings: Settings, x: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, n]"], critic_weights: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], actor_weights: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 1]"], t: typing.SupportsFloat | typing.SupportsIndex) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
    """
    HJB error of eq. (21) at each row of x (m, 2 n) for weights (K,) of settings.basis, with the desired state at time t; returns (n,).
    """
def initial_state(settings: Settings) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]:
    """
    The closed loop's initial state (S,).
    """
def paper_settings() -> Settings:
    """
    The C++ core's copy of the paper preset.
    """
def simulate_open_loop(parameters: ArmParameters, disturbance: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[2, 1]"], initial_state: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[4, 1]"], dt: typing.SupportsFloat | typing.SupportsIndex, steps: typing.SupportsInt | typing.SupportsIndex, compensate_gravity: bool) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 4]"]:
    """
    RK4 of the arm alone under tau = G(q) (or 0) from [q; dq] (4,); rows (steps + 1, 4).
    """
def two_link_regressors(q: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[2, 1]"], dq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[2, 1]"], ddq: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[2, 1]"], dq_r: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[2, 1]"], ddq_r: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[2, 1]"]) -> dict:
    """
    The two-link arm's regressors (2, 7) in beta = (p1, p2, p3, g1, g2, coulomb, viscous) (identifier.hpp): Y (M ddq + C dq + G + F), Y_r (M ddq_r + C(q, dq) dq_r + G + F), Y_M (M dq) and Y_N (G + F - C^T dq).
    """
def urdf_parse_count() -> int:
    """
    How many URDF texts the core has parsed so far, in every thread.
    """
RECORDED_SERIES: tuple = (('t', 'one'), ('q', 'joints'), ('dq', 'joints'), ('qd', 'joints'), ('e1', 'joints'), ('e2', 'joints'), ('tau', 'joints'), ('tau_commanded', 'joints'), ('u', 'joints'), ('u_hat', 'joints'), ('mu', 'joints'), ('probe', 'joints'), ('critic_weights', 'basis'), ('actor_weights', 'basis'), ('hjb_error', 'one'), ('cost', 'one'), ('model_parameters', 'parameters'), ('stack_singular_value', 'identifier'), ('stack_uncertainty', 'identifier'))
STATE_SIZE: int = 87
