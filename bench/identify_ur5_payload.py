"""Issue 25's target on a URDF arm: the UR5 with a 2 kg payload its model does not know.

The plant is the UR5 URDF (example-robot-data) with a 2 kg link fixed 0.1 m from wrist_3_link
(written next to this run, tests/test_identifier.py's urdf_with_payload); the model is the UR5
URDF; examples/ur5.toml with identifier.enabled and a 5 N m probe per joint at random phases.
Prints beta_hat's error (largest over the largest identified parameter), the stack's minimum
singular value and the critic's distance to the plant's W* over time.

    python bench/identify_ur5_payload.py [T (s), default 30] [probe amplitude (N m), default 5]
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import adparm

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_identifier import urdf_with_payload  # noqa: E402


def main() -> None:
    T = float(sys.argv[1]) if len(sys.argv) > 1 else 30.0
    amplitude = float(sys.argv[2]) if len(sys.argv) > 2 else 5.0
    ur5 = adparm.example_robot_urdf("ur5")
    folder = Path(tempfile.mkdtemp())
    plant = folder / "ur5_payload.urdf"
    urdf_with_payload(ur5, "wrist_3_link", 2.0, (0.0, 0.1, 0.0), plant)
    base = adparm.load_config(adparm.example_path("ur5.toml"))
    n = base.dof
    rng = np.random.default_rng(1)
    config = base.updated(
        {
            "plant": {"urdf": str(plant)},
            "model": {"urdf": str(ur5)},
            "identifier": {"enabled": True},
            "probe": {
                "until": 100.0,
                "amplitude": [amplitude] * n,
                "phases": rng.uniform(0.0, 2.0 * np.pi, (n, 4)).tolist(),
            },
            "sim": {"T": T, "record_every": 100},
        }
    )
    start = time.perf_counter()
    result = adparm.simulate(config, diagnose=False)
    print(f"computing {time.perf_counter() - start:.0f} s, {result.status}")
    beta = adparm.base_parameters(config, "plant")
    identified = adparm.identification.identified_parameters(config)
    scale = np.abs(beta[identified]).max()

    def error(b: np.ndarray) -> float:
        return float(np.abs(b[identified] - beta[identified]).max() / scale)

    W = adparm.optimal_weights(adparm.identification.plant_model_config(config))
    print(f"{beta.size} base parameters, {len(identified)} identified")
    print(f"model: beta {error(adparm.base_parameters(config, 'model')):.3g} off")
    for i in range(0, result.t.size, max(1, result.t.size // 15)):
        critic = np.linalg.norm(result.critic_weights[i] - W) / np.linalg.norm(W)
        print(
            f"t = {result.t[i]:5.2f} s  beta_hat {error(result.model_parameters[i]):.3g}  "
            f"sigma_min {result.stack_singular_value[i]:.3g}  critic {critic:.3g}"
        )


if __name__ == "__main__":
    main()
