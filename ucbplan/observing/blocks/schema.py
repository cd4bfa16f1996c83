"""The master blocks table's declaration: the single source every export (p2, starlist, ICS,
proposal) reads.

:data:`COLUMNS` declares the table once — name, type, unit, description, required — and the
table's maker (:mod:`ucbplan.observing.blocks.make`), its reader
(:mod:`ucbplan.observing.blocks.read`), :data:`REQUIRED_COLUMNS` / :data:`EXTRA_COLUMNS` and the
block-table reference (:func:`column_reference`) derive from it.

Times are written as ISO-8601 strings (``YYYY-MM-DDTHH:MM:SS.sss``) so that ECSV, CSV and JSON
carry exactly the same text: ``t_*_utc`` columns are UTC at the site with millisecond precision,
``t_mid_tdb_bary`` is the barycentric TDB epoch with microsecond precision. Provenance (ucbplan
version, target files and their SHA-256, site, time base, phase convention, constraints) lives in
the table ``meta`` and is preserved by ECSV.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ucbplan.core.constants import DAY_S
from ucbplan.observing.blocks.block import MAX_BLOCK_S, MAX_N_EXP, MAX_READOUT_S


@dataclass(frozen=True, slots=True)
class Column:
    """One column of the master blocks table: everything writers, readers and docs need.

    Attributes
    ----------
    name : str
        Column name.
    dtype : str
        Type of the values: ``str``, ``float64`` or ``int64``.
    unit : str or None
        Physical unit (astropy spelling); None for names, times and dimensionless numbers.
    description : str
        What the column holds (the block-table reference and, if ``in_header``, the ECSV header).
    required : bool
        Every reader needs it (:func:`~ucbplan.observing.blocks.read.read_blocks` checks);
        required columns come first.
    in_header : bool
        ``description`` is written into the file header. False for the columns whose files never
        carried one, so that tables stay byte-identical to those written before.
    kind : str
        How the value is made from a :class:`Block`: ``value`` (the attribute ``source``),
        ``utc`` / ``tdb`` (ISO time of ``source``, ms / µs), ``local`` (local civil time of
        ``source``), ``hms`` / ``dms`` (sexagesimal RA / Dec) or ``width`` (end − start).
    source : str
        The :class:`Block` attribute it comes from (default: ``name``).
    bounds : tuple of float, optional
        Smallest and largest value a reader accepts (in ``unit``); every value the planner
        writes lies well inside.
    nan_ok : bool
        NaN (unknown) is an accepted value.
    """

    name: str
    dtype: str
    unit: str | None
    description: str
    required: bool = False
    in_header: bool = True
    kind: str = "value"
    source: str = ""
    bounds: tuple[float, float] | None = None
    nan_ok: bool = False

    @property
    def attribute(self) -> str:
        """The :class:`Block` attribute the column is made from."""
        return self.source or self.name


#: Largest |u★| a table may hold [rad] (the planner writes 0 <= u★ < 2π).
_MAX_U = 4.0 * math.pi

#: The master blocks table, column by column, in file order: required columns first (issue 3).
COLUMNS: tuple[Column, ...] = (
    Column("target", "str", None, "target name", required=True),
    Column("block_id", "str", None, "unique block identifier", required=True),
    Column(
        "anchor",
        "str",
        None,
        "anchor name (quadrature, conjunction, zero-crossing, u=VALUE, fixed-u-pairs)",
        required=True,
    ),
    Column(
        "u_star_rad",
        "float64",
        "rad",
        "target argument of latitude of star 1",
        required=True,
        bounds=(-_MAX_U, _MAX_U),
    ),
    Column(
        "t_mid_utc",
        "str",
        None,
        "block centre, UTC at the site (light time removed), ISO ms",
        required=True,
        kind="utc",
    ),
    Column(
        "t_start_utc",
        "str",
        None,
        "block start (first exposure starts), UTC at the site, ISO ms",
        required=True,
        kind="utc",
    ),
    Column(
        "t_end_utc",
        "str",
        None,
        "block end (last exposure ends), UTC at the site, ISO ms",
        required=True,
        kind="utc",
    ),
    Column(
        "t_mid_tdb_bary",
        "str",
        None,
        "anchor epoch, TDB at the solar-system barycentre, ISO us",
        required=True,
        kind="tdb",
    ),
    Column(
        "sigma_t_s",
        "float64",
        "s",
        "1-sigma timing uncertainty of the anchor epoch (sigma_u / u_dot)",
        required=True,
        bounds=(0.0, DAY_S),
    ),
    Column(
        "t_alt_utc",
        "str",
        None,
        "phi_ref pi-mode alternative epoch (P_b/4 away), UTC at the site, ISO ms",
        required=True,
        kind="utc",
    ),
    Column(
        "exptime_s",
        "float64",
        "s",
        "single-exposure time",
        required=True,
        bounds=(0.0, MAX_BLOCK_S),
    ),
    Column(
        "n_exp",
        "int64",
        None,
        "number of exposures in the block",
        required=True,
        bounds=(1, MAX_N_EXP),
    ),
    Column(
        "lambda_k",
        "float64",
        None,
        "smearing attenuation of K over the block, sin(x)/x, x = n_b dt/2",
        required=True,
        bounds=(-1.0, 1.0),
    ),
    Column(
        "altitude_deg",
        "float64",
        "deg",
        "target altitude at block centre",
        required=True,
        bounds=(-90.0, 90.0),
    ),
    Column(
        "airmass",
        "float64",
        None,
        "airmass (sec z) at block centre",
        required=True,
        bounds=(1.0, 1000.0),
    ),
    Column(
        "moon_sep_deg",
        "float64",
        "deg",
        "smallest target-Moon separation over the block",
        required=True,
        bounds=(0.0, 180.0),
    ),
    Column(
        "ra_deg", "float64", "deg", "right ascension (ICRS)", in_header=False, bounds=(0.0, 360.0)
    ),
    Column(
        "dec_deg", "float64", "deg", "declination (ICRS)", in_header=False, bounds=(-90.0, 90.0)
    ),
    Column("ra_hms", "str", None, "right ascension, HH:MM:SS.sss", in_header=False, kind="hms"),
    Column("dec_dms", "str", None, "declination, +DD:MM:SS.ss", in_header=False, kind="dms"),
    Column("night", "str", None, "local date of the evening the night starts"),
    Column(
        "t_mid_local",
        "str",
        None,
        "block centre, local civil time at the site with UTC offset, ISO s",
        in_header=False,
        kind="local",
        source="t_mid_utc",
    ),
    Column(
        "t_start_local",
        "str",
        None,
        "block start, local civil time at the site with UTC offset, ISO s",
        in_header=False,
        kind="local",
        source="t_start_utc",
    ),
    Column(
        "t_end_local",
        "str",
        None,
        "block end, local civil time at the site with UTC offset, ISO s",
        in_header=False,
        kind="local",
        source="t_end_utc",
    ),
    Column("timezone", "str", None, "IANA time zone of the site", in_header=False),
    Column(
        "alt_start_deg",
        "float64",
        "deg",
        "target altitude at block start",
        in_header=False,
        bounds=(-90.0, 90.0),
    ),
    Column(
        "alt_end_deg",
        "float64",
        "deg",
        "target altitude at block end",
        in_header=False,
        bounds=(-90.0, 90.0),
    ),
    Column(
        "airmass_start",
        "float64",
        None,
        "airmass at block start",
        in_header=False,
        bounds=(1.0, 1000.0),
    ),
    Column(
        "airmass_end",
        "float64",
        None,
        "airmass at block end",
        in_header=False,
        bounds=(1.0, 1000.0),
    ),
    Column(
        "readout_s",
        "float64",
        "s",
        "dead time between exposures",
        in_header=False,
        bounds=(0.0, MAX_READOUT_S),
    ),
    Column(
        "block_width_s",
        "float64",
        "s",
        "block length, first exposure start to last exposure end",
        in_header=False,
        kind="width",
        bounds=(0.0, DAY_S),
    ),
    Column(
        "lambda_kappa",
        "float64",
        None,
        "attenuation of the eccentricity terms, sin(2x)/(2x)",
        bounds=(-1.0, 1.0),
    ),
    Column(
        "smear_kms",
        "float64",
        "km / s",
        "velocity smear K(1 - lambda_k); NaN if K unknown",
        bounds=(-1e5, 1e5),
        nan_ok=True,
    ),
    Column(
        "period_s",
        "float64",
        "s",
        "orbital period P_b",
        in_header=False,
        bounds=(1.0, 1e7),  # a zero period divided by zero in the exports (fuzz test)
        nan_ok=True,
    ),
    Column(
        "moon_illum",
        "float64",
        None,
        "illuminated fraction of the Moon at block centre",
        bounds=(0.0, 1.0),
    ),
    Column(
        "priority",
        "float64",
        None,
        "target priority (higher first)",
        in_header=False,
        bounds=(-1e9, 1e9),
    ),
    Column("session_id", "str", None, "blocks sharing a session (e.g. a quadrature pair)"),
    Column("pair_id", "str", None, "fixed-u pair identifier (same u at two epochs)"),
    Column(
        "delta_kappa",
        "float64",
        None,
        "predicted kappa change over the pair baseline (Eq. delta_kappa_rewrite)",
        bounds=(-2.0, 2.0),
        nan_ok=True,
    ),
    Column(
        "visit_id",
        "str",
        None,
        "visit (one acquisition followed by continuous exposures) the exposure belongs to",
    ),
    Column(
        "sigma_v_kms",
        "float64",
        "km / s",
        "RV precision of the exposure (--sigma-v, or instrument, magnitude and airmass); NaN "
        "if unknown",
        bounds=(0.0, 1e5),
        nan_ok=True,
    ),
)

#: Optional columns the planner does not write but exports read when a user adds them.
USER_COLUMNS: tuple[Column, ...] = (
    Column("vmag", "float64", "mag", "V magnitude", bounds=(-30.0, 40.0), nan_ok=True),
    Column(
        "acq_s", "float64", "s", "acquisition overhead before the block", bounds=(0.0, MAX_BLOCK_S)
    ),
    Column("tol_rad", "float64", "rad", "phase tolerance", bounds=(0.0, 10.0), nan_ok=True),
)

#: Columns by name.
COLUMN_BY_NAME: dict[str, Column] = {c.name: c for c in COLUMNS}

#: Every column a reader knows (planner columns and :data:`USER_COLUMNS`), by name.
KNOWN_COLUMNS: dict[str, Column] = {c.name: c for c in (*COLUMNS, *USER_COLUMNS)}

#: Columns whose cells may be empty: no π-mode alternative, no session, no pair, no visit.
BLANK_OK = frozenset(("t_alt_utc", "session_id", "pair_id", "visit_id"))

#: Largest blocks table [bytes] (a year of blocks of a 5-min binary is a few MB).
MAX_TABLE_BYTES = 100_000_000

#: Largest ECSV header [characters] (column declarations and provenance: a year-long plan writes
#: a few hundred kB).
MAX_HEADER_CHARS = 4_000_000

#: Years a blocks-table time may fall in (the planner plans nights in 1900-2100).
TIME_YEARS = (1900, 2101)

#: Columns every master table has, in this order; extras follow.
REQUIRED_COLUMNS: tuple[str, ...] = tuple(c.name for c in COLUMNS if c.required)

#: Extra columns (always present, in this order after the required ones).
EXTRA_COLUMNS: tuple[str, ...] = tuple(c.name for c in COLUMNS if not c.required)

#: The file formats of the blocks table (:func:`ucbplan.observing.blocks.write.write_table`).
TABLE_FORMATS = ("ecsv", "csv", "json")

#: Kinds of plain value the table ``meta`` holds, copied and written as they are.
META_SCALARS = frozenset((str, int, float, bool, type(None)))


def column_reference() -> str:
    """The block-table reference as a Markdown table (one row per column, in file order)."""
    lines = [
        "| column | type | unit | required | description |",
        "| --- | --- | --- | --- | --- |",
    ]
    for c in COLUMNS:
        required = "yes" if c.required else ""
        lines.append(f"| `{c.name}` | {c.dtype} | {c.unit or ''} | {required} | {c.description} |")
    return "\n".join(lines) + "\n"
