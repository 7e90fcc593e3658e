"""Where a default FE and modal ``collide`` spends its CPU time, part by part, one command:

    python benchmarks/default_cost.py [--repeats 30]

The parts of ``collide(0.6, 100, solver='fem', elements=800)``: each run's set-up (the two rods'
discretizations and stable step, :func:`wavecontact.fem.simulation.build_setup`) on a mesh not seen
before and on a kept one (:mod:`wavecontact.fem.reuse`), and each run's time loop, for the requested
run at 800 elements and the error estimate's at 400 and 200; and of
``collide(0.6, 100, solver='modal', modes=100)``: the end-response run, the energy the force left in the
omitted modes (``energy_drift`` only) and the error estimate's run at a tenth of the collocation
tolerance (restitution alone, one mode per rod: for rods at rest the restitution does not depend on the
modes, :func:`wavecontact.modal.solver._finer_options`; beside it the same run at the requested modes, as
the estimate made it before); the whole call adds the options, the cost check and the result.  Repeated
calls on one scene share its set-up (:func:`wavecontact.modal.solver._build`), as a user's repeated calls do.  Beside them the call
6684575 made by default (FE: the run at 800 elements, no estimate; modal: the static correction at
collocation tolerance 1e-2, no estimate), computed here with today's code.  CPU times of this process
(``time.process_time``), median over ``--repeats`` calls, kernels compiled before timing.  The
side-by-side comparison with the older commit itself is ``python benchmarks/against.py 6684575``.
"""

from __future__ import annotations

import argparse
import itertools
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

#: the block of docs/performance.md that ``--update-docs`` writes
DOCS_BLOCK = "default-cost"


def _cpu(calls: dict, repeats: int) -> dict:
    """Median CPU seconds of each ``calls[name]()`` over ``repeats`` rounds; every round calls each once, in
    turn, so that a change of the machine's load hits all parts alike (one untimed round first)."""
    times = {name: [] for name in calls}
    for round_ in range(repeats + 1):
        for name, call in calls.items():
            start = time.process_time()
            call()
            if round_:
                times[name].append(time.process_time() - start)
    return {name: statistics.median(values) for name, values in times.items()}


def fem_rows(repeats: int) -> list:
    """``(part, ms)`` of the default FE call."""
    from wavecontact import collide, two_rods
    from wavecontact.fem import reuse
    from wavecontact.fem.simulation import build_setup, run_collision

    scene = two_rods(0.6, 100.0)
    fresh = itertools.count(1)
    kept, new = {}, {}  # timed apart: new meshes would push the kept ones out of the solver's recent meshes
    for elements in (800, 400, 200):
        setup = build_setup(scene, elements=elements)
        # a gamma moved by 1e-9 per call: a mesh not seen before
        new[f"set-up at {elements} elements, new mesh"] = \
            lambda e=elements: build_setup(two_rods(0.6 + 1e-9 * next(fresh), 100.0), elements=e)
        kept[f"set-up at {elements} elements, kept mesh"] = lambda e=elements: build_setup(scene, elements=e)
        kept[f"time loop at {elements} elements"] = lambda s=setup: run_collision(s)
    kept["whole call, kept meshes"] = lambda: collide(0.6, 100.0, solver="fem", elements=800)
    new["whole call, new meshes"] = lambda: collide(0.6 + 1e-9 * next(fresh), 100.0, solver="fem", elements=800)
    kept["the call 6684575 made (one run at 800 elements, no estimate), today's code, kept mesh"] = \
        lambda: collide(0.6, 100.0, solver="fem", elements=800, estimate_error=False)
    rows = [*_cpu(kept, repeats).items(), *_cpu(new, repeats).items()]
    reuse.clear()
    return rows


def modal_rows(repeats: int) -> list:
    """``(part, ms)`` of the default modal call."""
    from wavecontact import collide, two_rods
    from wavecontact.modal import solver as modal

    scene = two_rods(0.6, 100.0)
    options = modal.SOLVER.options({"modes": 100})
    estimate = modal._finer_options(scene, options, modal._DEFAULT_TOLERANCE["end-response"])  # one mode per rod
    parts = _cpu({
        "run": lambda: modal._collide(scene, options, omitted_energy=False),
        "bookkept": lambda: modal._collide(scene, options),
        "estimating": lambda: modal._restitution_alone(scene, estimate, modal._EXPONENT_STEP),
        "estimating, all modes": lambda: modal._restitution_alone(scene, estimate.replace(modes=100),
                                                                  modal._EXPONENT_STEP),
        "whole": lambda: collide(0.6, 100.0, solver="modal", modes=100),
        "before": lambda: collide(0.6, 100.0, solver="modal", modes=100, correction="static",
                                  collocation_tolerance=1e-2, estimate_error=False),
    }, repeats)
    return [
        ("end-response run (tolerance 1e-3)", parts["run"]),
        ("energy left in the omitted modes (energy_drift)", parts["bookkept"] - parts["run"]),
        ("error estimate's run (tolerance 1e-4, one mode per rod, restitution alone)", parts["estimating"]),
        ("the same run at the requested 100 modes (the estimate's run before; same restitution)",
         parts["estimating, all modes"]),
        ("whole call", parts["whole"]),
        ("the call 6684575 made (static correction, tolerance 1e-2, no estimate), today's code", parts["before"]),
    ]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=30, help="timed calls per part (default 30)")
    parser.add_argument("--update-docs", action="store_true",
                        help=f"also write the tables into the block {DOCS_BLOCK!r} of docs/performance.md")
    args = parser.parse_args(argv)
    if args.update_docs:
        from docs_block import captured_stdout, write_block

        with captured_stdout() as tee:
            _print_tables(args)
        write_block("performance.md", DOCS_BLOCK, tee.copy.getvalue())
        return 0
    _print_tables(args)
    return 0


def _print_tables(args) -> None:
    """Measure and print the two tables."""
    load = os.getloadavg()[0]
    print(f"`python benchmarks/default_cost.py --repeats {args.repeats}`: load average {load:.1f} at the start, "
          f"{os.cpu_count()} cores; CPU ms, median over calls.\n")
    for title, rows in (("collide(0.6, 100, solver='fem', elements=800)", fem_rows(args.repeats)),
                        ("collide(0.6, 100, solver='modal', modes=100)", modal_rows(args.repeats))):
        print(f"| {title} | CPU ms |\n|---|---:|")
        for part, seconds in rows:
            print(f"| {part} | {1e3 * seconds:.2f} |")
        print()
    print(f"load average {os.getloadavg()[0]:.1f} at the end.")


if __name__ == "__main__":
    sys.exit(main())
