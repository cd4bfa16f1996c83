"""Property tests of the observing inputs: mutated blocks tables and site files, any plan value.

(a) A valid blocks table is written as ECSV, CSV or JSON and mutated — a column deleted, cells
blanked or garbled, unicode names, values of the wrong type, provenance paths naming folders,
FIFOs, devices or missing files, a byte-order mark, latin-1 bytes, cut or spliced bytes — and
run through ``ucbplan export --to FORMAT`` for every format, in process through the real entry
point. (b) Site files are mutated the same way and read by the site loader (and, marked slow,
by ``ucbplan plan --sites-file``). (c) Plan settings take any values.

Whatever the input: the exit code is 0 or 2, no traceback is printed, an error is one line
shorter than 400 characters, and a failed run writes no output file.
"""

from __future__ import annotations

import io
import json
import math
import os
from pathlib import Path
from typing import Any

import pytest
import yaml
from astropy.table import Table
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from support.cli import check_outcome, run_cli
from support.exports import fixture_table

from ucbplan.cli._flags import cli_message
from ucbplan.errors import UcbplanError
from ucbplan.observing.blocks.block import ExposurePlan
from ucbplan.observing.blocks.write import write_table
from ucbplan.observing.exports import EXPORT_FORMATS
from ucbplan.observing.observatory.sites import Site, load_sites
from ucbplan.observing.schedule import PlanSettings

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]

