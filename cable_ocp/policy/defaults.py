"""Defaults of learning a policy, read by the API and the command line alike (no imports).

``cable-ocp --help`` reads them without loading the learning's modules.
"""

# learn_policy's and cable-ocp learn's. The hidden layers by measurement: on hill_tow's MPC runs
# (12 scenes to fit, 4 held out, 2520 and 840 pairs), the held-out error in the action's variance
# was 5e-4 for (8,), 7e-4 for (16,), 3e-4 for (8, 8) and (16, 16); the fit took 23 s for (8, 8)
# and 63 s for (16, 16) (2000 L-BFGS iterations).
SCENES, ROUNDS, HIDDEN = 16, 2, (8, 8)
POLICY_FILE, C_NAME = "policy.nc", "policy"  # what they write in a results folder
