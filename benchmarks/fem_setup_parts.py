"""What an FE set-up on a mesh not seen before costs, step by step, at the default call's three meshes:

    python benchmarks/fem_setup_parts.py [--repeats 200]

For ``collide(0.6 + small, 100, solver='fem', elements=N)`` at N = 800 (the requested run) and 400, 200
(the error estimate's): the discretization of each rod (:func:`wavecontact.fem.discretization.discretize_rod`:
assembly, renumbering, lumping, bands), the stable step of the pair
(:func:`wavecontact.fem.stability.stable_step`), the whole set-up on a new mesh
(:func:`wavecontact.fem.simulation.build_setup` with the kept meshes forgotten first, so the reuse
bookkeeping is in it) and on a kept mesh.  CPU time of this process, median over ``--repeats`` calls, after
one untimed call.  Run it with another checkout first on ``sys.path`` (``PYTHONPATH=/other/tree``) for the
same table of that tree: the steps' functions have had these names since the reuse of meshes came in.
"""

from __future__ import annotations

import argparse
import statistics
import time


def _median_ms(call, repeats: int) -> float:
    call()
    times = []
    for _ in range(repeats):
        start = time.process_time()
        call()
        times.append(time.process_time() - start)
    return 1e3 * statistics.median(times)


def rows(repeats: int) -> list:
    """``(elements, step, ms)`` of the set-up's steps."""
    from wavecontact import two_rods
    from wavecontact.fem import reuse
    from wavecontact.fem.discretization import discretize_rod
    from wavecontact.fem.simulation import build_setup
    from wavecontact.fem.stability import stable_step

    scene = two_rods(0.6, 100.0)
    out = []
    for elements in (800, 400, 200):
        setup = build_setup(scene, elements=elements)
        left, right = setup.rods
        # the vertices the solver meshed: element end points (P1, matched: the nodes themselves)
        parts = {
            f"discretize_rod, short rod ({left.n_nodes} nodes)":
                lambda d=left: discretize_rod(d.rod, d.x[d.cells[:, 0].tolist() + [d.cells[-1, 1]]], 1, "lumped",
                                              "left"),
            f"discretize_rod, long rod ({right.n_nodes} nodes, far end point mass)":
                lambda d=right: discretize_rod(d.rod, d.x[d.cells[:, 0].tolist() + [d.cells[-1, 1]]], 1, "lumped",
                                               "right"),
            "stable_step of the pair": lambda rods=setup.rods: stable_step(rods),
            "build_setup, new mesh": lambda e=elements: (reuse.clear(), build_setup(scene, elements=e)),
            "build_setup, kept mesh": lambda e=elements: build_setup(scene, elements=e),
        }
        for name, call in parts.items():
            out.append((elements, name, _median_ms(call, repeats)))
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=200, help="timed calls per step (default 200)")
    args = parser.parse_args(argv)
    import wavecontact

    with open("/proc/loadavg") as handle:
        load = handle.read().split()[0]
    print(f"`python benchmarks/fem_setup_parts.py --repeats {args.repeats}` ({wavecontact.__file__}), "
          f"load average {load}; CPU ms, median over calls.\n")
    print("| elements | step | CPU ms |\n|---|---|---:|")
    for elements, name, ms in rows(args.repeats):
        print(f"| {elements} | {name} | {ms:.3f} |")


if __name__ == "__main__":
    main()