REPO = Path(__file__).resolve().parents[3]
HM = REPO / "catalogs" / "hm-cnc-simulated.yaml"
FAST = settings(
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
SLOW = settings(
    max_examples=300,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)

# Values a cell or a field may be garbled into.
SCALARS = st.one_of(
    st.sampled_from(
        [
            "",
            " ",
            "nan",
            "-inf",
            "1e400",
            "-0",
            "0x10",
            "١٢",
            "5 km/s",
            "2037-13-45T00:00:00",
            "9999-12-31T23:59:59.999",
            "0001-01-01T00:00:00",
            "yesterday",
            "Ŭcb J0806–1527",
            "a\rb\x07c",
            "\ud800",
            "x" * 5000,
            "[1, 2]",
            "{a: 1}",
            "*alias",
            '"',
            "#",
        ]
    ),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(10**20), 10**20),
    st.booleans(),
    st.none(),
    st.text(max_size=30),
)
NAMES = st.one_of(
    st.text(min_size=0, max_size=40),
    st.sampled_from(["Ŭcb J0806–1527", "白矮星", "HM_Cnc", "HM\tCnc", "a" * 300, "x,y;z\\"]),
)


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with the things a provenance path may name: a FIFO, a folder, a real file."""
    folder = tmp_path_factory.mktemp("observing-fuzz")
    os.mkfifo(folder / "fifo.yaml")
    (folder / "folder").mkdir()
    (folder / "hm.yaml").write_bytes(HM.read_bytes())
    (folder / "out").mkdir()
    return folder


def _provenance_paths(workdir: Path) -> list[Any]:
    return [
        str(workdir / "fifo.yaml"),
        str(workdir / "folder"),
        str(workdir / "missing.yaml"),
        str(workdir / "hm.yaml"),
        "/dev/zero",
        "/dev/null",
        "",
        None,
        42,
        ["a", "list"],
        "a\x00b",
        "x" * 5000,
    ]


def _set_cell(table: Table, column: str, row: int, value: Any) -> None:
    """Put any value into a cell (the column becomes text when the value does not fit)."""
    if table[column].dtype.kind not in "US":
        try:
            table[column][row] = value
            return
        except (TypeError, ValueError, OverflowError):
            pass
    text = [str(v) for v in table[column]]
    text[row] = str(value)
    table[column] = text  # a text column: no unit


@st.composite
def mutated_tables(draw: st.DrawFn, workdir: Path) -> bytes:
    """A blocks table, mutated, as the bytes of an ECSV, CSV or JSON file."""
    table = fixture_table()
    if draw(st.booleans()):
        table.remove_column("vmag")  # so that the exports read the provenance target files
    for _ in range(draw(st.integers(0, 3))):
        op = draw(st.sampled_from(["delete", "blank", "garble", "names", "meta", "rows"]))
        column = draw(st.sampled_from(table.colnames)) if table.colnames else None
        row = draw(st.integers(0, max(len(table) - 1, 0)))
        if op == "delete" and column is not None:
            table.remove_column(column)
        elif op in ("blank", "garble") and column is not None and len(table):
            _set_cell(table, column, row, "" if op == "blank" else draw(SCALARS))
        elif op == "names" and "target" in table.colnames:
            table["target"] = [draw(NAMES) for _ in range(len(table))]
        elif op == "meta" and table.meta.get("targets"):
            entry = table.meta["targets"][draw(st.integers(0, 1))]
            entry["file"] = draw(st.sampled_from(_provenance_paths(workdir)))
            entry["sha256"] = draw(st.sampled_from([None, "0" * 64, 5, ""]))
            if draw(st.booleans()):
                table.meta[draw(st.sampled_from(["site", "overhead_s", "created_utc"]))] = draw(
                    SCALARS
                )
        elif op == "rows":
            table = table[: draw(st.integers(0, len(table)))]
    fmt = draw(st.sampled_from(["ecsv", "csv", "json"]))
    buf = io.StringIO()
    try:
        write_table(table, buf, fmt)
    except (ValueError, TypeError, yaml.YAMLError):  # a value the writer itself cannot write
        buf = io.StringIO()
        write_table(fixture_table(), buf, fmt)
    data = buf.getvalue().encode("utf-8", "surrogatepass")
    return _mutate_bytes(draw, data)


def _mutate_bytes(draw: st.DrawFn, data: bytes) -> bytes:
    op = draw(st.sampled_from(["none", "none", "none", "none", "bom", "latin1", "cut", "splice"]))
    if op == "bom":
        return b"\xef\xbb\xbf" + data
    if op == "latin1":
        return data.decode("utf-8", "replace").encode("latin-1", "replace") + "é".encode("latin-1")
    if op == "cut":
        return data[: draw(st.integers(0, len(data)))]
    if op == "splice":
        at = draw(st.integers(0, len(data)))
        return data[:at] + draw(st.binary(max_size=20)) + data[at:]
    return data


def _export_every_format(path: Path, out_dir: Path) -> None:
    _export(path, out_dir, list(EXPORT_FORMATS))


def _export(path: Path, out_dir: Path, formats: list[str]) -> None:
    out = out_dir / "export.out"
    for to in formats:
        before = sorted(os.listdir(out_dir))
        code, err = run_cli(["export", str(path), "--to", to, "-o", str(out), "--overwrite"])
        check_outcome(code, err)
        assert code in (0, 2), f"exit {code} for --to {to}: {err[-600:]}"
        if code == 0:
            assert out.exists()
            out.unlink()
        else:
            assert sorted(os.listdir(out_dir)) == before, f"--to {to} left a file after failing"


def _blocks_property(workdir: Path, data: bytes, suffix: str) -> None:
    path = workdir / f"blocks{suffix}"
    path.write_bytes(data)
    _export_every_format(path, workdir / "out")


@FAST
@given(data=st.data())
def test_mutated_blocks_tables_export_or_fail_in_one_line(
    workdir: Path, data: st.DataObject
) -> None:
    blob = data.draw(mutated_tables(workdir))
    _blocks_property(workdir, blob, data.draw(st.sampled_from([".ecsv", ".csv", ".json", ""])))


@pytest.mark.slow
@SLOW
@given(data=st.data())
def test_mutated_blocks_tables_many(workdir: Path, data: st.DataObject) -> None:
    blob = data.draw(mutated_tables(workdir))
    _blocks_property(workdir, blob, data.draw(st.sampled_from([".ecsv", ".csv", ".json", ""])))


def test_blocks_paths_that_are_not_tables(workdir: Path) -> None:
    for path in (
        workdir / "fifo.yaml",
        workdir / "folder",
        workdir / "nope.ecsv",
        Path("/dev/zero"),
    ):
        _export_every_format(path, workdir / "out")


# --------------------------------------------------------------------------------- site files

SITE = {
    "name": "Test Site",
    "aliases": ["testsite"],
    "lon_deg": -70.4,
    "lat_deg": -24.6,
    "height_m": 2635.0,
    "timezone": "America/Santiago",
    "zenith_hole_deg": 4.0,
}


@st.composite
def mutated_site_files(draw: st.DrawFn) -> bytes:
    """A site table, mutated, as YAML bytes."""
    entry: dict[Any, Any] = dict(SITE)
    for _ in range(draw(st.sampled_from([0, 0, 1, 1, 2, 3]))):
        op = draw(st.sampled_from(["delete", "garble", "typo", "extra", "zone", "nest"]))
        key = draw(st.sampled_from(list(SITE)))
        if op == "delete":
            entry.pop(key, None)
        elif op == "garble":
            entry[key] = draw(SCALARS)
        elif op == "typo" and key in entry:
            entry[key[:-1] + "x"] = entry.pop(key)
        elif op == "extra":
            entry[draw(st.text(max_size=12))] = draw(SCALARS)
        elif op == "zone":
            entry["timezone"] = draw(
                st.one_of(
                    st.text(max_size=30),
                    st.sampled_from(["UTC", "Etc/GMT+5", "america/santiago", "../../etc/passwd"]),
                )
            )
        elif op == "nest":
            entry[key] = [entry.get(key)] * draw(st.integers(0, 3))
    entries = [entry] * draw(st.sampled_from([1, 1, 1, 0, 2]))
    doc: Any = {"sites": entries}
    if draw(st.integers(0, 3)) == 0:
        doc = draw(st.sampled_from([[doc], None, {"site": entries}, {"sites": entry}]))
    try:
        text = yaml.safe_dump(doc, allow_unicode=True, sort_keys=False)
    except (yaml.YAMLError, ValueError):
        text = "sites: []\n"
    if draw(st.integers(0, 3)) == 0:
        text += draw(
            st.sampled_from(
                [
                    "sites: []\n",  # a duplicate top-level key
                    "a: &a [1]\nb: [" + ", ".join(["*a"] * 60) + "]\n",  # too many aliases
                    "x: [[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[\n",
                ]
            )
        )
    return _mutate_bytes(draw, text.encode("utf-8", "surrogatepass"))


def _check_site(site: Site) -> None:
    assert -180.0 <= site.lon_deg <= 360.0 and -90.0 <= site.lat_deg <= 90.0
    assert -500.0 <= site.height_m <= 10000.0
    assert site.zone is not None
    assert site.name.strip() and all(a.strip() for a in site.aliases)


@FAST
@given(blob=mutated_site_files())
def test_mutated_site_files_load_or_fail_in_one_line(workdir: Path, blob: bytes) -> None:
    path = workdir / "sites.yaml"
    path.write_bytes(blob)
    try:
        sites = load_sites(path)
    except UcbplanError as exc:
        text = str(exc)
        assert "\n" not in text and len(text) < 400, text
        return
    for site in sites:
        _check_site(site)


def test_site_file_paths_that_are_not_files(workdir: Path) -> None:
    for path in (workdir / "fifo.yaml", workdir / "folder", workdir / "missing.yaml"):
        with pytest.raises(UcbplanError) as info:
            load_sites(path)
        assert len(str(info.value)) < 400


@pytest.mark.slow
@settings(
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(blob=mutated_site_files())
def test_mutated_site_files_through_plan(workdir: Path, blob: bytes) -> None:
    path = workdir / "sites-cli.yaml"
    path.write_bytes(blob)
    out_dir = workdir / "out"
    out = out_dir / "plan.ecsv"
    before = sorted(os.listdir(out_dir))
    args = ["plan", str(HM), "--sites-file", str(path), "--site", "Test Site"]
    code, err = run_cli([*args, "--night", "2040-02-15", "-o", str(out), "--overwrite"])
    check_outcome(code, err)
    assert code in (0, 2)
    if code == 0:
        out.unlink()
    else:
        assert sorted(os.listdir(out_dir)) == before


# ----------------------------------------------------------------------------- plan settings

NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(10**12), 10**12),
    st.sampled_from([0.0, -0.0, 1.0, 1e-300, 1e300, math.nan]),
)
OPTION_OF = {
    "airmass_max": "--airmass-max",
    "moon_sep_deg": "--moon-sep",
    "moon_illum_max": "--moon-illum",
    "zenith_hole_deg": "--zenith-hole",
    "alpha": "--alpha",
    "sigma_v_kms": "--sigma-v",
    "k_eff_kms": "--k-eff",
    "max_bin_fraction": "--max-bin-fraction",
    "overhead_s": "--overhead",
    "sessions_per_night": "--sessions",
    "twilight": "--twilight",
    "mode": "--mode",
    "max_smear": "--max-smear",
}


@FAST
@given(
    key=st.sampled_from(sorted(OPTION_OF)),
    value=st.one_of(NUMBERS, st.text(max_size=20), SCALARS),
    exposure=st.tuples(NUMBERS, st.integers(-5, 10**9), NUMBERS),
)
def test_plan_settings_take_any_value(key: str, value: Any, exposure: tuple[Any, ...]) -> None:
    try:
        plan = ExposurePlan(*exposure)
    except UcbplanError as exc:
        text = str(exc)
        assert "\n" not in text and len(text) < 400, text
        assert cli_message(text).startswith("--"), text  # the CLI names the flag
        plan = ExposurePlan()
    try:
        PlanSettings(exposure=plan, **{key: value})
    except UcbplanError as exc:
        text = str(exc)
        assert "\n" not in text and len(text) < 400, text
        assert OPTION_OF[key] in cli_message(text), text  # the CLI names its flag
    except TypeError:
        pytest.fail(f"TypeError for {key}={value!r}")


def test_json_rows_with_every_kind_of_value(workdir: Path) -> None:
    # Cells of every JSON type, in every column (each column through one of the exports).
    table = fixture_table()
    buf = io.StringIO()
    write_table(table, buf, "json")
    rows = json.loads(buf.getvalue())
    odd = [None, True, [1], {"a": 1}, "", 1e308, -1, "nan"]
    for k, column in enumerate(rows[0]):
        bad = [dict(r) for r in rows]
        bad[1][column] = odd[k % len(odd)]
        path = workdir / "odd.json"
        path.write_text(json.dumps(bad), encoding="utf-8")
        _export(path, workdir / "out", [EXPORT_FORMATS[k % len(EXPORT_FORMATS)]])
