"""The x-t diagram: writes a real image of the sampled stress and refuses results without fields."""

from __future__ import annotations

import dataclasses
import importlib.util

import numpy as np
import pytest
from test_io_fields import hard_impact_result  # exact fields of the hard-core impact

from wavecontact.errors import InvalidParameterError
from wavecontact.io.fields import MissingFieldsError
from wavecontact.plotting.xt import plot_xt_diagram, xt_figure
from wavecontact.result import CollisionResult


def _png_size(path):
    header = path.read_bytes()[:24]
    assert header[:8] == b"\x89PNG\r\n\x1a\n"
    return int.from_bytes(header[16:20], "big"), int.from_bytes(header[20:24], "big")


@pytest.mark.parametrize("coordinates", ["reference", "deformed"])
def test_xt_diagram_writes_a_png(tmp_path, coordinates):
    result = hard_impact_result(0.6, elements=30, samples=120)
    result = dataclasses.replace(result, contact_start=0.0, contact_duration=1.6)
    path = plot_xt_diagram(result, tmp_path / "xt.png", coordinates=coordinates)
    assert path.stat().st_size > 20_000
    width, height = _png_size(path)
    assert width > 800 and height > 600


def test_xt_diagram_colours_the_stress_symmetrically_about_zero():
    result = hard_impact_result(0.6, elements=20, samples=50)
    fig = xt_figure(result)
    ax = fig.axes[0]
    meshes = ax.collections
    assert len(meshes) == 2  # one colour field per rod
    norm = meshes[0].norm
    assert norm.vmin == -norm.vmax == -0.5  # the impact plateau -Z V / 2 is the extreme value
    assert "0.6" in ax.get_title() and r"\infty" in ax.get_title()
    # both rods on one axis at their positions: rod 1 left of the contact, rod 2 right of it
    x_min, x_max = ax.get_xlim()
    assert x_min <= -0.8 + 1e-9 and x_max >= 4 / 3 - 1e-9


def test_xt_diagram_thins_large_fields_but_keeps_ends():
    result = hard_impact_result(0.6, elements=200, samples=300)
    fig = xt_figure(result, max_nodes=50, max_times=40)
    coords = fig.axes[0].collections[0].get_coordinates()
    assert coords.shape[:2] == (40, 50)


def test_results_without_fields_are_refused(tmp_path):
    result = CollisionResult(
        restitution=0.75,
        solver="delay",
        wall_time_s=0.0,
        time=np.linspace(0, 1, 3),
        relative_velocity=np.zeros(3),
    )
    with pytest.raises(MissingFieldsError, match="record_fields=True"):
        plot_xt_diagram(result, tmp_path / "xt.png")
    assert not (tmp_path / "xt.png").exists()
    with pytest.raises(InvalidParameterError, match="field"):
        xt_figure(hard_impact_result(elements=4, samples=5), field="strain")


def test_reference_layout_closes_the_initial_gap():
    result = hard_impact_result(0.6, elements=10, samples=20)
    rod1, rod2 = result.extra["fields"]["rods"]
    rod1["x"] = rod1["x"] - 0.7  # rods placed apart, as a solver starts them
    rod2["x"] = rod2["x"] + 0.7
    x_min, x_max = xt_figure(result).axes[0].get_xlim()
    assert x_min == pytest.approx(-0.8) and x_max == pytest.approx(0.8 / 0.6)
    x_min, x_max = xt_figure(result, coordinates="deformed").axes[0].get_xlim()
    assert x_max - x_min > 0.8 / 0.6 + 0.8 + 1.0  # deformed: the real positions, gap included


FEM_IMPORTABLE = importlib.util.find_spec("wavecontact.fem.solver") is not None


@pytest.mark.skipif(not FEM_IMPORTABLE, reason="finite-element solver not installed")
def test_cli_collide_writes_fields_and_xt_diagram(tmp_path, capsys):
    from wavecontact.cli import main
    from wavecontact.io.fields import read_fields

    png, fields = tmp_path / "xt.png", tmp_path / "fields"
    code = main(
        [
            "collide",
            "--gamma",
            "0.6",
            "--kappa",
            "20",
            "--solver",
            "fem",
            "--elements",
            "20",
            "--fields",
            str(fields),
            "--xt-plot",
            str(png),
        ]
    )
    assert code == 0, capsys.readouterr().err
    assert png.stat().st_size > 20_000
    back = read_fields(fields)
    sizes = [rod["x"].size for rod in back["rods"]]
    assert sizes[0] == 21 and sizes[1] > 21  # N elements on the short rod (P1), more on the long one
    assert back["time"].size > 50


@pytest.mark.parametrize("units, length, duration, stress", [
    ("SI", "[m]", "[s]", "[Pa]"),
    (None, "(scene length unit)", "(scene time unit)", "[stress unit (E's)]"),
])
def test_xt_diagram_of_a_scene_of_materials_shows_no_nan_and_no_paper_units(units, length, duration, stress):
    """A two-rod scene of materials (gamma and kappa nan, fields in the scene's units, e.g. the steel striker):
    the title leaves gamma and kappa out and the axes do not claim the paper's l, l/c and rho c V."""
    paper = xt_figure(hard_impact_result(0.6, elements=20, samples=50)).axes
    assert "units of l" in paper[0].get_xlabel() and r"\rho c V" in paper[1].get_ylabel()
    result = dataclasses.replace(hard_impact_result(0.6, elements=20, samples=50), gamma=float("nan"),
                                 kappa=float("nan"))
    ax, bar = xt_figure(result, units=units).axes
    assert "nan" not in ax.get_title() and "0.6" in ax.get_title()  # epsilon = gamma stays
    assert length in ax.get_xlabel() and "units of l" not in ax.get_xlabel()
    assert duration in ax.get_ylabel() and "c/l" not in ax.get_ylabel()
    assert stress in bar.get_ylabel() and "rho" not in bar.get_ylabel()
