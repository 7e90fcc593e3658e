"""Output paths through the API: a directory, a wrong suffix or a missing directory is refused
with a message naming the argument, before anything is written."""

import math

import pytest

from wavecontact import collide
from wavecontact.errors import InvalidParameterError
from wavecontact.plotting.history import plot_velocity_history


@pytest.fixture(scope="module")
def result():
    return collide(0.6, math.inf)


def test_save_npz_refuses_a_directory(result, tmp_path):
    with pytest.raises(InvalidParameterError, match="path: .* is a directory"):
        result.save_npz(tmp_path)
    assert list(tmp_path.iterdir()) == []


def test_plot_refuses_a_directory_and_writes_nothing_beside_it(result, tmp_path):
    target = tmp_path / "figures"
    target.mkdir()
    with pytest.raises(InvalidParameterError, match="path: .* is a directory"):
        plot_velocity_history(result, target)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["figures"]


def test_plot_refuses_an_unknown_format_and_a_missing_directory(result, tmp_path):
    with pytest.raises(InvalidParameterError, match=r"\.png"):
        plot_velocity_history(result, tmp_path / "figure")
    with pytest.raises(InvalidParameterError, match="does not exist"):
        plot_velocity_history(result, tmp_path / "missing" / "figure.png")
    assert plot_velocity_history(result, tmp_path / "figure.png").is_file()
