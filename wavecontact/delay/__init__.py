"""The delay-differential equation of the relative velocity (Eq. 16) and its hard-core limit."""
