"""The public API (issue 21): ``import ucbplan`` in a fresh interpreter, offline, equals the CLI.

- the Python tutorial (docs/tutorials/python.md) runs in a fresh process with the network cut,
  and its plan, horizon, ephemeris and reduce equal the command line's outputs for the same
  inputs (the plan table value for value, the reduce report to the last digit); astropy's IERS
  configuration and ``IERS_Auto.open`` are unchanged afterwards;
- astroplan's constraints give the blocks of the equivalent CLI options; a user-defined
  constraint removes exactly the blocks it should;
- errors name the parameter and derive from ``UcbplanError``; warnings are filterable.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from astropy import units as u
from astropy.table import Table
from astropy.utils import data, iers
from hypothesis import given, settings
from hypothesis import strategies as st
from support.state import astropy_state
from support.strategies import any_value

import ucbplan
from ucbplan.errors import EpochRangeError, InputError, UcbplanError
from ucbplan.observing.constraints.objects import AstroplanConstraint, as_constraint

_ANY = any_value(units=[u.deg, u.rad, u.m, u.s, u.one])
pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::ucbplan.errors.UcbplanWarning"),
]

ROOT = Path(__file__).resolve().parents[2]
HM = "catalogs/hm-cnc-simulated.yaml"
ECC = "catalogs/fiducial-eccentric.yaml"
VEL = "catalogs/fiducial-eccentric-velocities.csv"
TUTORIAL = ROOT / "docs" / "tutorials" / "python.md"

#: Run first in the fresh process: no socket can connect (a download would fail loudly), and
#: astropy's state is recorded before any ucbplan call.
_PRELUDE = """
import socket, json, sys
def _no_network(*args, **kwargs):
    raise OSError("network disabled by tests/api/test_api.py")
socket.socket.connect = _no_network
socket.create_connection = _no_network
from astropy.utils import data as _data, iers as _iers
def _state():
    return [repr(_iers.conf.auto_download), repr(_iers.conf.auto_max_age),
            repr(_iers.conf.iers_degraded_accuracy), repr(_data.conf.allow_internet),
            repr(_iers.IERS_Auto.__dict__["open"]), repr(_iers.earth_orientation_table._value),
            repr(_iers.IERS_Auto.iers_table)]
_BEFORE = _state()
"""

#: Run last: the tutorial's results as files, and astropy's state again.
_EPILOGUE = """
from pathlib import Path as _Path
_out = _Path(sys.argv[1])
run.write(_out / "plan.ecsv")
epochs.write(_out / "ephemeris.ecsv", format="ascii.ecsv")
(_out / "horizon.json").write_text(json.dumps([dict(zip(horizons.colnames, map(
    lambda v: v.item() if hasattr(v, "item") else v, row))) for row in horizons]))
