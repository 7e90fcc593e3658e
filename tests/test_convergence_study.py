"""Mesh-convergence study: fitting, table, plot and CLI.

The logic is checked with a stand-in for ``wavecontact.collide`` whose error
is known analytically (``C N**-p``), so the fitted order must come out ``p``;
the study on the real finite-element solver is checked at the end (skipped
while that solver is not installed).
"""

from __future__ import annotations

import importlib.util
import itertools
import json
import math

import numpy as np
import pytest

from wavecontact.cli import main
from wavecontact.errors import InvalidParameterError, SolverFailure
from wavecontact.result import CollisionResult
from wavecontact.studies.convergence import convergence_study, fit_order, reference_restitution

EXACT_06_20 = 0.75301321  # MODEL.md section 5, (gamma, kappa) = (0.6, 20)
ORDER_OF = {1: 2.0, 2: 4.0}  # the stand-in's error exponent per element order
CONSTANT_OF = {"lumped": 3.0, "consistent": -0.7}


class StandIn:
    """``collide`` with epsilon = exact + C N**-p, steps = 40 N, wall time = 1e-6 N**2 s."""

    def __init__(self, exact=EXACT_06_20, fail_below=0, round_off=False):
        self.exact, self.fail_below, self.round_off = exact, fail_below, round_off
        self.calls = []

    def __call__(self, gamma, kappa, solver="delay", *, contact="exponential", **options):
        self.calls.append((gamma, kappa, solver, contact, dict(options)))
        if solver == "delay":
            return self._result(self.exact, solver, gamma, kappa)
        n, p, mass = options["elements"], options["order"], options["mass"]
        if n < self.fail_below:
            raise SolverFailure(f"energy drift too large on {n} elements: refine the mesh")
        error = 0.0 if self.round_off else CONSTANT_OF[mass] * n ** -ORDER_OF[p]
        return self._result(self.exact + error, solver, gamma, kappa, steps=40 * n, wall=1e-6 * n * n)

    @staticmethod
    def _result(eps, solver, gamma, kappa, steps=None, wall=1e-3):
        return CollisionResult(
            restitution=eps,
            solver=solver,
            wall_time_s=wall,
            time=np.zeros(2),
            relative_velocity=np.array([-1.0, eps]),
            gamma=gamma,
            kappa=kappa,
            work={} if steps is None else {"steps": steps},
        )


def test_fitted_order_recovers_the_known_exponent():
    fake = StandIn()
    table = convergence_study(
        0.6,
        20,
        orders=(1, 2),
        masses=("lumped", "consistent"),
        elements=(200, 25, 50, 100, 50),
        collide=fake,
        progress=False,
    )
    assert table.reference == EXACT_06_20 and table.reference_source == "delay solver"
    assert [(f.order, f.mass) for f in table.fits] == [
        (1, "lumped"),
        (1, "consistent"),
        (2, "lumped"),
        (2, "consistent"),
    ]
    for fit in table.fits:
        p = ORDER_OF[fit.order]
        assert fit.observed_order == pytest.approx(p, abs=1e-6)
        assert fit.constant == pytest.approx(abs(CONSTANT_OF[fit.mass]), rel=1e-5)
        rows = table.rows_for(fit.order, fit.mass)
        assert [r.elements for r in rows] == [25, 50, 100, 200]  # sorted, duplicates dropped
        assert rows[0].local_order is None
        for r in rows:
            assert r.error == pytest.approx(abs(CONSTANT_OF[fit.mass]) * r.elements**-p, rel=1e-6)
            assert r.steps == 40 * r.elements and r.wall_time_s == pytest.approx(1e-6 * r.elements**2)
        for r in rows[1:]:
            assert r.local_order == pytest.approx(p, abs=1e-6)
    # every fem run went through the public options, nothing else; one untimed warm-up run
    # on the coarsest mesh per discretization
    fem_calls = [c for c in fake.calls if c[2] == "fem"]
    assert len(fem_calls) == 16 + 4
    assert [c[4]["elements"] for c in fem_calls[:6]] == [25, 25, 50, 100, 200, 25]
    assert all(set(c[4]) == {"elements", "order", "mass"} for c in fem_calls)


