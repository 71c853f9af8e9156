"""
Tracking a sinusoid while learning
==================================

The desired trajectory is a sinusoid per joint. The augmented basis keeps V* and W* exact
while qd moves, and extrapolation replaces the probing signal.
"""

import matplotlib.pyplot as plt
import numpy as np

import adparm

# the same as the repository's examples/tracking.toml, cut to 10 s
sinusoid = adparm.SinusoidTrajectory(amplitude=[0.5, 0.3], frequency=[1.0, 2.0])
config = adparm.paper_config().updated(
    {
        "task": {"qd": sinusoid},
        "probe": {"until": 0.0},
        "extrapolation": {"points": 10},
        "sim": {"T": 10.0},
    }
)
result = adparm.simulate(config)
w_star = adparm.optimal_weights(config)
error = np.linalg.norm(result.critic_weights - w_star, axis=1) / np.linalg.norm(w_star)
print(f"critic relative error at {result.t[-1]:g} s: {error[-1]:.1e}")
print(f"largest |e1| over the last 2 s: {np.abs(result.e1[result.t > 8]).max():.1e} rad")

# %%
# Joint angles against the desired trajectory:
fig, axes = plt.subplots(2, 1, sharex=True, figsize=(7.5, 4), layout="constrained")
for j, ax in enumerate(axes):
    ax.plot(result.t, result.qd[:, j], color="k", ls="--", lw=1.5, label="$q_d$")
    ax.plot(result.t, result.q[:, j], color="#0072B2", lw=1.0, label="$q$")
    ax.set_ylabel(f"joint {j + 1} (rad)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
axes[-1].set_xlabel("time t (s)")

# %%
# The tracking errors, with the magnitude of e1 on a log scale:
result.plot("fig4_errors", fig=plt.figure(figsize=(7.5, 6.4), layout="constrained"))
