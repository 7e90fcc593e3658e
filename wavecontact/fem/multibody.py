"""The fem solver on scenes of many bodies on a line: run, records, error estimate, ImpactResult.

Every body and contact of the scene runs in one explicit time loop
(:mod:`wavecontact.fem.multibody_kernel`) on the meshes and step of
:mod:`wavecontact.fem.multibody_setup`.  :func:`solve_line` is what
``solve(scene, solver="fem", ...)`` calls for a scene beyond the paper's two
uniform rods; :func:`run_line` is one run (also usable on a two-rod scene, to
compare with the two-rod loop).

Error estimate: Richardson on every body's final velocity from the runs at
``elements // 2`` and ``elements // 4`` (and half and a quarter of the steps over
a soft contact between rigid sides, which no mesh resolves), assuming first order (the plastic
end-node rule of hard contact and a rigid body's contact with a rod end are
first order in ``h``; the force scheme of soft contacts is second): three
times the largest difference, over ``max |initial velocity|``.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .._jit import prepared_kernel_count
from ..bodies import PiecewiseRod, RigidBody
from ..errors import InvalidParameterError, SolverFailure
from ..impact_result import ContactRecord, ImpactResult
from ..limits import Cost, Limits, check_cost
from ..result import Outcome
from ..solvers.base import ERROR_SAFETY, Stopwatch, richardson_estimate
from . import multibody_kernel as mk
from .discretization import _stress_recovery
from .interleaved_step import node_position
from .multibody_setup import LineSetup, build_line_setup, mass_solves, rigid_contact_steps
from .multibody_store import G_CHUNK_ROWS, G_FLAT_U, G_FLAT_V, G_NODES, G_STEPPED_U, G_STEPPED_V, build_store

__all__ = ["ESTIMATE_ORDER", "LINE_OPTIONS", "field_bytes", "replay_fields", "run_line", "solve_line"]

#: Order in ``h`` the error estimate assumes (the slowest of the loop's contact treatments).
ESTIMATE_ORDER = 1.0
#: fem options the multi-body loop takes (the others must keep their defaults).
LINE_OPTIONS = ("elements", "order", "mass", "dt", "courant", "energy_tolerance", "max_time", "record_fields",
                "field_samples")
_CHUNK = 1 << 14
_PGS_ITERATIONS = 200


def _energies(setup: LineSetup, us, vs, ru, rv):
    """Per body: (momentum, mass, discrete energy of the leapfrog) now (energy: ``1/2 v M v + 1/2 u^n K u^(n+1)``)."""
    out = []
    for kind, slot in zip(setup.body_kind, setup.body_slot):
        if kind == mk.SIDE_RIGID:
            m = setup.rigid_masses[slot]
            out.append((m * rv[slot], m, 0.5 * m * rv[slot] ** 2))
            continue
        d = setup.rods[slot]
        u, v = us[slot], vs[slot]
        previous = u - setup.dt * v
        energy = 0.5 * float(v @ (d.mass_matrix @ v)) + 0.5 * float(previous @ (d.stiffness @ u))
        out.append((float(d.lumped_mass @ v), float(d.lumped_mass.sum()), energy))
    return out


def _gap(row, us, ru) -> float:
    """Gap of one contact (length) from its row of the contact table."""
    def displacement(kind, slot, node):
        if kind == mk.SIDE_ROD:
            return float(us[slot][node])
        return float(ru[slot]) if kind == mk.SIDE_RIGID else 0.0

    return float(row[mk.C_OFFSET] + displacement(int(row[mk.C_KIND_B]), int(row[mk.C_SLOT_B]), int(row[mk.C_NODE_B]))
                 - displacement(int(row[mk.C_KIND_A]), int(row[mk.C_SLOT_A]), int(row[mk.C_NODE_A])))


def _soft_potential(setup: LineSetup, us, ru) -> float:
    total = 0.0
    for c, law in enumerate(setup.laws):
        if setup.contacts[c, mk.C_HARD] == mk.HARD_NONE:
            total += float(law.potential(_gap(setup.contacts[c], us, ru)))
    return total


def _start(scene, setup: LineSetup) -> dict:
    """The loop's arrays at the start of a run (velocities half a step back), as a dict."""
    solves = mass_solves(setup)
    us = [u.copy() for u in setup.u0]
    vs = [v.copy() for v in setup.v0]
    ru = np.zeros(setup.rigid_masses.size)
    rv = np.array([scene.velocities[i] for i, k in enumerate(setup.body_kind) if k == mk.SIDE_RIGID], dtype=float)
    rinv = 1.0 / setup.rigid_masses if setup.rigid_masses.size else np.zeros(0)
    start = _energies(setup, us, vs, ru, rv)
    energy0 = sum(e for _, _, e in start) + _soft_potential(setup, us, ru)
    momentum0 = sum(p for p, _, _ in start)
    # half a step back: the loop keeps velocities at the half steps (soft forces at the start included)
    dt_ = setup.dt
    for c in range(setup.contacts.shape[0]):
        if setup.contacts[c, mk.C_HARD] == mk.HARD_NONE:
            gap = setup.contacts[c, mk.C_OFFSET]
            force = float(setup.laws[c].force(gap))
            if force:
                _half_kick(setup, c, -0.5 * dt_ * force, vs, rv, rinv)
    for d, u, v in zip(setup.rods, us, vs):
        v -= 0.5 * dt_ * np.asarray(-(d.stiffness @ u)) / d.lumped_mass if d.mass_kind == "lumped" else \
            0.5 * dt_ * _consistent_solve(d, -(d.stiffness @ u))
    # hard contacts of rod ends (or a rod end and a wall) on the exact lattice: characteristic free ends
    ends = np.zeros((setup.contacts.shape[0], mk.END_FIELDS))
    for c, row in enumerate(setup.contacts):
        kinds = (int(row[mk.C_KIND_A]), int(row[mk.C_KIND_B]))
        if setup.lattice and row[mk.C_HARD] != mk.HARD_NONE and mk.SIDE_RIGID not in kinds:
            row[mk.C_LATTICE] = 1.0
            for kind, slot_col, node_col, previous, incoming in (
                    (kinds[0], mk.C_SLOT_A, mk.C_NODE_A, mk.E_PREVIOUS_A, mk.E_INCOMING_A),
                    (kinds[1], mk.C_SLOT_B, mk.C_NODE_B, mk.E_PREVIOUS_B, mk.E_INCOMING_B)):
                if kind == mk.SIDE_ROD:
                    slot, node = int(row[slot_col]), int(row[node_col])
                    earlier = us[slot][node] - dt_ * vs[slot][node]
                    ends[c, previous] = earlier
                    ends[c, incoming] = 0.5 * (us[slot][node] - earlier)
    # every body's arrays in one store (the loop steps the flat ones, or for a consistent mass in the interleaved
    # layout the rows of the mass-solve table); us, vs, ru, rv become views of it
    store, layout, (rigid_u, rigid_v, zero) = build_store(setup.rods, us, vs, solves, ru, rv)
    us = [store[row[G_FLAT_U]:row[G_FLAT_U] + row[G_NODES]] for row in layout]
    vs = [store[row[G_FLAT_V]:row[G_FLAT_V] + row[G_NODES]] for row in layout]
    ru, rv = store[rigid_u:rigid_u + ru.size], store[rigid_v:rigid_v + rv.size]
    kernel_contacts = setup.contacts.copy()
    where = np.zeros(setup.columns.size, dtype=np.int64)
    # each contact side's displacement as an index in the store (a wall: the entry that stays 0) and how far
    # its velocity lies from it (the M^-1 e_end entries: ``where`` holds their displacements' indices)
    indices = np.zeros((setup.contacts.shape[0], mk.INDEX_FIELDS), dtype=np.int64)
    indices[:, [mk.I_U_A, mk.I_U_B]] = zero

    def position(slot, node):
        rows = int(layout[slot, G_CHUNK_ROWS])
        return int(node_position(node, rows, setup.rods[slot].order)) if rows else int(node)

    for row, index in zip(kernel_contacts, indices):
        for kind_col, slot_col, node_col, col_col, first_col, len_col, u_col, shift_col in (
                (mk.C_KIND_A, mk.C_SLOT_A, mk.C_NODE_A, mk.C_COL_A, mk.C_FIRST_A, mk.C_LEN_A, mk.I_U_A, mk.I_SHIFT_A),
                (mk.C_KIND_B, mk.C_SLOT_B, mk.C_NODE_B, mk.C_COL_B, mk.C_FIRST_B, mk.C_LEN_B, mk.I_U_B, mk.I_SHIFT_B)):
            slot = int(row[slot_col])
            if int(row[kind_col]) == mk.SIDE_ROD:
                base = int(layout[slot, G_STEPPED_U])
                col_start, first = int(row[col_col]), int(row[first_col])
                for j in range(int(row[len_col])):
                    where[col_start + j] = base + position(slot, first + j)
                row[node_col] = position(slot, int(row[node_col]))  # the end node's position in the stepped array
                index[u_col] = base + int(row[node_col])
                index[shift_col] = layout[slot, G_STEPPED_V] - base
            elif int(row[kind_col]) == mk.SIDE_RIGID:
                where[int(row[col_col])] = index[u_col] = rigid_u + slot
                index[shift_col] = rigid_v - rigid_u
    records = np.zeros((setup.contacts.shape[0], mk.RECORD_FIELDS))
    records[:, mk.R_FIRST] = -1.0
    values = np.zeros(setup.contacts.shape[0])
    targets = np.zeros(setup.contacts.shape[0])
    control = np.zeros(mk.CONTROL_SIZE)
    control[mk.K_DT] = dt_
    control[mk.K_PERIOD] = setup.period
    control[mk.K_CHECK_EVERY] = max(1, int(0.05 * setup.period / dt_))
    control[mk.K_SPEED_TOLERANCE] = 1e-12 * setup.speed_scale
    control[mk.K_ITERATIONS] = _PGS_ITERATIONS
    control[mk.K_LEFT_WALL] = float(setup.walls[0])
    control[mk.K_RIGHT_WALL] = float(setup.walls[1])
    state = np.zeros(mk.STATE_SIZE)
    return {"us": us, "vs": vs, "ru": ru, "rv": rv, "rinv": rinv, "start": start, "energy0": energy0,
            "momentum0": momentum0, "args_rods": (store, layout), "contacts": kernel_contacts, "where": where,
            "indices": indices,
            "records": records, "values": values, "targets": targets, "ends": ends, "control": control,
            "state": state}


