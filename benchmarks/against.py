"""Time this checkout against an older commit, side by side, case by case:

    python benchmarks/against.py REV [--repeats 5] [--only collide-100 ring] [--keep DIR]

REV (any git revision: a commit, a branch, ``HEAD``) is checked out into a temporary directory
(``git archive``, deleted at the end unless ``--keep``; nothing is registered in the repository).
Every case is a small python snippet run in a fresh process against one of the two trees: the package of that tree on
``sys.path``, its own numba cache (warm: each case runs once in each tree before the timed repeats,
so compiling and loading kernels are not timed), the timed statement measured inside the process
with ``time.process_time`` (CPU of the process, less disturbed by other jobs on a shared machine
than wall time) and ``time.perf_counter`` (wall).  The repeats alternate the trees (old, new, new,
old, ...) so a change of the machine's load hits both.

For each case the table gives the median CPU time of each tree, the median over repeats of the
per-repeat ratio new/old, and its spread (half the range of those ratios).  A case is flagged
``SLOWER`` when the median ratio minus the spread exceeds 1.10: slower by more than 10 % beyond the
noise between repeats.  A case the older tree cannot run (a module or option that did not exist
yet) is listed as ``n/a at REV``.  The last column says whether both trees do the same work: a solve
whose result carries an error estimate in this tree but none at REV (trees before the default
Richardson estimate of the FE and modal solvers, e.g. 6684575) is ``more now``: its ratio is what a
user's call costs now against then, not a slowdown of equal work (the ``-once`` cases are its equal-work
twins).  The exit status is 1 if any equal-work case is flagged.

The cases: the README commands' solves (delay at kappa = 100 and inf, FE, modal), the same FE and modal
solves once more without their error estimate (``-once``: ``estimate_error=False`` where the tree has the
option; trees before the default Richardson estimate made only the one run, so these compare equal work,
while the plain cases compare what a user's call costs; the modal one also with ``correction='static'``, the
default before the end-response correction), the FE solve with a new mesh on every call
(``collide-fem-new-mesh``: gamma moves by 1e-6 per call, so no call finds its meshes among the
solver's recent ones, :mod:`wavecontact.fem.reuse`), the ring of Fig. 1
at 1000 collisions, one FE run per discretization (P1/P2, lumped/consistent), an ensemble, a gas
and a Markov chain, at sizes that keep the whole comparison to a few minutes.  Run from the
repository root of the newer tree.
"""

from __future__ import annotations

import argparse
import inspect
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# `collide` without the error estimate's coarser runs where the tree has the option (estimate_error=False)
_ONCE = ("import inspect\nfrom wavecontact import api, collide as _collide\n"
         "_plain = 'estimate_error' in inspect.signature(api.solve).parameters\n"
         "def collide(*args, **kwargs):\n"
         "    return _collide(*args, estimate_error=False, **kwargs) if _plain else _collide(*args, **kwargs)\n")

# the modal solver's static correction where the tree can choose it (correction='static'), else its default
_STATIC = ("try:\n    collide(0.6, 100.0, solver='modal', modes=4, correction='static')\n"
           "    _static = {'correction': 'static'}\nexcept Exception:\n    _static = {}\n")

