"""The export registry, the ``ucbplan export`` command, and exports of incomplete tables."""

from __future__ import annotations

import hashlib
import json
from datetime import UTC, datetime
from pathlib import Path

import pytest
import typer
from astropy.table import Table
from astropy.time import Time
from support.exports import (
    GOLDEN_CASES,
    HM_P_S,
    fixture_table,
    golden,
    minimal_table,
    written_table,
)
from typer.testing import CliRunner

from ucbplan.cli._flags import cli_message
from ucbplan.errors import InputFileError, OutputExistsError, UcbplanError
from ucbplan.observing.exports import (
    EXPORT_FORMATS,
    EXPORTERS,
    PROPOSAL_FORMATS,
    ExportOptions,
    export_blocks,
)
from ucbplan.observing.exports.columns import floats
from ucbplan.observing.exports.text import iso_ms
from ucbplan.offline import offline


@pytest.fixture(scope="module")
def blocks_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("exports") / "blocks.ecsv"
    fixture_table().write(path, format="ascii.ecsv")
    return path


@pytest.fixture(scope="module")
def table(tmp_path_factory: pytest.TempPathFactory) -> Table:
    return written_table(tmp_path_factory.mktemp("exports"))


def test_every_registered_format_has_a_golden() -> None:
    assert {to for to, _ in GOLDEN_CASES.values()} == set(EXPORTERS) == set(EXPORT_FORMATS)
    proposal = {fmt for to, fmt in GOLDEN_CASES.values() if to == "proposal"}
    assert proposal == set(PROPOSAL_FORMATS)


def test_unknown_format_lists_known_names(table: Table) -> None:
    with pytest.raises(UcbplanError, match="expected one of eso-p2, keck-starlist, ics, proposal"):
        export_blocks(table, "eso", ExportOptions(force=True))


def test_exports_read_only_declared_columns(table: Table) -> None:
    # Column names come from the blocks-table schema; a typo or a renamed column fails loudly.
    with pytest.raises(LookupError, match="does not declare"):
        floats(table, "sigma_t", default=0.0)


# ------------------------------------------------------------------- robustness, missing extras


def test_minimal_table_uses_documented_defaults(table: Table) -> None:
    small = minimal_table(table)
    res = export_blocks(small, "proposal", ExportOptions(force=True))
    text = " ".join(res.notes)
    assert "assuming 600 s acquisition" in text
    assert "P_b estimated as 4|t_alt_utc - t_mid_utc|" in text
    assert "readout taken as block width" in text
    summary = Table.read(res.content.decode(), format="ascii.ecsv")
    hm = summary[summary["target"] == "HM Cnc"][0]
    # Readout from the block width: 50 s - 2 x 20 s = 10 s, one readout between the two
    # exposures (a readout_s column gives n_exp x readout_s = 20 s: the last readout is counted).
    assert hm["overhead_per_visit_s"] == pytest.approx(610.0, abs=1e-6)
    assert hm["p_orb_min"] == pytest.approx(HM_P_S / 60, abs=2e-3 / 60)  # ms ISO times: 4 x 0.5 ms
    for to in ("eso-p2", "keck-starlist", "ics", "ing-cat", "lco"):
        assert export_blocks(small, to, ExportOptions(force=True)).content


def test_missing_coordinates_is_a_clear_error(table: Table) -> None:
    small = minimal_table(table)
    small.remove_columns(["ra_deg", "dec_deg"])
    with pytest.raises(InputFileError, match="neither ra_deg/dec_deg nor ra_hms/dec_dms"):
        export_blocks(small, "keck-starlist", ExportOptions(force=True))


def test_sexagesimal_coordinates_suffice(table: Table) -> None:
    # Without ra_deg/dec_deg the exports read ra_hms/dec_dms and give the same starlist.
    t = Table(table, copy=True)
    t.remove_columns(["ra_deg", "dec_deg"])
    opts = ExportOptions(force=True)
    assert export_blocks(t, "keck-starlist", opts).content == (
        export_blocks(table, "keck-starlist", opts).content
    )


def test_bad_time_is_a_clear_error(table: Table) -> None:
    t = Table(table, copy=True)
    t["t_mid_utc"] = t["t_mid_utc"].astype("U30")
    t["t_mid_utc"][0] = "yesterday"
    with pytest.raises(
        InputFileError, match=r"row 1, column t_mid_utc: expected an ISO time.*got 'yesterday'"
    ):
        export_blocks(t, "ics", ExportOptions(force=True))


def test_empty_table(table: Table) -> None:
    with pytest.raises(InputFileError, match="no rows"):
        export_blocks(table[:0], "ics", ExportOptions(force=True))


