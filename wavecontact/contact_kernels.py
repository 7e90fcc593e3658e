"""Contact laws evaluated inside compiled kernels, from the codes of :mod:`wavecontact.contact`.

A kernel never sees a law object, only ``(code, alpha, strength, stiffness)``
from :meth:`wavecontact.contact.ContactLaw.kernel_parameters`.  These two
functions are the single compiled evaluation of those numbers; the tests hold
them to the Python ``force``/``potential`` methods of the law objects.
"""

from __future__ import annotations

import math

from ._jit import kernel
from .contact import LAW_EXPONENTIAL, LAW_HARD, LAW_PENALTY

__all__ = ["law_force", "law_potential"]


@kernel
def law_force(code, alpha, strength, stiffness, gap):
    """Repulsive force (>= 0) at end-to-end gap ``gap`` (force units; ``inf`` for a hard overlap)."""
    if code == LAW_EXPONENTIAL:
        return alpha * strength * math.exp(-alpha * gap)
    if code == LAW_PENALTY or code == LAW_HARD:
        if gap >= 0.0:
            return 0.0
        return stiffness * -gap
    return math.nan


@kernel
def law_potential(code, alpha, strength, stiffness, gap):
    """Interaction energy at gap ``gap`` (energy units), zero far apart (``inf`` for a hard overlap)."""
    if code == LAW_EXPONENTIAL:
        return strength * math.exp(-alpha * gap)
    if code == LAW_PENALTY or code == LAW_HARD:
        if gap >= 0.0:
            return 0.0
        return 0.5 * stiffness * gap * gap
    return math.nan
