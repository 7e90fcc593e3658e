"""``wavecontact gas``: an event-driven gas of rods with a fixed or a vibration-drawn restitution."""

from __future__ import annotations

import argparse
import json
import math
import sys
from contextlib import contextmanager
from pathlib import Path

from .common import nonnegative_int, positive_int, report_written
from .guard import check_outputs

CHECKPOINT_NAME = "gas_checkpoint.npz"
FIGURE_NAME = "gas.png"


def _fraction(name, low_open=True):
    def parse(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number, got {text!r}") from None
        ok = (0.0 < value < 1.0) if low_open else (0.0 <= value <= 1.0)
        if not ok:
            raise argparse.ArgumentTypeError(f"{name} must lie in {'(0, 1)' if low_open else '[0, 1]'}, got {text!r}")
        return value

    return parse


def _positive(name):
    def parse(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a positive number, got {text!r}") from None
        if not (math.isfinite(value) and value > 0):
            raise argparse.ArgumentTypeError(f"{name} must be a finite number > 0, got {text!r}")
        return value

    return parse



def add_parser(subparsers):
    p = subparsers.add_parser(
        "gas",
        help="event-driven gas of rods: energy decay, clusters, inelastic collapse (paper Sec. VIII)",
        description="N rods on a ring (or between walls) with random lengths and Maxwellian velocities. "
        "Each collision takes eps from a fixed value (--rule fixed) or draws eps^2 and the split of the lost "
        "energy between the rods' vibration baths from the hard-core collision law, which covers every pair state "
        "(--rule vibration), or from a restitution table (--table). Stops after "
        "COLLISIONS collisions, or earlier with a message on an inelastic collapse.",
    )
    p.add_argument("--rods", type=positive_int, required=True, help="number of rods N >= 2")
    p.add_argument("--collisions", type=positive_int, required=True, help="rod-rod collisions to simulate")
    p.add_argument("--rule", choices=("vibration", "fixed"), required=True, help="collision rule")
    p.add_argument("--restitution", type=_fraction("restitution", low_open=False),
                   help="eps of the fixed rule, in [0, 1] (no default: required with --rule fixed)")
    p.add_argument("--table", metavar="FILE",
                   help="restitution table (.npz/.json, T_B/E_tr grid) for the vibration rule instead of the "
                   "default hard-core collision law; a gas state outside its grid stops the run with a message")
    p.add_argument("--law", metavar="FILE",
                   help="collision law (.npz, wavecontact.gas.collision_law) of the vibration rule (default: "
                   "the hard-core law shipped in wavecontact/data)")
    p.add_argument("--contact-stiffness", type=_positive("contact-stiffness"), metavar="ALPHA",
                   help="alpha of the exponential contact V(r) = B exp(-alpha r), an inverse length in the units of "
                   "the rod lengths (vibration rule only): each collision then has its own softness kappa = alpha V l "
                   "(V the approach speed, l = 2 l_i l_j/(l_i + l_j), wave speed 1): the hard-core draw plus the soft "
                   "(finite-kappa) law's correction at that kappa; softer than the soft law's softest row (kappa 5) "
                   "that row's correction (counted as softer_than_law) (default: none, every collision in the hard-core limit)")
    p.add_argument("--damping", type=_positive("damping"), metavar="TAU",
                   help="relaxation time tau_diss of the baths (default: no dissipation)")
    p.add_argument("--seed", type=nonnegative_int, default=0, help="root seed (default 0)")
    p.add_argument("--lengths", type=_length, nargs=2, metavar=("SHORTEST", "LONGEST"),
                   default=(0.6, 1.0), help="rod lengths uniform in [SHORTEST, LONGEST] (default 0.6 1.0)")
    p.add_argument("--packing", type=_fraction("packing"), default=0.2,
                   help="total rod length over system length, in (0, 1) (default 0.2)")
    p.add_argument("--walls", action="store_true", help="a box with elastic walls instead of a ring")
    p.add_argument("--continue-after-collapse", action="store_true",
                   help="do not stop at a detected inelastic collapse: report where it was detected and go on with "
                   "the detector off, to see what happens next (a new run only; a resumed run keeps its setting)")
    p.add_argument("--out", metavar="DIR", help="write summary, histories, figure and a checkpoint into DIR")
    p.add_argument("--resume", action="store_true",
                   help=f"continue the run checkpointed in DIR/{CHECKPOINT_NAME} by COLLISIONS more collisions (an "
                   "interrupted run: COLLISIONS counted from where it began, so the same command finishes it); the "
                   "other options must be those of the checkpointed run")
    p.add_argument("--overwrite", action="store_true",
                   help=f"replace a checkpoint ({CHECKPOINT_NAME}) of another run found in DIR instead of refusing")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.add_argument("--no-progress", dest="progress", action="store_false", help="no progress bar")
    p.set_defaults(run=run)
    return p


def _length(text: str) -> float:
    """``--lengths``: a magnitude in the range every physical input takes (:data:`wavecontact.errors.MAGNITUDE_RANGE`)."""
    from ..errors import MAGNITUDE_RANGE

    value = _positive("lengths")(text)
    low, high = MAGNITUDE_RANGE
    if not low <= value <= high:
        raise argparse.ArgumentTypeError(f"lengths must lie in [{low:g}, {high:g}] (any consistent units; times and "
                                         f"energies computed from them leave the double range outside), got {text!r}")
    return value


#: What ``--out DIR`` holds.
OUT_FILES = ("gas_history.npz", "gas_summary.json", CHECKPOINT_NAME, FIGURE_NAME)


def _rule(args):
    from ..errors import InvalidParameterError
    from ..gas import FixedRestitution, VibrationLaw, VibrationTable, default_law, default_soft_law, load_law

    if args.rule == "fixed":
        if args.restitution is None:
            raise InvalidParameterError("--rule fixed needs --restitution E with E in [0, 1]")
        if args.contact_stiffness is not None:
            raise InvalidParameterError("--contact-stiffness applies to --rule vibration only")
        return FixedRestitution(args.restitution)
    if args.restitution is not None:
        raise InvalidParameterError("--restitution applies to --rule fixed only (the vibration rule draws eps)")
    if args.table and args.law:
        raise InvalidParameterError("pass either --table or --law, not both")
    if args.table:
        if args.contact_stiffness is not None:
            raise InvalidParameterError("--contact-stiffness needs the collision law, not --table")
        from ..restitution_table import load

        return VibrationTable(load(args.table))
    soft = default_soft_law() if args.contact_stiffness is not None else None
    return VibrationLaw(load_law(args.law) if args.law else default_law(), soft)


def _check_resumed(args, rule):
    """Refuse ``--resume`` with options that contradict the checkpointed run."""
    import numpy as np

    from ..errors import InvalidParameterError
    from ..gas import UniformLengths, random_gas

    def check(sim):
        params = sim._parameters()
        if sim.gas.rods != args.rods:
            raise InvalidParameterError(f"--resume: the checkpoint holds {sim.gas.rods} rods, not --rods {args.rods}")
        if (params["boundary"] == "walls") != bool(args.walls):
            raise InvalidParameterError(f"--resume: the checkpointed run has {params['boundary']} boundaries "
                                        f"({'with' if params['boundary'] == 'walls' else 'without'} --walls)")
        if params["seed_entropy"] != str(args.seed):
            raise InvalidParameterError(f"--resume: the checkpoint was written with --seed {params['seed_entropy']}, "
                                        f"not {args.seed}")
        if sim.damping != args.damping:
            raise InvalidParameterError(f"--resume: the checkpoint was written with --damping {sim.damping}, "
                                        f"not {args.damping}")
        if sim.rule.describe() != rule.describe():
            raise InvalidParameterError(f"--resume: the checkpoint was written with {sim.rule.describe()}, "
                                        f"not {rule.describe()}")
        if sim.contact_stiffness != args.contact_stiffness:
            raise InvalidParameterError(f"--resume: the checkpoint was written with --contact-stiffness "
                                        f"{sim.contact_stiffness}, not {args.contact_stiffness}")
        gas = random_gas(args.rods, seed=np.random.SeedSequence(args.seed).spawn(2)[0],
                         lengths=UniformLengths(*args.lengths), packing_fraction=args.packing,
                         boundary="walls" if args.walls else "ring")
        if not (np.array_equal(gas.lengths, sim.gas.lengths) and gas.system_length == sim.gas.system_length):
            raise InvalidParameterError("--resume: --lengths/--packing differ from those of the checkpointed run")

    return check


def _figure_title(summary: dict) -> str:
    """The run's parameters for the figure: rods, rule, damping, seed."""
    rule = summary["rule"] if isinstance(summary["rule"], dict) else {"rule": summary["rule"]}
    rule = ", ".join(f"{key} {rule[key]}" for key in ("rule", "restitution", "kappa", "bath_modes") if key in rule)
    damping = "no damping" if summary["damping"] is None else f"damping tau = {summary['damping']:g}"
    return f"{summary['rods']} rods, {rule}, {damping}, seed {summary['seed']}"


@contextmanager
def _compile_timer():
    """``[seconds]`` that numba spends compiling inside the block (not loading kernels from its cache, which
    fires no compile event); stays 0 without numba."""
    seconds = [0.0]
    try:
        from numba.core import event
    except ImportError:
        yield seconds
        return
    with event.install_timer("numba:compile", lambda duration: seconds.__setitem__(0, duration)):
        yield seconds


def run(args) -> int:
    from ..errors import InvalidParameterError
    from ..gas import GasSimulation, UniformLengths, random_gas
    from ..gas.simulation import MAX_COLLISIONS, run_gas
    from ..result import to_jsonable

    out = Path(args.out) if args.out else None
    if args.collisions > MAX_COLLISIONS:
        raise InvalidParameterError(f"--collisions must be at most {MAX_COLLISIONS:.0e} per run, got {args.collisions}; "
                                    "continue a run in pieces with --out DIR and --resume")
    check_outputs(directories=[("--out", args.out, OUT_FILES)])
    rule = _rule(args)
    shortest, longest = args.lengths
    if longest < shortest:
        raise InvalidParameterError(f"--lengths: LONGEST ({longest:g}) must be >= SHORTEST ({shortest:g})")
    if args.resume and out is None:
        raise InvalidParameterError(f"--resume needs --out DIR holding {CHECKPOINT_NAME}")

    def new_simulation():
        import numpy as np

        initial, dynamics = np.random.SeedSequence(args.seed).spawn(2)
        gas = random_gas(args.rods, seed=initial, lengths=UniformLengths(shortest, longest),
                         packing_fraction=args.packing, boundary="walls" if args.walls else "ring")
        return GasSimulation(gas, rule, damping=args.damping, contact_stiffness=args.contact_stiffness, seed=dynamics,
                             record_every=max(1, args.collisions // 400), frame_every=1, max_frames=400,
                             continue_after_collapse=args.continue_after_collapse)

    def write_outputs(sim, result):
        from ..plotting.gas import plot_gas

        result.save(out)
        title = _figure_title({"rods": sim.gas.rods, **result.summary(), "damping": args.damping, "seed": args.seed})
        plot_gas(result, out / FIGURE_NAME, system_length=sim.gas.system_length, title=title)

    from .._jit import prepared_kernel_count

    prepared = prepared_kernel_count()
    with _compile_timer() as compiling:
        sim, result = run_gas(new_simulation, args.collisions, out, resume=args.resume, overwrite=args.overwrite,
                              check_resumed=_check_resumed(args, rule), write_outputs=write_outputs,
                              progress=args.progress and sys.stderr.isatty(),
                              log=lambda message: print(f"wavecontact gas: {message}", file=sys.stderr, flush=True))
    summary = {"rods": sim.gas.rods, **result.summary(), "damping": args.damping, "seed": args.seed,
               # True when this call paid numba's one-time compilation or cache load (slower rate)
               "includes_kernel_preparation": prepared_kernel_count() > prepared,
               # of the wall time, the seconds numba spent compiling (0 when the kernels came from its cache)
               "kernel_compile_s": compiling[0]}
    written = [] if out is None else [out / name for name in OUT_FILES if (out / name).is_file()]
    summary["files_written"] = report_written(written)
    if result.status not in ("completed",):
        print(f"wavecontact gas: {result.message}", file=sys.stderr)
    if args.json:
        print(json.dumps(to_jsonable(summary), indent=2))
    else:
        print(f"{summary['rods']} rods, rule {args.rule}: {result.message}")
        print(f"  collisions            {result.collisions}")
        print(f"  simulated time        {result.simulated_time:.6g}")
        note = ""
        if compiling[0] > 0:
            note = f", of which {compiling[0]:.3g} s compiling numba's kernels"
        elif summary["includes_kernel_preparation"]:
            note = ", kernels loaded from numba's cache"
        print(f"  collisions per second {result.collisions_per_second:.4g} (wall time {result.wall_time_s:.3g} s{note})")
        print(f"  final kinetic energy  {result.final_energy:.6g}")
        print(f"  collapsed             {result.collapsed}")
        if result.collapse is not None and not result.collapsed:
            print(f"  collapse detected     at collision {result.collapse['collision']} (t = "
                  f"{result.collapse['time']:.6g}, a cluster of {result.collapse['cluster_rods']} rods); went on")
        if args.rule == "vibration":
            print(f"  bath-limited draws    {result.bath_limited} ({summary['bath_limited_fraction']:.3g} of all)")
            if args.contact_stiffness is not None:
                print(f"  contact stiffness     alpha = {args.contact_stiffness:g}; draws softer than the soft law: "
                      f"{result.softer_than_law}")
    return 0
