"""Lowering a load to the seabed: the descent, the landing, the hold, their checks and files.

- :mod:`.descent`: the landing line and the reference descent;
- :mod:`.plan`: the open-loop landing, verified on the scene's own model (a LandingPlan);
- :mod:`.landing`: the landing from a hover, optimised or closed-loop (:func:`~.landing.land`);
- :mod:`.hold`: the closed-loop hold after the landing (:func:`~.hold.hold`);
- :mod:`.checks`: every constraint measured on a run (:func:`~.checks.check_landing`);
- :mod:`.files`: the lowering's results as netCDF files (a result holding other results);
- :mod:`.results`: ``co.load_result``, any result read by the kind its file declares;
- :mod:`.arguments`: the numeric arguments checked where they enter.
"""
