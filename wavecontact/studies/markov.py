"""Successive collisions as a Markov chain of the translational energy (paper Sec. VII, Eq. 27-36).

Each step is one collision of the paper's two rods: the translational energy
of the relative motion goes from ``E_tr`` to ``epsilon^2 E_tr`` (Eq. 28),
with ``epsilon^2`` drawn from the law of the stochastic restitution at the
momentary ratio ``T_B / E_tr`` (Eq. 29).  The bath either keeps the
temperature ``T_B^0`` (``bath="fixed"``, Eq. 30-32) or takes up the lost
energy, spread over ``2 N_mod`` modes (``bath="conserved"``, Eq. 28)::

    T_B(j+1) = T_B(j) + (1 - epsilon_j^2) E_tr(j) / (2 N_mod).

Energies are in units of ``T_B^0``: the fixed temperature, or with
``bath="conserved"`` ``E_tot / (2 N_mod + 1)`` (Eq. 31), so the Boltzmann
law Eq. 30 is ``exp(-E)`` in both cases.

Rules for ``epsilon^2``
-----------------------
``solve``
    A new thermal collision per step (the bath's realisation drawn afresh: the
    Markov assumption), by any solver; the default is the delay solver in its
    stochastic hard-core mode (``kappa = inf``), which the paper's Sec. VI
    found to represent every ``kappa > 50``.
``table``
    Inverse-transform sampling from an exported
    :class:`wavecontact.restitution_table.RestitutionTable`.
``glauber``
    Glauber's rule, Eq. 35: ``epsilon^2 E_tr / T_B`` is a unit exponential,
    i.e. ``E_tr' = T_B x`` whatever ``E_tr`` (the heat-bath rule); its
    deterministic limit is the wrong one, ``epsilon^2 -> 0`` (Eq. 36).

Random streams
--------------
Chain ``c`` of a run with seed ``s`` owns ``SeedSequence(s).spawn(chains)[c]``
(built directly as ``SeedSequence(s, spawn_key=(c,))``).  The ``solve`` rule
draws step ``j``'s bath from that chain's ``j``-th child
(``spawn_key=(c, j)``); ``table`` and ``glauber`` take one uniform number per
step from ``default_rng`` of the chain's sequence.  Every chain is therefore
fixed by ``(s, c)`` alone: bit-identical whatever the executor, the number of
workers or the batch size.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from dataclasses import fields as dataclass_fields
from pathlib import Path

import numpy as np

from ..errors import InvalidParameterError, SolverFailure, WavecontactError, require_integer
from ..scene import validate_gamma_kappa
from ..solvers import get_solver
from ..solvers.base import HARD_CORE_THERMAL, THERMAL_BATCH

__all__ = [
    "MAX_STATES",
    "MarkovResult",
    "MarkovSpec",
    "chain_seed",
    "markov_chains",
    "run_chains",
    "step_seed",
    "symmetry_samples_needed",
    "symmetry_test",
    "thermal_restitution",
]

RULES = ("solve", "table", "glauber")
BATHS = ("fixed", "conserved")
MAX_STATES = 20_000_000  # chains x (steps + 1): bounds the memory (three float arrays) before work starts
_BLOCK = 1024  # uniform numbers drawn per chain at a time (the stream does not depend on it)
_SCHEMA = "wavecontact.markov"
_VERSION = 1


def chain_seed(seed: int, chain: int) -> np.random.SeedSequence:
    """Chain ``chain``'s sequence: ``SeedSequence(seed).spawn(chain + 1)[chain]``."""
    return np.random.SeedSequence(int(seed), spawn_key=(int(chain),))


def step_seed(chain: np.random.SeedSequence, step: int) -> np.random.SeedSequence:
    """The bath of collision ``step`` of a chain: ``chain.spawn(step + 1)[step]``, without spawn state."""
    return np.random.SeedSequence(chain.entropy, spawn_key=tuple(chain.spawn_key) + (int(step),))