def _advance(setup: LineSetup, loop: dict, steps: int):
    """Up to ``steps`` steps of the loop; ``(status, steps done)``."""
    links = (loop["contacts"], setup.columns, loop["where"], loop["records"], loop["values"], loop["targets"],
             loop["ends"], loop["indices"])
    return mk.advance_line(loop["args_rods"], (loop["ru"], loop["rv"]),
                           (setup.body_kind, setup.body_slot), links, loop["control"], loop["state"], steps)


def run_line(scene, elements: int = 800, order: int = 1, mass: str = "lumped", dt=None, courant=None,
             energy_tolerance: float = 0.05, max_time=None, record_fields: bool = False,
             field_samples: int = 300, contact_steps=None) -> dict:
    """One run of the multi-body loop on a line scene; a dict of the outcome (see :func:`solve_line`).

    ``contact_steps``: steps over the time scale of each soft contact between rigid sides
    (:func:`~wavecontact.fem.multibody_setup.build_line_setup`; default from ``elements``).

    With ``record_fields`` the loop runs a second time from the start to the same last step, stopping at
    ``field_samples`` evenly spread steps to copy the fields (:func:`replay_fields`); the first run, and so
    every result, is the same as without.
    """
    setup = build_line_setup(scene, elements, order, mass, dt, courant, contact_steps=contact_steps)
    loop = _start(scene, setup)
    dt_ = setup.dt
    ru, rv, records, state = loop["ru"], loop["rv"], loop["records"], loop["state"]
    start, energy0, momentum0 = loop["start"], loop["energy0"], loop["momentum0"]
    if max_time is None:
        gaps = setup.contacts[:, mk.C_OFFSET]
        max_time = 40.0 * float(np.sum(np.maximum(gaps, 0.0))) / setup.speed_scale + 100.0 * setup.period
    max_steps = math.ceil(max_time / dt_)
    status = mk.STATUS_RUNNING
    us_t, vs_t = loop["us"], loop["vs"]
    worst_drift = 0.0
    loop_seconds = 0.0
    while status == mk.STATUS_RUNNING:
        if state[mk.S_STEPS] >= max_steps:
            acting = [name for name, r in zip(setup.contact_names, records) if r[mk.R_ACTIVE]]
            raise SolverFailure(f"the bodies did not separate for good within t = {max_time:.4g} (still in contact: "
                                f"{', '.join(acting) or 'none'}); contacts may keep re-engaging (check the velocities "
                                "and the walls), a soft contact between bodies that separate slowly stays in range "
                                "for long, or the run needs a larger max_time", Outcome.TIME_LIMIT)
        started = time.perf_counter()
        status, _ = _advance(setup, loop, int(min(_CHUNK, max_steps - state[mk.S_STEPS])))
        loop_seconds += time.perf_counter() - started
        with np.errstate(all="ignore"):  # a blow-up is reported below, not as a warning
            now = _energies(setup, us_t, vs_t, ru, rv)
            energy = sum(e for _, _, e in now) + _soft_potential(setup, us_t, ru)
        drift = (energy - energy0) / setup.energy_scale
        worst_drift = max(worst_drift, abs(drift))
        too_far = drift > energy_tolerance if setup.hard else abs(drift) > energy_tolerance
        if status == mk.STATUS_FAILED or not math.isfinite(energy) or too_far:
            raise SolverFailure(
                f"energy balance violated at t = {state[mk.S_TIME]:.6g}: relative energy error {drift:.3g} "
                f"(energy_tolerance = {energy_tolerance:g}); use more elements or a smaller dt",
                Outcome.ENERGY_DRIFT)
    end = _energies(setup, us_t, vs_t, ru, rv)
    velocities = tuple(p / m for p, m, _ in end)
    internal = tuple(0.0 if k == mk.SIDE_RIGID else e - p * p / (2 * m) for k, (p, m, e) in zip(setup.body_kind, end))
    momentum = sum(p for p, _, _ in end)
    momentum_scale = sum(abs(p) for p, _, _ in start) or 1.0
    contacts = []
    for c, name in enumerate(setup.contact_names):
        r = records[c]
        never = r[mk.R_INTERVALS] == 0
        contacts.append(ContactRecord(name=name, impulse=float(r[mk.R_IMPULSE]), duration=float(r[mk.R_STEPS] * dt_),
                                      first_contact=math.nan if never else float(r[mk.R_FIRST]),
                                      last_contact=math.nan if never else float(r[mk.R_LAST]),
                                      intervals=int(r[mk.R_INTERVALS])))
    steps = int(state[mk.S_STEPS])
    elements_total = sum(d.n_elements for d in setup.rods)
    fields = replay_fields(scene, setup, loop, steps, field_samples) if record_fields else None
    return {
        "fields": fields,
        "velocities": velocities,
        "internal_energies": internal,
        "contacts": tuple(contacts),
        "end_time": float(state[mk.S_TIME]),
        "energy_drift": (sum(e for _, _, e in end) - energy0) / setup.energy_scale,
        "largest_energy_drift": worst_drift,
        "momentum_drift": abs(momentum - momentum0) / momentum_scale if not any(setup.walls) else math.nan,
        "masses": tuple(m for _, m, _ in end),
        "work": {"steps": steps, "elements": elements_total, "nodes": sum(d.n_nodes for d in setup.rods),
                 "element_steps": steps * elements_total, "dt": dt_,
                 "loop_seconds": loop_seconds},
        "extra": {"lattice": setup.lattice, "stable_step": setup.stable_step,
                  "impact_iterations": int(state[mk.S_MAX_ITERATIONS])},
        "setup": setup,
    }


