"""Ranked (k-best) linear assignment: Murty's algorithm on ``scipy.optimize.linear_sum_assignment``."""
