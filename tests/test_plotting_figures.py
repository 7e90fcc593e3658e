"""Every figure the package writes reads right (docs/figure_checklist.md), checked on the Figure itself.

Each figure-writing function of ``wavecontact.plotting`` runs here on a small input; the saved
matplotlib Figure is caught and inspected: every axes that shows data has labelled axes (an axis
shared with another panel or a twin may carry the label there; a colour bar needs its own label), every axes with more than one
labelled line has a legend (on it or its twin), and the figure carries a title (the parameters).
"""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from matplotlib.figure import Figure
from test_io_fields import hard_impact_result

import wavecontact
from wavecontact.plotting import bath, paper_figures

FIGURES = []


@pytest.fixture
def saved(monkeypatch):
    """The Figures saved while the test runs (``Figure.savefig`` still writes the file)."""
    FIGURES.clear()
    original = Figure.savefig

    def savefig(self, *args, **kwargs):
        FIGURES.append(self)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    return FIGURES


def _has_data(ax) -> bool:
    return bool(ax.lines or ax.collections or ax.images or ax.patches or ax.containers)


def _siblings(ax):
    fig_axes = ax.figure.axes
    return [other for other in fig_axes if other is not ax and other.bbox.bounds == ax.bbox.bounds]


def problems(fig) -> list[str]:
    """What the checklist misses in ``fig`` (empty when it reads right)."""
    found = []
    titled = bool(fig._suptitle and fig._suptitle.get_text())
    for index, ax in enumerate(fig.axes):
        name = f"axes {index} ({ax.get_title() or ax.get_ylabel() or 'untitled'})"
        titled = titled or bool(ax.get_title())
        if ax.get_label() == "<colorbar>":
            if not (ax.get_ylabel() or ax.get_xlabel()):
                found.append(f"{name}: colour bar without a label")
            continue
        twins = _siblings(ax)
        if not (_has_data(ax) or any(_has_data(t) for t in twins)):
            continue
        # an axis shared with another (a twin, or panels with sharex/sharey) may carry its label there
        if not any(a.get_xlabel() for a in ax.get_shared_x_axes().get_siblings(ax)):
            found.append(f"{name}: no x label")
        if not any(a.get_ylabel() for a in ax.get_shared_y_axes().get_siblings(ax)):
            found.append(f"{name}: no y label")
        labelled = [a for a in [*ax.lines, *ax.collections, *ax.patches, *ax.containers]
                    if not str(a.get_label()).startswith("_")]
        if len(labelled) >= 2 and ax.get_legend() is None and not any(t.get_legend() for t in twins) \
                and not fig.legends:
            found.append(f"{name}: {len(labelled)} labelled lines and no legend")
    if not titled:
        found.append("no title")
    return found


def assert_reads_right(figures, count=1):
    assert len(figures) >= count, "no figure was saved"
    for fig in figures:
        assert problems(fig) == [], problems(fig)


def test_the_checker_finds_what_is_missing():
    fig = Figure()
    ax = fig.add_subplot()
    ax.plot([0, 1], [0, 1], label="a")
    ax.plot([0, 1], [1, 0], label="b")
    assert set(problems(fig)) == {"axes 0 (untitled): no x label", "axes 0 (untitled): no y label",
                                  "axes 0 (untitled): 2 labelled lines and no legend", "no title"}
    ax.set(xlabel="x", ylabel="y", title="t")
    ax.legend()
    assert problems(fig) == []


def test_velocity_history(saved, tmp_path):
    from wavecontact.plotting.history import plot_velocity_history

    for kappa in (5.0, math.inf):
        plot_velocity_history(wavecontact.collide(0.6, kappa), tmp_path / f"w{kappa}.png")
    assert_reads_right(saved, 2)
    assert "\\kappa" in saved[0].axes[0].get_ylabel()  # W / kappa, as in Fig. 6 and 7


def test_xt_diagram(saved, tmp_path):
    from wavecontact.plotting.xt import plot_xt_diagram

    plot_xt_diagram(hard_impact_result(), tmp_path / "xt.png")
    assert_reads_right(saved)


def test_convergence_and_comparison(saved, tmp_path):
    from wavecontact.plotting.compare import plot_comparison
    from wavecontact.plotting.convergence import plot_convergence
    from wavecontact.studies.compare import Method, compare_solvers
    from wavecontact.studies.convergence import convergence_study

    table = convergence_study(0.6, 20, orders=(1,), masses=("lumped",), elements=(25, 50), progress=False)
    plot_convergence(table, tmp_path / "c.png")
    methods = [Method("delay", {"rtol": 1e-6}, "rtol=1e-06"),
               Method("fem", {"elements": 50}, "P1 lumped, 50 elements", "element_steps"),
               Method("modal", {"modes": 25}, "25 modes", "steps")]
    plot_comparison(compare_solvers(0.6, 100, methods, progress=False), tmp_path / "p.png")
    assert_reads_right(saved, 2)