def test_fit_order_ignores_round_off_and_missing_errors():
    n = np.array([10, 20, 40, 80])
    order, constant, points = fit_order(n, 5.0 * n**-1.5)
    assert order == pytest.approx(1.5) and constant == pytest.approx(5.0) and points == 4
    order, _, points = fit_order(n, [1e-3, 2.5e-4, 1e-16, None])
    assert order == pytest.approx(2.0) and points == 2
    assert fit_order(n, [1e-3, 0.0, 0.0, 0.0]) == (None, None, 1)


def test_hard_limit_reference_is_gamma_without_the_delay_solver():
    fake = StandIn(exact=0.6)
    table = convergence_study(
        0.6, math.inf, orders=(1,), masses=("lumped",), elements=(10, 20), collide=fake, progress=False
    )
    assert table.reference == 0.6 and table.contact == "hard"
    assert all(c[2] == "fem" and c[3] == "hard" for c in fake.calls)
    # penalty contact at kappa = inf (stiffness tied to the mesh) tends to hard contact: same reference;
    # at finite kappa the spring's stiffness follows kappa and there is no independent reference
    assert reference_restitution(0.6, math.inf, "penalty", collide=fake)[0] == 0.6
    with pytest.raises(InvalidParameterError, match="reference"):
        reference_restitution(0.6, 20, "penalty", collide=fake)
    # below gamma = 1/2 the hard limit comes from the delay solver's hard-core mode
    value, source = reference_restitution(0.3, math.inf, "hard", collide=StandIn(exact=0.31))
    assert value == 0.31 and "delay" in source


def test_exact_runs_give_no_order_and_say_why():
    table = convergence_study(
        0.6,
        20,
        orders=(1,),
        masses=("lumped",),
        elements=(10, 20, 40),
        collide=StandIn(round_off=True),
        progress=False,
    )
    fit = table.fits[0]
    assert fit.observed_order is None and "round-off" in fit.note
    assert all(r.error == 0.0 and r.local_order is None for r in table.rows)
    assert "n/a" in table.format_text()


def test_solver_failures_are_kept_as_rows_and_left_out_of_the_fit():
    table = convergence_study(
        0.6,
        20,
        orders=(1,),
        masses=("lumped",),
        elements=(10, 20, 40, 80),
        collide=StandIn(fail_below=15),
        progress=False,
    )
    rows = table.rows
    assert rows[0].failure.startswith("energy drift") and rows[0].error is None
    assert table.fits[0].points == 3 and table.fits[0].observed_order == pytest.approx(2.0)
    assert "failed: energy drift" in table.format_text()


def test_table_serializes_to_one_json_object():
    table = convergence_study(
        0.6,
        math.inf,
        orders=(1, 2),
        masses=("lumped",),
        elements=(10, 20, 40),
        collide=StandIn(exact=0.6),
        progress=False,
    )
    data = json.loads(table.to_json())
    assert data["kappa"] == "inf" and data["reference"] == 0.6
    assert [d["order"] for d in data["discretizations"]] == [1, 2]
    first = data["discretizations"][0]
    assert first["observed_order"] == pytest.approx(2.0)
    assert [r["elements"] for r in first["rows"]] == [10, 20, 40]
    assert set(first["rows"][0]) >= {
        "order",
        "mass",
        "elements",
        "restitution",
        "error",
        "local_order",
        "wall_time_s",
        "steps",
    }


