"""``ucbplan.plan``'s options: explicit keywords with units, declared once (issue 30), and the
option checks both doors share (issue 33, "wrong acceptances")."""

from __future__ import annotations

import inspect
from datetime import date, datetime
from pathlib import Path
from typing import Any

import astropy.units as u
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from support.strategies import any_value

import ucbplan
from ucbplan.api.planning import PLAN_FLAGS
from ucbplan.errors import InputError, TargetFileError, UcbplanError

HM = "catalogs/hm-cnc-simulated.yaml"
NOWHERE = "no-such-target.yaml"


def _settings(**options: Any) -> Any:
    """The planner settings ``ucbplan.plan`` builds from its keywords ``options`` (old names
    included), without planning."""
    from ucbplan.api.plan_options import renamed, settings_from

    params = inspect.signature(ucbplan.plan).parameters
    o = {k: p.default for k, p in params.items()}
    o.update(renamed(options, list(params), "plan"))
    return settings_from(o, None)


# ----------------------------------------------------------------------- the keyword signature


def test_plan_takes_explicit_keywords_not_a_catch_all() -> None:
    kinds = {p.kind for p in inspect.signature(ucbplan.plan).parameters.values()}
    assert inspect.Parameter.VAR_KEYWORD not in kinds
    documented = set()
    for line in (inspect.getdoc(ucbplan.plan) or "").splitlines():
        names, sep, _ = line.partition(" : ")
        if sep and not line.startswith(" "):
            documented.update(names.split(", "))
    assert set(PLAN_FLAGS) <= documented, set(PLAN_FLAGS) - documented


def test_every_flag_is_a_parameter_of_plan() -> None:
    params = inspect.signature(ucbplan.plan).parameters
    assert set(PLAN_FLAGS) <= set(params)


def test_max_visit_s_named_by_the_old_help_no_longer_a_type_error() -> None:
    # issue 30: ``plan(..., max_visit_s=21600)`` raised "got multiple values for keyword argument"
    s = _settings(max_visit_s=21600, goal="sigma_K=5km/s")
    assert s.max_visit_s == 21600.0
    assert _settings(max_visit=6 * u.h, goal="sigma_K=5km/s").max_visit_s == 21600.0
    assert _settings(max_visit="6h", goal="sigma_K=5km/s").max_visit_s == 21600.0
    with pytest.raises(InputError, match=r"^max_visit_s, max_visit: ") as info:
        _settings(max_visit_s=21600, max_visit="6h", goal="sigma_K=5km/s")
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    ("old", "new", "value", "field", "expected"),
    [
        ("exptime_s", "exptime", 80.0, "exposure", 80.0),
        ("moon_sep_deg", "moon_sep", 40.0, "moon_sep_deg", 40.0),
        ("zenith_hole_deg", "zenith_hole", 5.0, "zenith_hole_deg", 5.0),
        ("overhead_s", "overhead", 200.0, "overhead_s", 200.0),
        ("sessions_per_night", "sessions", 2, "sessions_per_night", 2),
        ("moon_illum_max", "moon_illum", 0.5, "moon_illum_max", 0.5),
    ],
)
def test_old_names_still_work(old: str, new: str, value: Any, field: str, expected: Any) -> None:
    def read(s: Any) -> Any:
        return s.exposure.exptime_s if field == "exposure" else getattr(s, field)

    assert read(_settings(**{old: value})) == read(_settings(**{new: value})) == expected


def test_quantities_and_floats_in_the_documented_unit() -> None:
    a = _settings(
        moon_sep=0.5 * u.rad, overhead=5 * u.min, exptime=1.5 * u.min, k_eff=500 * u.km / u.s
    )
    assert a.moon_sep_deg == pytest.approx(28.6478897565)
    assert a.overhead_s == 300.0 and a.exposure.exptime_s == 90.0 and a.k_eff_kms == 500.0
    with pytest.raises(InputError, match=r"^moon_sep: expected a quantity in deg"):
        _settings(moon_sep=3 * u.m)


def test_a_given_exposure_time_is_explicit_even_at_the_default_value() -> None:
    assert _settings().exptime_given is False
    assert _settings(exptime=60.0).exptime_given is True
    assert _settings(exptime=60 * u.s).exptime_given is True


def test_unknown_keyword_is_one_line_naming_it() -> None:
    with pytest.raises(InputError, match=r"^airmas_max: not an option of ucbplan.plan") as info:
        ucbplan.plan(NOWHERE, "paranal", "2040-02-15", airmas_max=2)
    assert info.value.parameter == "airmas_max" and "airmass_max" in str(info.value)


# --------------------------------------------------------------- issue 33: wrong acceptances


def test_empty_max_visit_is_refused_not_the_default() -> None:
    with pytest.raises(InputError, match=r"^max_visit: expected a duration") as info:
        _settings(max_visit="", goal="sigma_K=5km/s")
    assert "''" in str(info.value)


