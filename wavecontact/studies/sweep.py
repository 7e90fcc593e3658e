"""Restitution over a grid of ``(gamma, kappa)``: Fig. 5 and beyond.

Each point is one call of :func:`wavecontact.collide`; the points are
independent, so they run on a thread pool (the compiled kernels release the
GIL) with a progress bar.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from .. import progress as progress_bar
from ..api import collide
from ..errors import InvalidParameterError

__all__ = ["restitution_map"]


def restitution_map(gammas, kappas, solver: str = "delay", *, workers: int | None = None,
                    progress: bool | None = None, **options) -> np.ndarray:
    """epsilon on the grid ``gammas x kappas``.

    Parameters
    ----------
    gammas, kappas : array_like
        Length ratios in (0, 1] and softness values in (0, inf].
    solver : str
        Any registered solver; ``options`` go to it unchanged.
    workers : int or None
        Threads (default: the number of cores).
    progress : bool or None
        Show a tqdm bar on stderr (default: when stderr is a terminal).

    Returns
    -------
    ndarray, shape (len(gammas), len(kappas))
    """
    gammas = np.atleast_1d(np.asarray(gammas, dtype=float))
    kappas = np.atleast_1d(np.asarray(kappas, dtype=float))
    if gammas.ndim != 1 or kappas.ndim != 1:
        raise InvalidParameterError("gammas and kappas must be 1-D sequences")
    points = [(g, k) for g in gammas for k in kappas]
    collide(float(points[0][0]), float(points[0][1]), solver, **options)  # compile once, refuse bad input early
    if workers is None:
        workers = os.cpu_count() or 1

    def one(point):
        return collide(float(point[0]), float(point[1]), solver, **options).restitution

    values = np.empty(len(points))
    # advance once per finished point, so the bar ends at len(points) (a bar wrapped around the
    # iterator stops one short: the last item is counted only when the next one is asked for)
    with ThreadPoolExecutor(max_workers=max(1, int(workers))) as pool, \
            progress_bar.Progress(len(points), "restitution map", unit="point", enabled=progress) as bar:
        for index, value in enumerate(pool.map(one, points)):
            values[index] = value
            bar.advance()
    return values.reshape(gammas.size, kappas.size)
