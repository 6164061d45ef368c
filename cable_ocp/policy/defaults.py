"""Defaults of learning a policy, read by the API and the command line alike (no imports).

``cable-ocp --help`` reads them without loading the learning's modules.
"""

# learn_policy's and cable-ocp learn's. The hidden layers by measurement: on hill_tow's MPC runs
# (12 scenes to fit, 4 held out, 2520 and 840 pairs), the held-out error in the action's variance
# was 5e-4 for (8,), 7e-4 for (16,), 3e-4 for (8, 8) and (16, 16); the fit took 23 s for (8, 8)
# and 63 s for (16, 16) (2000 L-BFGS iterations).
SCENES, ROUNDS, HIDDEN = 16, 2, (8, 8)
POLICY_FILE, C_NAME = "policy.nc", "policy"  # what they write in a results folder
# Most L-BFGS iterations of a fit. On hill_tow's data of 3 rounds (8400 pairs, 1000 held out),
# (8, 8): held-out error 4.7e-3 of the action's variance after 2000, 2.4e-3 after 5000.
ITERATIONS = 5000
