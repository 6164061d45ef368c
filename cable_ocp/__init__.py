"""cable_ocp: dynamics and optimal winch control of a cable-suspended load."""
