"""Compile time of each README command's first run on an empty numba cache, one subprocess per command:

    python benchmarks/compile_times.py [--only collide-100 collide-inf] [--update-docs]

Each command runs in a fresh process with ``NUMBA_CACHE_DIR`` pointing to a new, empty directory
(numba then neither reads nor writes the package's own ``__pycache__`` kernels; see
wavecontact/_jit.py), in a temporary working directory that receives its output files.  The child
measures the time numba spent compiling (``wavecontact._jit.CompileClock``: wall and CPU time of
the outermost compilations; loading from the cache is not compiling) and when the command first
prints to standard output (its answer, for ``collide``) with how long numba had compiled by then (a
short ``collide`` runs its kernels interpreted and compiles them after the answer:
:func:`wavecontact._jit.answer_first`); the parent measures the child's whole wall time and its CPU
time (``resource.getrusage(RUSAGE_CHILDREN)``).  The machine's
load average is printed with each row: on a shared machine the wall times grow with the load, the
CPU times much less.

Compile time does not depend on a run's size, so the long commands run at small sizes (the
README's ``--collisions 4500`` ring with 40 collisions, and so on; the ``size`` column says what
was changed) and with ``--workers 1`` (with more workers every worker process compiles on its
own, at the same time).  ``paper-figures`` compiles what the commands above compile and is left out.
``--update-docs`` writes the table into docs/performance.md (block ``compile-times``).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from docs_block import DOCS, captured_stdout, run_and_write, run_header, write_block

ROOT = Path(__file__).resolve().parent.parent

# (name, README command line after ``wavecontact``, what this benchmark changed to keep it short)
COMMANDS = (
    ("collide-100", "collide --gamma 0.6 --kappa 100", ""),
    ("collide-json", "collide --gamma 0.6 --kappa 100 --json", ""),
    ("collide-plot", "collide --gamma 0.6 --kappa 5 --plot w.png", ""),
    ("collide-inf", "collide --gamma 0.6 --kappa inf", ""),
    ("collide-fem", "collide --solver fem --gamma 0.6 --kappa 100 --elements 800 --xt-plot xt.png --fields out/", ""),
    ("converge", "converge --gamma 0.6 --kappa 20 --order 1 2 --mass lumped consistent --elements 25 50 100 200", ""),
    ("compare", "compare --gamma 0.6 --kappa 100 --plot pareto.png --repeats 1 --no-progress", "--repeats 1"),
    ("ring", "ring --gamma 0.6173 --kappa 4000 --modes 75 --collisions 40 --out ring/ --no-progress",
     "--collisions 40 (README 4500)"),
    ("equipartition", ("equipartition --gamma 0.6173 --kappa 4000 --modes 10 20 --collisions 20 --realisations 1 "
     "--out eq/ --no-progress"), "--modes 10 20 --collisions 20 --realisations 1"),
    ("markov", "markov --gamma 0.6 --chains 2 --steps 200 --seed 1 --workers 1 --json --no-progress",
     "--chains 2 --steps 200 --workers 1"),
    ("ensemble", ("ensemble --gamma 0.6173 --kappa 100 --temperature 1 --samples 8 --seed 1 --workers 1 --json "
     "--no-progress"), "--samples 8 --workers 1"),
    ("bath-figure", "bath-figure 8 --samples 8 --workers 1 --out fig8.png --no-progress", "--samples 8 --workers 1"),
    ("restitution-table", ("restitution-table --gamma 0.2173 0.6173 --temperature 0 0.5 1 --samples 8 --seed 1 "
     "--workers 1 --out t.csv --no-progress"), "--samples 8 --workers 1"),
    ("gas", "gas --rods 50 --collisions 2000 --rule vibration --damping 50 --out gas/ --no-progress",
     "--rods 50 --collisions 2000"),
    ("map", "map --kappa inf 100 --out map/ --workers 1 --no-progress", "--workers 1"),
)

# the child: its own listener (not wavecontact._jit.CompileClock) so that it measures any checkout
_CHILD = """
import json, sys, time
started = time.perf_counter()
from numba.core import event


