"""Index tables of the packed float arrays the two-rod FE kernels share.

One table per packed array, read by the general loop
(:func:`wavecontact.fem.kernels.advance`), the exact lattice
(:func:`wavecontact.fem.lattice.advance_lattice`) and the code that packs
them (:mod:`wavecontact.fem.simulation`):

- ``S_*``: the run state carried between calls (``STATE_SIZE`` entries);
- ``C_*``: the contact law and its constants (``CONTACT_SIZE`` entries);
- ``K_*``: the run control (``CONTROL_SIZE`` entries; each loop reads the
  entries it needs, the rest are ignored);
- ``R_*``: one rod of the exact lattice (``ROD_SIZE`` entries).

The multi-body kernel keeps its own arrays and tables
(:mod:`wavecontact.fem.multibody_kernel`).
"""

from __future__ import annotations

from .._jit import kernel

# run state (one float array)
S_TIME = 0
S_MOMENTUM1 = 1
S_MOMENTUM2 = 2
S_LAST_IN_RANGE = 3
S_STEPS = 4
S_ENERGY0 = 5
S_MAX_DRIFT = 6
S_FAILED_ENERGY = 7
S_ENERGY_SCALE = 8
S_PREVIOUS_END1 = 9
S_PREVIOUS_END2 = 10
S_INCOMING = 11
S_INCOMING_EARLIER = 12  # incoming rate one step before S_INCOMING
S_LEVEL = 13  # time level of the exact lattice's waves, counted from the start of the run
STATE_SIZE = 14

# contact parameters (one float array)
C_LAW = 0
C_ALPHA = 1
C_STRENGTH = 2
C_STIFFNESS = 3
C_OFFSET = 4  # reference gap: gap = offset + u2[0] - u1[-1] (length)
C_R_STOP = 5  # gap beyond which the force counts as absent (length)
C_M_INV = 6  # (M1^-1)_ee + (M2^-1)_ee (1/mass)
C_COMPLIANCE = 7  # 1/Z1 + 1/Z2 = m_inv dt / 2 (time/mass)
CONTACT_SIZE = 8

# run control (one float array)
K_DT = 0  # time step (time)
K_PERIOD = 1  # stop once out of range for this long (time)
K_CHECK_EVERY = 2  # steps between energy checks
K_ENERGY_TOLERANCE = 3
K_SCHEME = 4  # contact treatment (kernels.SCHEME_*; the general loop takes it as its argument end_scheme)
K_KIND1 = 5  # general loop: mass solve of each rod (explicit_step.MASS_*)
K_KIND2 = 6
K_BOUND1 = 7  # general loop: separation bound factor of each rod
K_BOUND2 = 8
K_PLASTIC = 9  # general loop: 1 = the splitting scheme's hard node impact is perfectly plastic (0: elastic mirror)
K_SUBSTEPS = 10  # lattice: substeps of the gap equation
K_CENTERED = 11  # lattice: 1 = five step means of the incoming rate are read (rods of >= 5 nodes)
K_GAUSS = 12  # lattice: 1 = the exponential gap equation by a 16-point Gauss-Legendre integral (0: substeps)
CONTROL_SIZE = 13

# one rod of the exact lattice (one float array per rod)
R_MASK = 0  # circular buffers hold mask + 1 entries
R_FAR_THETA = 1  # unmeshed remainder beyond the far node, in elements (0 <= theta < 1)
R_CONTACT_COEFFICIENT = 2  # dt^2 M^-1 K (end, neighbour) of the contact end node
R_CONTACT_INVERSE_MASS = 3  # 1 / mass of the contact end node
R_BOUND = 4  # |u_end - u_mean| <= R_BOUND sqrt(internal energy): the separation bound
ROD_SIZE = 5


@kernel(inline="always")
def read_contact(contact):
    """``(law, alpha, strength, stiffness, offset, r_stop, m_inv)`` of a packed contact array (``C_*``)."""
    return (int(contact[C_LAW]), contact[C_ALPHA], contact[C_STRENGTH], contact[C_STIFFNESS], contact[C_OFFSET],
            contact[C_R_STOP], contact[C_M_INV])


@kernel(inline="always")
def read_run_control(control):
    """``(dt, period, check_every, energy_tolerance)`` of a packed control array, the entries both loops read."""
    return control[K_DT], control[K_PERIOD], int(control[K_CHECK_EVERY]), control[K_ENERGY_TOLERANCE]