def test_bath_figures(saved, tmp_path):
    lag = np.linspace(0, 2, 20)
    bath.save(bath.covariance_figure({"lag": lag, "sampled": np.cos(lag), "band": 0.1 + 0 * lag, "eq19": np.cos(lag),
                                      "realisations": 10, "gamma": 0.6, "modes": 20}), tmp_path / "4.png")
    tau = np.linspace(0, 6, 50)
    bath.save(bath.histories_figure([{"tau": tau, "W": 10 * tau, "kappa": 10.0, "restitution": 0.9},
                                     {"tau": tau, "W": 20 * tau, "kappa": 20.0, "restitution": 0.8}], 0.6, 1.0),
              tmp_path / "7.png")
    t = np.array([0.5, 1.0])
    bath.save(bath.spread_figure({"gamma": np.array([0.6]), "temperature": t, "mean": np.array([[0.9, 1.0]]),
                                  "mean_error": 0.01 + 0 * t[None], "std": np.array([[0.1, 0.2]]),
                                  "std_error": 0.01 + 0 * t[None], "kappa": 250.0, "samples": 10}), tmp_path / "8.png")
    assert "250.0" not in saved[-1].axes[0].get_title()
    law = wavecontact.ensemble(0.6173, 100.0, 1.0, 60, 3, bath_modes=10)
    bath.save(bath.law_figure([law]), tmp_path / "9.png")
    bath.plot_law(law, tmp_path / "law.png")
    assert_reads_right(saved, 5)
    distribution = [ax for ax in saved[-1].axes if "distribution" in ax.get_ylabel()]
    assert distribution and distribution[0].get_ylim()[1] <= 1.05  # its own axis, from 0 to 1, not rescaled


def test_paper_cold_figures(saved, tmp_path):
    kappas = np.logspace(0, 3, 5)
    paper_figures.save(paper_figures.restitution_figure(kappas, 0.6 + 1 / kappas, (kappas, 0.6 + 1 / kappas), 0.6),
                       tmp_path / "5.png")
    tau = np.linspace(0, 5, 30)
    paper_figures.save(paper_figures.velocity_increase_figure(
        [{"kappa": 10.0, "tau": tau, "W": 10 * tau, "eq22": 10 * tau}, {"kappa": math.inf, "tau": tau, "W": tau}], 0.6),
        tmp_path / "6.png")
    assert_reads_right(saved, 2)


def test_ring_and_equipartition(saved, tmp_path):
    from wavecontact.plotting.equipartition import plot_equipartition
    from wavecontact.plotting.ring import plot_ring_figures
    from wavecontact.studies.equipartition import equipartition_by_modes
    from wavecontact.studies.ring import run_ring

    plot_ring_figures(run_ring(0.6173, 4000, 10, 40, progress=False), tmp_path)
    study = equipartition_by_modes(0.6173, 4000, modes=(10, 20), collisions=20, realisations=2, progress=False)
    plot_equipartition(study, tmp_path / "eq.png")
    assert_reads_right(saved, 4)


def test_markov_and_material_map(saved, tmp_path):
    from wavecontact.plotting.markov import plot_cooling, plot_stationary_distribution
    from wavecontact.plotting.material_map import plot_material_map
    from wavecontact.studies.markov import markov_chains
    from wavecontact.studies.material_map import material_map

    chains = markov_chains(0.6, rule="glauber", chains=50, steps=40, modes_per_rod=10, bath="conserved",
                           initial_energy=21)
    plot_stationary_distribution(chains, tmp_path / "m.png", burn_in=10)
    plot_cooling({"Glauber": chains}, tmp_path / "cool.png")
    plot_material_map([material_map([0.5, 1.0, 2.0], [0.5, 1.0, 2.0], progress=False)], tmp_path / "map.png")
    assert_reads_right(saved, 3)


def test_gas(saved, tmp_path):
    from wavecontact.gas import random_gas
    from wavecontact.gas.rules import FixedRestitution
    from wavecontact.gas.simulation import GasSimulation
    from wavecontact.plotting.gas import plot_gas

    gas = random_gas(20, seed=1)
    result = GasSimulation(gas, FixedRestitution(0.8), seed=2, record_every=5, frame_every=1, max_frames=50).run(300)
    plot_gas(result, tmp_path / "gas.png", system_length=gas.system_length, title="20 rods, fixed rule 0.8")
    assert_reads_right(saved)
    assert "20 rods" in saved[0]._suptitle.get_text()