(_out / "reduce.json").write_text(json.dumps(report.to_dict()))
(_out / "state.json").write_text(json.dumps({"before": _BEFORE, "after": _state()}))
"""


def tutorial_code() -> str:
    """The ```python blocks of the tutorial, in order."""
    blocks = re.findall(r"```python\n(.*?)```", TUTORIAL.read_text(encoding="utf-8"), re.S)
    assert len(blocks) >= 6, "the tutorial lost its code blocks"
    return "\n".join(blocks)


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    proc = subprocess.run(
        [sys.executable, "-m", "ucbplan", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        env=_env(),
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc


def _env() -> dict[str, str]:
    import os

    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _same_tables(a: Table, b: Table) -> None:
    assert a.colnames == b.colnames
    assert len(a) == len(b) and len(a) > 0
    for name in a.colnames:
        x, y = np.asarray(a[name]), np.asarray(b[name])
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), name
        assert a[name].unit == b[name].unit, name
    stamp = "created_utc"  # when each was written: the only provenance that may differ
    assert {k: v for k, v in a.meta.items() if k != stamp} == {
        k: v for k, v in b.meta.items() if k != stamp
    }


@pytest.mark.slow
def test_tutorial_in_a_fresh_offline_interpreter_equals_the_cli(tmp_path: Path) -> None:
    script = tmp_path / "tutorial.py"
    script.write_text(_PRELUDE + tutorial_code() + _EPILOGUE, encoding="utf-8")
    proc = subprocess.run(
        [sys.executable, str(script), str(tmp_path)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=900,
        env=_env(),
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr and "ErfaWarning" not in proc.stderr, proc.stderr

    state = json.loads((tmp_path / "state.json").read_text())
    assert state["after"] == state["before"]  # astropy's IERS/data set-up as it was

    cli_plan = tmp_path / "cli-plan.ecsv"
    _cli("plan", HM, "--site", "paranal", "--night", "2040-02-15", "-o", str(cli_plan))
    _same_tables(Table.read(tmp_path / "plan.ecsv"), Table.read(cli_plan))

    cli_eph = tmp_path / "cli-ephemeris.ecsv"
    window = ["--start", "2040-02-15T00:00 UTC", "--end", "2040-02-15T02:00 UTC"]
    _cli("ephemeris", HM, *window, "-o", str(cli_eph))
    _same_tables(Table.read(tmp_path / "ephemeris.ecsv"), Table.read(cli_eph))

    hor = _cli("horizon", HM, "--alpha", "0.5", "--alpha", "1", "--format", "json")
    assert json.loads((tmp_path / "horizon.json").read_text()) == json.loads(hor.stdout)

    red = _cli("reduce", ECC, VEL, "--seed", "2", "--samples", "2000", "--format", "json")
    assert json.loads((tmp_path / "reduce.json").read_text()) == json.loads(red.stdout)


def test_import_is_light() -> None:
    # `import ucbplan` loads no numpy or astropy: the public names come on first use
    code = "import ucbplan, sys; print(sorted(m for m in ('numpy', 'astropy') if m in sys.modules))"
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, env=_env()
    )
    assert out.stdout.strip() == "[]", out.stderr
    assert set(ucbplan.__all__) <= set(dir(ucbplan))
    # the function, whether or not (and whenever) the subpackage ucbplan.reduce was imported
    code = (
        "import ucbplan.reduce.pipeline, ucbplan, ucbplan.api; "
        "print(ucbplan.reduce is ucbplan.api.reduce)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, env=_env()
    )
    assert out.stdout.strip() == "True", out.stderr
    from ucbplan.reduce import masses  # binds the subpackage on ucbplan again: reduce() stays

    assert masses.__name__ == "ucbplan.reduce.masses"
    assert ucbplan.reduce is ucbplan.api.reduce
    with pytest.raises(AttributeError):
        _ = ucbplan.no_such_name  # type: ignore[attr-defined]


def test_calls_leave_astropy_as_they_found_it(monkeypatch: pytest.MonkeyPatch) -> None:
    # step out of the session's offline scope (conftest) to astropy's defaults
    monkeypatch.setattr(iers.earth_orientation_table, "_value", None)
    with iers.conf.set_temp("auto_download", True), data.conf.set_temp("allow_internet", True):
        before = astropy_state()
        ucbplan.horizon(HM)
        ucbplan.ephemeris(HM, "2040-02-15T00:00", "2040-02-15T00:20")
        assert astropy_state() == before


# ------------------------------------------------------------------------------- constraints


def _blocks(run: ucbplan.Plan) -> list[tuple[str, str]]:
    t = run.text_table
    return list(zip(t["t_start_utc"].tolist(), t["t_end_utc"].tolist(), strict=True))


@pytest.fixture(scope="module")
def three_nights() -> dict[str, Any]:
    return {"targets": str(ROOT / HM), "site": "paranal", "night": "2040-02-14", "nights": 3}


@pytest.mark.slow
def test_astroplan_constraints_give_the_blocks_of_the_options(three_nights: dict[str, Any]) -> None:
    astroplan = pytest.importorskip("astroplan")
    opts = ucbplan.plan(**three_nights, airmass_max=1.5, moon_sep_deg=40.0)
    ap = ucbplan.plan(
        **three_nights,
        constraints=[
            astroplan.AirmassConstraint(1.5),
            astroplan.MoonSeparationConstraint(40 * u.deg),
        ],
    )
    # Equal although astroplan's Moon separation also counts while the Moon is down: a target
    # at airmass <= 1.5 is >= 41.8 deg up, so >= 41.8 deg from any Moon below the horizon; and
    # Paranal's 4 deg zenith hole (not in the list) is never reached by HM Cnc (culminates at 50
    # deg). The list gives nautical night, as the options' default.
    assert len(opts.table) >= 4
    assert _blocks(ap) == _blocks(opts)


def test_astroplan_builtins_are_native_and_subclasses_go_through_astroplan() -> None:
    astroplan = pytest.importorskip("astroplan")
    assert as_constraint(astroplan.AirmassConstraint(1.5)) == ucbplan.AirmassConstraint(1.5)
    night = as_constraint(astroplan.AtNightConstraint.twilight_astronomical())
    assert night == ucbplan.AtNightConstraint("astronomical")
    moon = as_constraint(astroplan.MoonSeparationConstraint(40 * u.deg))
    assert moon == ucbplan.MoonSeparationConstraint(40.0, moon_down_ok=False)

    class Mine(astroplan.AirmassConstraint):  # a subclass may change anything: astroplan decides
        pass

    assert isinstance(as_constraint(Mine(1.5)), AstroplanConstraint)
    assert isinstance(as_constraint(astroplan.AirmassConstraint(1.5, min=1.2)), AstroplanConstraint)


@pytest.mark.slow
def test_astroplan_subclass_evaluated_by_astroplan_gives_the_same_blocks(
    three_nights: dict[str, Any],
) -> None:
    astroplan = pytest.importorskip("astroplan")

    class Mine(astroplan.AltitudeConstraint):
        pass

    native = ucbplan.plan(**three_nights, constraints=[ucbplan.AltitudeConstraint(42 * u.deg)])
    through = ucbplan.plan(**three_nights, constraints=[Mine(min=42 * u.deg)])
    # astroplan's AltAz and ucbplan's sky model agree to < 2 arcsec
    # (tests/observing/constraints/test_constraints.py); no block sample of this plan lies that
    # close to 42 deg, so the blocks are the same
    assert len(native.table) >= 4
    assert _blocks(through) == _blocks(native)


class AltitudeAbove(ucbplan.Constraint):
    """A user's constraint: altitude at least ``limit`` deg (the native class's meaning)."""

    def __init__(self, limit: float) -> None:
        self.limit = limit

    def ok(self, sky: Any, i: int, x: np.ndarray) -> np.ndarray:
        return np.asarray(sky.target_alt_deg(i, x) >= self.limit)


class DomeClosed(ucbplan.Constraint):
    """No observing from ``start_h`` to ``end_h`` UTC."""

    def __init__(self, start_h: float, end_h: float) -> None:
        self.start_h, self.end_h = start_h, end_h

    def ok(self, sky: Any, i: int, x: np.ndarray) -> np.ndarray:
        hour = (sky.time(x).utc.mjd % 1.0) * 24.0
        return np.asarray((hour < self.start_h) | (hour >= self.end_h))


@pytest.mark.slow
def test_user_constraint_equals_the_native_one(three_nights: dict[str, Any]) -> None:
    base = ucbplan.default_constraints("paranal")
    native = ucbplan.plan(**three_nights, constraints=[*base, ucbplan.AltitudeConstraint(45.0)])
    mine = ucbplan.plan(**three_nights, constraints=[*base, AltitudeAbove(45.0)])
    assert len(native.table) >= 2
    assert _blocks(mine) == _blocks(native)  # screened or exact, the answer is the exact one


@pytest.mark.slow
def test_user_constraint_removes_exactly_its_blocks(three_nights: dict[str, Any]) -> None:
    base = ucbplan.default_constraints("paranal")
    free = ucbplan.plan(**three_nights, constraints=base)
    # HM Cnc's quadratures culminate near 03:00 UTC these nights: close 03:00-03:06 UTC
    closed = ucbplan.plan(**three_nights, constraints=[*base, DomeClosed(3.0, 3.1)])

    def in_window(block: tuple[str, str]) -> bool:
        start, end = (float(s[11:13]) + float(s[14:16]) / 60 + float(s[17:]) / 3600 for s in block)
        return start < 3.1 and end > 3.0  # overlaps the closure (all blocks start after 0 h)

    hit = [b for b in _blocks(free) if in_window(b)]
    kept = [b for b in _blocks(free) if not in_window(b)]
    assert hit and kept, "the test needs blocks on both sides of the closure"
    assert not any(in_window(b) for b in _blocks(closed))
    assert set(kept) <= set(_blocks(closed))  # nothing else is lost
    assert closed.not_planned[closed.table["target"][0]]


def test_constraints_and_limits_are_not_mixed() -> None:
    with pytest.raises(InputError, match=r"^airmass_max: ") as info:
        ucbplan.plan(HM, "paranal", "2040-02-15", constraints=[], airmass_max=1.5)
    assert info.value.parameter == "airmass_max"
    with pytest.raises(InputError, match=r"^constraints: expected ucbplan or astroplan"):
        ucbplan.plan(HM, "paranal", "2040-02-15", constraints=["airmass<1.5"])


# ------------------------------------------------------------------------- errors and warnings


@pytest.mark.parametrize(
    ("call", "parameter"),
    [
        (lambda: ucbplan.plan(HM, "paranal", "2040-02-15", airmass_max=0.5), "airmass_max"),
        (lambda: ucbplan.plan(HM, "paranal", "2040-02-15", sigma_v_kms=-1), "sigma_v"),
        (lambda: ucbplan.plan(HM, "paranal", "2040-02-15", airmas_max=2), "airmas_max"),
        (lambda: ucbplan.plan(HM, "paranal", "2040-02-15", exptime=3 * u.m), "exptime"),
        (lambda: ucbplan.horizon(HM, sigma_v=-1), "sigma_v"),
        (lambda: ucbplan.horizon(HM, alpha=0), "alpha"),
        (lambda: ucbplan.ephemeris(HM, "2040-02-16", "2040-02-15"), "end"),
        (lambda: ucbplan.ephemeris(HM, "2040-02-15", "2040-02-16", star=3), "star"),
        (lambda: ucbplan.reduce(ECC, VEL, mass_radius="x"), "mass_radius"),
        (lambda: ucbplan.AirmassConstraint(0.5), "max_airmass"),
        (lambda: ucbplan.MoonSeparationConstraint(200 * u.deg), "min_deg"),
    ],
)
def test_errors_name_the_parameter(call: Any, parameter: str) -> None:
    with pytest.raises(UcbplanError) as info:
        call()
    text = str(info.value)
    assert text.startswith(f"{parameter}") and "\n" not in text, text
    assert "--" not in text.split(":")[0], text


def test_every_bad_input_error_is_a_ucbplan_error() -> None:
    assert issubclass(EpochRangeError, UcbplanError) and issubclass(EpochRangeError, ValueError)
    with pytest.raises(UcbplanError, match="start"):
        ucbplan.ephemeris(HM, "9999-01-01", "9999-01-02")
    with pytest.raises(UcbplanError):
        ucbplan.get_site(42)
    with pytest.raises(UcbplanError):
        ucbplan.load_target(3.5)


def test_warnings_are_filterable() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", ucbplan.EarthOrientationWarning)
        with pytest.raises(ucbplan.EarthOrientationWarning, match="IERS"):
            ucbplan.plan(HM, "paranal", "2040-02-15")
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        run = ucbplan.plan(HM, "paranal", "2040-02-15")
    ours = [w for w in got if issubclass(w.category, ucbplan.UcbplanWarning)]
    assert [str(w.message) for w in ours] == run.warnings and len(ours) >= 2
    assert all(w.filename == __file__ for w in ours)  # points at the caller's line


def test_sites_from_astropy_and_astroplan() -> None:
    from astropy.coordinates import EarthLocation

    paranal = ucbplan.get_site("paranal")
    loc = ucbplan.get_site(paranal.location)
    assert abs(loc.lat_deg - paranal.lat_deg) < 1e-9 and abs(loc.lon_deg - paranal.lon_deg) < 1e-9
    assert loc.timezone == "America/Santiago"
    astroplan = pytest.importorskip("astroplan")
    obs = astroplan.Observer(location=EarthLocation.from_geodetic(-17.88, 28.76, 2396))
    assert ucbplan.get_site(obs).timezone == "Atlantic/Canary"


# ------------------------------------------------------------------------ any value, one line


_CLASSES = {
    "max_airmass": ucbplan.AirmassConstraint,
    "min_deg": ucbplan.MoonSeparationConstraint,
    "radius_deg": ucbplan.ZenithHoleConstraint,
    "max_fraction": ucbplan.MoonIlluminationConstraint,
}


@settings(max_examples=150, deadline=None)
@given(key=st.sampled_from(sorted(_CLASSES)), value=_ANY)
def test_constraint_classes_take_any_value(key: str, value: Any) -> None:
    # a constraint is built or refused in one line naming its parameter, never a TypeError
    try:
        c = _CLASSES[key](value)
    except InputError as exc:
        text = str(exc)
        assert text.startswith(f"{key}: ") and "\n" not in text and len(text) < 400, text
        return
    limit = getattr(c, key)
    assert isinstance(limit, float) and np.isfinite(limit)
    if hasattr(value, "unit") and value.unit == u.rad:  # angles convert, not reinterpret
        assert limit == pytest.approx(float(value.to_value(u.deg)))


@settings(max_examples=60, deadline=None)
@given(key=st.sampled_from(["exptime", "overhead", "moon_sep", "sigma_v"]), value=_ANY)
def test_plan_options_take_any_value_before_any_work(key: str, value: Any) -> None:
    # bad values fail in one line naming the parameter, before the targets are even read
    try:
        ucbplan.plan("no-such-target.yaml", "paranal", "2040-02-15", **{key: value})
    except InputError as exc:
        text = str(exc)
        assert "\n" not in text and len(text) < 400, text
        assert text.startswith(key) or "no-such-target.yaml" in text, text


def test_plan_time_account_is_what_the_table_records(three_nights: dict[str, Any]) -> None:
    plan = ucbplan.plan(**three_nights)
    account = plan.time_account
    assert account.as_meta() == dict(plan.table.meta["time_accounting"])
    assert account == plan.accounting  # typed
    # the total is the sum of the targets' accounts; one target here, so they are equal
    assert list(account.targets) == [plan.table["target"][0]]
    assert account.total == account.targets[plan.table["target"][0]]
    assert account.total.exposures == int(sum(plan.table["n_exp"]))