@pytest.mark.parametrize(
    "bad, match",
    [
        ({"masses": ("lumpy",)}, "masses"),
        ({"elements": (50,)}, "two different"),
        ({"elements": (50, 50)}, "two different"),
        ({"elements": (0, 10)}, "elements"),
        ({"orders": (1.5,)}, "orders"),
        ({"contact": "glue"}, "contact"),
        ({"reference": math.nan}, "reference"),
        ({"solver_options": {"elements": 3}}, "elements"),
    ],
)
def test_bad_study_parameters_are_refused(bad, match):
    kwargs = {
        "orders": (1,),
        "masses": ("lumped",),
        "elements": (10, 20),
        "collide": StandIn(),
        "progress": False,
    }
    kwargs.update(bad)
    with pytest.raises(InvalidParameterError, match=match):
        convergence_study(0.6, 20, **kwargs)
    with pytest.raises(InvalidParameterError, match="gamma"):
        convergence_study(1.5, 20, collide=StandIn(), progress=False)


def test_plot_writes_both_panels(tmp_path):
    from wavecontact.plotting.convergence import convergence_figure, plot_convergence

    table = convergence_study(0.6, 20, elements=(25, 50, 100, 200), collide=StandIn(), progress=False)
    path = plot_convergence(table, tmp_path / "conv.png")
    assert path.stat().st_size > 20_000
    fig = convergence_figure(table)
    ax_n, ax_t = fig.axes
    assert ax_n.get_xscale() == ax_n.get_yscale() == ax_t.get_xscale() == "log"
    assert len(ax_n.get_legend().get_texts()) == 4


@pytest.fixture
def stand_in_api(monkeypatch):
    import wavecontact.api

    fake = StandIn()
    monkeypatch.setattr(wavecontact.api, "collide", fake)
    return fake


def test_cli_prints_a_table_per_discretization(stand_in_api, capsys):
    code = main(
        [
            "converge",
            "--gamma",
            "0.6",
            "--kappa",
            "20",
            "--order",
            "1",
            "2",
            "--mass",
            "lumped",
            "--elements",
            "25",
            "50",
            "100",
        ]
    )
    out = capsys.readouterr().out
    assert code == 0
    assert "P1 lumped: observed order 2.000" in out and "P2 lumped: observed order 4.000" in out
    assert "reference epsilon = 0.75301321" in out
    assert out.count("\n       25 ") == 2  # one row for N = 25 in each table


def test_cli_json_and_plot(stand_in_api, capsys, tmp_path):
    plot = tmp_path / "c.png"
    code = main(
        [
            "converge",
            "--gamma",
            "0.6",
            "--kappa",
            "20",
            "--order",
            "1",
            "--mass",
            "consistent",
            "--elements",
            "25",
            "50",
            "--json",
            "--plot",
            str(plot),
            "--no-progress",
        ]
    )
    assert code == 0
    data = json.loads(capsys.readouterr().out)
    assert data["discretizations"][0]["mass"] == "consistent"
    assert plot.stat().st_size > 0


@pytest.mark.parametrize(
    "argv",
    [
        ["--gamma", "0.6", "--kappa", "20", "--elements", "50"],
        ["--gamma", "1.5", "--kappa", "20"],
        ["--gamma", "0.6", "--kappa", "-1"],
        ["--gamma", "0.6", "--kappa", "20", "--mass", "lumpy"],
        ["--gamma", "0.6", "--kappa", "20", "--order", "0"],
        ["--gamma", "0.6", "--kappa", "20", "--elements", "10", "x"],
    ],
)
def test_cli_refuses_bad_arguments_in_one_line(stand_in_api, capsys, argv):
    with pytest.raises(SystemExit) as exit_info:
        code = main(["converge", *argv])
        raise SystemExit(code)
    assert exit_info.value.code != 0
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("\n") == 1 and err.startswith("wavecontact: error:")


def test_default_reference_is_the_delay_solver_and_matches_model_md():
    # the study's errors go down to ~1e-8, so its reference must be better than that
    value, source = reference_restitution(0.6, 20)
    assert source == "delay solver"
    assert value == pytest.approx(EXACT_06_20, abs=1e-7)
    assert reference_restitution(0.6, math.inf)[0] == 0.6


FEM_IMPORTABLE = importlib.util.find_spec("wavecontact.fem.solver") is not None


