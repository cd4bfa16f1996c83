"""A saved plan read back, and exported for an observatory, a proposal or a calendar: what
``ucbplan export`` and ``ucbplan now`` call (and :class:`ucbplan.Plan`'s methods can call too).

The options of :func:`export` are declared here once: their defaults in its signature, their
flags and ``--help`` text in :data:`EXPORT_FLAGS`. Nothing heavy is imported at module level.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan.api._convert import as_float, scope
from ucbplan.api.flagspec import Flag
from ucbplan.api.plan_options import checked_flag, checked_text
from ucbplan.errors import InputError, shorten

if TYPE_CHECKING:
    from astropy.table import Table

#: The names of ``ucbplan.observing.exports.EXPORT_FORMATS`` (a test keeps them equal): spelled
#: out because importing the exports (astropy.coordinates) at start-up costs ~0.3 s on every
#: command; the library is imported only when an export runs.
EXPORT_FORMAT_NAMES = (
    "eso-p2",
    "keck-starlist",
    "ics",
    "proposal",
    "ing-cat",
    "lco",
    "gemini",
    "phase-table",
)

#: The blocks table argument, as ``export`` and ``now`` spell it.
_BLOCKS_HELP = "Master blocks table (ECSV, CSV or JSON) from `ucbplan plan -o`."

#: :func:`export`'s parameters as ``ucbplan export`` spells them: flag and ``--help`` text.
EXPORT_FLAGS: dict[str, Flag] = {
    "blocks": Flag((), _BLOCKS_HELP),
    "to": Flag(("--to",), f"Export format: {' | '.join(EXPORT_FORMAT_NAMES)}."),
    "proposal_format": Flag(
        ("--format",),
        "Proposal table format: ecsv | csv | latex (default: the -o suffix, else ecsv).",
    ),
    "acquisition": Flag(
        ("--acquisition",), "Acquisition overhead (s) (default: acq_s column, else 600 s).", "s"
    ),
    "tolerance_sigma": Flag(
        ("--tolerance-sigma",), "Window half-width in units of the block's 1σ timing error."
    ),
    "tolerance_floor": Flag(("--tolerance-floor",), "Smallest window half-width (s).", "s"),
    "merge_overlaps": Flag(
        ("--merge-overlaps",), "ESO p2: merge overlapping OBs of one target into one OB."
    ),
    "strict": Flag(
        ("--strict",),
        "Queue formats (eso-p2, lco, gemini): refuse a visit that waits between exposures "
        "instead of noting it.",
    ),
    "rotmode": Flag(("--rotmode",), "Keck starlist rotmode=: pa | vertical | stationary."),
    "force": Flag(
        ("--force",), "Write the file even if the plan's site is not the format's observatory."
    ),
    "semester": Flag(
        ("--semester",),
        "Proposal semester: 2041A | 2041B (A = Feb-Jul) or an ESO period like P147 "
        "(default: the one containing the plan).",
    ),
    "seeing": Flag(
        ("--seeing",), "ESO p2: seeing limit of the OB constraint set (arcsec).", "arcsec"
    ),
    "instrument": Flag(
        ("--instrument",),
        "ESO p2: instrument whose readout mode and overheads go into the OB templates.",
    ),
    "eso_templates": Flag(
        ("--eso-templates",),
        "ESO p2: YAML file with the acquisition/science template names and keywords.",
    ),
}

#: :func:`eso_p2_create`'s parameters as ``ucbplan export --create`` spells them.
P2_FLAGS: dict[str, Flag] = {
    "dry_run": Flag(
        ("--dry-run/--no-dry-run",),
        "With --create: list the OBs only (default) or create them.",
    ),
    "container": Flag(("--container",), "With --create: p2 container id (a run/folder)."),
    "environment": Flag(
        ("--p2-environment",), "With --create: demo | production | production_lasilla."
    ),
    "user": Flag(
        ("--p2-user",),
        "With --no-dry-run: ESO user name (password from UCBPLAN_P2_PASSWORD or a prompt).",
    ),
}

#: ``ucbplan now``'s argument and options.
NOW_FLAGS: dict[str, Flag] = {
    "plan": Flag((), "Blocks table written by `ucbplan plan -o` (ECSV, CSV or JSON)."),
    "at": Flag(
        ("--at",),
        "Run the clock from this UTC instant, ISO (2040-02-16T01:40:00Z), not from the "
        "computer's clock: a rehearsal.",
    ),
    "log": Flag(
        ("--log",),
        "Write the observing log (CSV, for `plan --observed`) to this file: press t (taken), "
        "m (missed) or s (skipped) for the exposure just started, q to quit; the file is "
        "rewritten at each key. An existing log of the same plan is continued.",
    ),
    "overwrite": Flag(("--overwrite",), "Start the --log file again if it exists."),
}


@dataclass(frozen=True)
class Export:
    """An exported plan: the file's bytes, its usual suffix, the notes for the user.

    Attributes
    ----------
    content : bytes
        The file, as ``ucbplan export`` writes it.
    suffix : str
        Its usual suffix (``.obx.json``, ``.ics`` …).
    notes : tuple of str
        Defaults taken and rounding warnings (``export`` prints them on stderr).
    n_blocks : int
        Blocks of the plan exported.
    """

    content: bytes
    suffix: str
    notes: tuple[str, ...]
    n_blocks: int

    def __repr__(self) -> str:
        return f"Export({len(self.content)} bytes, {self.suffix}, {self.n_blocks} blocks)"


def export_formats() -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The export formats (``to``) and the proposal table formats (``proposal_format``)."""
    from ucbplan.observing.exports import EXPORT_FORMATS, PROPOSAL_FORMATS

    return tuple(EXPORT_FORMATS), tuple(PROPOSAL_FORMATS)


