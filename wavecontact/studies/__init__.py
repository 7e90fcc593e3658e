"""Studies built on the solver interface: convergence, ensembles, ring runs."""
