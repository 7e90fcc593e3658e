"""Where a README command's first-run compile time goes, kernel by kernel, on an empty numba cache:

    python benchmarks/compile_breakdown.py converge [--top 40] [--tree DIR]

NAME is one of the commands of benchmarks/compile_times.py (same sizes).  The command runs once in a
fresh process with ``NUMBA_CACHE_DIR`` pointing to a new, empty directory (as in compile_times.py),
and every compilation numba makes is recorded from its ``numba:compile`` events (the dispatcher
and the argument types of each specialisation; loading from the cache is not compiling).  numba
compiles the kernels a kernel calls first, each on its own (type inference, lowering, LLVM
optimisation of its module with its own callees linked in, machine code), then the caller, so each
row gives:

- ``own``: CPU time of the kernel's own compilations, its callees' compilations left out (s);
- ``tree``: for a kernel compiled from Python (outermost), the CPU time of the whole compilation,
  callees included (s); ``-`` for a kernel only compiled on the way;
- ``specialisations``: how many argument-type signatures were compiled.

The ``tree`` column sums to the command's compile CPU (the ``compile CPU`` column of
compile_times.py).  CPU times on a shared machine still grow with its load: compare trees in the
same run (``--tree`` for another checkout) and quote the load average printed with the table.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from compile_times import COMMANDS, ROOT, empty_cache_run

_CHILD = """
import json, sys, time
from numba.core import event


class Recorder(event.Listener):
    def __init__(self):
        self.stack, self.rows = [], []

    def on_start(self, ev):
        self.stack.append([ev.data["dispatcher"], time.process_time(), 0.0])

    def on_end(self, ev):
        dispatcher, started, callees = self.stack.pop()
        total = time.process_time() - started
        func = dispatcher.py_func
        self.rows.append({"kernel": func.__module__ + "." + func.__qualname__, "total": total,
                          "own": total - callees, "outermost": not self.stack})
        if self.stack:
            self.stack[-1][2] += total


recorder = Recorder()
event.register("numba:compile", recorder)
from wavecontact.cli import main
status = main(sys.argv[2:])
with open(sys.argv[1], "w") as out:
    json.dump({"status": status, "rows": recorder.rows}, out)
"""


def record(command: str, root: Path = ROOT, timeout: float = 1800.0) -> list:
    """Every compilation of ``wavecontact COMMAND`` on an empty cache: a dict per specialisation."""
    with tempfile.TemporaryDirectory(prefix="wavecontact-breakdown-") as tmp:
        env, report, work = empty_cache_run(tmp, root)
        done = subprocess.run([sys.executable, "-c", _CHILD, str(report), *command.split()], cwd=work, env=env,
                              check=False, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                              timeout=timeout)
        if done.returncode != 0 or not report.is_file():
            raise SystemExit(f"wavecontact {command} failed (exit {done.returncode}):\n{done.stderr[-2000:]}")
        return json.loads(report.read_text())["rows"]


def table(rows: list, top: int) -> list:
    """Markdown lines: one per kernel, largest own time first (``top`` rows), then the totals."""
    kernels = defaultdict(lambda: {"own": 0.0, "tree": 0.0, "count": 0, "outermost": False})
    for row in rows:
        entry = kernels[row["kernel"]]
        entry["own"] += row["own"]
        entry["count"] += 1
        if row["outermost"]:
            entry["tree"] += row["total"]
            entry["outermost"] = True
    lines = ["| kernel | own (s) | tree (s) | specialisations |", "|---|---|---|---|"]
    ranked = sorted(kernels.items(), key=lambda item: -item[1]["own"])
    for name, entry in ranked[:top]:
        tree = f"{entry['tree']:.2f}" if entry["outermost"] else "-"
        lines.append(f"| `{name}` | {entry['own']:.2f} | {tree} | {entry['count']} |")
    if len(ranked) > top:
        rest = sum(entry["own"] for _, entry in ranked[top:])
        lines.append(f"| {len(ranked) - top} more kernels | {rest:.2f} | - | - |")
    total = sum(row["total"] for row in rows if row["outermost"])
    outermost = sum(1 for row in rows if row["outermost"])
    lines.append(f"| **all** ({len(rows)} specialisations of {len(kernels)} kernels, {outermost} compiled from "
                 f"Python) | {total:.2f} | {total:.2f} | {len(rows)} |")
    return lines


def main(argv=None) -> int:
    names = [name for name, _, _ in COMMANDS]
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("name", choices=names, metavar="NAME", help="a command of compile_times.py: " + ", ".join(names))
    parser.add_argument("--top", type=int, default=40, help="kernels listed (default 40; the rest summed)")
    parser.add_argument("--tree", type=Path, default=ROOT, help="the checkout whose package is measured")
    args = parser.parse_args(argv)
    command = {name: line for name, line, _ in COMMANDS}[args.name]
    load = os.getloadavg()[0]
    rows = record(command, args.tree.resolve())
    shown = " ".join(word for word in command.split() if word != "--no-progress")
    print(f"compile CPU of `wavecontact {shown}` on an empty cache, per kernel ({args.tree.resolve()}, "
          f"load {load:.1f})\n")
    print("\n".join(table(rows, args.top)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
