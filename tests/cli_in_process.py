"""Run the command line in the test's own process: ``main(argv)`` as ``python -m wavecontact`` runs it.

A subprocess costs about a second of interpreter start and imports per call; the refusals and plumbing
tests need only what ``main`` returns and prints (``python -m wavecontact`` is ``sys.exit(main())``; its
exit status through a real process is tested in test_cli_collide and test_cli).
"""

import subprocess

from wavecontact.cli import main


def run_in_process(capsys, *args):
    """``main(args)`` with its output captured by pytest's ``capsys``, as a ``subprocess.CompletedProcess``
    (``returncode``: the status main returned, or argparse's ``SystemExit`` code)."""
    capsys.readouterr()  # drop anything printed before
    try:
        status = main(list(args))
    except SystemExit as exit_:
        status = exit_.code
    captured = capsys.readouterr()
    return subprocess.CompletedProcess(["wavecontact", *args], status, captured.out, captured.err)
