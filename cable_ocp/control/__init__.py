"""Winch control: multiple shooting + IPOPT, Nelder-Mead, closed-loop MPC."""
