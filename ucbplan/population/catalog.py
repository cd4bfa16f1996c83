"""Source catalogs: LDC-style galactic-binary tables from ECSV, CSV or HDF5.

Columns follow the LISA Data Challenge (Sangria/Radler) galactic-binary tables. Each column is
declared once in :data:`COLUMNS` (name, SI unit, required or optional, description); readers,
the CLI help and the docs read that declaration. LDC parameters are referenced to the START of
the LISA observation (t = 0): Frequency, FrequencyDerivative and InitialPhase are start values.

Rows are numbered from 1, the first data row. A bad row (missing or non-finite value, value out
of range) is an error naming its row number and column, or, with ``skip_bad``, skipped and listed
in :attr:`Catalog.bad`.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ucbplan.errors import InputFileError, shorten
from ucbplan.inputs import read_text


@dataclass(frozen=True, slots=True)
class CatalogColumn:
    """One catalog column: LDC name, SI unit, bounds, whether required, description."""

    name: str
    unit: str
    lo: float
    hi: float
    required: bool
    description: str
    field: str


_TWO_PI = 2.0 * math.pi
#: Lightest star of a catalog binary [M_sun]: ~10 Jupiter masses, below any brown-dwarf donor;
#: a mass column in the wrong unit (0.44 labelled kg) lands far below it and is refused.
_MIN_MASS = 0.01
#: The catalog contract (LDC names). ``field`` is the attribute of :class:`Source`.
COLUMNS: tuple[CatalogColumn, ...] = (
    CatalogColumn("Frequency", "Hz", 1e-5, 1.0, True, "GW frequency at the start", "f_hz"),
    CatalogColumn(
        "FrequencyDerivative", "Hz / s", -1e-10, 1e-10, True, "ḟ at the start", "fdot_hz_s"
    ),
    CatalogColumn("Amplitude", "", 0.0, 1e-15, True, "GW strain amplitude", "amplitude"),
    CatalogColumn(
        "EclipticLatitude", "rad", -math.pi / 2, math.pi / 2, True, "ecliptic β", "ecl_lat_rad"
    ),
    CatalogColumn("EclipticLongitude", "rad", -_TWO_PI, _TWO_PI, True, "ecliptic λ", "ecl_lon_rad"),
    CatalogColumn("Inclination", "rad", 0.0, math.pi, True, "inclination ι", "inclination_rad"),
    CatalogColumn("Polarization", "rad", -_TWO_PI, _TWO_PI, True, "polarisation ψ", "psi_rad"),
    CatalogColumn("InitialPhase", "rad", -_TWO_PI, _TWO_PI, True, "GW phase at start", "phase_rad"),
    CatalogColumn("Magnitude", "mag", -5.0, 40.0, False, "optical (V or G) magnitude", "vmag"),
    CatalogColumn("Distance", "kpc", 0.0, 1e3, False, "distance", "distance_kpc"),
    CatalogColumn("Eccentricity", "", 0.0, 0.9, False, "orbital eccentricity", "eccentricity"),
    CatalogColumn("Mass1", "solMass", _MIN_MASS, 1.5, False, "mass of star 1", "m1_msun"),
    CatalogColumn("Mass2", "solMass", _MIN_MASS, 1.5, False, "mass of star 2", "m2_msun"),
)
_BY_NAME = {c.name: c for c in COLUMNS}
#: Optional identifier column (any type); default: the row number.
ID_COLUMN = "Name"


@dataclass(frozen=True, slots=True)
class Source:
    """One catalog row in SI units (start-of-observation LDC parameters)."""

    row: int
    source_id: str
    f_hz: float
    fdot_hz_s: float
    amplitude: float
    ecl_lat_rad: float
    ecl_lon_rad: float
    inclination_rad: float
    psi_rad: float
    phase_rad: float
    vmag: float | None = None
    distance_kpc: float | None = None
    eccentricity: float | None = None
    m1_msun: float | None = None
    m2_msun: float | None = None


@dataclass(frozen=True, slots=True)
class Catalog:
    """A read catalog: good sources in file order, bad rows (row, message), file SHA-256."""

    path: Path
    sources: tuple[Source, ...]
    bad: tuple[tuple[int, str], ...]
    sha256: str
    n_rows: int
    optional: tuple[str, ...] = field(default_factory=tuple)


def parse_column_map(text: str | None) -> dict[str, str]:
    """``old=new,old2=new2`` → {old: new}; ``new`` must be an LDC column name.

    Raises
    ------
    InputFileError
        Malformed pair or unknown target column.
    """
    if not text:
        return {}
    out: dict[str, str] = {}
    for pair in text.split(","):
        old, sep, new = (p.strip() for p in pair.partition("="))
        if not sep or not old or not new:
            raise InputFileError(
                f"columns: expected old=new pairs separated by commas, got {shorten(pair)}"
            )
        if new not in _BY_NAME and new != ID_COLUMN:
            known = ", ".join([*_BY_NAME, ID_COLUMN])
            raise InputFileError(f"columns: unknown catalog column {shorten(new)}; use {known}")
        out[old] = new
    return out


def _from_hdf5(path: Path, dataset: str | None) -> dict[str, Any]:
    try:
        import h5py
    except ImportError:
        raise InputFileError(
            f"{path}: reading HDF5 needs h5py: pip install 'ucbplan[hdf5]'"
        ) from None
    try:
        fh = h5py.File(path, "r")
    except OSError as exc:
        raise InputFileError(f"{path}: not a readable HDF5 file ({shorten(exc)})") from None
    with fh:
        found: list[str] = []

        def _visit(name: str, obj: Any) -> None:
            if isinstance(obj, h5py.Dataset) and obj.dtype.names and "Frequency" in obj.dtype.names:
                found.append(name)
            elif isinstance(obj, h5py.Group) and "Frequency" in obj:
                found.append(name)

        if dataset is None:
            fh.visititems(_visit)
            if not found:
                raise InputFileError(
                    f"{path}: no table with a Frequency column (a compound dataset or a group "
                    "of 1-D datasets); name it with `hdf5_path`"
                )
            dataset = found[0]
        if dataset not in fh:
            raise InputFileError(f"{path}: `hdf5_path`: no dataset {shorten(dataset)}")
        obj = fh[dataset]
        if isinstance(obj, h5py.Group):
            return {k: np.asarray(obj[k][()]) for k in obj if isinstance(obj[k], h5py.Dataset)}
        arr = np.asarray(obj[()])
        if not arr.dtype.names:
            raise InputFileError(f"{path}: {shorten(dataset)}: expected a compound table")
        return {k: arr[k].reshape(-1) for k in arr.dtype.names}


def _from_text(path: Path) -> tuple[dict[str, Any], dict[str, str]]:
    from astropy.io import ascii as asc

    text = read_text(path, "catalog")
    fmt = "ecsv" if text.lstrip("\ufeff").startswith("# %ECSV") else "csv"
    if not text.strip("\ufeff \t\r\n"):
        raise InputFileError(
            f"{path}: the catalog is empty; expected a header row of LDC column names "
            "(Frequency, FrequencyDerivative, ...) and one row per source"
        )
    try:
        tab = asc.read(text, format=fmt, guess=False, fast_reader=False)
    except Exception as exc:  # astropy raises many types for malformed tables
        msg = " ".join(str(exc).split())
        raise InputFileError(
            f"{path}: not a readable {fmt.upper()} table ({shorten(msg)})"
        ) from None
    _check_unique_names(path, text, fmt, tab.colnames)
    cols = {n: tab[n] for n in tab.colnames}
    units = {n: str(tab[n].unit) for n in tab.colnames if tab[n].unit is not None}
    return {n: _filled(c) for n, c in cols.items()}, units


def _check_unique_names(path: Path, text: str, fmt: str, names: list[str]) -> None:
    """Refuse a header naming a column twice (astropy would rename the second ``NAME_1``)."""
    if fmt == "ecsv":
        header = list(names)
    else:
        import csv

        lines = (ln for ln in text.lstrip("\ufeff").splitlines() if ln.strip())
        lines = (ln for ln in lines if not ln.lstrip().startswith("#"))
        header = [h.strip() for h in next(csv.reader(lines), [])]
    seen: set[str] = set()
    for name in header:
        if name in seen:
            raise InputFileError(f"{path}: column {shorten(name)} appears twice; keep one")
        seen.add(name)


def _filled(col: Any) -> np.ndarray:
    """Column values with masked cells as NaN (numbers) or "" (text)."""
    if hasattr(col, "filled"):
        if col.dtype.kind in "iuf":
            return np.ma.asarray(col, dtype=np.float64).filled(np.nan)
        return np.asarray(col.filled(""))
    return np.asarray(col)


def _convert(values: np.ndarray, unit: str | None, col: CatalogColumn, path: Path) -> np.ndarray:
    if not unit or unit == col.unit:
        return values
    import astropy.units as u

    try:
        scale = u.Unit(unit).to(u.Unit(col.unit) if col.unit else u.dimensionless_unscaled)
    except (ValueError, u.UnitsError):
        raise InputFileError(
            f"{path}: {col.name}: expected a unit convertible to {col.unit or '1'}, "
            f"got {shorten(unit)}"
        ) from None
    return values * scale


def _number(raw: Any) -> float:
    if isinstance(raw, bytes | str | np.str_ | np.bytes_):
        text = raw.decode() if isinstance(raw, bytes | np.bytes_) else str(raw)
        return float(text.strip()) if text.strip() else math.nan
    if np.ma.is_masked(raw):
        return math.nan
    return float(raw)


def read_catalog(
    path: Path,
    columns: Mapping[str, str] | None = None,
    *,
    skip_bad: bool = False,
    hdf5_path: str | None = None,
) -> Catalog:
    """Read an LDC-style catalog (ECSV, CSV or HDF5 by suffix .h5/.hdf5).

    Parameters
    ----------
    path : Path
        Catalog file.
    columns : mapping, optional
        {name in the file: LDC name} for catalogs with other column names.
    skip_bad : bool
        Skip bad rows (listed in :attr:`Catalog.bad`) instead of raising.
    hdf5_path : str, optional
        Dataset or group inside an HDF5 file (default: the first table with a Frequency column).

    Raises
    ------
    InputFileError
        Unreadable file, missing required column, a bad row (without ``skip_bad``), no rows.
    """
    path = Path(path)
    if not path.is_file():
        raise InputFileError(f"{path}: catalog: no such file")
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    data, units = _columns_of(path, columns, hdf5_path)
    present = [c for c in COLUMNS if c.name in data]
    conv = {c.name: _convert_column(data[c.name], units.get(c.name), c, path) for c in present}
    ids, n_rows = data.get(ID_COLUMN), len(data["Frequency"])
    sources: list[Source] = []
    bad: list[tuple[int, str]] = []
    for i in range(n_rows):
        row = i + 1
        vals, problem = _row_values(data, units, present, conv, i)
        if problem is not None:
            if not skip_bad:
                raise InputFileError(f"{path}: row {row}: {problem} (or use `skip_bad`)")
            bad.append((row, problem))
            continue
        sid = str(_id_text(ids[i])) if ids is not None else str(row)
        sources.append(Source(row=row, source_id=sid, **vals))  # type: ignore[arg-type]
    _check_sources(path, sources, len(bad))
    optional = tuple(c.name for c in present if not c.required)
    return Catalog(path.resolve(), tuple(sources), tuple(bad), digest, n_rows, optional)


def _columns_of(
    path: Path, columns: Mapping[str, str] | None, hdf5_path: str | None
) -> tuple[dict[str, Any], dict[str, str]]:
    """The file's columns under their LDC names and their units; every required one present,
    at least one row."""
    units: dict[str, str] = {}
    if path.suffix.lower() in (".h5", ".hdf5", ".hdf"):
        raw = _from_hdf5(path, hdf5_path)
    else:
        raw, units = _from_text(path)
    rename = dict(columns or {})
    for old in rename:
        if old not in raw:
            raise InputFileError(f"{path}: `columns`: no column {shorten(old)} in the catalog")
    data = {rename.get(k, k): v for k, v in raw.items()}
    units = {rename.get(k, k): v for k, v in units.items()}
    missing = [c.name for c in COLUMNS if c.required and c.name not in data]
    if missing:
        raise InputFileError(
            f"{path}: missing column(s) {', '.join(missing)}; map other names with "
            "`columns` old=new"
        )
    if len(data["Frequency"]) == 0:
        raise InputFileError(f"{path}: catalog has no rows")
    return data, units


def _row_values(
    data: Mapping[str, Any],
    units: Mapping[str, str],
    present: list[CatalogColumn],
    conv: Mapping[str, np.ndarray],
    i: int,
) -> tuple[dict[str, float | None], str | None]:
    """The :class:`Source` fields of row index ``i``, or what is wrong with the row."""
    vals: dict[str, float | None] = {}
    for c in present:
        v = conv[c.name][i]
        if not math.isfinite(v):
            if c.required:
                return (
                    vals,
                    f"{c.name}: expected a finite number, got {shorten(raw_of(data, c, i))}",
                )
            vals[c.field] = None
            continue
        if not c.lo <= v <= c.hi:
            return vals, _out_of_range(c, v, raw_of(data, c, i), units.get(c.name))
        vals[c.field] = float(v)
    if vals.get("amplitude") == 0.0:
        return vals, "Amplitude: expected > 0, got 0.0"
    return vals, None


def _check_sources(path: Path, sources: list[Source], n_bad: int) -> None:
    """Refuse a catalog without usable rows or with an identifier twice."""
    if not sources:
        raise InputFileError(f"{path}: no usable rows ({n_bad} bad)")
    seen: set[str] = set()
    for s in sources:
        if s.source_id in seen:
            raise InputFileError(
                f"{path}: row {s.row}: {ID_COLUMN}: duplicate {shorten(s.source_id)}"
            )
        seen.add(s.source_id)


def _out_of_range(col: CatalogColumn, value: float, raw: Any, unit: str | None) -> str:
    """``COLUMN: expected LO..HI UNIT, got V`` (and the cell in the file's unit, if converted)."""
    unit_text = f" {col.unit}" if col.unit else ""
    got = shorten(float(value))
    if unit and unit != col.unit:
        got += f" (the file's {shorten(raw)} {unit}; is the column's unit right?)"
    return f"{col.name}: expected {col.lo:g}..{col.hi:g}{unit_text}, got {got}"


def _id_text(value: Any) -> str:
    if isinstance(value, bytes | np.bytes_):
        return value.decode(errors="replace").strip()
    return str(value).strip()


def raw_of(data: Mapping[str, Any], col: CatalogColumn, i: int) -> Any:
    """The raw cell of ``col`` in row index ``i`` (for messages)."""
    v = data[col.name][i]
    return "" if np.ma.is_masked(v) else v


def _convert_column(values: Any, unit: str | None, col: CatalogColumn, path: Path) -> np.ndarray:
    arr = np.asarray(values)
    if arr.dtype.kind in "fiub":
        out = arr.astype(np.float64)
    else:
        out = np.empty(arr.shape[0])
        for i, v in enumerate(arr):
            try:
                out[i] = _number(v)
            except (TypeError, ValueError):
                out[i] = math.nan
    return _convert(out, unit, col, path)
