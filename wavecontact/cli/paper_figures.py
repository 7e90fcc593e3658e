"""``wavecontact paper-figures``: all ten figures of the paper, each with claim, measurement and verdict."""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

from .common import nonnegative_int, report_written
from .executors import executor_from
from .guard import check_outputs


def _figure_number(text: str) -> int:
    import argparse

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"figure numbers are 1-10, got {text!r}") from None
    if not 1 <= value <= 10:
        raise argparse.ArgumentTypeError(f"figure numbers are 1-10, got {text!r}")
    return value


def add_parser(subparsers):
    p = subparsers.add_parser(
        "paper-figures",
        help="reproduce the paper's ten figures and state a verdict for each claim",
        description="Run the studies behind the paper's Fig. 1-10, write each figure (PNG) into DIR and a page "
        "with the table of claims, measured numbers and verdicts (DIR/paper_figures.md, or --page FILE). "
        "--quick uses small sizes (seconds per figure); the default uses the paper's sizes except where the "
        "page says what was reduced.",
    )
    p.add_argument("--out", metavar="DIR", required=True, help="directory for the figures (created if missing)")
    p.add_argument("--quick", action="store_true", help="small sizes, for a test")
    p.add_argument("--only", type=_figure_number, nargs="+", metavar="N", help="only these figures, 1-10 (default: all ten)")
    p.add_argument("--page", metavar="FILE", help="write the Markdown page here (default DIR/paper_figures.md)")
    p.add_argument("--workers", type=nonnegative_int, default=1, help="worker processes for the ensembles (default 1)")
    p.add_argument("--seed", type=nonnegative_int, default=0, metavar="ROOT",
                   help="root seed from which every realisation is derived (default 0; printed on the page)")
    p.add_argument("--no-progress", dest="progress", action="store_false", help="no progress lines on stderr")
    p.set_defaults(run=run)
    return p


# --quick: what its verdicts are worth, said wherever they are printed (page, table on stdout, log on stderr)
QUICK_NOTE = ("Quick mode: sizes far below the paper's, for testing the command; the statistical verdicts "
              "(Fig. 1-3, 8-10) mean little at these sizes.")
QUICK_CAVEAT = "quick sizes: not a judgement of the paper"


def _log(message: str) -> None:
    print(f"wavecontact paper-figures: {message}", file=sys.stderr, flush=True)


def command_line(args) -> str:
    """The command that reproduces this run, rebuilt from the parsed options."""
    words = ["wavecontact", "paper-figures", "--out", str(args.out)]
    if args.quick:
        words.append("--quick")
    if args.only:
        words += ["--only", *map(str, args.only)]
    if args.page:
        words += ["--page", str(args.page)]
    if args.workers != 1:
        words += ["--workers", str(args.workers)]
    if args.seed != 0:
        words += ["--seed", str(args.seed)]
    return " ".join(shlex.quote(w) for w in words)


def run(args) -> int:
    from ..studies.paper_figures import run_figures, write_page

    out = Path(args.out)
    page = Path(args.page) if args.page else out / "paper_figures.md"
    check_outputs(files=[("--page", args.page, (".md",))],
                  directories=[("--out", args.out, () if args.page else ("paper_figures.md",))])
    out.mkdir(parents=True, exist_ok=True)
    page.parent.mkdir(parents=True, exist_ok=True)
    log = _log if args.progress else None
    if log is not None and args.quick:  # every verdict printed carries the caveat, on stderr too
        def log(message):
            _log(f"{message} [{QUICK_CAVEAT}]")
    with executor_from(args.workers, None) as executor:
        reports = run_figures(out, quick=args.quick, only=args.only, executor=executor, log=log,
                              root_seed=args.seed, caveat=QUICK_CAVEAT if args.quick else None)
    machine = (f"Run with {args.workers} worker process(es) on a 2-core machine shared with other jobs; "
               "wall times are indicative only.")
    if args.quick:
        machine += f" {QUICK_NOTE}"
    write_page(reports, page, command_line(args), machine, root_seed=args.seed)
    if args.quick:
        print(f"{QUICK_NOTE}\n")
    print("| Fig. | verdict | measured |")
    print("|---:|---|---|")
    for r in reports:
        for c in r.claims:
            print(f"| {r.number} | {c.verdict} | {c.measured} |")
    report_written([page, *(image for r in reports for image in r.images)])
    return 0