class Clock(event.Listener):
    depth, wall, cpu, count = 0, 0.0, 0.0, 0

    def on_start(self, ev):
        self.depth += 1
        if self.depth == 1:
            self.count += 1
            self.started = (time.perf_counter(), time.process_time())

    def on_end(self, ev):
        self.depth -= 1
        if self.depth == 0:
            self.wall += time.perf_counter() - self.started[0]
            self.cpu += time.process_time() - self.started[1]


class FirstAnswer:  # standard output that notes when the command first prints, and how long numba had compiled

    def __init__(self, stream):
        self.stream, self.at = stream, None

    def write(self, text):
        if self.at is None and text.strip():
            self.at = (time.perf_counter() - started, clock.wall)
        return self.stream.write(text)

    def __getattr__(self, name):
        return getattr(self.stream, name)


clock = Clock()
event.register("numba:compile", clock)
sys.stdout = FirstAnswer(sys.stdout)
from wavecontact.cli import main
status = main(sys.argv[2:])
answer = sys.stdout.at or (time.perf_counter() - started, clock.wall)
record = {"status": status, "compile_wall_s": clock.wall, "compile_cpu_s": clock.cpu,
          "compilations": clock.count, "wall_s": time.perf_counter() - started,
          "answer_s": answer[0], "compile_before_answer_s": answer[1]}
with open(sys.argv[1], "w") as out:
    json.dump(record, out)
"""


def empty_cache_run(tmp: str, root: Path) -> tuple:
    """``(env, report, work)`` of a child run in the scratch directory ``tmp``: the package of ``root`` first on
    its path, numba compiling (never loading) into an empty cache there; its record file and working directory."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(Path(tmp) / "numba-cache"),
               PYTHONPATH=os.pathsep.join(filter(None, (str(root), os.environ.get("PYTHONPATH")))))
    env.pop("WAVECONTACT_PURE_PYTHON", None)
    work = Path(tmp) / "work"
    work.mkdir()
    return env, Path(tmp) / "record.json", work


def first_run(command: str, root: Path = ROOT, timeout: float = 1800.0) -> dict:
    """Run ``wavecontact COMMAND`` once with an empty numba cache; its compile and whole times (s)."""
    with tempfile.TemporaryDirectory(prefix="wavecontact-compile-") as tmp:
        env, report, work = empty_cache_run(tmp, root)
        load = os.getloadavg()[0]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        started = time.perf_counter()
        done = subprocess.run([sys.executable, "-c", _CHILD, str(report), *command.split()], cwd=work, env=env, check=False,
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, timeout=timeout)
        wall = time.perf_counter() - started
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if done.returncode != 0 or not report.is_file():
            raise SystemExit(f"wavecontact {command} failed (exit {done.returncode}):\n{done.stderr[-2000:]}")
        record = json.loads(report.read_text())
        record.update(process_wall_s=wall, process_cpu_s=(after.ru_utime - before.ru_utime)
                      + (after.ru_stime - before.ru_stime), load=load,
                      announced="compiling numba kernels" in done.stderr)
        return record


def seconds(value: float) -> str:
    """3 significant digits in s."""
    return f"{value:#.3g}".rstrip(".")


def measure(names=None, root: Path = ROOT) -> list:
    """Print the table (markdown) of the chosen commands (default: all) of the package in ``root``."""
    print("| command (`wavecontact ...`) | first output after (s) | compiled before it, wall (s) | compile wall (s) "
          "| compile CPU (s) | whole run wall (s) | whole run CPU (s) | load | size changed |")
    print("|---|---|---|---|---|---|---|---|---|")
    records = []
    for name, command, size in COMMANDS:
        if names and name not in names:
            continue
        record = first_run(command, root)
        records.append((name, record))
        shown = " ".join(word for word in command.split() if word != "--no-progress")
        print(f"| `{shown}` | {seconds(record['answer_s'])} | {seconds(record['compile_before_answer_s'])} | "
              f"{seconds(record['compile_wall_s'])} | {seconds(record['compile_cpu_s'])} | "
              f"{seconds(record['process_wall_s'])} | {seconds(record['process_cpu_s'])} | {record['load']:.1f} | "
              f"{size} |", flush=True)
    return records