def read_blocks(path: str | Path) -> Table:
    """A blocks table written by ``ucbplan plan -o`` (or :meth:`Plan.write`): ECSV, CSV or
    JSON, recognised by its content, every cell checked.

    Parameters
    ----------
    path : str or Path
        The blocks table (``.ecsv``, ``.csv`` or ``.json``).

    Returns
    -------
    astropy.table.Table
        The blocks, with the plan's provenance in ``.meta``.

    Raises
    ------
    UcbplanError
        One line naming the file, the row and column at fault.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import ucbplan
    >>> run = ucbplan.plan("catalogs/hm-cnc-simulated.yaml", site="paranal", night="2040-02-15")
    >>> tmp = tempfile.TemporaryDirectory()
    >>> path = run.write(pathlib.Path(tmp.name) / "plan.ecsv")
    >>> blocks = ucbplan.read_blocks(path)
    >>> len(blocks), str(blocks["t_mid_utc"][0])
    (2, '2040-02-16T03:05:33.800')
    >>> tmp.cleanup()
    """
    from ucbplan.observing.blocks.read import read_blocks as _read

    if not isinstance(path, str | Path):
        raise InputError(f"path: expected a file path, got {shorten(path, 40)}", "path")
    with scope():
        return _read(path)


def export(
    blocks: Any,
    to: str,
    *,
    proposal_format: str | None = None,
    acquisition: float | Any | None = None,
    tolerance_sigma: float = 3.0,
    tolerance_floor: float | Any = 10.0,
    merge_overlaps: bool = False,
    strict: bool = False,
    rotmode: str = "vertical",
    force: bool = False,
    semester: str | None = None,
    seeing: float | Any = 1.0,
    instrument: str | None = None,
    eso_templates: str | Path | None = None,
) -> Export:
    """A plan exported for an observatory (ESO p2, Keck, ING, LCO, Gemini), as a phase table,
    a calendar or a proposal table: ``ucbplan export``.

    Parameters
    ----------
    blocks : path, astropy Table or Plan
        The blocks table (a file from ``plan -o``, the table, or a :class:`ucbplan.Plan`).
    to : str
        The format, one of :data:`EXPORT_FORMAT_NAMES`.
    proposal_format : str, optional
        ``proposal``: ``ecsv`` (None), ``csv`` or ``latex``.
    acquisition : float or Quantity, optional
        Acquisition overhead [s] (None: the ``acq_s`` column, else the plan's, else 600 s).
    tolerance_sigma : float
        Window half-width in units of the block's 1σ timing error.
    tolerance_floor : float or Quantity
        Smallest window half-width [s].
    merge_overlaps : bool
        ESO p2: merge overlapping OBs of one target into one OB.
    strict : bool
        Queue formats (``eso-p2``, ``lco``, ``gemini``): refuse (:class:`ServiceModeError`) a
        visit that waits between exposures, which a service-mode queue cannot execute as
        planned, instead of noting it.
    rotmode : str
        Keck starlist ``rotmode=``: ``pa``, ``vertical`` or ``stationary``.
    force : bool
        Export even if the plan's site is not the format's observatory.
    semester : str, optional
        Proposal semester ``2041A``/``2041B`` or an ESO period ``P147`` (None: the plan's).
    seeing : float or Quantity
        ESO p2: seeing limit of the OB constraint set [arcsec].
    instrument : str, optional
        ESO p2: the instrument whose readout mode and overheads go into the OB templates.
    eso_templates : path, optional
        ESO p2: YAML file with the acquisition/science template names and keywords.

    Returns
    -------
    Export

    Raises
    ------
    UcbplanError
        An unknown format, a bad option or table cell, a site that is not the format's
        observatory (without ``force``): one line each.

    Examples
    --------
    >>> import ucbplan
    >>> run = ucbplan.plan("catalogs/hm-cnc-simulated.yaml", site="paranal", night="2040-02-15")
    >>> ucbplan.export(run, "phase-table")
    Export(... bytes, .ecsv, 2 blocks)
    """
    from ucbplan.observing.exports import PROPOSAL_FORMATS, ExportOptions, export_blocks

    if to not in EXPORT_FORMAT_NAMES:
        raise InputError(
            f"to: unknown export format {shorten(to, 40)}; expected one of "
            f"{', '.join(EXPORT_FORMAT_NAMES)}",
            parameter="to",
        )
    fmt = checked_text(proposal_format, "proposal_format", "ecsv, csv or latex")
    if fmt is not None and fmt not in PROPOSAL_FORMATS:
        raise InputError(
            f"proposal_format: expected {', '.join(PROPOSAL_FORMATS)}, got {shorten(fmt, 40)}",
            parameter="proposal_format",
        )
    options = ExportOptions(  # the options first: cheap, one line each, before the file
        acquisition_s=as_float(acquisition, "s", "acquisition"),
        tolerance_sigma=tolerance_sigma,
        tolerance_floor_s=as_float(tolerance_floor, "s", "tolerance_floor"),
        merge_overlaps=checked_flag(merge_overlaps, "merge_overlaps"),
        proposal_format=fmt or PROPOSAL_FORMATS[0],
        keck_rotmode=rotmode,
        force=checked_flag(force, "force"),
        semester=checked_text(semester, "semester", "a semester such as 2041A or P147"),
        seeing_arcsec=as_float(seeing, "arcsec", "seeing"),
        instrument=checked_text(instrument, "instrument", "an instrument name"),
        eso_templates=_templates(eso_templates),
        strict=checked_flag(strict, "strict"),
    )
    table = _blocks_table(blocks)
    with scope():
        result = export_blocks(table, to, options)
    return Export(result.content, result.suffix, tuple(result.notes), len(table))


