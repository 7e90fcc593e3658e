"""Hashes of the fem multi-body loop's results on every kind of scene, to check a change leaves them bit-identical:

    PYTHONPATH=CHECKOUT python benchmarks/multibody_scene_hashes.py CHECKOUT > hashes.txt

(run it on both checkouts and diff).  Scenes: the example scene files, soft chains (exponential, penalty), a
hard chain, a rigid body on a rod (Hertz), a rigid body on a hard wall, a rigid body and a rod on a penalty
wall, two rigid bodies (penalty, exponential), a hammer on a chain with a wall; each P1 lumped and P2
consistent at 40 elements.  Hashed: velocities, internal energies, end time, steps, impact iterations, the
contact records, and ``solve``'s velocities, error estimate and impulses.  A scene that raises is listed.
"""
import glob
import hashlib
import sys

import numpy as np

import wavecontact
from wavecontact import Exponential, Hard, Hertz, Penalty, RigidBody, Rod, Scene, Wall, solve
from wavecontact.fem.multibody import run_line
from wavecontact.io.scene_file import read_scene_file

print(wavecontact.__file__, file=sys.stderr)
root = sys.argv[1] if len(sys.argv) > 1 else "."
scenes = {}
for p in sorted(glob.glob(root + "/examples/scenes/*")):
    scenes[p.split("/")[-1]] = read_scene_file(p).scene
for name, law in (("exp", Exponential(40.0, 0.01)), ("pen", Penalty(300.0))):
    scenes["soft_chain_" + name] = Scene(rods=(Rod(1.0), Rod(0.7), Rod(1.3)), velocities=(1.0, 0.0, -0.2), contact=law)
scenes["hard_chain"] = Scene(rods=(Rod(1.0), Rod(0.5), Rod(1.0)), velocities=(1.0, 0.0, -0.2), contact=Hard(),
                             gaps=(0.0, 0.0))
scenes["rigid_on_rod_hertz"] = Scene(rods=(RigidBody(0.5), Rod(1.0)), velocities=(1.0, 0.0), contact=Hertz(1e3))
scenes["rigid_hard_wall"] = Scene(rods=(RigidBody(2.0),), velocities=(1.5,), contact=(),
                                  walls=(None, Wall(gap=0.3, contact=Hard())))
scenes["rigid_rod_penalty_wall"] = Scene(rods=(RigidBody(0.5), Rod(1.0)), velocities=(1.0, 0.0), contact=Hard(),
                                         walls=(None, Wall(gap=0.1, contact=Penalty(300.0))))
scenes["rigid_rigid_soft"] = Scene(rods=(RigidBody(1.0), RigidBody(2.0)), velocities=(1.0, -0.5),
                                   contact=Penalty(50.0), gaps=(0.3,))
scenes["rigid_rigid_exp"] = Scene(rods=(RigidBody(1.0), RigidBody(2.0)), velocities=(1.0, -0.5),
                                  contact=Exponential(20.0), gaps=(0.3,))
scenes["hammer_chain"] = Scene(rods=(RigidBody(2.0), Rod(1.0), Rod(1.5)), velocities=(1.0, 0.0, 0.0),
                               contact=(Hard(), Exponential(200.0, 1e-3)), gaps=(0.0, None),
                               walls=(None, Wall(gap=0.0, contact=Hard())))
total = hashlib.sha256()
for name, scene in scenes.items():
    for order, mass in ((1, "lumped"), (2, "consistent")):
        h = hashlib.sha256()
        try:
            r = run_line(scene, elements=40, order=order, mass=mass)
            vals = list(r["velocities"]) + list(r["internal_energies"]) + [r["end_time"], r["work"]["steps"],
                                                                            r["extra"]["impact_iterations"]]
            for c in r["contacts"]:
                vals += [c.impulse, c.duration, c.first_contact, c.last_contact, c.intervals]
            res = solve(scene, "fem", elements=40, order=order, mass=mass)
            vals += list(res.velocities) + [res.error_estimate] + [c.impulse for c in res.contacts]
            h.update(np.array(vals, dtype=float).tobytes())
            line = (f"{name} P{order}{mass[0]} {h.hexdigest()[:16]} steps={r['work']['steps']} "
                    f"est={res.error_estimate:.3g}")
        except Exception as exc:  # noqa: BLE001 - a scene that raises is part of the record
            line = f"{name} P{order}{mass[0]} RAISED {type(exc).__name__}: {exc}"
            h.update(line.encode())
        total.update(h.digest())
        print(line, flush=True)
print("TOTAL", total.hexdigest())