# name -> (setup, timed statement, repetitions of the statement per process); both run with the
# tree's package first on sys.path.  Keep them to APIs that older commits also have where possible.
CASES = {
    "collide-100": ("from wavecontact import collide", "collide(0.6, 100.0)", 200),
    "collide-inf": ("from wavecontact import collide", "collide(0.6, float('inf'))", 400),
    "collide-fem": ("from wavecontact import collide",
                    "collide(0.6, 100.0, solver='fem', elements=800)", 3),
    "collide-modal": ("from wavecontact import collide", "collide(0.6, 100.0, solver='modal', modes=100)", 3),
    # the FE solve on meshes it has not built before (a gamma sweep): every set-up assembled anew
    "collide-fem-new-mesh": ("import itertools\nfrom wavecontact import collide\n_calls = itertools.count()",
                             "collide(0.6 + 1e-6 * next(_calls), 100.0, solver='fem', elements=800)", 3),
    # the same solves with the error estimate left out where the tree has one (its coarser runs were not
    # made before, so these compare equal work; at trees without the option they run the plain solve)
    "collide-fem-once": (_ONCE, "collide(0.6, 100.0, solver='fem', elements=800)", 3),
    # and the modal solve with the static correction of the omitted modes, the default before the end-response one
    "collide-modal-static-once": (_ONCE + _STATIC, "collide(0.6, 100.0, solver='modal', modes=100, **_static)", 3),
    "fem-P1-lumped-once": (_ONCE, "collide(0.6, 20.0, solver='fem', elements=200, order=1, mass='lumped')", 5),
    "fem-P2-lumped-once": (_ONCE, "collide(0.6, 20.0, solver='fem', elements=100, order=2, mass='lumped')", 5),
    "fem-P1-lumped": ("from wavecontact import collide",
                      "collide(0.6, 20.0, solver='fem', elements=200, order=1, mass='lumped')", 5),
    "fem-P1-consistent": ("from wavecontact import collide",
                          "collide(0.6, 20.0, solver='fem', elements=200, order=1, mass='consistent')", 5),
    "fem-P2-lumped": ("from wavecontact import collide",
                      "collide(0.6, 20.0, solver='fem', elements=100, order=2, mass='lumped')", 5),
    "fem-P2-consistent": ("from wavecontact import collide",
                          "collide(0.6, 20.0, solver='fem', elements=100, order=2, mass='consistent')", 5),
    # the fem multi-body loop on a 3-rod chain (one run, no error estimate; n/a before the multi-body loop)
    "chain-fem-once": (("from wavecontact import Exponential, Rod, Scene\nfrom wavecontact.fem.multibody import "
                        "run_line\n_chain = Scene(rods=(Rod(1.0), Rod(1.0), Rod(1.0)), velocities=(1.0, 0.0, -1.0), "
                        "contact=Exponential(20.0, 0.01))"), "run_line(_chain, elements=200)", 5),
    "ensemble": ("import wavecontact", "wavecontact.ensemble(0.6173, 100.0, 1.0, samples=40, seed=1)", 1),
    "gas": ("import tempfile\nfrom wavecontact.cli import main",
            ("main(['gas', '--rods', '100', '--collisions', '20000', '--rule', 'vibration', '--damping', '50', "
            "'--out', tempfile.mkdtemp() + '/gas', '--no-progress'])"), 1),
    "scene": ("from wavecontact import two_rods", "two_rods(0.6, 100.0)", 2000),  # no kernel: the test's case
    "markov": ("import tempfile\nfrom wavecontact.cli import main",
               ("main(['markov', '--gamma', '0.6', '--chains', '2', '--steps', '2000', '--seed', '1', '--workers', "
               "'1', '--out', tempfile.mkdtemp() + '/markov', '--no-progress'])"), 1),
    # a new --out directory on every run: the ring resumes from a checkpoint it finds there
    "ring-1000": ("import tempfile\nfrom wavecontact.cli import main",
                  ("main(['ring', '--gamma', '0.6173', '--kappa', '4000', '--modes', '75', '--collisions', '1000', "
                  "'--out', tempfile.mkdtemp() + '/ring'])"), 1),
}

# runs in the child: argv = tree, setup, statement, repetitions; prints one JSON line
_CHILD = r"""
import contextlib, io, json, os, sys, time
tree, setup, statement, repetitions = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
sys.path.insert(0, tree)
space = {}
try:
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        exec(setup, space)
        code = compile(statement, "<case>", "eval")
        value = eval(code, space)  # warm: kernels loaded (or compiled) before timing
except (ImportError, AttributeError, TypeError, SystemExit, Exception) as exc:  # the tree cannot run it
    print(json.dumps({"unavailable": f"{type(exc).__name__}: {exc}"[:200]}))
    sys.exit(0)
import wavecontact
assert os.path.realpath(os.path.dirname(wavecontact.__file__)).startswith(os.path.realpath(tree)), wavecontact.__file__
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    wall, cpu = time.perf_counter(), time.process_time()
    for _ in range(repetitions):
        eval(code, space)
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
print(json.dumps({"cpu_s": cpu / repetitions, "wall_s": wall / repetitions, "estimated": estimated(value)}))
"""

