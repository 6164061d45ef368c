"""Winch control: the WinchProblem and its solvers.

Direct shooting + IPOPT (single shooting by default, multiple shooting on request), the paper's
Nelder-Mead, the verification on the scene's model, and closed-loop MPC.
"""
