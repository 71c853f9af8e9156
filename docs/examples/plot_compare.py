"""
Comparing controllers
=====================

The learning ADP run, the policy it learned (rerun without probing), RISE alone, PD and the
exact optimal policy, on the same arm and initial state. The horizon is shortened to 40 s here;
the learning run still reaches W* (it needs about 15 s).
"""

import matplotlib.pyplot as plt

import adparm

config = adparm.paper_config().updated({"sim": {"T": 40.0}, "probe": {"until": 30.0}})
comparison = adparm.compare(config)
print(comparison.table_markdown())

# %%
# The learning run has its own column; the other controllers share the second, each in its own
# colour and line style ("adp (learned)" wide and light, "optimal" black dashes on top of it).
comparison.plot(fig=plt.figure(figsize=(8.5, 6.8), layout="constrained"))
