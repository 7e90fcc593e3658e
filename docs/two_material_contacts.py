"""Is there ever a second contact between two rods of different materials?

    python docs/two_material_contacts.py [--hard 10000] [--soft 1000] [--seed 14]

Regenerates the numbers of docs/theory.md, "Can the ends meet a second time?".
Random pairs (one SeedSequence stream per sample):

* hard core: impedance ratio Z2/Z1 log-uniform in [1e-3, 1e3], transit-time
  ratio T1/T2 in [1e-2, 1e2]; counts the separate contacts of the exact
  recursion and the pairs whose gap ever shrinks after the contact;
* finite kappa: Z2/Z1 in [0.01, 100], T1/T2 in [0.1, 10], kappa in [1, 1e5];
  counts force pulses after the first (the force falls below 1e-6 of its peak
  and comes back above 1e-3 of it) with the integration continued for 30 more
  round trips, and the largest change of epsilon that the longer run makes.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from wavecontact.delay.hardcore import closest_return, contact_intervals, hard_core_history
from wavecontact.delay.parameters import echoes_from_ratios
from wavecontact.delay.solver import solve_delay_equation


def hard_pairs(count, seed):
    streams = np.random.SeedSequence(seed).spawn(count)
    several = shrinking = 0
    for stream in streams:
        impedance_ratio, time_ratio = 10.0 ** np.random.default_rng(stream).uniform([-3, -2], [3, 2])
        delays, weights = echoes_from_ratios(impedance_ratio, time_ratio)
        knots_t, knots_w = hard_core_history(delays, weights)
        several += len(contact_intervals(knots_t, knots_w, delays, weights)) > 1
        shrinking += np.isfinite(closest_return(knots_t, knots_w, delays, weights))
    return several, shrinking


def soft_pairs(count, seed):
    streams = np.random.SeedSequence(seed).spawn(count)
    second_pulses = 0
    largest_change = 0.0
    for stream in streams:
        impedance_ratio, time_ratio, kappa = 10.0 ** np.random.default_rng(stream).uniform([-2, -1, 0], [2, 1, 5])
        delays, _weights = echoes_from_ratios(impedance_ratio, time_ratio)
        base = solve_delay_equation(time_ratio, kappa, rtol=1e-9, impedance_ratio=impedance_ratio)
        late = solve_delay_equation(time_ratio, kappa, rtol=1e-9, impedance_ratio=impedance_ratio,
                                    end_time=40.0 / kappa + 30.0 * sum(delays))
        largest_change = max(largest_change, abs(base[1][-1] - late[1][-1]) / kappa)
        force = late[2] / late[2].max()
        peak = int(np.argmax(force))
        quiet = np.flatnonzero(force[peak:] < 1e-6)
        second_pulses += bool(quiet.size and force[peak + quiet[0]:].max() > 1e-3)
    return second_pulses, largest_change


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hard", type=int, default=10_000)
    parser.add_argument("--soft", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=14)
    args = parser.parse_args()
    started = time.perf_counter()
    several, shrinking = hard_pairs(args.hard, args.seed)
    print(f"hard core, {args.hard} pairs (Z2/Z1 in [1e-3, 1e3], T1/T2 in [1e-2, 1e2]): "
          f"{several} with more than one contact, {shrinking} whose gap shrinks after the contact "
          f"({time.perf_counter() - started:.1f} s)")
    started = time.perf_counter()
    pulses, change = soft_pairs(args.soft, args.seed + 1)
    print(f"finite kappa, {args.soft} pairs (Z2/Z1 in [0.01, 100], T1/T2 in [0.1, 10], kappa in [1, 1e5]): "
          f"{pulses} with a second force pulse, largest change of epsilon with 30 more round trips "
          f"{change:.1e} ({time.perf_counter() - started:.1f} s)")


if __name__ == "__main__":
    main()
