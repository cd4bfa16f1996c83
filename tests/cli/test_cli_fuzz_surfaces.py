"""Property tests of the newer command-line surfaces: ``ephemeris fit``, ``population``, the
newer ``plan`` and ``feasibility`` options, the exports and several targets per ``horizon``.

As in ``test_cli_fuzz.py``: hypothesis draws option values (numbers of every kind, non-finite and
huge values, unicode, paths that are folders or devices); whatever the input, the exit code is 0,
2 or 130, no traceback, an error is one line, and a failed run leaves its output folder exactly as
it was (no file, no folder). JSON on stdout must parse with NaN refused.

Commands whose valid values start real work (a forecast per source, a plan) are marked slow;
``population simulate`` is fuzzed with ``--out-dir`` naming an existing file, so every value is
checked before that refusal and no chain ever runs.
"""

from __future__ import annotations

import contextlib
import json
import os
from pathlib import Path

import pytest
from astropy.table import Table
from hypothesis import HealthCheck, given, settings
from support.bad_options import FUZZED_FAST, FUZZED_SLOW, SURFACE_VALUES
from support.cli import check_outcome, run_cli, run_main

ROOT = Path(__file__).resolve().parents[2]
CAT = ROOT / "catalogs"
HM = str(CAT / "hm-cnc-simulated.yaml")


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """Small inputs made once: a 2-source catalog, its forecast, eclipse times, a blocks table."""
    root = tmp_path_factory.mktemp("surfaces")
    cat = root / "c2.ecsv"
    Table.read(CAT / "population" / "ldc-200.ecsv")[:2].write(cat)
    forecast = root / "f.ecsv"
    code, err = run_cli(["population", "forecast", str(cat), "-o", str(forecast)])
    assert code == 0, err
    times = root / "times.csv"
    times.write_text(
        "bjd_tdb,sigma_s,kind,cycle\n2458305.6827886,2,primary,0\n2458305.6875891,2,primary,1\n"
        "2458305.6923896,2,primary,2\n2458305.6971901,2,primary,3\n2458306.6971901,2,primary,"
        "210\n",
        encoding="utf-8",
    )
    blocks = root / "b.ecsv"
    code, err = run_cli(
        ["plan", HM, "--site", "paranal", "--night", "2040-02-15", "-o", str(blocks)]
    )
    assert code == 0, err
    taken = root / "taken"
    taken.write_text("a file where a folder belongs\n")
    return {
        "CAT": str(cat),
        "FORECAST": str(forecast),
        "TIMES": str(times),
        "BLOCKS": str(blocks),
        "TAKEN": str(taken),
    }


# (command line without the option, option under test): the corpus of fuzzed options,
# tests/support/bad_options.py.
PARAMS = [
    *(pytest.param(b, o, id=f"{'-'.join(b[:2])}{o}") for b, o in FUZZED_FAST),
    *(
        pytest.param(b, o, id=f"{'-'.join(b[:2])}{o}", marks=pytest.mark.slow)
        for b, o in FUZZED_SLOW
    ),
]


def _fill(args: list[str], inputs: dict[str, str], out_dir: Path) -> list[str]:
    names = {**inputs, "OUT": str(out_dir / "result"), "DIR": str(out_dir / "new" / "deeper")}
    return [a.format(**names) if "{" in a else a for a in args]


def _tree(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


@pytest.mark.parametrize(("base", "option"), PARAMS)
@settings(
    max_examples=8,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(value=SURFACE_VALUES)
def test_any_option_value_on_the_new_surfaces(
    tmp_path: Path, inputs: dict[str, str], base: list[str], option: str, value: str
) -> None:
    out_dir = tmp_path / "out"
    out_dir.mkdir(exist_ok=True)
    for old in out_dir.iterdir():  # each example starts from an empty folder
        if old.is_file():
            old.unlink()
    before = _tree(out_dir)
    args = _fill(base, inputs, out_dir)
    args += [option, value]
    if base[0] == "plan":
        args += ["-o", str(out_dir / "result.ecsv"), "--overwrite"]
    with contextlib.chdir(out_dir):  # a relative path drawn as a value lands in the watched folder
        code, err, out = _run(args)
    check_outcome(code, err)
    if code != 0:
        assert _tree(out_dir) == before, f"a failed run changed the output folder: {args}"
    elif out.strip().startswith(("{", "[")):
        json.loads(out, parse_constant=_refuse_constant)
    _clear(out_dir)


def _refuse_constant(token: str) -> None:
    raise AssertionError(f"JSON with {token}")


def _run(args: list[str]) -> tuple[int, str, str]:
    """``ucbplan ARGS`` in this process: exit code, stderr and stdout."""
    code, out, err = run_main(args)
    return code, err, out


def _clear(folder: Path) -> None:
    for path in sorted(folder.rglob("*"), key=lambda p: -len(p.parts)):
        if path.is_dir():
            path.rmdir()
        else:
            path.unlink()
    assert not os.listdir(folder)
