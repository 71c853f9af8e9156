"""adparm: exact linearization, RISE and online actor-critic ADP for robot manipulators.

A C++ core (adparm._core) integrates the closed loop of the paper; this package configures it,
runs it and returns NumPy arrays.
"""

# first: finds Pinocchio's libraries where the extension's run path cannot (_libraries.py)
from . import _libraries  # noqa: F401  # isort: skip
from ._examples import example_path
from .bases import ExpressionBasis, basis_terms
from .comparison import Comparison, compare
from .config import (
    ActorConfig,
    Config,
    ControlConfig,
    ControllerConfig,
    CostConfig,
    CriticConfig,
    DiagnosticsConfig,
    ExtrapolationConfig,
    IdentifierConfig,
    InitConfig,
    ModelConfig,
    PlantConfig,
    ProbeConfig,
    SampledTrajectory,
    SimConfig,
    SinusoidTrajectory,
    TaskConfig,
    load_config,
    paper_config,
)
from .optimal import (
    BASIS_NAMES,
    arm_terms,
    base_parameter_names,
    base_parameters,
    basis,
    basis_names,
    initial_error_state,
    optimal_value,
    optimal_weights,
    saturated_cost,
    solvable_cost,
    value_scale,
)
from .physical import two_link_parameters
from .plotting import FIGURES  # noqa: F401 - registers SimulationResult.plot
from .report import write_report
from .residual import hjb_residual
from .simulation import (
    SimulationDiverged,
    SimulationInterrupted,
    SimulationResult,
    desired_state,
    extrapolation_points,
    simulate,
    simulate_batch,
)
from .storage import load_result
from .summary import summarize  # noqa: F401 - registers SimulationResult.summary
from .sweep import SweepResult, grid_points, sweep
from .truth import ApproximationWarning, check_step_size, diagnose, lqr_value, optimal_cost
from .urdf import EXAMPLE_ROBOTS, UrdfArm, example_robot_urdf
from .urdf_payload import urdf_with_payload, urdf_with_scaled_inertia

__version__ = "0.1.0"

__all__ = [
    "BASIS_NAMES",
    "EXAMPLE_ROBOTS",
    "ActorConfig",
    "ApproximationWarning",
    "Comparison",
    "Config",
    "ExpressionBasis",
    "ControlConfig",
    "ControllerConfig",
    "CostConfig",
    "CriticConfig",
    "ExtrapolationConfig",
    "IdentifierConfig",
    "InitConfig",
    "ModelConfig",
    "PlantConfig",
    "ProbeConfig",
    "SampledTrajectory",
    "SimConfig",
    "DiagnosticsConfig",
    "SimulationDiverged",
    "SimulationInterrupted",
    "SimulationResult",
    "SinusoidTrajectory",
    "SweepResult",
    "TaskConfig",
    "UrdfArm",
    "arm_terms",
    "base_parameter_names",
    "base_parameters",
    "basis",
    "basis_names",
    "basis_terms",
    "check_step_size",
    "compare",
    "desired_state",
    "diagnose",
    "example_path",
    "example_robot_urdf",
    "extrapolation_points",
    "grid_points",
    "hjb_residual",
    "initial_error_state",
    "load_config",
    "load_result",
    "lqr_value",
    "optimal_cost",
    "optimal_value",
    "optimal_weights",
    "paper_config",
    "simulate",
    "simulate_batch",
    "saturated_cost",
    "solvable_cost",
    "sweep",
    "two_link_parameters",
    "urdf_with_payload",
    "urdf_with_scaled_inertia",
    "value_scale",
    "write_report",
]
