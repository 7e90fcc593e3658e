"""Progress reporting for long runs: one object, a tqdm bar on stderr or nothing."""

from __future__ import annotations

import sys

__all__ = ["Progress", "shows_bars"]


def shows_bars() -> bool:
    """The one rule for progress bars: only when stderr is a terminal (cursor codes never go into files),
    or in a Jupyter kernel (where ``tqdm.auto`` draws a widget, not text)."""
    if "ipykernel" in sys.modules:
        return True
    try:
        return bool(sys.stderr.isatty())
    except (AttributeError, ValueError):  # replaced or closed stderr
        return False


class Progress:
    """A progress bar that studies update without knowing whether one is shown.

    Parameters
    ----------
    total : int
        Number of units of work (collisions, runs, samples).
    description : str
        Label shown before the bar.
    unit : str
        Name of one unit.
    enabled : bool or None
        ``False``: never a bar.  ``True`` or ``None``: a tqdm bar on stderr when
        stderr is a terminal (:func:`shows_bars`), never in a redirected file or pipe.
    initial : int
        Units already done (a resumed run).

    Examples
    --------
    >>> with Progress(3, "demo", enabled=False) as progress:
    ...     for _ in range(3):
    ...         progress.advance()
    >>> progress.done
    3
    """

    def __init__(self, total: int, description: str, unit: str = "it", enabled: bool | None = None,
                 initial: int = 0):
        self.total = int(total)
        self.done = int(initial)
        self._bar = None
        if enabled is not False and shows_bars():
            from tqdm.auto import tqdm

            self._bar = tqdm(total=self.total, initial=self.done, desc=description, unit=unit,
                             file=sys.stderr, dynamic_ncols=True)

    def advance(self, count: int = 1) -> None:
        """Record ``count`` more units of work."""
        self.done += int(count)
        if self._bar is not None:
            self._bar.update(int(count))

    def describe(self, text: str) -> None:
        """Change the label shown before the bar (what is being worked on now)."""
        if self._bar is not None:
            self._bar.set_description(text)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
