"""How the model is driven: vessel motion, winch angle and its bounds, end force."""