def test_time_columns_give_the_same_export(table: Table) -> None:
    # A table holding astropy Time columns instead of ISO strings exports identically.
    t = Table(table, copy=True)
    with offline():
        for col in ("t_mid_utc", "t_start_utc", "t_end_utc"):
            t[col] = Time(list(t[col]), scale="utc", precision=3)
    for to in ("eso-p2", "ics", "keck-starlist"):
        opts = ExportOptions(force=True, acquisition_s=600.0)
        assert export_blocks(t, to, opts).content == export_blocks(table, to, opts).content


def test_iso_rounding_is_half_up() -> None:
    t = datetime(2037, 1, 16, 3, 10, 11, 250000, tzinfo=UTC)
    assert iso_ms(t, 1) == "2037-01-16T03:10:11.3"
    assert iso_ms(t.replace(second=59, microsecond=960000), 1) == "2037-01-16T03:11:00.0"


def test_acquisition_from_plan_meta_and_vmag_from_target_file(table: Table) -> None:
    hm_file = Path(__file__).resolve().parents[3] / "catalogs" / "hm-cnc-simulated.yaml"
    t = minimal_table(table)
    digest = hashlib.sha256(hm_file.read_bytes()).hexdigest()
    t.meta = {
        "overhead_s": 300.0,
        "targets": [{"name": "HM Cnc", "file": str(hm_file), "sha256": digest}],
    }
    res = export_blocks(t, "keck-starlist", ExportOptions(force=True))
    # vmag 21.1 is in catalogs/hm-cnc-simulated.yaml; the table itself has no vmag.
    assert "HM_Cnc          08 06 23.20 +15 27 30.0 2000 vmag=21.1 rotmode=vertical" in (
        res.content.decode().splitlines()
    )
    doc = json.loads(export_blocks(t, "eso-p2", ExportOptions(force=True)).content)
    assert {ob["acquisition_s"] for ob in doc["obs"]} == {300.0}
    # A file that changed since planning (sha256 mismatch) is not trusted: no vmag.
    t.meta["targets"][0]["sha256"] = "0" * 64
    assert (
        "vmag=" not in export_blocks(t, "keck-starlist", ExportOptions(force=True)).content.decode()
    )


# ----------------------------------------------------------------------------------------- CLI


def _app() -> typer.Typer:
    from ucbplan.cli.export import register

    app = typer.Typer()

    @app.callback()
    def _root() -> None:
        """Test shell."""

    register(app)
    return app


def test_cli_help_lists_the_registered_formats() -> None:
    from ucbplan.api.exporting import EXPORT_FLAGS, EXPORT_FORMAT_NAMES

    assert EXPORT_FORMAT_NAMES == EXPORT_FORMATS
    assert " | ".join(EXPORT_FORMATS) in EXPORT_FLAGS["to"].help


def test_cli_export_writes_file_and_refuses_overwrite(blocks_path: Path, tmp_path: Path) -> None:
    out = tmp_path / "plan.ics"
    runner = CliRunner()
    args = ["export", str(blocks_path), "--to", "ics", "-o", str(out)]
    res = runner.invoke(_app(), args)
    assert res.exit_code == 0, res.output
    assert out.read_bytes() == golden("exports_calendar.ics")
    res = runner.invoke(_app(), args)
    assert isinstance(res.exception, OutputExistsError)
    res = runner.invoke(_app(), [*args, "--overwrite"])
    assert res.exit_code == 0


def test_cli_export_passes_options_through(blocks_path: Path) -> None:
    # --format and --acquisition reach the exporter: stdout is the 600 s LaTeX golden.
    args = ["export", str(blocks_path), "--to", "proposal", "--format", "latex"]
    res = CliRunner().invoke(_app(), [*args, "--acquisition", "600"])
    assert res.exit_code == 0
    assert res.stdout.encode() == golden("exports_proposal.tex")
    res = CliRunner().invoke(_app(), [*args, "--acquisition", "300"])
    assert res.exit_code == 0 and res.stdout.encode() != golden("exports_proposal.tex")


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--to", "nope"], "unknown export format 'nope'"),
        (["--to", "proposal", "--format", "xlsx"], "expected one of ecsv, csv, latex"),
        (["--to", "ics", "--tolerance-sigma", "-1"], "--tolerance-sigma: expected a number in [0,"),
        (["--to", "ics", "--tolerance-floor", "nan"], "--tolerance-floor: expected a number"),
        (["--to", "ics", "--acquisition", "1e300"], "--acquisition: expected a number"),
        (["--to", "keck-starlist", "--rotmode", "sideways"], "--rotmode: expected pa, vertical"),
        (["--to", "ics", "--format", "latex"], "--format chooses the proposal table format"),
        (["--to", "proposal", "-o", "x.tex", "--format", "csv"], "the suffix says latex"),
    ],
)
def test_cli_export_refuses_bad_options(blocks_path: Path, args: list[str], message: str) -> None:
    res = CliRunner().invoke(_app(), ["export", str(blocks_path), *args])
    assert isinstance(res.exception, UcbplanError)
    assert message in cli_message(str(res.exception))  # as the command line prints it