def field_bytes(nodes: float, rigid: int, samples: int) -> float:
    """Bytes the sampled fields take: displacement, velocity and stress per node, two values per rigid body."""
    return 8.0 * samples * (3.0 * nodes + 2.0 * rigid + 1.0)


def replay_fields(scene, setup: LineSetup, first_run: dict, steps: int, samples: int) -> dict:
    """Run the loop again from the start for ``steps`` steps, copying the fields at ``samples`` steps.

    The replay takes the same steps as the first run (the loop's state does not depend on where a call
    of the kernel ends; the separation check, which only reads it, is switched off), and its last
    state is checked to be the first run's, bit for bit.

    Returns
    -------
    dict
        ``{"time": (nt,), "rods": [{"body", "x", "displacement", "velocity", "stress", "cells"}, ...],
        "points": [{"body", "x", "displacement", "velocity"}, ...], "walls": [x_left, x_right]}``:
        node coordinates on the line (each body at its reference position, :mod:`.multibody_setup`),
        displacement (length), velocity (length/time, half a step before the sample time, as the
        leapfrog keeps it) and stress ``E du/dx`` (force/area, averaged over the elements at a node)
        of every rod; the same without stress for each rigid body (a point); wall positions (None
        where there is no wall).
    """
    at = np.unique(np.linspace(0, steps, max(int(samples), 2)).round().astype(np.int64))
    loop = _start(scene, setup)
    loop["control"][mk.K_PERIOD] = math.inf  # never stop on separation: run exactly to the first run's end
    flat_u, flat_v, ru, rv, state = loop["us"], loop["vs"], loop["ru"], loop["rv"], loop["state"]
    n_rods, n_rigid = len(setup.rods), setup.rigid_masses.size
    times = np.empty(at.size)
    u_samples = [np.empty((at.size, d.n_nodes)) for d in setup.rods]
    v_samples = [np.empty((at.size, d.n_nodes)) for d in setup.rods]
    rigid_u, rigid_v = np.empty((at.size, n_rigid)), np.empty((at.size, n_rigid))
    for k, target in enumerate(at):
        while state[mk.S_STEPS] < target:
            status, _ = _advance(setup, loop, int(target - state[mk.S_STEPS]))
            if status == mk.STATUS_FAILED:
                raise SolverFailure("the replay that samples the fields failed where the first run did not",
                                    Outcome.ENERGY_DRIFT)
        times[k] = state[mk.S_TIME]
        for b in range(n_rods):
            u_samples[b][k] = flat_u[b]
            v_samples[b][k] = flat_v[b]
        rigid_u[k], rigid_v[k] = ru, rv
    if not (all(np.array_equal(a, b) for a, b in zip(first_run["us"], flat_u))
            and np.array_equal(first_run["ru"], ru) and np.array_equal(first_run["rv"], rv)):
        raise SolverFailure("the replay that samples the fields did not end in the first run's state")
    rods, points = [], []
    for i, (kind, slot) in enumerate(zip(setup.body_kind, setup.body_slot)):
        origin = float(setup.positions[i])
        if kind == mk.SIDE_RIGID:
            points.append({"body": i, "x": origin, "displacement": rigid_u[:, slot].copy(),
                           "velocity": rigid_v[:, slot].copy()})
            continue
        d = setup.rods[slot]
        recovery = _stress_recovery(d.x, d.cells, _element_moduli(scene.rods[i], d)).tocsr()
        rods.append({"body": i, "x": d.x + origin, "displacement": u_samples[slot], "velocity": v_samples[slot],
                     "stress": np.asarray((recovery @ u_samples[slot].T).T), "cells": d.cells.copy()})
    return {"time": times, "rods": rods, "points": points, "walls": list(_wall_positions(scene, setup))}


