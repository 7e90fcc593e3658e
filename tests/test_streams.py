"""NumPy's per-sample streams without the objects: bit for bit against SeedSequence, PCG64 and Generator."""

import os
import subprocess
import sys

import numpy as np
import pytest

from wavecontact.bath.streams import SpawnedSeeds, seed_states, spawned_states, standard_normals
from wavecontact.errors import InvalidParameterError


@pytest.mark.parametrize("seed", [0, 1, 12345, 2**32 - 1, 2**32, 2**63 + 11, 2**130 + 3])
def test_spawned_states_are_the_children_seed_words(seed):
    # entropy of one word, of several words (padding rule), and spawn keys of one and two words
    for start, stop in ((0, 40), (2**32 - 3, 2**32 + 2)):
        mine = spawned_states(seed, start, stop)
        numpy_children = [np.random.SeedSequence(seed, spawn_key=(j,)) for j in range(start, stop)]
        expected = np.array([child.generate_state(4, np.uint64) for child in numpy_children])
        assert np.array_equal(mine, expected)
    children = np.random.SeedSequence(seed).spawn(6)
    assert np.array_equal(spawned_states(seed, 0, 6), np.array([c.generate_state(4, np.uint64) for c in children]))


def test_normals_are_the_generators_numbers_including_the_ziggurat_tails():
    # 400 streams x 2000 draws: about 0.1 % of draws take the ziggurat's wedge branch and a few the tail
    seeds = SpawnedSeeds(77, 0, 400)
    mine = standard_normals(seed_states(seeds), 2000)
    expected = np.array([np.random.default_rng(s).standard_normal(2000) for s in seeds])
    assert np.array_equal(mine, expected)
    assert np.abs(expected).max() > 3.6541528853610088  # the tail (beyond the ziggurat's last layer) was drawn


def test_arbitrary_seeds_take_the_general_path():
    seeds = [0, 5, np.random.SeedSequence(9), np.random.SeedSequence(9, spawn_key=(3, 4))]
    mine = standard_normals(seed_states(seeds), 50)
    expected = np.array([np.random.default_rng(s).standard_normal(50) for s in seeds])
    assert np.array_equal(mine, expected)


def test_spawned_seeds_behave_as_the_sequence_of_children():
    seeds = SpawnedSeeds(3, 10, 20)
    assert len(seeds) == 10
    assert seeds[0].spawn_key == (10,) and seeds[-1].spawn_key == (19,)
    part = seeds[2:5]
    assert isinstance(part, SpawnedSeeds) and (part.start, part.stop) == (12, 15)
    assert np.array_equal(seed_states(part), seed_states(list(part)))
    with pytest.raises(IndexError):
        seeds[10]


@pytest.mark.parametrize("args", [(-1, 0, 3), (1, 5, 2), (True, 0, 1)])
def test_bad_seed_ranges_are_refused(args):
    with pytest.raises(InvalidParameterError):
        SpawnedSeeds(*args)


def test_pure_python_kernel_gives_the_same_numbers():
    # WAVECONTACT_PURE_PYTHON=1 runs the kernel as plain Python with numpy uint64 scalars
    code = ("import numpy as np; from wavecontact.bath.streams import spawned_states, standard_normals;"
            "print(standard_normals(spawned_states(4, 0, 2), 300).tobytes().hex())")
    env = dict(os.environ, WAVECONTACT_PURE_PYTHON="1")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True,
                         cwd=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    expected = np.array([np.random.default_rng(np.random.SeedSequence(4, spawn_key=(j,))).standard_normal(300)
                         for j in range(2)])
    assert bytes.fromhex(out.stdout.strip()) == expected.tobytes()
