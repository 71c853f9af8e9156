"""adparm: exact linearization, RISE and online actor-critic ADP for robot manipulators.

A C++ core (adparm._core) integrates the closed loop of the paper; this package configures it,
runs it and returns NumPy arrays.
"""

from .config import (
    ActorConfig,
    Config,
    ControlConfig,
    CostConfig,
    CriticConfig,
    InitConfig,
    ModelConfig,
    PlantConfig,
    ProbeConfig,
    SimConfig,
    TaskConfig,
    load_config,
    paper_config,
)
from .optimal import BASIS_NAMES, hjb_residual, optimal_weights
from .report import write_report
from .simulation import SimulationDiverged, SimulationResult, simulate
from .storage import load_result

__version__ = "0.1.0"

__all__ = [
    "BASIS_NAMES",
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
    "SimulationDiverged",
    "SimulationResult",
    "TaskConfig",
    "hjb_residual",
    "load_config",
    "load_result",
    "optimal_weights",
    "paper_config",
    "simulate",
    "write_report",
]