@dataclass(frozen=True)
class MarkovSpec:
    """What a Markov run computes (saved next to its results).

    Parameters
    ----------
    gamma : float
        Length ratio ``l1 / l2`` in (0, 1].
    kappa : float
        ``alpha V l / c`` in (0, inf] of each solved collision (``solve`` rule; ``inf``:
        the stochastic hard-core mode).
    rule : {'solve', 'table', 'glauber'}
        Where ``epsilon^2`` comes from (module docstring).
    chains, steps : int
        Independent chains and collisions per chain; ``chains x (steps + 1)`` at most 2e7.
    seed : int
        Non-negative root seed.
    bath : {'fixed', 'conserved'}
        Bath temperature held at ``T_B^0`` (Eq. 30-32) or updated by energy conservation (Eq. 28).
    modes_per_rod : int
        ``N_mod`` of Eq. 28 and 31, in [1, 10^6] (used with ``bath="conserved"``).
    initial_energy : float or 'boltzmann'
        ``E_tr(0) / T_B^0``; with ``bath="conserved"`` at most ``2 N_mod + 1`` (then the
        bath starts at ``T_B(0) = (2 N_mod + 1 - E_tr(0)) / (2 N_mod)``, cold at the maximum).
        ``'boltzmann'`` (fixed bath only) draws it per chain from Eq. 30, the
        first number of the chain's uniform stream: the chains then start stationary,
        and ``steps=1`` gives independent transitions ``E -> E'`` for detailed balance.
    bath_modes : int
        ``nu_max``: excited modes per rod in each solved collision (``solve`` rule), in [1, 100000].
    solver : str
        Solver of each collision (``solve`` rule; a name of :func:`wavecontact.solvers.solver_names`).
    options : dict
        Solver options (JSON values), e.g. ``{"hard_core_resolution": 16}``.  At finite kappa the
        solver's ``batch_defaults`` fill in what is not given, as in an ensemble (the delay solver's
        ``ENSEMBLE_DELAY_OPTIONS``: ``rtol = 1e-3``, the Lobatto-Kronrod rule, 16 noise table nodes per period).
    table : str or None
        Path of a restitution table (``.npz`` or ``.json``) for the ``table`` rule.
    batch_size : int
        Chains per task, in [1, 100000].
    """

    gamma: float
    kappa: float = math.inf
    rule: str = "solve"
    chains: int = 1
    steps: int = 10_000
    seed: int = 0
    bath: str = "fixed"
    modes_per_rod: int = 250
    initial_energy: float = 1.0
    bath_modes: int = 250
    solver: str = "delay"
    options: dict = field(default_factory=dict)
    table: str | None = None
    batch_size: int = 1

    def __post_init__(self):
        gamma, kappa = validate_gamma_kappa(self.gamma, self.kappa)
        object.__setattr__(self, "gamma", gamma)
        object.__setattr__(self, "kappa", kappa)
        if self.rule not in RULES:
            raise InvalidParameterError(f"rule must be one of {', '.join(RULES)}, got {self.rule!r}")
        if self.bath not in BATHS:
            raise InvalidParameterError(f"bath must be one of {', '.join(BATHS)}, got {self.bath!r}")
        # the largest values the product bound below allows (one chain of MAX_STATES - 1 steps; chains of 1 step)
        chains = require_integer("chains", self.chains, 1, MAX_STATES // 2)
        steps = require_integer("steps", self.steps, 1, MAX_STATES - 1)
        if chains * (steps + 1) > MAX_STATES:
            raise InvalidParameterError(
                f"chains x (steps + 1) must be at most {MAX_STATES}, got {chains} x {steps + 1}; split the run"
            )
        object.__setattr__(self, "chains", chains)
        object.__setattr__(self, "steps", steps)
        object.__setattr__(self, "seed", require_integer("seed", self.seed, 0, 2**63 - 1))
        object.__setattr__(self, "modes_per_rod", require_integer("modes_per_rod (N_mod)", self.modes_per_rod, 1, 10**6))
        object.__setattr__(self, "bath_modes", require_integer("bath_modes (nu_max)", self.bath_modes, 1, 100_000))
        object.__setattr__(self, "batch_size", require_integer("batch_size", self.batch_size, 1, 100_000))
        top = 2 * self.modes_per_rod + 1 if self.bath == "conserved" else 1e12
        if self.initial_energy == "boltzmann":
            if self.bath != "fixed":
                raise InvalidParameterError("initial_energy='boltzmann' needs bath='fixed'")
        else:
            try:
                energy = float(self.initial_energy)
            except (TypeError, ValueError):
                raise InvalidParameterError(
                    f"initial_energy must be a number or 'boltzmann', got {self.initial_energy!r}") from None
            if not (math.isfinite(energy) and 0.0 < energy <= top):
                raise InvalidParameterError(f"initial_energy E_tr(0)/T_B^0 must lie in (0, {top:g}], got {energy!r}")
            object.__setattr__(self, "initial_energy", energy)
        solver = get_solver(self.solver)  # refuses an unknown name, listing the registered ones
        if not isinstance(self.options, dict):
            raise InvalidParameterError("options must be a dict of solver options")
        if self.rule == "solve" and math.isfinite(kappa):
            # the ensemble's defaults at finite kappa (the delay solver's: each epsilon within a few 1e-5
            # of rtol = 1e-10)
            object.__setattr__(self, "options", {**solver.batch_defaults, **self.options})
        if self.rule == "table" and self.table is None:
            raise InvalidParameterError("the table rule needs a restitution table file (table=PATH, --table PATH)")
        if self.table is not None:
            object.__setattr__(self, "table", str(self.table))

    @property
    def initial_temperature(self) -> float:
        """``T_B(0) / T_B^0``."""
        if self.bath == "fixed" or self.initial_energy == "boltzmann":
            return 1.0
        n2 = 2 * self.modes_per_rod
        return (n2 + 1 - self.initial_energy) / n2

    def batches(self) -> list:
        """``(start, stop)`` of each batch of chains."""
        return [(i, min(i + self.batch_size, self.chains)) for i in range(0, self.chains, self.batch_size)]

    def describe(self) -> dict:
        out = asdict(self)
        out["kappa"] = "inf" if math.isinf(self.kappa) else self.kappa
        return out


def thermal_restitution(gamma, kappa, temperature_ratio, seed, *, bath_modes=250, solver="delay", options=None):
    """epsilon of one collision whose rods start in a thermal bath (the ``solve`` rule's step).

    Parameters
    ----------
    gamma, kappa : float
        The paper's numbers (``kappa = inf`` with a solver that offers it, the delay
        solver: the stochastic hard-core mode, Eq. 26 on a grid).
    temperature_ratio : float
        ``T_B / E_tr`` >= 0, finite.
    seed : numpy.random.SeedSequence or int
        Source of the bath realisation.
    bath_modes : int
        ``nu_max``.
    solver : str
        Any solver; collisions other than the stochastic hard-core mode go through
        :func:`wavecontact.collide`.
    options : dict or None
        Solver options; the hard-core delay mode takes only ``hard_core_resolution``
        (grid points per period of the fastest bath mode, in [2, 4096], default 8).

    Returns
    -------
    float
        The coefficient of restitution (dimensionless).
    """
    options = dict(options or {})
    if not math.isfinite(temperature_ratio) or temperature_ratio < 0.0:
        raise SolverFailure(f"bath temperature ratio T_B/E_tr must be finite and >= 0, got {temperature_ratio!r}")
    if math.isinf(kappa) and get_solver(solver).offers(HARD_CORE_THERMAL):
        from ..bath.model import ThermalBath

        lengths = (0.5 * (1.0 + gamma), 0.5 * (1.0 + gamma) / gamma)  # l = 1 (docs/theory.md)
        vibrations = ThermalBath(float(temperature_ratio), bath_modes).draw(lengths, seed)
        return get_solver(solver).hard_core_thermal_restitution(gamma, vibrations, _hard_core_resolution(options))
    from ..api import collide

    return float(collide(gamma, kappa, solver, bath_temperature=float(temperature_ratio), bath_modes=bath_modes,
                         seed=seed, **options).restitution)


def _load_table(spec: MarkovSpec):
    if spec.rule != "table":
        return None
    from ..restitution_table import load

    table = load(spec.table)
    if not table.gamma[0] <= spec.gamma <= table.gamma[-1]:
        raise InvalidParameterError(
            f"gamma {spec.gamma:g} lies outside the table's range [{table.gamma[0]:g}, {table.gamma[-1]:g}]"
        )
    return table


def _uniform_blocks(generators, block):
    """Per chain, an endless supply of uniform numbers in blocks (same stream whatever the block size)."""
    while True:
        yield np.stack([g.random(block) for g in generators])


def _draw_eps2(spec, table, energy, temperature, level, seeds, step):
    """``epsilon^2`` of every chain of a batch at one step (energies in units of T_B^0)."""
    if spec.rule == "glauber":
        # Eq. 35: E' = T x with x a unit exponential (inverse transform of the uniform level)
        new_energy = temperature * -np.log1p(-level)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(energy > 0.0, new_energy / energy, np.inf), new_energy
    with np.errstate(divide="ignore"):
        ratio = temperature / energy
    if not np.all(np.isfinite(ratio)):
        raise SolverFailure(f"step {step}: E_tr reached 0, where T_B/E_tr is infinite; the {spec.rule} rule cannot go on")
    if spec.rule == "table":
        lo, hi = table.temperature_ratio[0], table.temperature_ratio[-1]
        outside = (ratio < lo) | (ratio > hi)
        if np.any(outside):
            raise InvalidParameterError(
                f"step {step}: T_B/E_tr = {ratio[outside][0]:.4g} lies outside the table's range [{lo:g}, {hi:g}]; "
                "use a table that covers it (E_tr/T_B is exponential in the stationary state, so its ratio "
                "exceeds 1e3 about once in 1000 steps)"
            )
        eps2 = table.quantile(spec.gamma, ratio, level)
    elif _batched(spec):
        # Python's float power, as the per-collision path squared: pow(x, 2) and numpy's x * x differ
        # in the last bit for some x (seed 2026, chain 1, step 330 of docs/markov.md's Fig. 10)
        eps2 = np.array([eps**2 for eps in _batch(spec, ratio, [step_seed(s, step) for s in seeds]).tolist()])
    else:
        eps2 = np.array([
            thermal_restitution(spec.gamma, spec.kappa, float(r), step_seed(s, step), bath_modes=spec.bath_modes,
                                solver=spec.solver, options=spec.options) ** 2
            for r, s in zip(ratio, seeds)
        ])
    return eps2, eps2 * energy


def _batched(spec) -> bool:
    """Whether the solver samples a step of every chain at once: it offers the stochastic hard-core
    mode (``kappa = inf``) or thermal batches (finite ``kappa``)."""
    return get_solver(spec.solver).offers(HARD_CORE_THERMAL if math.isinf(spec.kappa) else THERMAL_BATCH)


def _batch(spec, ratio, seeds):
    """epsilon of one step of every chain of a batch, in one call of the solver's batched samplers.

    ``kappa = inf``: the hard-core batch of ``ensemble`` with one temperature ratio per seed;
    each value is what :func:`thermal_restitution` gives for its ratio and seed, bit for bit.
    Finite ``kappa``: ``thermal_restitutions`` with one bath per seed (the ensemble's path).
    """
    from ..bath.model import ThermalBath

    solver = get_solver(spec.solver)
    if math.isinf(spec.kappa):
        # one (T_1, T_2) pair per chain: a flat array of two ratios would read as one pair for both chains
        pairs = np.repeat(np.asarray(ratio, dtype=float)[:, None], 2, axis=1)
        return solver.hard_core_thermal_batch(spec.gamma, pairs, seeds, spec.bath_modes,
                                              _hard_core_resolution(spec.options))
    baths = [ThermalBath(float(r), spec.bath_modes) for r in ratio]
    return solver.thermal_restitutions(spec.gamma, spec.kappa, baths, seeds, spec.options)[0]


def _hard_core_resolution(options) -> int:
    """The hard-core mode's grid points per period (its only option), checked."""
    unknown = set(options) - {"hard_core_resolution"}
    if unknown:
        raise InvalidParameterError(
            f"the hard-core delay mode takes only the option hard_core_resolution, not {', '.join(sorted(unknown))}"
        )
    return require_integer("hard_core_resolution", options.get("hard_core_resolution", 8), 2, 4096)


def run_chains(spec_fields: dict, start: int, stop: int) -> tuple:
    """Chains ``start`` to ``stop - 1`` of a run (a task: plain arguments, plain results).

    Returns
    -------
    (start, energy, temperature, eps2)
        Arrays of shape ``(chains, steps + 1)``, ``(chains, steps + 1)`` and
        ``(chains, steps)``; energies and temperatures in units of ``T_B^0``.
    """
    spec = MarkovSpec(**spec_fields)
    table = _load_table(spec)
    count = stop - start
    sequences = [chain_seed(spec.seed, c) for c in range(start, stop)]
    energy = np.empty((count, spec.steps + 1))
    temperature = np.empty((count, spec.steps + 1))
    eps2 = np.empty((count, spec.steps))
    generators = [np.random.default_rng(s) for s in sequences]
    if spec.initial_energy == "boltzmann":
        # Eq. 30 by inverse transform of the stream's first number
        energy[:, 0] = -np.log1p(-np.array([g.random() for g in generators]))
    else:
        energy[:, 0] = spec.initial_energy
    temperature[:, 0] = spec.initial_temperature
    block = min(_BLOCK, spec.steps)
    blocks = _uniform_blocks(generators, block) if spec.rule != "solve" else None
    levels = None
    share = 1.0 / (2 * spec.modes_per_rod)
    for j in range(spec.steps):
        if blocks is not None and j % block == 0:
            levels = next(blocks)
        level = levels[:, j % block] if levels is not None else None
        e, t = energy[:, j], temperature[:, j]
        eps2[:, j], energy[:, j + 1] = _draw_eps2(spec, table, e, t, level, sequences, j)
        if spec.bath == "conserved":
            temperature[:, j + 1] = t + (e - energy[:, j + 1]) * share
            if np.any(temperature[:, j + 1] < 0.0):
                raise SolverFailure(
                    f"step {j}: the bath temperature became negative (a collision gained more energy than "
                    f"2 N_mod T_B holds); raise modes_per_rod above {spec.modes_per_rod}"
                )
        else:
            temperature[:, j + 1] = t
    return start, energy, temperature, eps2


@dataclass
class MarkovResult:
    """The chains of a Markov run and their statistics.

    Attributes
    ----------
    spec : MarkovSpec
    energy : ndarray (chains, steps + 1)
        ``E_tr(j) / T_B^0`` before collision ``j`` (``j = 0``: the start).
    temperature : ndarray (chains, steps + 1)
        ``T_B(j) / T_B^0``.
    eps2 : ndarray (chains, steps)
        ``epsilon_j^2``; ``inf`` where ``E_tr(j)`` was 0 (only Glauber's rule after its
        total loss from a cold bath, Eq. 36: the new energy is then finite, the ratio is not).
    """

    spec: MarkovSpec
    energy: np.ndarray
    temperature: np.ndarray
    eps2: np.ndarray

    def default_burn_in(self) -> int:
        """Steps discarded before stationary statistics: three relaxation times of the slowest chain
        (at least a tenth of the run, at most half)."""
        from .ring_statistics import relaxation_collisions

        steps = self.spec.steps
        worst = 0
        for series in self.energy:
            relaxed = relaxation_collisions(series, 1.0, window=min(20, steps))
            worst = max(worst, steps // 2 if relaxed is None else 3 * relaxed)
        return int(min(steps // 2, max(steps // 10, worst)))

    def stationary(self, burn_in: int | None = None) -> np.ndarray:
        """``E_tr / T_B^0`` after the burn-in, shape ``(chains, n)``."""
        burn_in = self.default_burn_in() if burn_in is None else int(burn_in)
        if not 0 <= burn_in <= self.spec.steps - 2:
            raise InvalidParameterError(f"burn_in must lie in [0, {self.spec.steps - 2}], got {burn_in}")
        return self.energy[:, burn_in + 1:]

    def summary(self, burn_in: int | None = None) -> dict:
        """Stationary mean with its standard error, fraction below ``T_B^0``, KS test against Eq. 30
        (thinned), and the run's parameters.

        The standard errors account for the chains' autocorrelation: ``sqrt(C(0) tau / N)`` over
        all ``N`` stationary states, with the integrated autocorrelation time ``tau`` of the
        chains pooled (Sokal's automatic window, :mod:`wavecontact.studies.autocorrelation`);
        ``autocorrelation_time_reliable`` says whether each chain is at least 50 ``tau`` long.
        ``mean_energy_standard_error_between_chains`` is the spread of the chains' means
        (``None`` for one chain), an independent check of the same error.
        The KS test takes every ``k``-th state of each chain, ``k`` the lag at which
        the energy's autocorrelation has fallen below 0.1, so that its samples are
        close to independent (the p-value assumes independence).
        """
        from .autocorrelation import integrated_autocorrelation_time
        from .ring_statistics import decorrelation_stride, ks_exponential

        burn_in = self.default_burn_in() if burn_in is None else int(burn_in)
        states = self.stationary(burn_in)
        stride = max(decorrelation_stride(row) for row in states)
        thinned = states[:, ::stride].ravel()
        ks = ks_exponential(thinned, 1.0)
        chain_means = states.mean(axis=1)
        finite = self.eps2[:, burn_in:]
        spread = float(np.std(chain_means, ddof=1) / math.sqrt(chain_means.size)) if chain_means.size > 1 else None
        energy_time = integrated_autocorrelation_time(states)
        below_time = integrated_autocorrelation_time((states < 1.0).astype(float))
        spec = self.spec
        return {
            "mean_energy": float(states.mean()),
            "mean_energy_standard_error": energy_time.standard_error,
            "mean_energy_standard_error_between_chains": spread,
            "integrated_autocorrelation_time": energy_time.tau,
            "autocorrelation_window": energy_time.window,
            "effective_samples": energy_time.effective_samples,
            "autocorrelation_time_reliable": energy_time.reliable,
            "fraction_below_bath_temperature": float(np.mean(states < 1.0)),
            "fraction_below_bath_temperature_standard_error": below_time.standard_error,
            "boltzmann_fraction_below": 1.0 - math.exp(-1.0),
            "ks_statistic": float(ks.statistic),
            "ks_pvalue": float(ks.pvalue),
            "ks_samples": int(thinned.size),
            "ks_stride": int(stride),
            "burn_in": burn_in,
            "mean_eps2": float(np.mean(finite[np.isfinite(finite)])) if np.isfinite(finite).any() else None,
            "steps": spec.steps,
            "chains": spec.chains,
            "gamma": spec.gamma,
            "kappa": "inf" if math.isinf(spec.kappa) else spec.kappa,
            "rule": spec.rule,
            "bath": spec.bath,
            "modes_per_rod": spec.modes_per_rod,
            "bath_modes": spec.bath_modes,
            "seed": spec.seed,
        }

    def save(self, directory) -> Path:
        """Write ``markov.npz`` (with the run's description, checked on reading) into ``directory``."""
        from ..io.checkpoint import write_checkpoint

        path = Path(directory) / "markov.npz"
        Path(directory).mkdir(parents=True, exist_ok=True)
        write_checkpoint(path, _SCHEMA, _VERSION, self.spec.describe(),
                         {"energy": self.energy, "temperature": self.temperature, "eps2": self.eps2})
        return path


def load_result(directory, spec: MarkovSpec | None = None) -> MarkovResult:
    """Read ``markov.npz`` from ``directory`` (refused if ``spec`` is given and differs)."""
    from ..io.checkpoint import read_checkpoint

    arrays, meta = read_checkpoint(Path(directory) / "markov.npz", _SCHEMA, _VERSION,
                                   None if spec is None else spec.describe())
    fields = dict(meta["parameters"])
    fields["kappa"] = float(fields["kappa"])
    return MarkovResult(MarkovSpec(**fields), arrays["energy"], arrays["temperature"], arrays["eps2"])


def _check_chains(spec: MarkovSpec):
    """The arrays of a stored batch of chains, refused unless a run of ``spec`` could have produced them."""

    def check(arrays, start, stop):
        energy, temperature, eps2 = (np.asarray(arrays[k]) for k in ("energy", "temperature", "eps2"))
        n = stop - start
        shapes = ((n, spec.steps + 1), (n, spec.steps + 1), (n, spec.steps))
        if (energy.shape, temperature.shape, eps2.shape) != shapes:
            raise InvalidParameterError(f"arrays of shapes {energy.shape}, {temperature.shape}, {eps2.shape}, "
                                        f"expected {', '.join(map(str, shapes))}")
        if any(a.dtype.kind != "f" for a in (energy, temperature, eps2)):
            raise InvalidParameterError("arrays must hold floating-point numbers")
        for name, value in (("energy", energy), ("temperature", temperature)):
            if not np.all(np.isfinite(value)) or np.any(value < 0.0):
                raise InvalidParameterError(f"{name} must be finite and >= 0")
        # eps2 is inf only after Glauber's total loss (E_tr = 0), never NaN or negative
        if np.any(np.isnan(eps2)) or np.any(eps2 < 0.0) or (spec.rule != "glauber" and np.any(np.isinf(eps2))):
            raise InvalidParameterError("eps2 must be >= 0 (inf only with the glauber rule), never NaN")
        if spec.initial_energy != "boltzmann" and np.any(energy[:, 0] != spec.initial_energy):
            raise InvalidParameterError(f"the chains do not start at E_tr(0) = {spec.initial_energy!r}")
        if np.any(temperature[:, 0] != spec.initial_temperature):
            raise InvalidParameterError("the chains do not start at the run's bath temperature")
        if spec.bath == "fixed" and np.any(temperature != temperature[:, :1]):
            raise InvalidParameterError("a fixed bath's temperature changed along a chain")
        # the steps' own arithmetic, repeated: Eq. 28 for the energy (table and solve rules) and the bath
        if spec.rule != "glauber" and np.any(energy[:, 1:] != eps2 * energy[:, :-1]):
            raise InvalidParameterError("E_tr(j + 1) differs from eps2(j) E_tr(j)")
        if spec.rule == "glauber":
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = np.where(energy[:, :-1] > 0.0, energy[:, 1:] / energy[:, :-1], np.inf)
            if np.any(eps2 != ratio):
                raise InvalidParameterError("eps2(j) differs from E_tr(j + 1) / E_tr(j)")
        share = 1.0 / (2 * spec.modes_per_rod)
        expected = temperature[:, :-1] + (energy[:, :-1] - energy[:, 1:]) * share
        if spec.bath == "conserved" and np.any(temperature[:, 1:] != expected):
            raise InvalidParameterError("T_B(j + 1) differs from T_B(j) + (E_tr(j) - E_tr(j + 1)) / (2 N_mod)")
        return energy, temperature, eps2

    return check


def _store(out, spec: MarkovSpec):
    from ..io.run_controller import BatchStore

    return BatchStore(out, "markov.json", {"schema": _SCHEMA, "version": _VERSION, "spec": spec.describe()},
                      lambda start: f"chains_{start:09d}.npz", "chains_*.npz", _SCHEMA + "_batch", _VERSION,
                      lambda start, stop: {"spec": spec.describe(), "start": int(start), "stop": int(stop)},
                      _check_chains(spec), "a Markov run")


# the keywords of markov_chains that describe the run (the other fields: gamma, the solver options, the batches)
_SPEC_KEYWORDS = tuple(f.name for f in dataclass_fields(MarkovSpec) if f.name not in ("gamma", "options", "batch_size"))


def markov_chains(gamma, *, run=None, **settings) -> MarkovResult:
    """Run ``chains`` independent Markov chains of ``steps`` collisions (see module docstring).

    Parameters
    ----------
    gamma : float
        Length ratio ``l1 / l2`` in (0, 1].
    run : RunSettings, optional
        How the chains run (:class:`~wavecontact.io.run_controller.RunSettings`): ``executor`` (where
        batches of chains run, as for :func:`wavecontact.studies.ensemble.ensemble`; None: here),
        ``batch_size`` (chains per task, results do not depend on it; None: all chains in one task
        without an executor, else about 16 tasks), ``progress`` (a bar over chains on stderr; None: when
        stderr is a terminal), ``out`` (folder for the run's description ``markov.json`` and each
        finished batch of chains ``chains_*.npz``, locked against a second run while this one writes:
        the same call again skips the batches on disk, an interrupt loses only the batches in progress,
        a batch is all its chains' steps; a folder holding another Markov run is refused unless
        ``overwrite``, a stored batch whose values no run can produce is refused) and ``overwrite``.
    **settings
        What the chains compute: the fields of :class:`MarkovSpec` (``kappa``, ``rule``, ``chains``,
        ``steps``, ``seed``, ``bath``, ``modes_per_rod``, ``initial_energy``, ``bath_modes``, ``solver``,
        ``table``; its defaults where not given); the fields of ``run`` given one by one
        (``executor=pool, out="runs"``, :meth:`~wavecontact.io.run_controller.KeywordGroup.gather`); any
        other keyword is a solver option of the ``solve`` rule (``hard_core_resolution=16``).

    Returns
    -------
    MarkovResult
    """
    from ..io.run_controller import RunController, RunSettings
    from .ensemble import _executor_for, run_batches

    options = dict(settings)
    run = RunSettings.gather(run, options)
    described = {name: options.pop(name) for name in _SPEC_KEYWORDS if name in options}
    batch_size = run.batch_size
    if batch_size is None:
        chains = described.get("chains", 1)
        batch_size = chains if run.executor is None else max(1, math.ceil(chains / 16))
    spec = MarkovSpec(gamma, **described, options=options,
                      batch_size=min(int(batch_size), 100_000) if isinstance(batch_size, int) else batch_size)
    _load_table(spec)  # a bad table file fails here, before any task is sent
    fields = asdict(spec)
    store = None if run.out is None else _store(run.out, spec)
    pool = _executor_for(run.executor)
    with RunController(spec.chains, "markov", unit="chain", out_dir=run.out, progress=run.progress) as bar:
        done = {} if store is None else {a: (a, *v) for a, v in store.open(spec.batches(), run.overwrite).items()}
        todo = [(a, b) for a, b in spec.batches() if a not in done]
        bar.resumed(spec.chains - sum(b - a for a, b in todo))

        def collect(result):
            done[result[0]] = result
            if store is not None:
                store.save(result[0], result[0] + result[1].shape[0],
                           {"energy": result[1], "temperature": result[2], "eps2": result[3]})
            bar.advance(result[1].shape[0])

        try:
            run_batches(pool, run_chains, fields, todo, collect)
        except WavecontactError:
            raise
        except OSError as exc:
            raise InvalidParameterError(f"markov chains could not reach their workers: {exc}") from None
    order = [done[a] for a, _b in spec.batches()]
    return MarkovResult(spec, *(np.concatenate([o[k] for o in order]) for k in (1, 2, 3)))


@dataclass(frozen=True)
class SymmetryTest:
    """Bowker's test of the symmetry of binned transitions ``E -> E'`` (detailed balance, Eq. 33).

    Attributes
    ----------
    statistic : float
        ``sum_{i<j} (n_ij - n_ji)^2 / (n_ij + n_ji)``.
    dof : int
        Bin pairs with at least one count (chi-square degrees of freedom under symmetry).
    pvalue : float
        Chi-square tail probability of ``statistic``.
    asymmetry : float
        ``(statistic - dof) / n``: an estimate of the violation's size per transition,
        ``sum_{i<j} (p_ij - p_ji)^2 / (p_ij + p_ji)`` (0 under detailed balance).
    stationarity_pvalue : float
        KS p-value of the final energies against Eq. 30 (Eq. 32: Boltzmann in, Boltzmann out).
    counts : ndarray (bins, bins)
        ``n_ij``: transitions from bin ``i`` to bin ``j``.
    """

    statistic: float
    dof: int
    pvalue: float
    asymmetry: float
    stationarity_pvalue: float
    counts: np.ndarray


def _boltzmann_edges(bins):
    with np.errstate(divide="ignore"):
        return -np.log1p(-np.arange(bins + 1) / bins)  # equal-probability bins of Eq. 30 (last edge inf)


def symmetry_test(before, after, bins: int = 6) -> SymmetryTest:
    """Detailed balance on independent transitions whose starts follow Eq. 30.

    With ``E`` drawn from the stationary law ``exp(-E)`` and ``E'`` from the
    transition density, Eq. 33 says the pair ``(E, E')`` is exchangeable: the
    binned counts ``n_ij`` and ``n_ji`` have equal expectations.  Bins are the
    ``bins`` equal-probability intervals of Eq. 30.

    Parameters
    ----------
    before, after : array_like
        ``E / T_B^0`` and ``E' / T_B^0`` of independent transitions.
    bins : int
        Number of bins, in [2, 50].
    """
    from scipy import stats

    from .ring_statistics import ks_exponential

    bins = require_integer("bins", bins, 2, 50)
    e0, e1 = np.asarray(before, dtype=float), np.asarray(after, dtype=float)
    if e0.shape != e1.shape or e0.ndim != 1 or e0.size < 2:
        raise InvalidParameterError("before and after must be one-dimensional arrays of equal size >= 2")
    edges = _boltzmann_edges(bins)
    i = np.clip(np.searchsorted(edges, e0, side="right") - 1, 0, bins - 1)
    j = np.clip(np.searchsorted(edges, e1, side="right") - 1, 0, bins - 1)
    counts = np.zeros((bins, bins))
    np.add.at(counts, (i, j), 1.0)
    upper = np.triu_indices(bins, 1)
    a, b = counts[upper], counts.T[upper]
    used = (a + b) > 0
    statistic = float(np.sum((a[used] - b[used]) ** 2 / (a[used] + b[used])))
    dof = int(np.count_nonzero(used))
    pvalue = float(stats.chi2.sf(statistic, dof)) if dof else 1.0
    return SymmetryTest(statistic, dof, pvalue, (statistic - dof) / e0.size, float(ks_exponential(e1, 1.0).pvalue),
                        counts)


def symmetry_samples_needed(joint, alpha: float = 1e-3) -> float:
    """Transitions Bowker's test needs to reject a given asymmetry at level ``alpha``, on average.

    Parameters
    ----------
    joint : ndarray (bins, bins)
        Probabilities ``p_ij`` of the binned transitions (summing to 1).
    alpha : float
        Significance level in (0, 1).

    Returns
    -------
    float
        ``n`` at which the expected statistic ``dof + n sum_{i<j} (p_ij - p_ji)^2 / (p_ij + p_ji)``
        reaches the chi-square critical value (``inf`` for a symmetric ``joint``).
    """
    from scipy import stats

    p = np.asarray(joint, dtype=float)
    upper = np.triu_indices(p.shape[0], 1)
    a, b = p[upper], p.T[upper]
    used = (a + b) > 0
    lam = float(np.sum((a[used] - b[used]) ** 2 / (a[used] + b[used])))
    dof = int(np.count_nonzero(used))
    return math.inf if lam == 0.0 else (float(stats.chi2.isf(alpha, dof)) - dof) / lam
