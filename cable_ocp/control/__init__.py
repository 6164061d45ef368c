"""Winch control: the WinchProblem and its solvers.

One transcription of the winch problem (:mod:`.problem` with its named parameters,
:mod:`.parameters`) by direct shooting (:mod:`.shooting`), solved by Gauss-Newton SQP
(:mod:`.gauss_newton`, the default) or IPOPT (:mod:`.ipopt`, single or multiple shooting); the
paper's Nelder-Mead; the registry of these solvers (:mod:`.solvers`); the verification on the
scene's model; and the closed loop (:mod:`.closed_loop`), which solves the same problem over a
receding horizon.
"""