def _element_moduli(body, d) -> np.ndarray:
    """Young's modulus of each element (of the segment holding its midpoint)."""
    from ..bodies import body_segments

    segments = body_segments(body)
    ends = np.cumsum([s.length for s in segments])
    middle = d.x[d.cells[:, :2]].mean(axis=1)
    index = np.clip(np.searchsorted(ends, middle, side="right"), 0, len(segments) - 1)
    return np.array([s.youngs_modulus for s in segments])[index]


def _wall_positions(scene, setup: LineSetup) -> tuple:
    """Reference positions of the left and right wall (None where absent)."""
    left = right = None
    for name, row in zip(setup.contact_names, setup.contacts):
        if name == "left wall":
            left = float(setup.positions[0]) - float(row[mk.C_OFFSET])
        elif name == "right wall":
            last = len(setup.body_kind) - 1
            right = float(setup.positions[last]) + float(scene.rods[last].length) + float(row[mk.C_OFFSET])
    return left, right


def _consistent_solve(d, rhs):
    import scipy.linalg

    return scipy.linalg.cho_solve_banded((d.mass_cholesky, True), rhs)


def _half_kick(setup, c, impulse, vs, rv, rinv):
    """Kick the two sides of contact ``c`` apart by ``impulse`` along their ``M^-1 e_end`` (no shift)."""
    row = setup.contacts[c]
    for kind_col, slot_col, col_col, first_col, len_col, sign in (
            (mk.C_KIND_B, mk.C_SLOT_B, mk.C_COL_B, mk.C_FIRST_B, mk.C_LEN_B, 1.0),
            (mk.C_KIND_A, mk.C_SLOT_A, mk.C_COL_A, mk.C_FIRST_A, mk.C_LEN_A, -1.0)):
        kind, slot = int(row[kind_col]), int(row[slot_col])
        if kind == mk.SIDE_ROD:
            start, first, length = int(row[col_col]), int(row[first_col]), int(row[len_col])
            vs[slot][first:first + length] += sign * impulse * setup.columns[start:start + length]
        elif kind == mk.SIDE_RIGID:
            rv[slot] += sign * impulse * rinv[slot]


