"""
Learning without probing: Bellman-error extrapolation
=====================================================

With 10 fixed extrapolation points and no probing signal, the critic reaches W* within a few
seconds, and the arm never leaves the neighbourhood of the set-point.
"""

import matplotlib.pyplot as plt
import numpy as np

import adparm

# the same as the repository's examples/extrapolation.toml, cut to 10 s
config = adparm.paper_config().updated(
    {"probe": {"until": 0.0}, "extrapolation": {"points": 10, "mode": "fixed"}, "sim": {"T": 10.0}}
)
result = adparm.simulate(config)
w_star = adparm.optimal_weights(config)
error = np.linalg.norm(result.critic_weights - w_star, axis=1) / np.linalg.norm(w_star)
print(f"within 1 % of W* from t = {result.t[np.argmax(error < 0.01)]:.2f} s")
print(f"relative error at {result.t[-1]:g} s: {error[-1]:.1e}")

# %%
# The critic weights and their relative error:
result.plot("fig2_critic_weights", fig=plt.figure(figsize=(7.5, 5.2), layout="constrained"))

# %%
# The points, projected on the (e1_1, e2_1) plane:
points = adparm.extrapolation_points(config)
fig, ax = plt.subplots(figsize=(4, 4), layout="constrained")
ax.scatter(points[:, 0], points[:, 2], color="#0072B2")
ax.set_xlabel("$e_{1,1}$ (rad)")
ax.set_ylabel("$e_{2,1}$ (rad/s)")
ax.set_title(f"{len(points)} fixed extrapolation points")
