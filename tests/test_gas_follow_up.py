"""The damped gas in the 1998 follow-up paper's set-up (docs/gas_study.py follow_up, docs/gas.md)."""

import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest

from wavecontact.gas import AlternatingLengths, GasSimulation, VibrationLaw, default_law, random_gas

ROOT = Path(__file__).resolve().parents[1]


def _study():
    spec = importlib.util.spec_from_file_location("gas_study", ROOT / "docs" / "gas_study.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_variant_of_the_study_gets_the_same_realisation():
    """SeedSequence.spawn gives new children on every call: the study builds them from the key instead, so the
    variants and damping times of a realisation share its gas, as gas_ensemble's runs would."""
    study = _study()
    seed = np.random.SeedSequence(study.FOLLOW_UP_ROOT).spawn(3)[2]
    first = study._follow_up_simulation(seed, VibrationLaw(study.LAW), 1.0)
    second = study._follow_up_simulation(seed, VibrationLaw(study.LAW), 10.0)
    np.testing.assert_array_equal(first.gas.positions, second.gas.positions)
    np.testing.assert_array_equal(first.gas.velocities, second.gas.velocities)
    fresh = np.random.SeedSequence(study.FOLLOW_UP_ROOT).spawn(3)[2].spawn(2)[0]  # gas_ensemble's split
    reference = random_gas(study.FOLLOW_UP_RODS, seed=fresh, lengths=AlternatingLengths(0.8, 1.0), packing_fraction=0.2)
    np.testing.assert_array_equal(first.gas.positions, reference.positions)


def test_gas_page_quotes_the_generated_follow_up_counts():
    """docs/gas.md quotes the collapse counts of docs/gas_follow_up_results.md (written by the study)."""
    results = (ROOT / "docs" / "gas_follow_up_results.md").read_text()
    prose = " ".join((ROOT / "docs" / "gas.md").read_text().split())
    counts = {}
    for line in results.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) == 9 and re.fullmatch(r"\d+/\d+", cells[2]):
            counts.setdefault(cells[0], {})[cells[1]] = cells[2]
    law = counts["law (two temperatures), 250 modes"]
    assert law["none"] == "0/8" and f"Without damping {law['none']} runs collapse" in prose
    damped = [law[t] for t in ("1", "10", "100", "1000")]
    assert f"With damping {', '.join(damped[:-1])} and {damped[-1]} runs collapse" in prose
    single = [counts["one-temperature law (s = 1/2 slice)"][t] for t in ("1", "10", "100", "1000")]
    assert f"collapses in {', '.join(single[:-1])} and {single[-1]} runs" in prose
    soft = next(rows for name, rows in counts.items() if name.startswith("law with soft contacts"))
    assert set(soft.values()) == {"0/8"} and "(0/8 each)" in prose
    reached = [int(v.replace(",", "")) for line in results.splitlines() if line.startswith("| law with soft")
               for v in re.findall(r"(\d[\d,]*)-(\d[\d,]*) collisions", line)[0]]
    assert f"after {min(reached):,} to {max(reached):,} collisions" in prose


@pytest.mark.slow  # ~10 s: the paper's first claim in its own set-up
def test_the_undamped_gas_of_two_lengths_in_turn_does_not_collapse():
    """Aspelmeier, Giese and Zippelius (1998): the fluctuations of the energy given to the vibrations suppress
    inelastic collapse. 200 rods with gamma = 4/5 at every collision, 25 times McNamara and Young's N_c of the
    cold law's restitution 0.8 (8), three realisations of 1,000,000 collisions."""
    for seed in np.random.SeedSequence(7).spawn(3):
        gas = random_gas(200, seed=seed, lengths=AlternatingLengths(0.8, 1.0), packing_fraction=0.2)
        result = GasSimulation(gas, VibrationLaw(default_law()), seed=seed, record_every=100_000,
                               max_frames=0).run(1_000_000)
        assert result.status == "completed", result.message