def _describe(body) -> str:
    if isinstance(body, RigidBody):
        return f"rigid, mass {body.mass:g}"
    if isinstance(body, PiecewiseRod):
        tapered = sum(s.tapered for s in body.segments)
        return f"piecewise rod, {len(body.segments)} segment(s){f', {tapered} tapered' if tapered else ''}, " \
               f"length {body.length:g}"
    return f"rod, length {body.length:g}"


def line_cost(scene, options: dict) -> Cost:
    """Nodes and steps of one run, estimated from the meshes' sizes (the step at the coarsest stable value)."""
    from ..bodies import body_segments

    elements = options.get("elements", 800)
    deformable = [b for b in scene.rods if not isinstance(b, RigidBody)]
    if not deformable:
        return Cost(steps=1e4, work=1e4, memory=1e6, detail="rigid bodies only")
    travel = min(sum(s.travel_time for s in body_segments(b)) for b in deformable) / elements
    nodes = options.get("order", 1) * sum(max(1, round(s.travel_time / travel)) for b in deformable
                                          for s in body_segments(b)) + len(deformable)
    longest = max(2.0 * sum(s.travel_time for s in body_segments(b)) for b in deformable)
    span = 105.0 * longest if options.get("max_time") is None else float(options["max_time"])
    steps = span / (0.2 * travel)
    if options.get("record_fields"):  # a second run samples the fields, held in memory at once
        rigid = sum(isinstance(b, RigidBody) for b in scene.rods)
        fields = field_bytes(nodes, rigid, options.get("field_samples", 300))
        return Cost(steps=steps, work=2.0 * steps * nodes, memory=8.0 * 48 * nodes + fields,
                    detail=f"{nodes:.3g} nodes, at most {steps:.3g} steps, {options.get('field_samples', 300)} "
                    f"field samples of {fields:.3g} bytes")
    return Cost(steps=steps, work=steps * nodes, memory=8.0 * 48 * nodes,
                detail=f"{nodes:.3g} nodes, at most {steps:.3g} steps")


