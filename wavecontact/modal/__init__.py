"""Rod modes and the modal-expansion integrator (paper Eq. 4, 7, 14).

* :mod:`.modes` -- analytic and finite-element free-free modes, residual
  (static) end compliance of the omitted modes;
* :mod:`.kernels` -- the compiled integrator (exact free flight, splitting
  during contact);
* :mod:`.system` -- the assembled system of rods, modes and contact pairs;
* :mod:`.ring` -- two rods on a ring, collision after collision.
"""

from .modes import RodModes, analytic_modes, fe_modes, rod_modes, uniform_residual_compliance
from .ring import RingSimulation
from .system import ModalSystem, StepControl

__all__ = [
    "ModalSystem",
    "RingSimulation",
    "RodModes",
    "StepControl",
    "analytic_modes",
    "fe_modes",
    "rod_modes",
    "uniform_residual_compliance",
]
