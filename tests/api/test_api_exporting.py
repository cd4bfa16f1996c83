"""``ucbplan.export`` and ``ucbplan.read_blocks``: what ``ucbplan export`` writes, from Python
(issue 30), and the plan family's command line as a shell over the API (issue 33's option
checks at the command line too)."""

from __future__ import annotations

import inspect
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from support.strategies import any_value

import ucbplan
from ucbplan.api.exporting import EXPORT_FLAGS
from ucbplan.errors import InputError, UcbplanError

HM = "catalogs/hm-cnc-simulated.yaml"
ROOT = Path(__file__).resolve().parents[2]


def _cli(*args: str) -> subprocess.CompletedProcess[bytes]:
    return subprocess.run(
        [sys.executable, "-m", "ucbplan", *args], capture_output=True, cwd=ROOT, check=False
    )


@pytest.fixture(scope="module")
def saved(tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, Path]:
    """A one-night plan and the file ``Plan.write`` made of it."""
    plan = ucbplan.plan(HM, "paranal", "2040-02-15")
    path = plan.write(tmp_path_factory.mktemp("plan") / "plan.ecsv")
    return plan, path


@pytest.mark.parametrize("to", ["phase-table", "proposal", "eso-p2"])
def test_export_equals_the_cli_from_a_file_a_table_or_a_plan(
    saved: tuple[Any, Path], to: str
) -> None:
    plan, path = saved
    cli = _cli("export", str(path), "--to", to)
    assert cli.returncode == 0, cli.stderr
    from_file = ucbplan.export(path, to)
    assert from_file.content == cli.stdout
    assert ucbplan.export(plan, to).content == cli.stdout
    assert ucbplan.export(ucbplan.read_blocks(path), to).content == cli.stdout
    assert from_file.n_blocks == len(plan.table) and repr(from_file).startswith("Export(")


def test_read_blocks_round_trips_write(saved: tuple[Any, Path]) -> None:
    plan, path = saved
    table = ucbplan.read_blocks(path)
    assert table.colnames == plan.table.colnames and len(table) == len(plan.table)
    assert list(table["block_id"]) == list(plan.table["block_id"])


def test_export_flags_are_parameters_of_export() -> None:
    params = inspect.signature(ucbplan.export).parameters
    assert set(EXPORT_FLAGS) <= set(params)
    assert inspect.Parameter.VAR_KEYWORD not in {p.kind for p in params.values()}


@pytest.mark.parametrize(
    ("call", "parameter"),
    [
        (lambda p: ucbplan.export(p, "nope"), "to"),
        (lambda p: ucbplan.export(p, 3), "to"),
        (lambda p: ucbplan.export(42, "phase-table"), "blocks"),
        (lambda p: ucbplan.read_blocks(42), "path"),
        (
            lambda p: ucbplan.export(p, "eso-p2", acquisition=3 * __import__("astropy").units.m),
            "acquisition",
        ),
    ],
)
def test_bad_input_is_one_line_naming_the_parameter(
    saved: tuple[Any, Path], call: Any, parameter: str
) -> None:
    with pytest.raises(UcbplanError) as info:
        call(saved[1])
    text = str(info.value)
    assert text.startswith(f"{parameter}: ") and "\n" not in text, text


_ANY = any_value(integers=10**9, text=10)
_KEYWORDS = sorted(
    p for p, v in inspect.signature(ucbplan.export).parameters.items() if v.kind == v.KEYWORD_ONLY
)


@settings(
    max_examples=80, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(key=st.sampled_from(_KEYWORDS), value=_ANY)
def test_any_value_of_any_option_is_refused_in_one_line_or_exported(
    saved: tuple[Any, Path], key: str, value: Any
) -> None:
    try:
        ucbplan.export(saved[0], "eso-p2", **{key: value})
    except UcbplanError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 500, str(exc)


def test_the_plan_default_exposure_time_is_the_planners() -> None:
    from ucbplan.api.plan_options import DEFAULT_EXPTIME
    from ucbplan.observing.schedule.options import DEFAULT_EXPTIME_S

    assert DEFAULT_EXPTIME == DEFAULT_EXPTIME_S


# ----------------------------------------------- issue 33: the same checks at the command line

_PLAN = ("plan", HM, "--site", "paranal", "--night", "2040-02-15")


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("--max-visit", "", "--goal", "sigma_K=5km/s"), "--max-visit: expected a duration"),
        (("--max-visit", "1h"), "--max-visit: the longest visit a goal plans, and no goal"),
        (
            ("--visit", "1h", "--max-visit", "30min", "--goal", "sigma_K=5km/s"),
            "--max-visit: 1800 s is shorter than the visit (3600 s)",
        ),
    ],
)
def test_plan_refuses_ignored_or_contradictory_max_visit(
    args: tuple[str, ...], message: str, tmp_path: Path
) -> None:
    out = tmp_path / "plan.ecsv"
    run = _cli(*_PLAN, *args, "-o", str(out))
    err = run.stderr.decode()
    assert run.returncode == 2 and err.startswith(f"error: {message}"), err
    assert err.count("\n") == 1 and not out.exists()


def test_an_unknown_plan_option_is_refused_as_before() -> None:
    with pytest.raises(InputError, match="did you mean 'moon_sep'"):
        ucbplan.plan(HM, "paranal", "2040-02-15", moon_sepp=3)


def test_countdown_equals_now_once(saved: tuple[Any, Path]) -> None:
    from datetime import UTC, datetime

    from astropy.time import Time

    plan, path = saved
    first = plan.table["t_start_utc"][0]
    at = f"{str(first)[:19].replace(' ', 'T')}Z"
    cli = _cli("now", str(path), "--at", at, "--once")
    assert cli.returncode == 0, cli.stderr
    lines = ucbplan.api.exporting.countdown(path, at)
    assert "\n".join(lines) + "\n" == cli.stdout.decode()
    instant = datetime.fromisoformat(at[:-1]).replace(tzinfo=UTC)
    assert ucbplan.api.exporting.countdown(plan, instant) == lines
    assert ucbplan.api.exporting.countdown(plan, Time(at[:-1], scale="utc")) == lines


@pytest.mark.parametrize("at", [3, "tomorrow", ["2040-02-16"]])
def test_countdown_refuses_a_bad_instant_in_one_line(saved: tuple[Any, Path], at: Any) -> None:
    with pytest.raises(InputError, match=r"^at: expected an ISO UTC time") as info:
        ucbplan.api.exporting.countdown(saved[1], at)
    assert "\n" not in str(info.value)