def _templates(value: Any) -> str | None:
    """``eso_templates`` as the exporter takes it (a path's text)."""
    if value is None or isinstance(value, Path):
        return str(value) if value else None
    return checked_text(value, "eso_templates", "a YAML file path") or None


def _blocks_table(blocks: Any) -> Table:
    """The blocks table of a path, a Table or a Plan."""
    from astropy.table import Table

    if isinstance(blocks, str | Path):
        return read_blocks(blocks)
    # a Plan: the text table its files hold (Plan.table is a copy with Time columns)
    table = getattr(blocks, "text_table", blocks)
    if not isinstance(table, Table):
        raise InputError(
            f"blocks: expected a blocks table file, an astropy Table or a Plan, got "
            f"{shorten(blocks, 60)}",
            parameter="blocks",
        )
    return table


def eso_p2_create(
    content: bytes,
    container: int,
    *,
    dry_run: bool = True,
    environment: str = "demo",
    user: str | None = None,
    password: str | None = None,
) -> str:
    """List (dry run) or create in ESO p2 the OBs of an ``eso-p2`` export, with ``p2api``.

    Parameters
    ----------
    content : bytes
        The ``eso-p2`` export (:attr:`Export.content`).
    container : int
        The p2 container id (a run or folder) the OBs go into.
    dry_run : bool
        List the OBs only (no connection).
    environment, user, password : str
        The p2 environment (``demo``, ``production``, ``production_lasilla``) and the ESO user
        portal login (only without ``dry_run``).

    Returns
    -------
    str
        The report, one line per OB.
    """
    from ucbplan.observing.exports.eso_create import connect, create_from_export

    connection = None
    if not dry_run:
        connection = connect(environment, user or "", password or "")
    return create_from_export(content, container, dry_run=dry_run, connection=connection)


