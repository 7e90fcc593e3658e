"""One entry point for a collision, the same for every solver."""

from __future__ import annotations

import functools

from .contact import ContactLaw
from .errors import InvalidParameterError
from .result import CollisionResult
from .scene import Scene, two_rods
from .solvers import get_solver

__all__ = ["collide", "solve"]


def _cold_scene(gamma, kappa, contact) -> Scene:
    """The cold two-rod scene, from the cache where the arguments allow (a named law, hashable numbers)."""
    try:
        if isinstance(contact, str):
            return _cached_cold_scene(gamma, kappa, contact)
    except TypeError:  # unhashable numbers: two_rods refuses them with a message
        pass
    return two_rods(gamma, kappa, contact=contact)


@functools.lru_cache(maxsize=256)
def _cached_cold_scene(gamma, kappa, contact: str) -> Scene:
    # a Scene is frozen and no solver changes it: sweeps of fast solves reuse it instead of rebuilding
    # and revalidating its rods on every call
    return two_rods(gamma, kappa, contact=contact)


def solve(scene: Scene, solver: str = "auto", *, tolerance=None, max_work=None, max_memory=None,
          estimate_error: bool = True, **options) -> CollisionResult:
    """Run one collision of ``scene`` with the named solver.

    Parameters
    ----------
    scene : Scene
        What to simulate.
    solver : {'auto', 'delay', 'fem', 'modal'}
        How to simulate it.  ``'auto'`` (the default): the method and resolution
        predicted cheapest to meet ``tolerance``, refined until they do
        (:func:`wavecontact.solvers.auto.solve_auto`; docs/performance.md, section
        "Choosing the method"); it takes no solver options and always estimates the error.
    tolerance : float or None
        Largest acceptable ``error_estimate`` of the restitution; a result
        above it raises :class:`~wavecontact.errors.AccuracyError`, whose
        message says which resolution should reach it.  With ``solver='auto'``
        None means :data:`wavecontact.solvers.auto.DEFAULT_TOLERANCE` (1e-6).
    max_work, max_memory : float or None
        Limits on the estimated work (updates, default 2e11) and memory
        (bytes, default half the available memory), checked before the solve
        (:mod:`wavecontact.limits`); exceeding one raises
        :class:`~wavecontact.errors.LimitError` with the estimate.
    estimate_error : bool
        Estimate the error (FE and modal: one more run at half the resolution,
        about a quarter of the cost); False leaves ``error_estimate`` NaN.
    **options
        Solver options; unknown names are refused (each solver's ``Options``
        dataclass lists them: ``get_solver(name).Options``).

    Returns
    -------
    CollisionResult
        With ``error_estimate`` (docs/error_estimates.md), ``wall_time_s``
        measured around the whole solve (the error estimate's run included), and
        ``diagnostics["includes_kernel_preparation"]`` True when numba compiled or
        loaded kernels during it (a first call: that time is not the solver's cost).
    """
    if solver == "auto":
        from .solvers.auto import solve_auto

        return solve_auto(scene, tolerance=tolerance, max_work=max_work, max_memory=max_memory, **options)
    return get_solver(solver).solve(scene, options, tolerance=tolerance, max_work=max_work,
                                    max_memory=max_memory, estimate_error=estimate_error)


def collide(gamma: float, kappa: float, solver: str = "delay", *, contact="exponential", bath_temperature=None,
            bath_modes: int = 250, seed=0, **options) -> CollisionResult:
    """Collide the paper's two rods (length ratio ``gamma``, softness ``kappa``).

    Parameters
    ----------
    gamma : float
        Length ratio ``l1 / l2`` in (0, 1].
    kappa : float
        ``alpha V l / c`` in [1e-2, 1e7] or ``inf`` (the hard-core limit);
        :data:`wavecontact.limits.KAPPA_MIN`, :data:`~wavecontact.limits.KAPPA_MAX`.
    solver : {'delay', 'fem', 'modal', 'auto'}
        Which solver to use (``'auto'``: see :func:`solve`).
    contact : {'exponential', 'penalty', 'hard'} or ContactLaw
        Contact law between the facing ends (``kappa = inf`` forces ``hard``).
    bath_temperature : float, pair of float or None
        ``T_B / E_tr`` (>= 0): the rods start with thermal vibrations
        (Eq. 18), one realisation drawn from ``seed``; a pair gives each rod
        its own temperature.  ``None``: a cold collision.
    bath_modes : int
        Excited modes per rod ``nu_max`` (default 250, the paper's).
    seed : int or numpy.random.SeedSequence
        Source of the realisation (only with ``bath_temperature``).
    **options
        ``tolerance``, ``max_work``, ``max_memory``, ``estimate_error`` as
        :func:`solve`, and solver options, e.g. ``elements=800`` for ``fem``, ``modes=100`` for
        ``modal``, ``rtol=1e-11`` for ``delay``.

    Returns
    -------
    CollisionResult
        ``.restitution`` is the coefficient of restitution epsilon.  With a
        bath, ``extra['vibration_energy_gain']`` holds the energy each rod's
        vibrations gained (units with ``E_tr = 1/4``; not in the hard-core
        mode, ``kappa = inf``, whose grid gives only the total) and
        ``extra['bath']`` the bath's parameters and the seed.

    Examples
    --------
    >>> from wavecontact import collide
    >>> round(collide(0.6, 100).restitution, 8)
    0.64669709
    """
    if not isinstance(contact, (str, ContactLaw)):
        raise InvalidParameterError(f"contact must be a name or a ContactLaw, got {contact!r}")
    # gamma and kappa are validated once, by two_rods where the scene is built (and its solver does not
    # check them again)
    if bath_temperature is None:
        return solve(_cold_scene(gamma, kappa, contact), solver, **options)
    from .bath.collide import thermal_scene
    from .bath.model import ThermalBath

    scene = thermal_scene(gamma, kappa, ThermalBath(bath_temperature, bath_modes), seed, contact=contact)
    return solve(scene, solver, **options)
