"""Winch control: the WinchProblem, direct shooting + IPOPT (single by default, multiple shooting
on request), the paper's Nelder-Mead, the verification on the scene's model, closed-loop MPC."""