def countdown(blocks: Any, at: Any = None) -> list[str]:
    """The telescope countdown at ``at``: what ``ucbplan now --once`` prints (the exposure that
    should be running, the next start in UTC and the wait, the one after, what to do if a start
    was missed; after the last exposure, that the plan is over).

    Parameters
    ----------
    blocks : path, astropy Table or Plan
        The plan (as :func:`export` takes it).
    at : str, datetime or Time, optional
        The instant: ISO UTC text (``2040-02-16T01:40:00Z``), a ``datetime`` (naive = UTC) or
        an astropy ``Time``; None: the computer's clock.

    Returns
    -------
    list of str
        The lines of the frame.

    Raises
    ------
    UcbplanError
        A bad instant or table (one line naming it).

    Examples
    --------
    >>> import ucbplan
    >>> from ucbplan.api import countdown
    >>> run = ucbplan.plan("catalogs/hm-cnc-simulated.yaml", site="paranal", night="2040-02-15")
    >>> for line in countdown(run, at="2040-02-16T03:00:00"):
    ...     print(line)
    now       2040-02-16 03:00:00 UTC
    next      HM Cnc (simulated) V01/01, anchor quadrature (u★ = 0.000 rad)
              start 03:05:04 UTC (±0.71 s), in 5 min 4 s; 60 s exposure
              new visit: acquisition starts 03:00:04 UTC
    then      HM Cnc (simulated) V01/02, start 03:07:45 UTC, in 7 min 45 s
    """
    from ucbplan.observing.night.countdown import countdown_lines, plan_exposures, what_next

    instant = _instant(at)
    table = _blocks_table(blocks)
    with scope():
        return countdown_lines(what_next(plan_exposures(table), instant))


def _instant(at: Any) -> datetime:
    """``at`` (None, ISO UTC text, a datetime or a Time) as an aware UTC datetime."""
    from ucbplan.observing.night.countdown import parse_utc

    if at is None:
        return datetime.now(UTC)
    if isinstance(at, str):
        return parse_utc(at, "at")
    if isinstance(at, datetime):
        return at.astimezone(UTC) if at.tzinfo is not None else at.replace(tzinfo=UTC)
    if type(at).__name__ == "Time" and getattr(at, "isscalar", False):
        with scope():
            return datetime.fromisoformat(at.utc.isot).replace(tzinfo=UTC)
    raise InputError(
        f"at: expected an ISO UTC time, a datetime or a Time, got {shorten(at, 40)}", "at"
    )