def solve_line(scene, options: dict, *, tolerance=None, max_work=None, max_memory=None,
               estimate_error: bool = True) -> ImpactResult:
    """``solve(scene, solver="fem", ...)`` for a line scene beyond the paper's two rods.

    ``options``: the fem options; of them the loop takes ``elements`` (on the rod of the shortest wave
    travel time, every segment at about the same ``h / c``), ``order``, ``mass``, ``dt``, ``courant``,
    ``energy_tolerance``, ``max_time``, ``record_fields`` and ``field_samples`` (the fields of
    :func:`replay_fields` in ``result.fields``: a second run, its memory counted in the cost checked
    against ``max_memory`` before any work); any other option must keep its default.
    """
    from .solver import FemOptions

    given = dict(options)
    checked = FemOptions.from_mapping(given)
    defaults = FemOptions()
    for name in given:
        if name not in LINE_OPTIONS and getattr(checked, name) != getattr(defaults, name):
            raise InvalidParameterError(f"fem option {name} is not available for multi-body scenes; the multi-body "
                                        f"loop takes {', '.join(LINE_OPTIONS)}")
    run_options = {name: getattr(checked, name) for name in LINE_OPTIONS}
    limits = Limits(max_work=max_work, max_memory=max_memory)
    check_cost("fem", line_cost(scene, run_options), limits)
    prepared = prepared_kernel_count()
    with Stopwatch() as watch:
        run = run_line(scene, **run_options)
        levels = [(run_options["elements"], run["velocities"])]
        method = "not requested"
        estimate = math.nan
        if estimate_error or tolerance is not None:
            estimate, method, levels = _estimate(scene, run_options, run, levels)
    scale = max(abs(v) for v in scene.velocities) or 1.0
    result = ImpactResult(
        velocities=tuple(float(v) for v in run["velocities"]),
        internal_energies=tuple(float(e) for e in run["internal_energies"]),
        contacts=run["contacts"],
        error_estimate=float(estimate),
        solver="fem",
        end_time=run["end_time"],
        initial_velocities=tuple(float(v) for v in scene.velocities),
        masses=run["masses"],
        bodies=tuple(_describe(b) for b in scene.rods),
        wall_time_s=watch.seconds,
        options=dict(checked.as_dict()),
        work=run["work"],
        diagnostics={"energy_drift": float(run["energy_drift"]), "momentum_drift": float(run["momentum_drift"]),
                     "includes_kernel_preparation": prepared_kernel_count() > prepared,
                     "error_estimate_method": method,
                     "error_estimate_levels": [(n, [float(x) for x in v]) for n, v in levels],
                     "velocity_scale": scale, **run["extra"]},
        fields=run["fields"],
    )
    if tolerance is not None and not estimate <= tolerance:
        from ..errors import AccuracyError

        wanted = math.ceil(1.2 * run_options["elements"] * estimate / tolerance)
        advice = f"try elements={wanted}"
        raise AccuracyError(f"fem: error estimate {estimate:.2g} of the velocities exceeds tolerance={tolerance:g}; "
                            f"{advice}", result=result, advice=advice)
    return result