def test_max_visit_without_a_goal_is_refused() -> None:
    with pytest.raises(InputError, match=r"^max_visit: .*goal") as info:
        _settings(max_visit="1h")
    assert "\n" not in str(info.value)
    _settings(max_visit="1h", goal="sigma_K=5km/s")  # with a goal it is what the goal plans


def test_max_visit_shorter_than_the_visit_is_refused() -> None:
    with pytest.raises(InputError, match=r"^max_visit: .*visit") as info:
        _settings(visit="1h", max_visit="30min", goal="sigma_K=5km/s")
    assert "\n" not in str(info.value)
    # a maximum the visit keeps is consistent
    assert _settings(visit="1h", max_visit="2h", goal="sigma_K=5km/s").visit_s == 3600.0


def test_feasibility_can_call_the_same_check() -> None:
    from ucbplan.observing.schedule import check_max_visit

    check_max_visit("1h", goal=None, compared=True)  # a strategy comparison uses it
    with pytest.raises(InputError, match=r"^max_visit: "):
        check_max_visit("1h", goal=None)
    check_max_visit(None, goal=None)


# --------------------------------------------------------------------- issue 33: the API list


def test_night_may_be_a_datetime() -> None:
    from ucbplan.api._convert import as_date

    assert as_date(datetime(2040, 2, 15, 20, 30), "night") == date(2040, 2, 15)
    assert as_date(date(2040, 2, 15), "night") == date(2040, 2, 15)
    with pytest.raises(TargetFileError):  # the night is accepted: the file is read next
        ucbplan.plan(NOWHERE, "paranal", datetime(2040, 2, 15, 20, 30))


def test_the_same_file_twice_is_refused_like_the_cli(tmp_path: Path) -> None:
    with pytest.raises(TargetFileError, match="the same target file twice"):
        ucbplan.plan([HM, HM], "paranal", "2040-02-15")
    with pytest.raises(TargetFileError, match="the same target file twice"):
        ucbplan.plan([HM, Path(HM).resolve()], "paranal", "2040-02-15")
    target = ucbplan.load_target(HM)
    with pytest.raises(TargetFileError, match=r"^targets: target .* is given twice"):
        ucbplan.plan([HM, target], "paranal", "2040-02-15")
    with pytest.raises(TargetFileError, match=r"^targets: target .* is given twice"):
        ucbplan.plan([target, target], "paranal", "2040-02-15")


def test_default_constraints_refuse_an_unknown_limit_in_one_line() -> None:
    with pytest.raises(
        InputError, match=r"^foo: not an option of ucbplan.default_constraints"
    ) as info:
        ucbplan.default_constraints("paranal", foo=1)
    assert info.value.parameter == "foo" and "\n" not in str(info.value)


def test_default_constraints_take_the_plan_names() -> None:
    a = ucbplan.default_constraints("paranal", moon_sep=40 * u.deg, airmass_max=1.5)
    b = ucbplan.default_constraints("paranal", moon_sep_deg=40.0, airmass_max=1.5)
    assert repr(a) == repr(b)


@pytest.mark.parametrize(
    ("options", "parameter"),
    [
        ({"nights": 1.5}, "nights"),
        ({"nights": 0}, "nights"),
        ({"nights": "3"}, "nights"),
        ({"night": 20400215}, "night"),
        ({"night": "yesterday"}, "night"),
        ({"priorities": 3}, "priorities"),
        ({"timezone": 5}, "timezone"),
        ({"budgets": "x"}, "budgets"),
        ({"n_exp": 2.5}, "n_exp"),
        ({"allow_smeared": "yes"}, "allow_smeared"),
        ({"instrument": 3}, "instrument"),
        ({"goal": 3}, "goal"),
        ({"mode": None}, "mode"),
    ],
)
def test_wrong_types_and_ranges_name_the_parameter(options: dict[str, Any], parameter: str) -> None:
    call = {"targets": NOWHERE, "site": "paranal", "night": "2040-02-15", **options}
    with pytest.raises(UcbplanError) as info:
        ucbplan.plan(**call)
    text = str(info.value)  # the Python parameter, never the flag
    assert text.startswith(parameter) and "\n" not in text, text


_ANY = any_value(
    more=[
        st.lists(st.text(max_size=6), max_size=2),
        st.dictionaries(st.text(max_size=6), st.floats(), max_size=2),
    ],
    units=[u.deg, u.rad, u.m, u.s, u.h, u.km / u.s, u.one],
)
_KEYWORDS = sorted(p for p in inspect.signature(ucbplan.plan).parameters if p != "targets")


@settings(max_examples=200, deadline=None)
@given(key=st.sampled_from(_KEYWORDS), value=_ANY)
def test_any_value_of_any_keyword_is_refused_in_one_line_or_accepted(key: str, value: Any) -> None:
    # the file does not exist: every option is checked before it is read, so the call fails
    # with an error of ucbplan's tree, one line, whatever the value
    call: dict[str, Any] = {"site": "paranal", "night": "2040-02-15", key: value}
    with pytest.raises(UcbplanError) as info:
        ucbplan.plan(NOWHERE, **call)
    text = str(info.value)
    assert "\n" not in text and len(text) < 500, text