def estimated(value):
    """Whether a statement's value is one collision's result carrying an error estimate (True), one without
    (False: None at trees before the estimate, NaN with ``estimate_error=False``) or no single result (None).
    The child runs this same function (its source is prepended to the child's)."""
    import math

    estimate = getattr(value, "error_estimate", None)
    if not hasattr(value, "restitution") or not (estimate is None or isinstance(estimate, (int, float))):
        return None
    return estimate is not None and not math.isnan(estimate)


_CHILD = inspect.getsource(estimated) + _CHILD



#: the block of docs/performance.md that ``--update-docs`` writes
DOCS_BLOCK = "against-old-commit"

#: A case is flagged when its median ratio new/old minus the spread exceeds this.
SLOWER_THAN = 1.10


def judge(ratios) -> tuple:
    """``(median ratio, spread, slower)`` of per-repeat ratios new/old; the spread is half their range and a
    case is slower when the median minus the spread exceeds :data:`SLOWER_THAN`."""
    ratio = statistics.median(ratios)
    spread = (max(ratios) - min(ratios)) / 2.0
    return ratio, spread, ratio - spread > SLOWER_THAN

def regressions(rows) -> list:
    """Names of the flagged cases that do the same work in both trees (the ones that set the exit status)."""
    return [row["case"] for row in rows if row.get("slower") and row.get("work", "equal") == "equal"]