@pytest.mark.skipif(not FEM_IMPORTABLE, reason="finite-element solver not installed")
def test_real_study_p1_lumped_converges_at_its_declared_order():
    from wavecontact.fem import solver as fem

    # the solver declares its expected order per discretization; second order is the theory
    # of central differences on lumped P1 when the contact is resolved
    expected = getattr(fem, "EXPECTED_ORDER", {}).get((1, "lumped"), 2)
    # meshes on which the long rod (l2 = l1 / 0.6) is a whole number of elements: otherwise the
    # far-end remainder alternates between 1/3 and 2/3 of an element and scatters the fit
    table = convergence_study(
        0.6, 20, orders=(1,), masses=("lumped",), elements=(24, 48, 96, 192), progress=False
    )
    assert table.reference_source == "delay solver"
    assert table.reference == pytest.approx(EXACT_06_20, abs=1e-7)
    rows = table.rows
    assert all(r.failure is None and r.steps > 0 and r.wall_time_s > 0 for r in rows)
    errors = [r.error for r in rows]
    assert all(a > b for a, b in itertools.pairwise(errors))  # refinement helps on every step
    assert errors[-1] < 1e-5
    fit = table.fit_for(1, "lumped")
    assert fit.points == 4
    assert fit.observed_order == pytest.approx(expected, abs=0.25)


def test_plot_draws_exact_runs_on_the_round_off_floor(tmp_path):
    """At kappa = inf lumped P1 is exact on every mesh: it must stay in the figure and its legend."""
    from wavecontact.plotting.convergence import convergence_figure, plot_convergence
    from wavecontact.studies.convergence import ERROR_FLOOR

    exact = convergence_study(
        0.6,
        20,
        orders=(1,),
        masses=("lumped",),
        elements=(10, 20),
        collide=StandIn(round_off=True),
        progress=False,
    )
    path = plot_convergence(exact, tmp_path / "c.png")
    assert path.stat().st_size > 0
    ax_n = convergence_figure(exact).axes[0]
    floor = [line for line in ax_n.lines if line.get_label() == ax_n.get_legend().get_texts()[0].get_text()]
    assert len(floor) == 1 and list(floor[0].get_ydata()) == [ERROR_FLOOR, ERROR_FLOOR]
    assert "exact on 2 meshes" in ax_n.get_legend().get_texts()[0].get_text()
    mixed = convergence_study(
        0.6, 20, orders=(1, 2), masses=("lumped",), elements=(10, 20), collide=StandIn(), progress=False
    )
    mixed.rows[0] = type(mixed.rows[0])(**{**mixed.rows[0].__dict__, "error": 1e-16})
    ax_n = convergence_figure(mixed).axes[0]
    assert len(ax_n.lines[0].get_xdata()) == 1  # the line joins the inexact runs only
    assert list(ax_n.lines[1].get_ydata()) == [ERROR_FLOOR]  # the exact one on the floor
    assert "exact on 1 mesh" in ax_n.get_legend().get_texts()[0].get_text()


def test_progress_bar_goes_to_stderr_only_when_asked_and_only_on_a_terminal(capsys, monkeypatch):
    """A bar when asked and stderr is a terminal; never into a pipe or file (wavecontact.progress's one rule)."""
    import io
    import sys

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    kwargs = {"orders": (1,), "masses": ("lumped",), "elements": (10, 20, 40)}
    terminal = Terminal()
    with monkeypatch.context() as patch:
        patch.setattr(sys, "stderr", terminal)
        convergence_study(0.6, 20, collide=StandIn(), progress=True, **kwargs)
    assert "/3 " in terminal.getvalue() and "P1 lumped" in terminal.getvalue()
    assert capsys.readouterr().out == ""
    convergence_study(0.6, 20, collide=StandIn(), progress=True, **kwargs)  # stderr is no tty here
    convergence_study(0.6, 20, collide=StandIn(), progress=None, **kwargs)
    convergence_study(0.6, 20, collide=StandIn(), progress=False, **kwargs)
    assert capsys.readouterr().err == ""
