"""The wave theory of impact in numbers: hard contact of rods of length ratio 0.6.

    python examples/hard_core_collision.py
"""

import math

import wavecontact
from wavecontact.analytic import hard_core_modal_energies


def main():
    result = wavecontact.collide(0.6, math.inf)
    print(f"epsilon          = {result.restitution:.15f}  (wave theory: 0.6)")
    print(f"contact duration = {result.contact_duration:.15f}  (2 l1 / c = 1.6 in units of l / c)")
    print(f"force plateau    = {result.contact_force.max():.15f}  (Z V / 2 = 0.5)")
    lost = hard_core_modal_energies(0.6, 100_000).sum()
    print(f"energy in the long rod's modes (Eq. 25) = {lost:.6f} E_tr  (1 - gamma^2 = 0.64)")
    return result


if __name__ == "__main__":
    main()
