"""Issue 25's target on a URDF arm: the UR5 with a 2 kg payload its model does not know.

The plant is the UR5 URDF (example-robot-data) with a 2 kg link fixed 0.1 m from wrist_3_link
(adparm.urdf_with_payload, written next to this run); the model is the UR5
URDF; examples/ur5.toml with identifier.enabled and a 5 N m probe per joint at random phases.
Prints beta_hat's error (largest over the largest identified parameter), the stack's minimum
singular value, the critic's distance to the plant's W* and to its current target W*(beta_hat)
(the plant's W* with beta_hat's kinetic-energy parameters as its tail) over time, when the probe
stopped (identifier.stop_probe) and from when beta_hat and the critic both stay within 1 %.

    python bench/identify_ur5_payload.py [T (s), default 30] [probe amplitude (N m), default 5]
        [identifier.key=value ...]   (e.g. identifier.stop_probe=false)
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import adparm


def main() -> None:
    T = float(sys.argv[1]) if len(sys.argv) > 1 else 30.0
    amplitude = float(sys.argv[2]) if len(sys.argv) > 2 else 5.0
    identifier: dict = {"enabled": True}
    for setting in sys.argv[3:]:
        key, value = setting.removeprefix("identifier.").split("=")
        identifier[key] = json.loads(value)  # true, false or a number
    ur5 = adparm.example_robot_urdf("ur5")
    folder = Path(tempfile.mkdtemp())
    plant = folder / "ur5_payload.urdf"
    adparm.urdf_with_payload(ur5, "wrist_3_link", 2.0, (0.0, 0.1, 0.0), path=plant)
    base = adparm.load_config(adparm.example_path("ur5.toml"))
    n = base.dof
    rng = np.random.default_rng(1)
    config = base.updated(
        {
            "plant": {"urdf": str(plant)},
            "model": {"urdf": str(ur5)},
            "identifier": identifier,
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
    # the critic's current target: W* of the arm of beta_hat, whose tail is s beta_hat's
    # kinetic-energy parameters (the structured basis; s = W*'s tail over the plant's)
    tail = W.size - n * (n + 1) // 2
    s = W[-tail:] / beta[:tail]
    targets = np.tile(W, (result.t.size, 1))
    targets[:, -tail:] = s * result.model_parameters[:, :tail]
    critic = np.linalg.norm(result.critic_weights - W, axis=1) / np.linalg.norm(W)
    to_target = np.linalg.norm(result.critic_weights - targets, axis=1) / np.linalg.norm(W)
    beta_error = np.array([error(b) for b in result.model_parameters])
    print(f"{beta.size} base parameters, {len(identified)} identified")
    print(f"model: beta {error(adparm.base_parameters(config, 'model')):.3g} off")
    print(f"Gamma resets: {result.covariance_resets}")
    for i in range(0, result.t.size, max(1, result.t.size // 15)):
        print(
            f"t = {result.t[i]:5.2f} s  beta_hat {beta_error[i]:.3g}  "
            f"sigma_min {result.stack_singular_value[i]:.3g}  critic {critic[i]:.3g}  "
            f"(from W*(beta_hat) {to_target[i]:.3g})"
        )
    print(f"end t = {result.t[-1]:.2f} s: beta_hat {beta_error[-1]:.3g}, critic {critic[-1]:.3g}")
    diagnosis = adparm.identification.identifier_diagnosis(result)
    print(f"probe stopped at: {diagnosis['probe_stopped_time']}")
    for name, series in (("beta_hat", beta_error), ("critic", critic)):
        over = np.flatnonzero(series > 0.01)
        if over.size and over[-1] + 1 < result.t.size:
            print(f"{name} within 1 % from t = {result.t[over[-1] + 1]:.2f} s")
    if diagnosis["informative_time"] is not None:  # full rank, its equations in agreement
        print(f"stack informative from t = {diagnosis['informative_time']:.2f} s")
    outside = np.flatnonzero((beta_error > 0.01) | (critic > 0.01))
    if outside.size == 0:
        print("both within 1 % throughout")
    elif outside[-1] + 1 < result.t.size:
        print(f"both within 1 % from t = {result.t[outside[-1] + 1]:.2f} s")
    else:
        print("not both within 1 % at the end")


if __name__ == "__main__":
    main()
