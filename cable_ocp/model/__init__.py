"""The rfe cable model: parameters, symbolic equations, compiled Functions."""
