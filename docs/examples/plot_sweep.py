"""
A sweep over settings
=====================

Every combination of critic gain and probe amplitude, run on parallel C++ threads; one row per
run. Each run is cut to 30 s, which shows how fast each setting learns.
"""

import matplotlib.pyplot as plt
import numpy as np

import adparm

base = adparm.paper_config().updated({"sim": {"T": 30.0}})
grid = {"critic.eta_c": [100, 400, 800], "probe.amplitude": [[36, 12], [71, 23]]}
table = adparm.sweep(base, grid)
for row in table:
    print(
        f"eta_c = {row['critic.eta_c']:>5}, amplitude = {row['probe.amplitude']}: "
        f"{row['status']}, relative error {row['critic_relative_error']:.1e}"
    )

# %%
# The critic's relative error at the end of each run, by setting:
eta = np.array([row["critic.eta_c"] for row in table.rows], dtype=float)
error = table["critic_relative_error"]
fig, ax = plt.subplots(figsize=(6, 3.5), layout="constrained")
for amplitude, colour, marker in (([36, 12], "#0072B2", "o"), ([71, 23], "#D55E00", "s")):
    rows = [i for i, row in enumerate(table.rows) if list(row["probe.amplitude"]) == amplitude]
    ax.semilogy(eta[rows], error[rows], color=colour, marker=marker, label=f"amplitude {amplitude}")
ax.axhline(0.02, color="0.3", ls=":", label="2 %")
ax.set_xlabel("critic gain $\\eta_c$")
ax.set_ylabel("$\\|\\hat W_c - W^*\\| / \\|W^*\\|$ at 30 s")
ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
