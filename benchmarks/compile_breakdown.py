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
- ``of which LLVM``: the part of ``own`` spent in LLVM (optimisation passes and machine code, timed
  around numba's code library methods; the rest is numba's own Python: type inference, lowering);
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
from numba.core import codegen, event


class Recorder(event.Listener):
    def __init__(self):
        self.stack, self.rows = [], []
        self.llvm = {"function passes": 0.0, "module passes": 0.0, "machine code": 0.0}

    def on_start(self, ev):
        self.stack.append([ev.data["dispatcher"], time.process_time(), 0.0, 0.0])

    def on_end(self, ev):
        dispatcher, started, callees, llvm = self.stack.pop()
        total = time.process_time() - started
        func = dispatcher.py_func
        self.rows.append({"kernel": func.__module__ + "." + func.__qualname__, "total": total,
                          "own": total - callees, "llvm": llvm, "outermost": not self.stack})
        if self.stack:
            self.stack[-1][2] += total

    def timed(self, cls, name, phase):
        original = getattr(cls, name)

        def run(library, *args, **kwargs):
            started = time.process_time()
            try:
                return original(library, *args, **kwargs)
            finally:
                if self.stack:  # compiling (loading from the cache makes no machine code worth counting)
                    spent = time.process_time() - started
                    self.stack[-1][3] += spent
                    self.llvm[phase] += spent

        setattr(cls, name, run)


recorder = Recorder()
recorder.timed(codegen.CPUCodeLibrary, "_optimize_functions", "function passes")
recorder.timed(codegen.CPUCodeLibrary, "_optimize_final_module", "module passes")
recorder.timed(codegen.JITCodeLibrary, "_finalize_specific", "machine code")
event.register("numba:compile", recorder)
from wavecontact.cli import main
status = main(sys.argv[2:])
with open(sys.argv[1], "w") as out:
    json.dump({"status": status, "rows": recorder.rows, "llvm": recorder.llvm}, out)
"""


def record(command: str, root: Path = ROOT, timeout: float = 1800.0) -> dict:
    """Every compilation of ``wavecontact COMMAND`` on an empty cache.

    Returns ``{"rows": [a dict per specialisation], "llvm": {phase: CPU s}}``: LLVM's share of the
    compile CPU by phase (function passes, module passes, machine code)."""
    with tempfile.TemporaryDirectory(prefix="wavecontact-breakdown-") as tmp:
        env, report, work = empty_cache_run(tmp, root)
        done = subprocess.run([sys.executable, "-c", _CHILD, str(report), *command.split()], cwd=work, env=env,
                              check=False, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                              timeout=timeout)
        if done.returncode != 0 or not report.is_file():
            raise SystemExit(f"wavecontact {command} failed (exit {done.returncode}):\n{done.stderr[-2000:]}")
        return json.loads(report.read_text())


def table(rows: list, top: int) -> list:
    """Markdown lines: one per kernel, largest own time first (``top`` rows), then the totals."""
    kernels = defaultdict(lambda: {"own": 0.0, "llvm": 0.0, "tree": 0.0, "count": 0, "outermost": False})
    for row in rows:
        entry = kernels[row["kernel"]]
        entry["own"] += row["own"]
        entry["llvm"] += row["llvm"]
        entry["count"] += 1
        if row["outermost"]:
            entry["tree"] += row["total"]
            entry["outermost"] = True
    lines = ["| kernel | own (s) | of which LLVM (s) | tree (s) | specialisations |", "|---|---|---|---|---|"]
    ranked = sorted(kernels.items(), key=lambda item: -item[1]["own"])
    for name, entry in ranked[:top]:
        tree = f"{entry['tree']:.2f}" if entry["outermost"] else "-"
        lines.append(f"| `{name}` | {entry['own']:.2f} | {entry['llvm']:.2f} | {tree} | {entry['count']} |")
    if len(ranked) > top:
        rest = sum(entry["own"] for _, entry in ranked[top:])
        rest_llvm = sum(entry["llvm"] for _, entry in ranked[top:])
        lines.append(f"| {len(ranked) - top} more kernels | {rest:.2f} | {rest_llvm:.2f} | - | - |")
    total = sum(row["total"] for row in rows if row["outermost"])
    llvm = sum(row["llvm"] for row in rows)
    outermost = sum(1 for row in rows if row["outermost"])
    lines.append(f"| **all** ({len(rows)} specialisations of {len(kernels)} kernels, {outermost} compiled from "
                 f"Python) | {total:.2f} | {llvm:.2f} | {total:.2f} | {len(rows)} |")
    return lines


def phases(rows: list, llvm: dict) -> str:
    """One sentence: the compile CPU split between numba's front end and LLVM's phases."""
    total = sum(row["total"] for row in rows if row["outermost"])
    spent = sum(llvm.values())
    split = ", ".join(f"{phase} {seconds:.2f} s" for phase, seconds in llvm.items())
    return (f"Of the {total:.2f} s: LLVM {spent:.2f} s ({split}); numba's front end (bytecode analysis, type "
            f"inference, lowering to LLVM IR, wrappers, the disk cache) {total - spent:.2f} s.")


def main(argv=None) -> int:
    names = [name for name, _, _ in COMMANDS]
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("name", choices=names, metavar="NAME", help="a command of compile_times.py: " + ", ".join(names))
    parser.add_argument("--top", type=int, default=40, help="kernels listed (default 40; the rest summed)")
    parser.add_argument("--tree", type=Path, default=ROOT, help="the checkout whose package is measured")
    args = parser.parse_args(argv)
    command = {name: line for name, line, _ in COMMANDS}[args.name]
    load = os.getloadavg()[0]
    report = record(command, args.tree.resolve())
    rows = report["rows"]
    shown = " ".join(word for word in command.split() if word != "--no-progress")
    print(f"compile CPU of `wavecontact {shown}` on an empty cache, per kernel ({args.tree.resolve()}, "
          f"load {load:.1f})\n")
    print("\n".join(table(rows, args.top)))
    print("\n" + phases(rows, report["llvm"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