def run_case(tree: Path, name: str, timeout: float = 900.0) -> dict:
    """One process: the case ``name`` against the package in ``tree``; its CPU and wall time per statement (s)."""
    setup, statement, repetitions = CASES[name]
    env = {key: value for key, value in os.environ.items() if key not in ("PYTHONPATH", "WAVECONTACT_PURE_PYTHON")}
    env["MPLBACKEND"] = "Agg"
    with tempfile.TemporaryDirectory(prefix="wavecontact-against-") as work:
        done = subprocess.run([sys.executable, "-c", _CHILD, str(tree), setup, statement, str(repetitions)], check=False,
                              cwd=work, env=env, capture_output=True, text=True, timeout=timeout)
    if done.returncode != 0:
        raise SystemExit(f"case {name} failed in {tree} (exit {done.returncode}):\n{done.stderr[-2000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def compare(old: Path, new: Path, names, repeats: int, report=None) -> list:
    """Warm-up run per tree and case, then ``repeats`` alternating timed runs; one summary dict per case
    (``report(row)``, if given, is called as soon as a case is done)."""
    rows = []
    for name in names:
        first = {"old": run_case(old, name), "new": run_case(new, name)}
        unavailable = first["old"].get("unavailable") or first["new"].get("unavailable")
        if unavailable:
            rows.append({"case": name, "unavailable": "old" if first["old"].get("unavailable") else "new",
                         "why": unavailable})
            if report:
                report(rows[-1])
            continue
        # more work now: this tree's result carries an error estimate, the older one's none
        more = first["new"].get("estimated") is True and first["old"].get("estimated") is False
        times = {"old": [], "new": []}
        ratios = []
        for repeat in range(repeats):
            order = ("old", "new") if repeat % 2 == 0 else ("new", "old")
            got = {}
            for which in order:
                got[which] = run_case(old if which == "old" else new, name)["cpu_s"]
                times[which].append(got[which])
            ratios.append(got["new"] / got["old"])
        ratio, spread, slower = judge(ratios)
        rows.append({"case": name, "old_s": statistics.median(times["old"]), "new_s": statistics.median(times["new"]),
                     "ratio": ratio, "spread": spread, "slower": slower, "work": "more" if more else "equal"})
        if report:
            report(rows[-1])
    return rows


def table_header(rev: str) -> str:
    return (f"| case | CPU at {rev} | CPU now | ratio now/{rev} (median) | spread | flag | work |\n"
            "|---|---|---|---|---|---|---|")


def table_row(row, rev: str) -> str:
    if "unavailable" in row:
        where = f"n/a at {rev}" if row["unavailable"] == "old" else "n/a now"
        return f"| {row['case']} | | | | | {where} | |"
    work = "equal" if row.get("work", "equal") == "equal" else f"more now: an error estimate, none at {rev}"
    return (f"| {row['case']} | {_time(row['old_s'])} | {_time(row['new_s'])} | {row['ratio']:.3f} | "
            f"{row['spread']:.3f} | {'SLOWER' if row['slower'] else ''} | {work} |")


def _time(seconds: float) -> str:
    if seconds < 1.0:
        return f"{1e3 * seconds:#.3g}".rstrip(".") + " ms"
    return f"{seconds:#.3g}".rstrip(".") + " s"


def export(rev: str, where: Path) -> Path:
    """The tree of ``rev`` written into the new directory ``where`` (``git archive``); its path.

    An export rather than ``git worktree add``: nothing is registered in the repository, so
    concurrent runs (or an interrupted one) leave no worktree entries behind.
    """
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", "--format=tar", rev], capture_output=True, check=False)
    if archive.returncode != 0:
        raise SystemExit(f"against.py: error: git archive {rev}: {archive.stderr.decode().strip()}")
    where.mkdir(parents=True)
    subprocess.run(["tar", "-x", "-C", str(where)], input=archive.stdout, check=True)
    return where


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rev", help="the older revision (commit, branch, tag, HEAD~3, ...)")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per tree and case (default 5)")
    parser.add_argument("--only", nargs="+", choices=sorted(CASES), metavar="CASE",
                        help="run only these cases (" + ", ".join(CASES) + ")")
    parser.add_argument("--keep", metavar="DIR", help="check REV out into DIR and leave it there (an existing DIR is "
                        "reused as it is, with its warm numba cache)")
    parser.add_argument("--json", action="store_true", help="print the rows as JSON after the table")
    parser.add_argument("--update-docs", action="store_true", help="also write what it printed into the block "
                        f"{DOCS_BLOCK!r} of docs/performance.md (the comparison with an older commit)")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    if args.update_docs:
        sys.path.insert(0, str(ROOT / "benchmarks"))
        from docs_block import captured_stdout, write_block

        with captured_stdout() as tee:
            status = _compare_and_print(args)
        write_block("performance.md", DOCS_BLOCK, tee.copy.getvalue())
        return status
    return _compare_and_print(args)


def _compare_and_print(args) -> int:
    """Run the comparison ``args`` ask for and print its table; the exit status."""
    names = args.only or list(CASES)
    load = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="wavecontact-rev-") as tmp:
        if args.keep and Path(args.keep).is_dir():
            old = Path(args.keep).resolve()
        else:
            old = export(args.rev, Path(args.keep).resolve() if args.keep else Path(tmp) / "old")
        print(f"`python benchmarks/against.py {args.rev} --repeats {args.repeats}`: load average {load[0]:.1f} at "
              f"the start, {os.cpu_count()} cores; CPU time per statement, median over repeats.\n")
        print(table_header(args.rev), flush=True)
        rows = compare(old, ROOT, names, args.repeats, lambda row: print(table_row(row, args.rev), flush=True))
    print(f"\nload average {os.getloadavg()[0]:.1f} at the end.")
    if any("unavailable" in row for row in rows):
        print("n/a: " + "; ".join(f"{row['case']}: {row['why']}" for row in rows if "unavailable" in row))
    more = [row["case"] for row in rows if row.get("work") == "more"]
    if more:
        print(f"more work now than at {args.rev} (each result carries an error estimate, {args.rev}'s none; "
              f"their equal-work twins are the -once cases): " + ", ".join(more))
    if args.json:
        print(json.dumps(rows))
    return 1 if regressions(rows) else 0


if __name__ == "__main__":
    sys.exit(main())