def _estimate(scene, run_options: dict, run: dict, levels: list) -> tuple:
    """Richardson on every body's velocity from the runs at elements // 2 and // 4 (first order)."""
    scale = max(abs(v) for v in scene.velocities) or 1.0
    elements = run_options["elements"]
    for divisor in (2, 4):
        coarse = elements // divisor
        if coarse < 1:
            break
        try:
            # a soft contact between rigid sides has no mesh: its steps are halved with the elements
            coarse_options = {**run_options, "elements": coarse, "record_fields": False,
                              "contact_steps": rigid_contact_steps(elements) / divisor}
            if run["setup"].rigid_soft and run_options["dt"] is not None:  # a given step: coarsened with them
                coarse_options["dt"] = run_options["dt"] * divisor
            levels.append((coarse, run_line(scene, **coarse_options)["velocities"]))
        except SolverFailure as failure:
            if len(levels) == 1:
                return math.nan, f"none (the run at elements={coarse} failed: {failure})", levels
            break
    if len(levels) == 1:
        return math.nan, "none (no coarser resolution)", levels
    bodies = len(levels[0][1])
    estimate = max(richardson_estimate([level[1][i] / scale for level in levels], ESTIMATE_ORDER,
                                       safety=ERROR_SAFETY) for i in range(bodies))
    runs = "; ".join(f"elements={n}" for n, _ in levels[1:])
    return estimate, f"Richardson on the velocities: {runs}; order {ESTIMATE_ORDER:g}, safety {ERROR_SAFETY:g}", levels
