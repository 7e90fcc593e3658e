"""Solver ``delay``: the delay-differential equation for the relative velocity.

Integrating the rod modes out of the Hamiltonian leaves one scalar equation
for the scaled velocity increase ``W(tau)`` (Eq. 16), exact for infinitely
many modes.  It holds for two rods on a line with exponential contact, and in
its hard-core limit (Eq. 26); rods of different materials and sections only
change the round trips and give each rod's echoes the weight ``2 Z_s / Z_i``
(:mod:`wavecontact.delay.parameters`).  See :mod:`wavecontact.delay.kernels`
for the method and ``docs/theory.md``.  The same equation with ``I' = F(r)``
holds for any force law of the gap; laws acting on overlap only (penalty with
its stiffness given, Hertz) are integrated by :mod:`wavecontact.delay.overlap`.

Results are in the scene's units (for :func:`wavecontact.two_rods` scenes those
are the paper's dimensionless ones): time ``t = tau mu / Z_s`` from the start
at the scaled gap ``a0``, relative velocity ``v2 - v1``, contact force.

Its options are :class:`DelayOptions`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from ..bath.model import ThermalBath, seed_sequence
from ..bath.noise import MAX_POINTS_PER_PERIOD, NOISE_EXCURSION, NoiseTables, noise_table_batch, table_points
from ..bath.scene import EXPONENTIAL_MARGIN, end_reaches, scene_noise
from ..errors import InvalidParameterError, LimitError, SolverFailure, UnsupportedSceneError
from ..limits import Cost
from ..result import Outcome
from ..scene import Scene, two_rods
from ..solvers.base import (
    ENERGY_SPLIT,
    HARD_CORE_THERMAL,
    MATERIAL_RATIOS,
    THERMAL_BATCH,
    CollisionFields,
    SolverBase,
    SolverOptions,
    option,
)
from . import kernels
from .energy_split import NODES, WEIGHTS, vibration_energy_gain
from .hardcore import contact_intervals, hard_core_history
from .noise import COLD, FourierNoise
from .overlap import collide_overlap_law, overlap_cost
from .parameters import DelayParameters, delay_parameters, echoes_from_ratios
from .stochastic_hardcore import hard_core_noise

__all__ = ["BATCH_OPTIONS", "ORDER", "SOLVER", "DelayOptions", "DelaySolver", "solve_delay_equation"]

ORDER = 6  # Gauss-Kronrod (3, 7) on the smooth remainder, quintic Hermite history

GAP_MARGIN = 40.0  # exp(-40) ~ 4e-18: the force at the start is below round-off
# Soft contacts last many round trips; there W is smooth on the scale of a round trip, and the
# copies older than DIRECT_COPIES round trips are summed through running comb sums (one
# interpolation per rod instead of one per copy).  Sharp features (kappa >> 1) keep every copy.
COMB_BELOW_KAPPA = 2.0
DIRECT_COPIES = 1
# Below this gamma (finite kappa) the solve is refused: W must be followed until the long rod's
# echo is back (Gamma_2 = 1 + 1/gamma) in steps shorter than Gamma_1, each summing about
# Gamma_2 / Gamma_1 delayed copies, so the cost grows like 1/gamma^2 (gamma = 1e-3: 100x gamma = 0.1)
GAMMA_MIN = 1e-2

_OUTCOMES = {
    kernels.STATUS_MAX_STEPS: (Outcome.STEP_LIMIT, "raise max_steps or rtol"),
    kernels.STATUS_NONFINITE: (Outcome.NON_FINITE, "report this scene: the equation's state left the floats"),
    kernels.STATUS_STEP_UNDERFLOW: (Outcome.STEP_UNDERFLOW, "raise rtol"),
    kernels.STATUS_TIME_LIMIT: (Outcome.TIME_LIMIT, "W did not settle (is kappa extremely small?)"),
}


_NO_TABLES = NoiseTables.empty()  # read only by the kernels

# The options of a batch of many finite-kappa thermal samples (ensembles, Markov chains) where the caller
# gives none.  The step control is pessimistic (its rtol bounds a sum of local error estimates): at rtol
# 1e-3 the samples of the Fig. 8 set differ from rtol 1e-10 by at most a few 1e-5 and their mean by about
# 1e-6, far below the ~6e-3 standard error of a 2500-sample mean (docs/bath.md, "The thermal delay solve";
# benchmarks/ensemble_accuracy.py).  The end nodes of the Lobatto rule are the step's ends (6 evaluations
# of the exponent a step instead of 8, at the same measured accuracy), and noise tables with 16 nodes per
# period of the fastest mode move the samples by about 1e-6 (32: 6e-8).
BATCH_OPTIONS = {"rtol": 1e-3, "quadrature": "lobatto-kronrod", "noise_resolution": 16}


def _noise(value):
    if not isinstance(value, FourierNoise):
        raise InvalidParameterError("delay option noise must be a wavecontact.delay.noise.FourierNoise or None")
    return value


@dataclass(frozen=True)
class DelayOptions(SolverOptions):
    """Options of the delay solver (every time is the dimensionless tau: ``l / c``
    for one material, ``mu / Z_s`` for two)."""

    solver_name = "delay"
    rtol: float = option(1e-11, "target accuracy of epsilon (absolute)", low=1e-14, high=1e-2)
    initial_gap: float | None = option(
        None, "scaled initial gap alpha R0; None: 40 + max|Q| (out of range of the force)",
        low=0.0, allow_none=True)
    end_time: float | None = option(
        None, "integrate at least until this time tau; None: stop once W has settled", low=0.0, allow_none=True)
    noise: FourierNoise | None = option(
        None, "initial vibrations as the noise Q(tau) (Eq. 17), frequencies in units of 1/tau; None: a cold bath "
        "or the scene's thermal vibrations", kind="object", allow_none=True, check=_noise)
    max_steps: int = option(2_000_000, "safety limit on accepted steps", kind="int", low=10, high=10**9)
    quadrature: str = option(
        "gauss-kronrod", "rule of each step: Gauss-Kronrod (3, 7), or Lobatto-Kronrod (4, 7), whose end nodes are "
        "the step's ends (6 evaluations of the exponent a step instead of 8; ensembles)", kind="choice",
        choices=tuple(kernels.QUADRATURE_RULES))
    noise_resolution: int = option(
        32, "least table nodes per period of the fastest bath mode for a scene with vibrations (cubic Hermite); "
        "doubled while the tables' interpolation error bound exceeds rtol (up to 1024), and that bound is part "
        "of the error estimate", kind="int", low=4, high=MAX_POINTS_PER_PERIOD)
    hard_core_resolution: int = option(
        8, "kappa = inf with vibrations: grid points per period of the short rod's fastest bath mode; the result "
        "comes from twice that, its error estimate from the changes over half and the given resolution",
        kind="int", low=2, high=4096)
    energy_split: bool = option(
        True, "also compute each rod's vibrational energy gain (extra['vibration_energy_gain'], E_tr = 1/4; one "
        "material)", kind="bool")


_LAST_SCENE = (None, None)  # (scene, its parameters): estimate_cost and _collide check the same scene


def _check_scene(scene: Scene) -> DelayParameters:
    global _LAST_SCENE
    last, params = _LAST_SCENE
    if scene is not last:  # a Scene is frozen (rods, velocities and contact law too): same object, same numbers
        params = delay_parameters(scene)  # refuses rings, other rod counts and receding rods
        _LAST_SCENE = (scene, params)
    if scene.contact.stiffness_from_solver:
        raise UnsupportedSceneError(
            f"the delay solver needs an explicit {scene.contact.name} stiffness (it has no mesh to choose one "
            "from); use solver='fem', or give the stiffness"
        )
    if scene.vibrations is not None and "two_rods" not in scene.metadata:
        raise UnsupportedSceneError("thermal vibrations need the paper's two rods (two_rods(..., vibrations=))")
    if not scene.is_cold and scene.vibrations is None:
        raise UnsupportedSceneError(
            "the delay solver takes initial vibrations only as a modal sum, the noise Q(tau): pass "
            "noise=FourierNoise(...) on a cold scene, or use solver='fem' or 'modal' for initial fields"
        )
    return params


def solve_delay_equation(gamma, kappa, *, rtol=1e-11, initial_gap=None, end_time=None, noise=None, max_steps=2_000_000,
                         impedance_ratio=1.0, tables=None):
    """Integrate the delay equation for transit-time ratio ``gamma`` and softness ``kappa``.

    ``gamma = T_1 / T_2`` is the ratio of the round-trip times ``2 l_i / c_i``
    (``l_1 / l_2`` for one material, Eq. 16) and ``impedance_ratio = Z_2 / Z_1``
    (1: one material); see :mod:`wavecontact.delay.parameters`.

    ``tables`` (:class:`wavecontact.bath.noise.NoiseTables`) adds tabulated
    noise (a thermal bath) to ``noise``.

    Returns ``(t, W, W', error_estimate, work, a0)`` with ``W`` on the adaptive
    grid ``t`` (dimensionless time, ``tau = 0`` at the start, scaled gap ``a0``).
    """
    options = DelayOptions(rtol=rtol, initial_gap=initial_gap, end_time=end_time, noise=noise, max_steps=max_steps)
    t, w, d1, _d2, error, work, a0 = _integrate(gamma, kappa, options.rtol, options.initial_gap, options.end_time,
                                                options.noise, options.max_steps, impedance_ratio, tables)
    return t, w, d1, error, work, a0


def _integrate(gamma, kappa, rtol, a0, end_time, noise, max_steps, impedance_ratio, tables, quadrature="gauss-kronrod"):
    """The kernel call behind :func:`solve_delay_equation`, for options already validated (DelayOptions)."""
    noise = COLD if noise is None else noise
    tables = _NO_TABLES if tables is None else tables
    if a0 is None:
        a0 = GAP_MARGIN + (noise.amplitude_bound if noise.freq.size else 0.0)
    delays, weights = (np.array(x) for x in echoes_from_ratios(impedance_ratio, gamma))
    free_time = a0 / kappa
    settle = float(delays.sum())
    t_end_min = free_time if end_time is None else max(free_time, end_time)
    # the collision lasts about Gamma_1 for kappa >> 1 and ~ (|ln rtol| + a0) / (kappa gamma) when soft
    ratio = min(delays) / max(delays)
    t_limit = t_end_min + 50.0 * settle + 50.0 * (abs(math.log(rtol)) + a0) / (kappa * min(ratio, 0.5))
    t, w, d1, d2, status, error, rejected, evaluations = kernels.integrate_delay_equation(
        float(kappa), float(a0), delays, weights, rtol, (noise.freq, noise.cos_amp, noise.sin_amp),
        (tables.periods, tables.values, tables.slopes, tables.block_max, tables.curvature_blocks, NOISE_EXCURSION),
        (float(t_end_min), float(t_limit), settle, max_steps), kernels.QUADRATURE_RULES[quadrature],
        DIRECT_COPIES if kappa <= COMB_BELOW_KAPPA else 0,
    )
    if status != kernels.STATUS_OK:
        outcome, advice = _OUTCOMES[status]
        raise SolverFailure(
            f"delay solver (gamma={gamma:g}, impedance_ratio={impedance_ratio:g}, kappa={kappa:g}): "
            f"{outcome.message}; {advice}", outcome)
    work = {"steps": int(t.size - 1), "rejected_steps": int(rejected), "evaluations": int(evaluations)}
    if tables.interpolation_bound > 0.0:
        # the tables' interpolation error of Q (a bound on the exponent's error, so on W's to first order)
        error = float(error) + tables.interpolation_bound / kappa
    return t, w, d1, d2, float(error), work, a0




class DelaySolver(SolverBase):
    """The delay equation (Eq. 16) and its hard-core limit (Eq. 26): the reference solver."""

    name = "delay"
    Options = DelayOptions
    resolution = "rtol"
    refines = -1
    title = "delay solver"
    cli_flags = MappingProxyType({"rtol": None, "max_steps": None})
    capabilities = frozenset({THERMAL_BATCH, HARD_CORE_THERMAL, MATERIAL_RATIOS, ENERGY_SPLIT})
    line_scenes_taken = "two uniform rods, or a rigid body against one uniform rod (no walls), only"
    batch_defaults = MappingProxyType(BATCH_OPTIONS)
    order_case = MappingProxyType({"resolutions": (1e-4, 1e-6, 1e-8), "options": {}})
    agreement_case = ({}, 1e-9)

    def comparison_methods(self, kappa: float) -> list:
        """Three tolerances, ``rtol`` 1e-5, 1e-8 and 1e-11."""
        del kappa
        return [({"rtol": r}, f"rtol={r:.0e}", "steps") for r in (1e-5, 1e-8, 1e-11)]

    def vibration_energy_gain(self, fields: CollisionFields, scene: Scene):
        """The per-rod split of :mod:`wavecontact.delay.energy_split`, computed during the solve; None in the
        stochastic hard-core mode (its grid gives only the total) and with ``energy_split=False``."""
        del scene
        gain = fields.extra.get("vibration_energy_gain")
        return None if gain is None else np.asarray(gain, dtype=float)

    # -- fast paths for large sweeps: the same equations without Scene and CollisionResult objects ----------
    def check_ratios(self, impedance_ratio: float, time_ratio: float) -> None:
        """Refuse ratios outside the supported range ``[1e-6, 1e6]`` (names the ratio)."""
        echoes_from_ratios(impedance_ratio, time_ratio)

    def restitution_of_ratios(self, impedance_ratio: float, time_ratio: float, kappa: float,
                              rtol: float = 1e-8) -> float:
        """epsilon of a cold two-material collision from ``Z_2 / Z_1``, ``T_1 / T_2`` and ``kappa`` alone.

        ``kappa = inf`` runs the hard-core max-plus recursion; otherwise the delay equation at
        tolerance ``rtol``.  What :meth:`solve` returns for the scene with these numbers, without
        building it (about 10 us per hard-core point, for maps of 10^4 points).
        """
        if math.isinf(kappa):
            delays, weights = echoes_from_ratios(impedance_ratio, time_ratio)
            return float(hard_core_history(delays, weights)[1][-1] - 1.0)
        w = solve_delay_equation(time_ratio, kappa, rtol=rtol, impedance_ratio=impedance_ratio)[1]
        return float(w[-1] / kappa - 1.0)

    def hard_core_thermal_restitution(self, gamma: float, vibrations, resolution: int = 8,
                                      tau_free: float = 0.0) -> float:
        """epsilon of one hard-core collision of the paper's rods carrying ``vibrations``.

        ``vibrations`` is a :class:`~wavecontact.bath.BathRealisation` at the nominal contact time
        (the stochastic max-plus limit of Eq. 26; ``resolution`` grid points per period of the
        short rod's fastest bath mode; ``tau_free``, the nominal contact time, only shifts the
        recursion and is not needed).  The same number as :meth:`hard_core_thermal_batch` for
        the seed that drew ``vibrations``, bit for bit.
        """
        from .stochastic_hardcore_batch import cached_grid

        return cached_grid(float(gamma), int(vibrations.modes), int(resolution)).restitution_of(vibrations)

    def hard_core_thermal_batch(self, gamma: float, temperature, seeds, modes: int = 250,
                                resolution: int = 8):
        """epsilon of many hard-core thermal collisions, one per seed (``ThermalBath.draw``'s realisation
        of each seed; ``temperature`` is ``T_B / E_tr``, a pair per rod, or one per seed).  See
        :func:`wavecontact.delay.stochastic_hardcore_batch.hard_core_restitutions`."""
        from .stochastic_hardcore_batch import cached_grid, hard_core_restitutions

        return hard_core_restitutions(gamma, temperature, seeds, grid=cached_grid(float(gamma), int(modes),
                                                                                   int(resolution)))

    def hard_core_grid_points(self, gamma: float, modes: int = 250, resolution: int = 8) -> int:
        """Grid points per ``Gamma_1`` of the hard-core grid at ``resolution`` points per period of the
        short rod's fastest bath mode (``max(resolution nu_max, 256)``): the step is ``(1 + gamma)`` over it."""
        from .stochastic_hardcore_batch import cached_grid

        return int(cached_grid(float(gamma), int(modes), int(resolution)).n1)

    def hard_core_thermal_split(self, gamma: float, temperature_ratio, seed, *, bath_modes: int = 250,
                                resolution: int = 8, temperatures=None) -> tuple:
        """``(epsilon^2, gain_1, gain_2)`` of one hard-core thermal collision with each rod's share.

        The gains are what each rod's vibrations gained, in units of the incoming
        ``E_tr`` (``gain_1 + gain_2 = 1 - epsilon^2``).  See
        :func:`wavecontact.delay.stochastic_hardcore_split.hard_core_collision`.
        """
        from .stochastic_hardcore_split import hard_core_collision

        return hard_core_collision(gamma, temperature_ratio, seed, bath_modes=bath_modes, resolution=resolution,
                                   temperatures=temperatures)

    def thermal_restitution(self, scene: Scene, options=None) -> float:
        """epsilon of a finite-kappa thermal scene (``two_rods(..., vibrations=)``), as :meth:`solve` gives it.

        The same start gap, noise tables and integration, without the result
        object, the contact window and the energy split (ensembles of many
        samples).  ``options``: a mapping of :class:`DelayOptions` (validated).
        """
        options = self.options(options)
        params = _check_scene(scene)
        self.estimate_cost(scene, options)  # refuses what solve() refuses before any work
        if scene.vibrations is None or math.isinf(params.kappa) or scene.contact.hard:
            raise UnsupportedSceneError("thermal_restitution needs a finite-kappa scene with vibrations")
        if options.noise is not None:
            raise InvalidParameterError("a scene with vibrations brings its own noise: leave the option noise=None")
        initial_gap, tables = _start(scene, params, options)
        w = _integrate(params.time_ratio, params.kappa, options.rtol, initial_gap, options.end_time, None,
                       options.max_steps, params.impedance_ratio, tables, options.quadrature)[1]
        return float(w[-1] / params.kappa - 1.0)

    def thermal_restitutions(self, gamma: float, kappa: float, bath, seeds, options=None) -> tuple:
        """epsilon and its error estimate for many finite-kappa thermal collisions of the paper's rods.

        Sample ``j`` is what :meth:`thermal_restitution` gives, bit for bit, for
        ``thermal_scene(gamma, kappa, bath, seeds[j])``: the same draw, start gap,
        noise tables and integration, with the scene object, the option checks and the
        cost checks done once for all seeds (an ensemble's batch).

        Parameters
        ----------
        gamma, kappa : float
            Length ratio in ``[GAMMA_MIN, 1]`` and a finite softness.
        bath : wavecontact.bath.ThermalBath or sequence of ThermalBath
            Temperature(s) ``T_B / E_tr`` and ``nu_max``; a sequence gives each seed its own
            bath (equal ``nu_max``; Markov chains, whose ratios differ from chain to chain).
        seeds : sequence of int or numpy.random.SeedSequence
            One realisation per seed (:meth:`ThermalBath.draw`).
        options : mapping or DelayOptions, optional
            Validated as :class:`DelayOptions`; ``noise`` must stay None.

        Returns
        -------
        restitution, error_estimate : ndarray
            Per seed: epsilon (dimensionless) and the solver's estimate of its error
            (the sum of the local error estimates, :func:`solve_delay_equation`).
        """
        options = self.options(options)
        bath = _per_seed_baths(bath, len(seeds))
        prototype = two_rods(gamma, kappa)  # the rods, contact and parameters of every sample (cold)
        params = _check_scene(prototype)
        self.estimate_cost(prototype, options)
        if math.isinf(params.kappa) or prototype.contact.hard:
            raise UnsupportedSceneError("thermal_restitutions needs a finite kappa (kappa = inf: "
                                        "hard_core_thermal_batch)")
        if options.noise is not None:
            raise InvalidParameterError("a scene with vibrations brings its own noise: leave the option noise=None")
        contact, kappa = prototype.contact, params.kappa
        lengths = tuple(rod.length for rod in prototype.rods)
        gamma = prototype.metadata["two_rods"].gamma
        periods = (1.0 + gamma, 1.0 + 1.0 / gamma)
        # _start's shift of the scaled gap: ln(B alpha^2 mu / Z_s^2)
        shift = math.log(contact.strength * contact.alpha**2 * params.reduced_mass / params.series_impedance**2)
        # chunks of seeds whose noise spectra take at most about 32 MB (2^21 complex numbers), at the finest
        # table that the tolerance may ask for
        modes = bath.modes if isinstance(bath, ThermalBath) else (bath[0].modes if bath else 1)
        finest = table_points(modes, max(options.noise_resolution, MAX_POINTS_PER_PERIOD))
        chunk = max(1, min(32, (1 << 21) // (2 * finest)))
        out = np.empty((2, len(seeds)))
        for start in range(0, len(seeds), chunk):
            part = seeds[start:start + chunk]
            baths = bath if isinstance(bath, ThermalBath) else bath[start:start + chunk]
            for j, (gap, tables) in enumerate(_thermal_starts(baths, part, lengths, contact, shift, kappa, periods,
                                                              options), start):
                _t, w, _d1, _d2, error, _work, _a0 = _integrate(params.time_ratio, kappa, options.rtol, gap,
                                                                options.end_time, None, options.max_steps,
                                                                params.impedance_ratio, tables, options.quadrature)
                out[0, j] = w[-1] / kappa - 1.0
                out[1, j] = error
        return out[0], out[1]

    def expected_order(self, options) -> float:
        """1: the error is proportional to (and below) the tolerance ``rtol``."""
        return 1.0

    def estimate_cost(self, scene: Scene, options: DelayOptions) -> Cost | None:
        """Refuse, before any step, what the method of steps cannot do in bounded time: round trips
        more than ``1/GAMMA_MIN`` apart at finite kappa, and an ``end_time`` beyond ``max_steps`` steps."""
        params = _check_scene(scene)
        if not scene.contact.hard and scene.contact.decay_rate == 0.0:  # a law acting on overlap only
            return overlap_cost(scene, params, options)
        if math.isinf(params.kappa) or scene.contact.hard:
            return None
        short, long = sorted(params.round_trip_times)
        if long / short > 1.0 / GAMMA_MIN:
            raise LimitError(
                f"delay: the round trips differ by a factor {long / short:.3g} > {1 / GAMMA_MIN:g} (gamma < "
                f"{GAMMA_MIN:g} for one material) at finite kappa: the equation must be followed until the long "
                "rod's echo returns in steps shorter than the short rod's round trip, each summing all its "
                "echoes, so the cost grows like the square of that factor; use solver='modal' or solver='fem' "
                "(or kappa=inf)")
        largest_step = 0.95 * short  # the method of steps' largest step
        if options.end_time is not None:
            steps = options.end_time / largest_step
            if steps > options.max_steps:
                raise LimitError(
                    f"delay: end_time={options.end_time:g} needs at least {steps:.3g} steps (each at most "
                    f"0.95 Gamma_1 = {largest_step:.3g}), more than max_steps={options.max_steps}; "
                    f"lower end_time or pass max_steps={math.ceil(steps * 1.1)}")
        return None

    def solve_line(self, scene: Scene, options=None, **limits):
        """Saint-Venant's scene (a rigid body against one uniform rod): :mod:`wavecontact.delay.rigid_mass`;
        any other line scene is refused, naming the fem solver."""
        from . import rigid_mass

        if not rigid_mass.takes(scene):
            return super().solve_line(scene, options, **limits)
        return rigid_mass.solve_scene(scene, self.options(options), **limits)

    def _collide(self, scene: Scene, options: DelayOptions) -> CollisionFields:
        params = _check_scene(scene)
        if not scene.contact.hard and scene.contact.decay_rate == 0.0:  # a law acting on overlap only
            return collide_overlap_law(scene, params, options)
        kappa = params.kappa
        vibrations = scene.vibrations
        if vibrations is not None and options.noise is not None:
            raise InvalidParameterError("a scene with vibrations brings its own noise: leave the option noise=None")
        if scene.contact.hard or math.isinf(kappa):
            if options.noise is not None:
                raise UnsupportedSceneError("the hard-core delay solver takes thermal vibrations on the scene "
                                            "(two_rods(..., vibrations=)), not the option noise")
            if vibrations is not None:
                return _collide_hard_stochastic(scene, params, options.hard_core_resolution)
            return _collide_hard(params)
        initial_gap, tables = _start(scene, params, options)
        t, w, d1, d2, error, work, a0 = _integrate(params.time_ratio, kappa, options.rtol, initial_gap,
                                                   options.end_time, options.noise, options.max_steps,
                                                   params.impedance_ratio, tables, options.quadrature)
        unit = params.time_unit
        extra = {"scaled_initial_gap": a0, "free_flight_time": a0 / kappa * unit, "velocity_increase_slope": d1,
                 "delay_parameters": _as_dict(params)}
        if options.energy_split and options.noise is None and params.impedance_ratio == 1.0:
            # one material: the per-rod split of wavecontact.delay.energy_split (units with E_tr = 1/4)
            tab = tables if tables is not None else _NO_TABLES
            extra["vibration_energy_gain"] = vibration_energy_gain(
                float(kappa), t, w, d1, d2, np.asarray(params.round_trip_times, dtype=float), tab.periods,
                tab.values, tab.slopes, NODES, WEIGHTS, 2)
        if vibrations is not None:
            extra["vibration_energy_before"] = vibrations.vibration_energy()
            extra["bath_modes"] = vibrations.modes
        return CollisionFields(
            restitution=w[-1] / kappa - 1.0,
            time=t * unit,
            relative_velocity=params.approach_speed * (w / kappa - 1.0),
            # mu dv_rel/dt = Z_s V W' / kappa
            contact_force=params.force_unit * d1 / kappa,
            error_estimate=error,
            work=work,
            extra=extra,
        )


_PARAMETER_NAMES = tuple(f.name for f in dataclasses.fields(DelayParameters))


def _per_seed_baths(bath, count: int):
    """``bath`` itself (one ThermalBath for every seed) or a list of ``count`` baths of equal ``nu_max``."""
    if isinstance(bath, ThermalBath):
        return bath
    baths = list(bath) if isinstance(bath, (list, tuple)) else None
    if baths is None or len(baths) != count or not all(isinstance(b, ThermalBath) for b in baths):
        raise InvalidParameterError("bath must be a wavecontact.bath.ThermalBath or one ThermalBath per seed")
    if baths and any(b.modes != baths[0].modes for b in baths):
        raise InvalidParameterError("the baths of one call must have equal nu_max (bath modes)")
    return baths


def _thermal_starts(bath, seeds, lengths, contact, shift, kappa, periods, options) -> list:
    """``(initial_gap, tables)`` of each seed's realisation: what :func:`_start` gives for its thermal scene.

    The draws, start gaps and noise spectra of all seeds are formed at once, with the arithmetic of
    the per-scene path (``ThermalBath.draw``, ``start_gap``, ``noise_coefficients``, ``noise_tables``).
    ``bath``: one ThermalBath, or a list with one per seed (each seed drawn at its own temperature).
    """
    if isinstance(bath, ThermalBath):
        q, r = bath.draw_amplitudes(lengths, [seed_sequence(seed) for seed in seeds])
    else:  # draw_amplitudes per seed: the same arithmetic, row by row
        rows = [b.draw_amplitudes(lengths, [seed_sequence(seed)]) for b, seed in zip(bath, seeds)]
        q, r = (np.concatenate([row[k] for row in rows]) for k in (0, 1))
        bath = bath[0]
    if options.initial_gap is None:
        margin = EXPONENTIAL_MARGIN / contact.alpha  # start_gap's margin for exponential contact
        gaps = [contact.alpha * float(float(reach) + margin) - shift for reach in end_reaches(q, r)]
    else:
        gaps = [options.initial_gap] * len(seeds)
    signs = ((-1.0) ** np.arange(1, bath.modes + 1), -np.ones(bath.modes))  # BathRealisation.contact_end_signs
    factors = [kappa * math.sqrt(2.0) * sign for sign in signs]  # alpha = kappa (noise_coefficients)
    a = np.stack([factors[i] * q[:, i] for i in range(2)], axis=1)
    b = np.stack([factors[i] * r[:, i] for i in range(2)], axis=1)
    contact_times = np.array([float(gap) / kappa for gap in gaps])
    return list(zip(gaps, noise_table_batch(a, b, periods, contact_times, 0.0, options.noise_resolution,
                                            noise_tolerance(options.rtol, kappa))))


def _start(scene: Scene, params: DelayParameters, options: DelayOptions) -> tuple:
    """``(initial_gap, tables)``: the scaled start gap (None: the solver's choice) and the scene's noise tables."""
    initial_gap = options.initial_gap
    if scene.gaps is not None and initial_gap is None:
        # a user-placed start: alpha * gap, shifted by ln(B alpha^2 mu / Z_s^2) for B != Z_s^2 / (mu alpha^2)
        alpha = scene.contact.alpha
        initial_gap = alpha * scene.gaps[0] - math.log(
            scene.contact.strength * alpha**2 * params.reduced_mass / params.series_impedance**2
        )
    tables = None
    if scene.vibrations is not None:
        if initial_gap is None:
            raise UnsupportedSceneError("a scene with vibrations needs its start gap "
                                        "(two_rods(..., vibrations=) sets it)")
        tables = scene_noise(scene, params.kappa, float(initial_gap), options.noise_resolution,
                             noise_tolerance(options.rtol, params.kappa))
    return initial_gap, tables


def noise_tolerance(rtol: float, kappa: float) -> float:
    """The interpolation error of the noise tables allowed at tolerance ``rtol`` (a scaled length).

    An error ``dQ`` of the exponent ``g`` moves ``W = log(1 + integral e^g)`` by at most ``max|dQ|``
    on its own (the memory terms carry it on), and epsilon by that over ``kappa``: the tables are
    refined until their bound (:func:`wavecontact.bath.noise.interpolation_error`) is ``kappa rtol``,
    and the bound over ``kappa`` joins the error estimate (:func:`_integrate`).
    """
    return float(rtol) * float(kappa)


def _as_dict(params: DelayParameters) -> dict:
    # a shallow copy: dataclasses.asdict deep-copies every field and cost more than a soft solve
    values = {name: getattr(params, name) for name in _PARAMETER_NAMES}
    return {**values, "impedance_ratio": params.impedance_ratio, "time_ratio": params.time_ratio}


def _collide_hard_stochastic(scene, params: DelayParameters, resolution) -> CollisionFields:
    """The hard-core limit with the scene's vibrations (max-plus recursion on a grid).

    The answer comes from the grid at 2 x resolution; the grid converges at
    first order but unevenly (f often peaks at a kink of the memory terms,
    between nodes), so the error is estimated by the larger change over the
    two coarser grids.  The per-rod split needs ``W'`` times the noise's
    slope, which the max-plus grid resolves too slowly: only the total
    ``(1 - epsilon^2) / 4`` is implied; use a finite kappa for the split.
    """
    from .stochastic_hardcore_batch import cached_grid

    vibrations = scene.vibrations
    gamma = scene.metadata["two_rods"].gamma
    tau_free = float(scene.gaps[0])  # V = 1, l = 1: the gap is the free-flight time
    # epsilon from the batched grid, so that it equals an ensemble's sample of the same seed at
    # hard_core_resolution = 2 x resolution bit for bit; the history from the per-sample grid
    *coarser, restitution = [cached_grid(float(gamma), int(vibrations.modes), r).restitution_of(vibrations)
                            for r in (max(resolution // 2, 2), resolution, 2 * resolution)]
    t, w = hard_core_noise(gamma, vibrations, tau_free, 2 * resolution)
    slopes = np.diff(w) / np.diff(t)
    return CollisionFields(
        restitution=restitution,
        time=t,
        relative_velocity=w - 1.0,
        # the force is constant between grid points: force[i] is its value on (time[i-1], time[i]]
        contact_force=params.force_unit * np.concatenate([[0.0], slopes]),
        force_sampling="interval",
        error_estimate=max(abs(coarser[1] - restitution), abs(coarser[0] - coarser[1])),
        work={"steps": int(t.size)},
        extra={"hard_core": True, "free_flight_time": tau_free, "bath_modes": vibrations.modes,
               "vibration_energy_before": vibrations.vibration_energy(), "grid_step": float(t[1] - t[0])},
    )


def _collide_hard(params: DelayParameters) -> CollisionFields:
    delays, weights = params.round_trip_times, params.echo_weights
    knots_t, knots_w = hard_core_history(delays, weights)
    restitution = float(knots_w[-1] - 1.0)
    contacts = contact_intervals(knots_t, knots_w, delays, weights)
    slopes = np.diff(knots_w) / np.diff(knots_t)
    # show the flat parts before and after the contact as well
    knots_t = np.concatenate([[knots_t[0] - 1.0], knots_t, [knots_t[-1] + sum(delays)]])
    knots_w = np.concatenate([[0.0], knots_w, [knots_w[-1]]])
    # the force is constant between knots: force[i] is its value on (time[i-1], time[i]], units Z_s V
    force = np.concatenate([[0.0, 0.0], slopes, [0.0]])
    unit = params.time_unit
    return CollisionFields(
        restitution=restitution,
        time=knots_t * unit,
        relative_velocity=params.approach_speed * (knots_w - 1.0),
        contact_force=params.force_unit * force,
        force_sampling="interval",
        error_estimate=1e-14,
        work={"steps": int(knots_t.size)},
        extra={"hard_core": True, "contacts": [(a * unit, b * unit) for a, b in contacts],
               "delay_parameters": _as_dict(params)},
    )


SOLVER = DelaySolver()
