"""Finite-element model of rods in contact: discretization, stable step, contact flows, time loop."""

from .discretization import ELEMENT_ORDERS, MASS_KINDS, RodDiscretization, discretize_rod
from .stability import largest_eigenvalue, stable_step

__all__ = [
    "ELEMENT_ORDERS",
    "MASS_KINDS",
    "RodDiscretization",
    "discretize_rod",
    "largest_eigenvalue",
    "stable_step",
]
