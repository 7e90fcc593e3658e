"""A toy solver that is not shipped: the delay equation by scipy's Radau, window by window.

It exists to show that a new solver is its module plus one registry line: the contract tests
register it (``wavecontact.solvers.registered("toy", "toy_solver")``) and run every contract case
on it, the order case included, with nothing else changed.  Its method is that of
``delay_reference.py`` (method of steps, delayed values from the dense output of earlier windows),
independent of the package's delay kernels (it uses that module's windows); it takes two rods of one or two materials with
exponential contact, cold.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
from delay_reference import radau_windows

from wavecontact.contact import Exponential
from wavecontact.delay.parameters import delay_parameters
from wavecontact.errors import UnsupportedSceneError
from wavecontact.solvers.base import CollisionFields, SolverBase, SolverOptions, option

A0 = 40.0  # scaled start gap: exp(-40) ~ 4e-18, the force at the start is below round-off


@dataclass(frozen=True)
class ToyOptions(SolverOptions):
    solver_name = "toy"
    rtol: float = option(1e-10, "Radau's relative tolerance", low=1e-13, high=1e-2)
    samples: int = option(400, "history samples per window", kind="int", low=2, high=100_000)
    history: bool = option(True, "return the history (False: its two ends only)", kind="bool")


class ToySolver(SolverBase):
    """W' = exp(kappa tau - a0 - W - sum_i beta_i sum_n W(tau - n Gamma_i)) by Radau."""

    name = "toy"
    title = "toy solver"
    Options = ToyOptions
    resolution = "rtol"
    refines = -1
    contact_names = ("exponential",)
    order_case = MappingProxyType({"resolutions": (1e-4, 1e-6, 1e-8), "options": {}})
    agreement_case = ({"rtol": 1e-11}, 1e-7)

    def expected_order(self, options) -> float:
        return 1.0

    def _collide(self, scene, options) -> CollisionFields:
        if not isinstance(scene.contact, Exponential) or not scene.is_cold:
            raise UnsupportedSceneError("the toy solver takes cold rods with exponential contact")
        params = delay_parameters(scene)
        kappa = params.kappa
        windows, rate = radau_windows(params.round_trip_times, params.echo_weights, kappa, A0, options.rtol)
        samples = options.samples if options.history else 2
        tau = np.concatenate([np.linspace(start, stop, samples) for start, stop, _ in windows])
        big_w = np.concatenate([sol.sol(np.linspace(start, stop, samples))[0] for start, stop, sol in windows])
        force = np.array([rate(s, x) for s, x in zip(tau, big_w)])
        w, steps = windows[-1][2].y[0, -1], sum(sol.t.size - 1 for _, _, sol in windows)
        return CollisionFields(restitution=w / kappa - 1.0, time=tau * params.time_unit,
                               relative_velocity=params.approach_speed * (big_w / kappa - 1.0),
                               contact_force=params.force_unit * force / kappa, work={"steps": steps})


SOLVER = ToySolver()
