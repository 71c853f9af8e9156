"""
Your own two-link arm from physical parameters
==============================================

Two uniform rods of 1 m and 1 kg instead of the paper's arm. ``adparm.two_link_parameters``
turns masses, lengths, centre-of-mass distances and inertias into the lumped p1, p2, p3, g1, g2
of eq. (1). The analytic optimum W* changes with the arm (its e2 block holds M(q)); the critic
finds it from 10 extrapolation points, without probing.
"""

import matplotlib.pyplot as plt
import numpy as np

import adparm

rods = adparm.two_link_parameters(
    m1=1.0, m2=1.0, l1=1.0, lc1=0.5, lc2=0.5, I1=1.0 / 12.0, I2=1.0 / 12.0
)
print({key: round(value, 4) for key, value in rods.items()})

config = adparm.paper_config().updated(
    {"plant": rods, "probe": {"until": 0.0}, "extrapolation": {"points": 10}, "sim": {"T": 10.0}}
)
w_star = adparm.optimal_weights(config)
print("W* =", w_star.round(4))

result = adparm.simulate(config)
error = np.linalg.norm(result.critic_weights - w_star, axis=1) / np.linalg.norm(w_star)
print(f"within 1 % of W* from t = {result.t[np.argmax(error < 0.01)]:.2f} s")

# %%
# The critic weights against this arm's W*:
result.plot("fig2_critic_weights", fig=plt.figure(figsize=(7.5, 5.2), layout="constrained"))
