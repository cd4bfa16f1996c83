"""Bad blocks tables and awkward names: `export` answers in one line, never hangs or crashes. The
cases are the blocks-table bad-input corpus, tests/support/bad_blocks.py.

The blocks-table reader (blank cells, missing columns, encodings, non-files, ECSV/CSV/JSON), the
target files named in a table's provenance (FIFOs, folders, missing or changed files), non-ASCII
and control characters in names for every format, and names that collide after sanitising.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import signal
from collections.abc import Iterator
from pathlib import Path

import icalendar
import pytest
from astropy.table import Table
from support.bad_blocks import (
    ASCII_FORMATS,
    BAD_CELLS,
    COLLIDING_NAMES,
    EXPORT_OPTIONS,
    PROVENANCE_KINDS,
    ecsv_text,
    replace_cell,
    untrusted_files,
)
from support.cli import check_outcome, run_cli
from support.exports import fixture_table, golden

from ucbplan.errors import InputFileError, UcbplanError
from ucbplan.observing.blocks.read import read_blocks
from ucbplan.observing.blocks.write import write_table
from ucbplan.observing.exports import EXPORT_FORMATS, ExportOptions, export_blocks

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]

REPO = Path(__file__).resolve().parents[3]
OPTS = ExportOptions(force=True, acquisition_s=600.0)
UNICODE_NAME = "Ŭcb J0806–1527"  # a breve and an en dash


@contextlib.contextmanager
def deadline(seconds: int) -> Iterator[None]:
    """Fail (instead of hanging the test run) if the block takes longer than ``seconds``."""

    def _expired(signum: int, frame: object) -> None:
        raise TimeoutError(f"took longer than {seconds} s")

    old = signal.signal(signal.SIGALRM, _expired)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def _one_line(exc: BaseException, *parts: str) -> str:
    text = str(exc)
    assert "\n" not in text and len(text) < 400, text
    for part in parts:
        assert part in text, text
    return text


# ------------------------------------------------------------------------------ read_blocks


@pytest.mark.parametrize(("column", "value", "expected"), BAD_CELLS)
def test_bad_cells_are_named_by_row_and_column(
    tmp_path: Path, column: str, value: str, expected: str
) -> None:
    path = tmp_path / "blocks.ecsv"
    path.write_text(replace_cell(ecsv_text(fixture_table()), 1, column, value), encoding="utf-8")
    with pytest.raises(InputFileError) as info:
        read_blocks(path)
    _one_line(info.value, expected)


def test_reader_refuses_files_it_cannot_trust(tmp_path: Path) -> None:
    text = ecsv_text(fixture_table())
    cases = untrusted_files(text)
    for name, (data, message) in cases.items():
        path = tmp_path / name
        assert data is not None
        path.write_bytes(data)
        with pytest.raises(InputFileError) as info:
            read_blocks(path)
        _one_line(info.value, message)
    for path, message in (
        (tmp_path, "not a regular file"),
        (tmp_path / "missing.ecsv", "file not found"),
    ):
        with pytest.raises(InputFileError) as info:
            read_blocks(path)
        _one_line(info.value, message, "pass a blocks table from `ucbplan plan -o`")
    fifo = tmp_path / "fifo.ecsv"
    os.mkfifo(fifo)
    with deadline(10), pytest.raises(InputFileError, match="not a regular file"):
        read_blocks(fifo)


def test_bom_csv_and_json_tables_export_like_ecsv(tmp_path: Path) -> None:
    table = fixture_table()
    table.meta = {}  # CSV and JSON carry no provenance; compare like with like
    bom = tmp_path / "bom.ecsv"
    bom.write_bytes(b"\xef\xbb\xbf" + ecsv_text(table).encode())
    ref = {to: export_blocks(read_blocks(bom), to, OPTS).content for to in EXPORT_FORMATS}
    for fmt in ("csv", "json"):
        path = tmp_path / f"blocks.{fmt}"
        with path.open("w", encoding="utf-8") as handle:
            write_table(table, handle, fmt)
        back = read_blocks(path)
        for to in EXPORT_FORMATS:
            assert export_blocks(back, to, OPTS).content == ref[to], (fmt, to)


def test_json_table_with_a_lone_surrogate_is_refused(tmp_path: Path) -> None:
    # "\ud800" is valid JSON text but cannot be written as UTF-8 (ICS, proposal) later.
    table = fixture_table()
    buf = io.StringIO()
    write_table(table, buf, "json")
    rows = json.loads(buf.getvalue())
    rows[0]["target"] = "HM \ud800Cnc"
    path = tmp_path / "blocks.json"
    path.write_text(json.dumps(rows), encoding="utf-8")
    with pytest.raises(InputFileError) as info:
        read_blocks(path)
    _one_line(info.value, "row 1, column target: expected Unicode text")


# ------------------------------------------------------------------- provenance target files


@pytest.mark.parametrize("kind", PROVENANCE_KINDS)
def test_provenance_target_file_never_hangs(tmp_path: Path, kind: str) -> None:
    table = fixture_table()
    table.remove_column("vmag")
    entry = table.meta["targets"][0]
    target = tmp_path / "hm.yaml"
    target.write_bytes((REPO / "catalogs" / "hm-cnc-simulated.yaml").read_bytes())
    paths: dict[str, object] = {
        "fifo": tmp_path / "fifo.yaml",
        "folder": tmp_path,
        "missing": tmp_path / "gone.yaml",
        "device": "/dev/zero",
        "changed": target,
        "not-a-path": ["a", "list"],
    }
    if kind == "fifo":
        os.mkfifo(tmp_path / "fifo.yaml")
    value = paths[kind]
    entry["file"] = str(value) if isinstance(value, Path) else value
    entry["sha256"] = "f" * 64
    with deadline(10):
        res = export_blocks(table, "keck-starlist", OPTS)
    notes = [n for n in res.notes if "target file" in n]
    assert len(notes) == 1 and len(notes[0]) < 400, res.notes
    assert "magnitude" in notes[0] or "not a path" in notes[0]


def test_provenance_target_file_read_when_unchanged(tmp_path: Path) -> None:
    from ucbplan.observing.blocks.make import file_sha256

    table = fixture_table()
    table.remove_column("vmag")
    path = REPO / "catalogs" / "hm-cnc-simulated.yaml"
    table.meta["targets"][0].update(file=str(path), sha256=file_sha256(path))
    res = export_blocks(table, "keck-starlist", OPTS)
    line = next(ln for ln in res.content.decode().splitlines() if ln.startswith("HM_Cnc"))
    assert "vmag=" in line and not [n for n in res.notes if "target file" in n]


def test_export_cli_with_a_fifo_in_the_provenance(tmp_path: Path) -> None:
    table = fixture_table()
    table.remove_column("vmag")
    os.mkfifo(tmp_path / "fifo.yaml")
    table.meta["targets"][0]["file"] = str(tmp_path / "fifo.yaml")
    blocks = tmp_path / "blocks.ecsv"
    blocks.write_text(ecsv_text(table), encoding="utf-8")
    out = tmp_path / "list.txt"
    with deadline(30):
        code, err = run_cli(
            ["export", str(blocks), "--to", "keck-starlist", "--force", "-o", str(out)]
        )
    check_outcome(code, err)
    assert code == 0 and out.exists() and "not a regular file" in err


# ------------------------------------------------------------------------ names and formats


def _named(name: str) -> Table:
    table = fixture_table()
    table["target"] = [name if n == "HM Cnc" else n for n in table["target"]]
    return table


@pytest.mark.parametrize("to", EXPORT_FORMATS)
def test_non_ascii_names_in_every_format(to: str) -> None:
    # Was UnicodeEncodeError for the Keck starlist and the ING catalogue.
    res = export_blocks(_named(UNICODE_NAME), to, OPTS)
    text = res.content.decode("utf-8")
    if to in ("keck-starlist", "ing-cat"):
        res.content.decode("ascii")
        assert "Ucb_J0806-1527" in text
        assert any("written as 'Ucb_J0806-1527' (ASCII only)" in n for n in res.notes)
    elif to == "eso-p2":
        doc = json.loads(text)
        assert doc["target_list_csv"][0].startswith("Ucb_J0806-1527,")
        assert doc["obs"][0]["target"] == UNICODE_NAME  # JSON keeps the name
    elif to in ("ics", "proposal"):
        assert UNICODE_NAME in text or UNICODE_NAME.replace(" ", "\\ ") in text


@pytest.mark.parametrize("to", ASCII_FORMATS)
def test_name_without_ascii_spelling_is_one_line(to: str) -> None:
    with pytest.raises(InputFileError) as info:
        export_blocks(_named("白矮星"), to, OPTS)
    _one_line(info.value, "'白矮星' has no ASCII spelling")


def test_ics_has_no_control_characters() -> None:
    res = export_blocks(_named("HM\rCnc\x07;x,y\u2028z"), "ics", OPTS)
    body = res.content.replace(b"\r\n", b"")
    assert b"\r" not in body and b"\x07" not in body and "\u2028" not in body.decode()
    cal = icalendar.Calendar.from_ical(res.content)
    assert str(cal.walk("VEVENT")[0]["SUMMARY"]).startswith("HM\nCnc;x,y\nz quadrature")


def test_latex_escapes_specials_and_drops_controls() -> None:
    opts = ExportOptions(force=True, acquisition_s=600.0, proposal_format="latex")
    tex = export_blocks(_named("A_{b}~c^d\\e\x07"), "proposal", opts).content.decode()
    assert r"A\_\{b\}\textasciitilde{}c\textasciicircum{}d\textbackslash{}e &" in tex
    assert "\x07" not in tex


@pytest.mark.parametrize(("to", "message"), COLLIDING_NAMES)
def test_names_colliding_after_sanitising_are_an_error(to: str, message: str) -> None:
    # ING silently dropped the second target (issue 15).
    table = fixture_table()
    table["target"] = ["HM Cnc", "HM_Cnc", "HM Cnc", "HM Cnc"]
    with pytest.raises(InputFileError) as info:
        export_blocks(table, to, OPTS)
    _one_line(info.value, message)


def test_ing_names_colliding_after_truncation_are_an_error() -> None:
    table = fixture_table()
    long = "Fiducial eccentric dWD"
    table["target"] = [f"{long} A", f"{long} B", f"{long} A", f"{long} A"]
    with pytest.raises(InputFileError) as info:
        export_blocks(table, "ing-cat", OPTS)
    _one_line(info.value, "both become 'Fiducial_eccentric_d", "(20-character limit)")


def test_long_eso_ob_names_stay_unique() -> None:
    # block ids of the bundled injection target are 44 characters: cut at 32 they all collided.
    table = fixture_table()
    stem = "Fiducial_eccentric_dWD_injection-20400301"
    table["block_id"] = [f"{stem}-{k:02d}" for k in range(1, 5)]
    res = export_blocks(table, "eso-p2", OPTS)
    names = [ob["name"] for ob in json.loads(res.content)["obs"]]
    assert len(set(names)) == len(names) == 4
    assert all(len(n) <= 32 and n.startswith(stem[:25]) for n in names)
    assert any("hash suffix" in n for n in res.notes)
    # short ids keep their name (the golden file)
    assert export_blocks(fixture_table(), "eso-p2", OPTS).content == golden("exports_eso_p2.json")


def test_export_options_are_range_checked() -> None:
    for kwargs, option in EXPORT_OPTIONS:
        with pytest.raises(UcbplanError) as info:
            ExportOptions(**kwargs)  # type: ignore[arg-type]
        _one_line(info.value, option)


def test_export_cli_format_rule(tmp_path: Path) -> None:
    blocks = tmp_path / "blocks.ecsv"
    blocks.write_text(ecsv_text(fixture_table()), encoding="utf-8")
    tex = tmp_path / "time.tex"
    args = ["export", str(blocks), "--to", "proposal", "--acquisition", "600"]
    code, err = run_cli([*args, "-o", str(tex)])
    assert code == 0, err
    assert tex.read_bytes() == golden("exports_proposal.tex")  # -o x.tex means LaTeX
    for extra, message in (
        (["-o", str(tmp_path / "t.tex"), "--format", "csv"], "the suffix says latex"),
        (["--format", "table"], "--format: expected one of ecsv, csv, latex"),
    ):
        code, err = run_cli([*args, *extra])
        check_outcome(code, err)
        assert code == 2 and message in err.splitlines()[-1]
    assert not (tmp_path / "t.tex").exists()
    code, err = run_cli(["export", str(blocks), "--to", "ics", "--format", "csv"])
    check_outcome(code, err)
    assert code == 2 and "--format chooses the proposal table format" in err


def test_shared_references_in_meta_cannot_expand() -> None:
    # A YAML alias bomb read by another tool: 10^10 leaves through shared lists.
    table = fixture_table()
    bomb: list = ["lol"] * 10
    for _ in range(9):
        bomb = [bomb] * 10
    table.meta["site"] = {"name": "Paranal", "bomb": bomb}
    table.meta["constraints"] = [bomb]
    with deadline(20):
        for to in EXPORT_FORMATS:
            res = export_blocks(table, to, ExportOptions(force=True, acquisition_s=600.0))
            assert len(res.content) < 2_000_000
