"""Posture optimisation: the book's cost (eq. 2.87), PSO with pyswarms, local refinement."""
