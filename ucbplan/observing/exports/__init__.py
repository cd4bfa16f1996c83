"""Observatory and proposal exports of the master blocks table, one module per format.

Each format is a function ``(table, options) -> ExportResult`` in its own module
(:mod:`.eso_p2`, :mod:`.keck`, :mod:`.ics`, :mod:`.ing`, :mod:`.lco`, :mod:`.proposal`,
:mod:`.gemini`, :mod:`.phase_table`), built
on the shared helpers, grouped by what they serve (:mod:`.interface`: the options, result and
signature; :mod:`.columns`: reading the blocks table, with documented defaults; :mod:`.text`:
times, angles and names as text; :mod:`.provenance`: the plan's meta; :mod:`.windows`: the
window on an observation's start), and registered here by name in :data:`EXPORTERS`;
:func:`export_blocks` looks the name up and fails with the list of known names. Imports point one
way: this registry → format modules → shared helpers. Formats are described in docs/exports.md.
"""

from __future__ import annotations

from dataclasses import replace

from astropy.table import Table

from ucbplan.errors import InputError, InputFileError, shorten
from ucbplan.observing.blocks.read import check_blocks
from ucbplan.observing.exports.eso_p2 import export_eso_p2
from ucbplan.observing.exports.format_sites import check_site
from ucbplan.observing.exports.gemini import export_gemini
from ucbplan.observing.exports.ics import export_ics
from ucbplan.observing.exports.ing import export_ing_cat
from ucbplan.observing.exports.interface import (
    DEFAULT_ACQUISITION_S,
    Exporter,
    ExportOptions,
    ExportResult,
)
from ucbplan.observing.exports.keck import export_keck_starlist
from ucbplan.observing.exports.lco import export_lco
from ucbplan.observing.exports.phase_table import export_phase_table
from ucbplan.observing.exports.proposal import PROPOSAL_FORMATS, export_proposal
from ucbplan.observing.exports.provenance import meta

__all__ = [
    "DEFAULT_ACQUISITION_S",
    "EXPORTERS",
    "EXPORT_FORMATS",
    "PROPOSAL_FORMATS",
    "ExportOptions",
    "ExportResult",
    "Exporter",
    "export_blocks",
    "export_eso_p2",
    "export_gemini",
    "export_ics",
    "export_ing_cat",
    "export_keck_starlist",
    "export_lco",
    "export_phase_table",
    "export_proposal",
]

#: Export formats by name (``ucbplan export --to NAME``), in the order the CLI help lists them.
EXPORTERS: dict[str, Exporter] = {
    "eso-p2": export_eso_p2,
    "keck-starlist": export_keck_starlist,
    "ics": export_ics,
    "proposal": export_proposal,
    "ing-cat": export_ing_cat,
    "lco": export_lco,
    "gemini": export_gemini,
    "phase-table": export_phase_table,
}

#: The names ``--to`` accepts.
EXPORT_FORMATS = tuple(EXPORTERS)


def export_blocks(table: Table, to: str, options: ExportOptions | None = None) -> ExportResult:
    """Export a master blocks table in the format named ``to``.

    Parameters
    ----------
    table : astropy.table.Table
        Master blocks table (:func:`ucbplan.observing.blocks.read.read_blocks`).
    to : str
        Format name, one of :data:`EXPORT_FORMATS`.
    options : ExportOptions, optional
        Acquisition overhead, window rule and per-format choices (defaults when None).

    Returns
    -------
    ExportResult
        The file's bytes, its usual suffix and notes for the user.

    Raises
    ------
    UcbplanError
        For an unknown format name (the message lists the known ones), an empty table or a bad
        cell (:func:`~ucbplan.observing.blocks.read.check_blocks`).
    SiteError
        The plan's site is not one of the format's observatory sites and ``options.force`` is
        False (:func:`~ucbplan.observing.exports.format_sites.check_site`).
    """
    exporter = EXPORTERS.get(to) if isinstance(to, str) else None
    if exporter is None:
        raise InputError(
            f"to: unknown export format {shorten(to, 40)}; expected one of {', '.join(EXPORTERS)}"
        )
    if len(table) == 0:
        raise InputFileError("blocks table has no rows: nothing to export; re-run `ucbplan plan`")
    options = options or ExportOptions()
    site_notes = check_site(meta(table).get("site"), to, options.force)
    result = exporter(check_blocks(table), options)
    return replace(result, notes=(*site_notes, *result.notes)) if site_notes else result
