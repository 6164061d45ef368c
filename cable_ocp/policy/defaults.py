"""Defaults of learning a policy, read by the API and the command line alike (no imports).

``cable-ocp --help`` reads them without loading the learning's modules.
"""

SCENES, ROUNDS, HIDDEN = 16, 2, (8, 8)  # learn_policy's and cable-ocp learn's
POLICY_FILE, C_NAME = "policy.nc", "policy"  # what they write in a results folder
