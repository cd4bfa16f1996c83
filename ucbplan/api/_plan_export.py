"""``Plan.export``: the bytes ``ucbplan export`` writes, as text or a file."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import fields
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from ucbplan.errors import InputError, shorten

if TYPE_CHECKING:
    from astropy.table import Table

#: The export choices that are text (or a path).
_TEXT = ("proposal_format", "keck_rotmode", "semester", "instrument", "eso_templates")


def _options(to: str, path: Path | None, given: Mapping[str, Any]) -> Any:
    """:class:`ExportOptions` from the choices given (None: the option's default); the proposal
    format as the command picks it (``proposal_format``, else the suffix of ``path``)."""
    from ucbplan.io import output_format
    from ucbplan.observing.exports import PROPOSAL_FORMATS, ExportOptions

    known = {f.name for f in fields(ExportOptions)}
    chosen = {k: v for k, v in given.items() if v is not None and k in known}
    for key in _TEXT:
        if key in chosen and not isinstance(chosen[key], str | Path):
            raise InputError(f"{key}: expected text, got {shorten(chosen[key], 40)}", parameter=key)
    if "eso_templates" in chosen:
        chosen["eso_templates"] = str(chosen["eso_templates"])
    if to == "proposal":
        fmt = output_format(path, chosen.get("proposal_format"), PROPOSAL_FORMATS, "ecsv")
        chosen["proposal_format"] = fmt
    elif "proposal_format" in chosen:
        raise InputError(
            f"proposal_format: chooses the proposal table's format; to={to!r} writes one fixed "
            "format: leave proposal_format out",
            parameter="proposal_format",
        )
    return ExportOptions(**chosen)


def export_plan(
    table: Table,
    to: str,
    path: Path | None,
    overwrite: bool,
    given: Mapping[str, Any],
) -> tuple[str | Path, tuple[str, ...]]:
    """The export of ``table`` named ``to``: its text (``path`` None) or the path written, and
    the notes ``ucbplan export`` prints.

    Raises
    ------
    UcbplanError
        As :func:`~ucbplan.observing.exports.export_blocks`; OutputExistsError for an existing
        ``path`` without ``overwrite``.
    """
    from ucbplan.io import check_output_path, write_output
    from ucbplan.observing.exports import export_blocks

    out = path
    if out is not None:
        check_output_path(out, overwrite)
    result = export_blocks(table, to, _options(to, out, given))
    if out is None:
        return result.content.decode("utf-8"), result.notes

    def _write(handle: IO[bytes]) -> None:
        handle.write(result.content)

    write_output(out, _write, overwrite=overwrite, binary=True)
    return out, result.notes