SECTION = """## Compile time of a first run

numba compiles the kernels a command needs the first time it runs and caches them on disk; later
runs load them (a few hundred ms on a quiet machine).  A short `collide` (the delay equation at
kappa >= 5, the hard core) does not wait for them: on an empty cache it answers from its kernels run
as plain Python (the same bits, tests/test_jit_interpreted.py), then compiles them for the next runs
(the hard core's recursion, a millisecond of Python, is not compiled at all).  The first run of each
README command on an empty cache (`python benchmarks/compile_times.py`; the table is its output,
`--update-docs` rewrites it alone, `--tree DIR` measures another checkout, e.g. an older commit, for a
before/after): when it first printed to standard output (its answer; a command that writes files
prints its summary last) and how long numba had compiled by then, and the whole run.  The CPU columns
are the ones to compare between runs: on a loaded machine the wall times grow with the load (column
`load`), the CPU times much less.
"""


def compile_section() -> str:
    """The section of docs/performance.md: heading, prose and the marked block with a fresh table."""
    from docs_block import captured_stdout, run_header

    header = run_header([str(Path(__file__).resolve())])
    with captured_stdout() as tee:
        measure()
    table = tee.copy.getvalue().strip()
    return f"{SECTION}\n<!-- compile-times:start -->\n{header}\n\n{table}\n<!-- compile-times:end -->"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", choices=[name for name, _c, _s in COMMANDS], metavar="NAME",
                        help="run only these commands (names: " + ", ".join(name for name, _c, _s in COMMANDS) + ")")
    parser.add_argument("--tree", type=Path, default=ROOT,
                        help="the checkout whose package is measured (default: this one), e.g. an older commit's")
    parser.add_argument("--update-docs", action="store_true",
                        help="write the table into docs/performance.md (block compile-times)")
    args = parser.parse_args(argv)
    if args.only and args.update_docs:  # rewrite these rows only; the others keep their run's numbers
        header = run_header(argv and [str(Path(__file__).resolve()), *argv])
        with captured_stdout() as tee:
            measure(args.only, args.tree.resolve())
        write_block("performance.md", "compile-times", merged_rows(read_block("performance.md", "compile-times"),
                                                                   tee.copy.getvalue(), header))
        return
    run_and_write(lambda: measure(args.only, args.tree.resolve()), "performance.md", "compile-times",
                  args.update_docs)


def read_block(page: str, name: str) -> str:
    """The text between a block's markers on docs/``page``."""
    text = (DOCS / page).read_text(encoding="utf-8")
    return text.split(f"<!-- {name}:start -->\n", 1)[1].split(f"<!-- {name}:end -->", 1)[0]


def merged_rows(block: str, fresh: str, header: str) -> str:
    """``block`` with each of its table rows that ``fresh`` measured again replaced (new ones appended), and
    ``header`` (the rerun's command and load) added under the block's first line."""
    rows = {line.split(" | ", 1)[0]: line for line in fresh.splitlines() if line.startswith("| `")}
    remeasured = _only_names(header)
    lines = [rows.pop(line.split(" | ", 1)[0], line) if line.startswith("| `") else line
             for line in block.strip().splitlines()
             # an older header whose rows were all measured again describes none of the table any more
             if not (line.startswith("The rows of ") and _only_names(line) <= remeasured)]
    lines[1:1] = [f"The rows of {header}"]
    return "\n".join(lines + list(rows.values()))


def _only_names(header: str) -> set:
    """The case names after ``--only`` in a header line (empty for a line without ``--only``)."""
    command = header.split("`")[1] if header.count("`") >= 2 else header
    return set(command.split("--only", 1)[1].split()) if "--only" in command else set()


if __name__ == "__main__":
    main()
