"""Winch control: the WinchProblem and its solvers.

One transcription of the winch problem (:mod:`.problem` with its named parameters,
:mod:`.parameters`) by direct shooting, solved by Gauss-Newton SQP (:mod:`.gauss_newton`, the
default) or IPOPT (:mod:`.ocp`, single or multiple shooting); the paper's Nelder-Mead; the
verification on the scene's model; and the closed loop (:mod:`.closed_loop`), which solves the
same problem over a receding horizon.
"""
