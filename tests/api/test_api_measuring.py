"""The measuring half of the public API (issues 30 and 33): ``reduce``, ``simulate``,
``fisher``, ``waveform``, ``population_forecast``.

- bad arguments are refused at the door, in one line naming the Python parameter (not the
  command-line flag), as a :class:`ucbplan.UcbplanError`: the cases issue 33 found, then a
  property test over every argument;
- inputs accept what their type hints say (an astropy ``Table`` of velocities, a ``Quantity``
  observation length);
- results are first-class: short reprs, typed fields, ``to_dict`` without JSON text.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from astropy import units as u
from astropy.table import Table
from hypothesis import given, settings
from hypothesis import strategies as st
from support.strategies import any_value

import ucbplan
from ucbplan.errors import InputError, UcbplanError

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::ucbplan.errors.UcbplanWarning"),
]

ROOT = Path(__file__).resolve().parents[2]
ECC = str(ROOT / "catalogs" / "fiducial-eccentric.yaml")
VEL = str(ROOT / "catalogs" / "fiducial-eccentric-velocities.csv")
INJ = str(ROOT / "catalogs" / "fiducial-injection.yaml")
LDC = ROOT / "catalogs" / "population" / "ldc-200.ecsv"
MISSING = "no-such-file.yaml"


def _refused(call: Any, parameter: str) -> str:
    with pytest.raises(InputError) as info:
        call()
    text = str(info.value)
    assert text.startswith(f"{parameter}: ") and "\n" not in text, text
    assert info.value.parameter in (parameter, None)  # None: a shared parser that names it
    return text


# ------------------------------------------------------------ issue 33: refused at the door


@pytest.mark.parametrize("samples", [0, -5, 1.5, "20", True, 10**9])
def test_reduce_refuses_a_sample_count_that_is_not_one(samples: Any) -> None:
    # was: 0 accepted (a report of NaNs), -5 a numpy ValueError, 1.5 a TypeError
    _refused(lambda: ucbplan.reduce(ECC, VEL, samples=samples), "samples")


@pytest.mark.parametrize("seed", [-1, 1.5, "x", True])
def test_reduce_refuses_a_seed_that_is_not_one(seed: Any) -> None:
    # was: -1 a numpy ValueError ("expected non-negative integer")
    _refused(lambda: ucbplan.reduce(ECC, VEL, seed=seed), "seed")


@pytest.mark.parametrize(
    ("kwargs", "parameter"),
    [
        ({"seed": "x"}, "seed"),  # was: numpy TypeError from SeedSequence
        ({"seed": -3}, "seed"),
        ({"walkers": 20.5}, "walkers"),  # was: TypeError from emcee
        ({"steps": 0}, "steps"),
        ({"max_steps": 2.5}, "max_steps"),
        ({"n_bins": 17}, "n_bins"),
    ],
)
def test_simulate_refuses_bad_options_before_any_work(kwargs: dict, parameter: str) -> None:
    # the target does not exist: a refused option is found before the file is read
    _refused(lambda: ucbplan.simulate(MISSING, **kwargs), parameter)


@pytest.mark.parametrize(
    ("kwargs", "parameter"),
    [({"t_obs": 4 * u.m}, "t_obs"), ({"t_obs": "1 hr"}, "t_obs"), ({"walkers": 4}, "walkers")],
)
def test_simulate_refuses_options_that_depend_on_the_target(kwargs: dict, parameter: str) -> None:
    text = _refused(lambda: ucbplan.simulate(INJ, n_bins=64, **kwargs), parameter)
    assert "--" not in text


def _small_catalog(tmp_path: Path, n: int = 3) -> Path:
    path = tmp_path / "small.ecsv"
    Table.read(LDC)[:n].write(path, format="ascii.ecsv")
    return path


def test_population_forecast_takes_a_quantity_t_obs(tmp_path: Path) -> None:
    # was: AttributeError ('Quantity' object has no 'replace' member), though the docs accept it
    cat = _small_catalog(tmp_path)
    by_quantity = ucbplan.population_forecast(cat, t_obs=4 * u.yr)
    by_text = ucbplan.population_forecast(cat, t_obs="4yr")
    assert len(by_quantity) == 3
    assert by_quantity.meta["t_obs_s"] == pytest.approx(4 * 365.25 * 86400, rel=1e-15)
    assert by_quantity.colnames == by_text.colnames
    for name in by_text.colnames:
        a, b = np.asarray(by_quantity[name]), np.asarray(by_text[name])
        assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), name
    assert "PopulationForecast small.ecsv: 3 sources" in repr(by_quantity)


@pytest.mark.parametrize(
    ("kwargs", "parameter"),
    [
        ({"t_obs": 4 * u.m}, "t_obs"),
        ({"t_obs": "soon"}, "t_obs"),
        ({"sigma_v": -1}, "sigma_v"),
        ({"sigma_v": 3 * u.m}, "sigma_v"),
        ({"k_eff": 0}, "k_eff"),
        ({"n_bins": 15}, "n_bins"),
        ({"t_start": "tomorrow"}, "t_start"),
        ({"workers": 0}, "workers"),
    ],
)
def test_population_forecast_refuses_bad_options(kwargs: dict, parameter: str) -> None:
    _refused(lambda: ucbplan.population_forecast(MISSING, **kwargs), parameter)


# ------------------------------------------------------------------------ any value, one line

_ANY = any_value(text=8, units=[u.s, u.yr, u.m, u.km / u.s, u.one], magnitude=1e9)

#: Every option of each function (the target or catalog is a missing file, so a call whose
#: option passes the door stops at reading it, fast).
_OPTIONS = {
    "reduce": (
        lambda **kw: ucbplan.reduce(MISSING, VEL, **kw),
        ("seed", "samples", "light_time", "mass_radius", "cos_i_sigma", "site"),
    ),
    "simulate": (
        lambda **kw: ucbplan.simulate(MISSING, **kw),
        (
            *("seed", "t_obs", "n_bins", "circular", "walkers", "steps"),
            *("until_converged", "max_steps", "noise"),
        ),
    ),
    "fisher": (lambda **kw: ucbplan.fisher(MISSING, **kw), ("t_obs", "n_bins", "circular")),
    "waveform": (lambda **kw: ucbplan.waveform(MISSING, **kw), ("t_obs", "n_bins")),
    "population_forecast": (
        lambda **kw: ucbplan.population_forecast(MISSING, **kw),
        ("sigma_v", "k_eff", "t_obs", "t_start", "n_bins", "workers"),
    ),
}


@settings(max_examples=300, deadline=None)
@given(data=st.data(), function=st.sampled_from(sorted(_OPTIONS)), value=_ANY)
def test_any_option_value_is_refused_in_one_line_naming_it(
    data: st.DataObject, function: str, value: Any
) -> None:
    call, names = _OPTIONS[function]
    name = data.draw(st.sampled_from(names))
    with pytest.raises(UcbplanError) as info:
        call(**{name: value})
    text = str(info.value)
    assert "\n" not in text and text, text
    assert not text.startswith("--"), text
    if MISSING not in text:  # refused at the door: it says which parameter
        assert text.startswith(f"{name}: "), (name, value, text)


# ------------------------------------------------------------ inputs as their type hints say


@pytest.fixture(scope="module")
def report() -> ucbplan.Report:
    return ucbplan.reduce(ECC, VEL, seed=2, samples=2000)


def test_reduce_takes_an_astropy_table(report: ucbplan.Report) -> None:
    # was: a raw TypeError from pathlib (issue 30)
    from_table = ucbplan.reduce(ECC, _velocity_table(), seed=2, samples=2000)
    a, b = from_table.to_dict(), report.to_dict()
    assert a.pop("velocity_file") == "velocities" and b.pop("velocity_file") == VEL
    assert a == b


def test_reduce_names_the_parameter_for_a_table_it_cannot_use() -> None:
    with pytest.raises(InputError, match=r"^velocities: expected a file"):
        ucbplan.reduce(ECC, 42)
    bad = _velocity_table()
    bad["v1"][0] = np.nan
    with pytest.raises(UcbplanError, match=r"^velocities: row 1, column 'v1': got nan"):
        ucbplan.reduce(ECC, bad)


# ------------------------------------------------------------------------ first-class results


def test_report_is_a_short_typed_record(report: ucbplan.Report) -> None:
    from ucbplan.io import dumps_json

    text = repr(report)
    assert "\n" not in text and len(text) < 200 and text.startswith("<Report ")
    assert report.seed == 2 and report.n_spectra == report.to_dict()["n_spectra"]
    k1 = report.K1
    assert k1 is not None and k1.unit == "km / s"
    assert k1.value == report.to_dict()["K1"]["value"]
    assert k1.quantity.to_value(u.m / u.s) == pytest.approx(1000 * k1.value, rel=1e-15)
    assert "K1" in report.quantities and report["no-such"] is None
    # to_dict builds Python values directly; they equal the JSON the CLI prints
    assert report.to_dict() == json.loads(dumps_json(report._doc))


def test_report_plot_returns_axes(report: ucbplan.Report) -> None:
    ax = report.plot()
    assert ax.get_xlabel() == "" and "v–F" in ax.get_title()
    assert len(ax.figure.axes) == 2  # with the residuals below
    from ucbplan.plotting import pyplot

    _, mine = pyplot().subplots()
    assert report.plot(mine) is mine and mine.get_xlabel().startswith("F̄")
    assert len(mine.lines) >= len(report.reduction.fits)  # a fitted line per star
    with pytest.raises(InputError, match=r"^ax: expected a matplotlib Axes"):
        report.plot(42)


def test_report_has_an_html_summary(report: ucbplan.Report) -> None:
    html = report._repr_html_()
    assert html.startswith("<p><b>") and "<td>K1</td>" in html and "seed 2" in html


def test_fisher_and_waveform_results_have_short_reprs() -> None:
    forecast = ucbplan.fisher(INJ, n_bins=64)
    assert repr(forecast).startswith("<FisherForecast ") and "SNR" in repr(forecast)
    lines = ucbplan.waveform(INJ, n_bins=64, t_obs=1 * u.yr)
    assert repr(lines).startswith("<WaveformLines ") and "x 64 bins" in repr(lines)


def _velocity_table() -> Table:
    return Table.read(VEL, format="ascii.csv", comment="#")


# ------------------------------------------------------- the CLI's options derive from the API


def _command_params(*path: str) -> dict[str, Any]:
    import typer

    from ucbplan.cli.app import app

    cmd: Any = typer.main.get_command(app)
    for name in path:
        cmd = cmd.commands[name]
    return {p.name: p for p in cmd.params}


@pytest.mark.parametrize(
    ("path", "function", "flags"),
    [
        (("reduce",), "ucbplan.api.reduction:reduce", "REDUCE_FLAGS"),
        (("simulate",), "ucbplan.api.lisa_analysis:simulate", "SIMULATE_FLAGS"),
        (("fisher",), "ucbplan.api.lisa_analysis:fisher", "FISHER_FLAGS"),
        (("waveform",), "ucbplan.api.lisa_analysis:waveform", "WAVEFORM_FLAGS"),
        (
            ("population", "forecast"),
            "ucbplan.api.populations:population_forecast",
            "POPULATION_FLAGS",
        ),
        (("population", "simulate"), "ucbplan.api.populations:population_forecast", "PARTS_FLAGS"),
        (
            ("population", "visibility"),
            "ucbplan.api.population_runs:visibility_settings",
            "VISIBILITY_FLAGS",
        ),
        (("population", "rank"), "ucbplan.api.population_runs:rank_settings", "RANK_FLAGS"),
        (
            ("population", "simulate"),
            "ucbplan.api.population_runs:simulation_settings",
            "POPULATION_SIMULATE_FLAGS",
        ),
    ],
)
def test_cli_options_take_their_default_and_help_from_the_api(
    path: tuple[str, ...], function: str, flags: str
) -> None:
    import importlib

    from ucbplan.api.flagspec import default_of

    module_name, name = function.split(":")
    module = importlib.import_module(module_name)
    func, table = getattr(module, name), getattr(module, flags)
    params = _command_params(*path)
    options = {p: f for p, f in table.items() if f.decls}
    assert options and set(options) <= set(params)
    for parameter, flag in options.items():
        got = params[parameter]
        assert got.help == flag.help, parameter
        if not got.required:
            assert got.default == default_of(func, parameter), parameter


def test_population_forecast_without_masses_needs_k_eff(tmp_path: Path) -> None:
    path = tmp_path / "no-masses.ecsv"
    tab = Table.read(LDC)[:2]
    tab.remove_columns([c for c in ("Mass1", "Mass2") if c in tab.colnames])
    tab.write(path, format="ascii.ecsv")
    _refused(lambda: ucbplan.population_forecast(path), "k_eff")
    assert len(ucbplan.population_forecast(path, k_eff=600 * u.km / u.s)) == 2
