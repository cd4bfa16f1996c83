"""Many target files at once, validated column by column (issue 34).

:func:`load_target_files` reads every file, then validates its plain LISA documents together:
each field's values of all of them gathered into a column and each check run once over the
column (a unit string converted once per distinct string, ranges and finiteness as array
comparisons, the covariance σ's a column per parameter), and the targets built at the end.

A document the columns do not read is validated by the one-file path
(:func:`~ucbplan.targets.parse.targets_of_documents`) in its turn: another shape (a timing
ephemeris, galactic coordinates, samples, a start-referenced or non-TDB epoch, a correlated or
full covariance, magnitudes, references …) or any value a column check does not pass. So the
first file that fails raises exactly the message it raises alone (the files before it pass
either way), and every target is the one :func:`~ucbplan.targets.parse.load_target` builds:
``tests/targets/test_target_columnwise.py`` compares both, field by field and bit for bit, on
the bundled catalogs, the bad-input corpus and random mutations of them.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ucbplan.core.constants import E_MAX
from ucbplan.core.params import PARAM_NAMES, PhaseParams
from ucbplan.errors import TargetFileError
from ucbplan.targets.column_covariance import covariances, plain_covariance
from ucbplan.targets.column_values import (
    Column,
    angles,
    choices,
    epochs,
    numbers,
    quantities,
)
from ucbplan.targets.covariance import batched_checks
from ucbplan.targets.epoch_batch import prebuilt_epochs
from ucbplan.targets.model import Spectroscopy, Target
from ucbplan.targets.parse import (
    MAX_NAME_CHARS,
    many_files,
    read_documents,
    resolved_source,
    targets_of_documents,
)
from ucbplan.targets.schema import field, section_fields
from ucbplan.targets.sections import names
from ucbplan.targets.timing_section import parse_magnitudes, parse_references
from ucbplan.targets.values import MALFORMED, Ctx

#: The sections and fields a plain document may have (anything else: the one-file path).
_TOP = frozenset(names("")) - {"timing"}
_SKY = frozenset(("ra", "dec", "frame"))
_LISA = frozenset(names("lisa")) - {"samples", "t_ref_scale"}
_LISA_REQUIRED = tuple(f.name for f in section_fields("lisa") if f.required)
_SPECTROSCOPY = frozenset(names("spectroscopy"))
_MASSES = frozenset(names("masses"))
#: The quantities read as columns, by section.
_LISA_VALUES = tuple(
    field(f"lisa.{n}")
    for n in ("t_obs", *PARAM_NAMES, "cos_inclination", "amplitude", "psi", "distance")
)
_SPECTROSCOPY_VALUES = tuple(f for f in section_fields("spectroscopy") if f.kind == "quantity")
_MASS_VALUES = tuple(section_fields("masses"))
#: The context of the one-file readers used here (their messages are never shown: a document
#: they refuse goes the one-file way).
_CTX = Ctx(None)


def load_target_files(paths: Sequence[Path | str]) -> list[Target]:
    """Every target of several files, in order: :func:`~ucbplan.targets.load_target_documents`
    of each, validated column by column across the files (each folder resolved once).

    Raises
    ------
    TargetFileError
        As :func:`~ucbplan.targets.load_target_documents`, for the first file that fails.
    """
    with many_files(), batched_checks():
        files = [_read(p) for p in paths]
        built = _built(files)
        with prebuilt_epochs(_timing_epochs(files, built)):
            return _in_turn(files, built)


Built = list[list[Target] | None]


def _built(files: list[tuple[Path, Any]]) -> Built:
    """Each file's targets as the columns build them (None: a document of the file is not
    plain, or fails a column check; the one-file path reads the file)."""
    plain = [k for k, (_, docs) in enumerate(files) if _all_plain(docs)]
    targets = iter(_columns([(doc, files[k][0]) for k in plain for doc in files[k][1]]))
    built: Built = [None] * len(files)
    for k in plain:
        got = [next(targets) for _ in files[k][1]]
        done = [t for t in got if t is not None]
        built[k] = done if len(done) == len(got) else None
    return built


def _in_turn(files: list[tuple[Path, Any]], built: Built) -> list[Target]:
    """The targets of every file in order: those the columns built, the others' from the
    one-file path (the first file that fails raises its error)."""
    out: list[Target] = []
    for (path, docs), targets in zip(files, built, strict=True):
        if isinstance(docs, Exception):
            raise docs
        out.extend(targets if targets is not None else targets_of_documents(docs, path))
    return out


def _timing_epochs(files: list[tuple[Path, Any]], built: Built) -> list[Any]:
    """``timing.t0`` of the documents the one-file path reads (to read them ahead)."""
    out = []
    for (_, docs), targets in zip(files, built, strict=True):
        if targets is None and not isinstance(docs, Exception):
            for doc in docs:
                timing = doc.get("timing") if type(doc) is dict else None
                if type(timing) is dict and "t0" in timing:
                    out.append(timing["t0"])
    return out


def _read(raw: Path | str) -> tuple[Path, list[Any] | Exception]:
    """A file's documents, or the error reading it raises (raised in the file's turn, as
    ``load_target_documents`` raises it: also a TypeError for a path that is not one)."""
    try:
        path = Path(raw)
    except TypeError as exc:
        return raw, exc  # type: ignore[return-value]
    try:
        return path, read_documents(path)
    except TargetFileError as exc:
        return path, exc


def _all_plain(docs: list[Any] | Exception) -> bool:
    """Whether every document of a file (read) is plain (:func:`_plain`)."""
    return not isinstance(docs, Exception) and all(map(_plain, docs))


# ---------------------------------------------------------------------------------------------
# the shape of a plain document
# ---------------------------------------------------------------------------------------------


def _plain(doc: Any) -> bool:
    """Whether ``doc`` has the shape the columns read: a LISA posterior with ICRS ra, dec, a
    TDB t_ref at the midpoint, no samples, and σ's alone as its covariance."""
    if type(doc) is not dict or not doc.keys() <= _TOP:
        return False
    sky, lisa = doc.get("sky"), doc.get("lisa")
    if type(sky) is not dict or not (sky.keys() <= _SKY and "ra" in sky and "dec" in sky):
        return False
    if type(lisa) is not dict or not lisa.keys() <= _LISA:
        return False
    if not all(k in lisa for k in _LISA_REQUIRED) or not plain_covariance(lisa.get("covariance")):
        return False
    spec = doc.get("spectroscopy")
    if spec is not None and not (type(spec) is dict and spec.keys() <= _SPECTROSCOPY):
        return False
    masses = doc.get("masses", {})
    return type(masses) is dict and masses.keys() <= _MASSES and _plain_name(doc.get("name"))


def _plain_name(name: Any) -> bool:
    """A printable one-line name (so no control character) of at most
    :data:`~ucbplan.targets.parse.MAX_NAME_CHARS` characters."""
    return (
        type(name) is str
        and len(name) <= MAX_NAME_CHARS
        and name.isprintable()
        and bool(name.strip())
    )


# ---------------------------------------------------------------------------------------------
# the columns
# ---------------------------------------------------------------------------------------------


def _columns(items: list[tuple[dict[str, Any], Path]]) -> list[Target | None]:
    """The targets of plain documents (with their paths), None where a check fails."""
    if not items:
        return []
    docs = [doc for doc, _ in items]
    lisa = [doc["lisa"] for doc in docs]
    got: dict[str, list[Any]] = {}
    ok = np.ones(len(docs), dtype=bool)
    for name, (values, good) in _read_columns(docs, lisa).items():
        got[name] = values
        ok &= good
    ok &= [_small_e(e, k) for e, k in zip(got["eta"], got["kappa"], strict=True)]
    got["has_spectroscopy"] = [doc.get("spectroscopy") is not None for doc in docs]
    rows = zip(*(got[name] for name in _ROW), strict=True)
    return [
        _target(row, path) if good else None
        for row, good, (_, path) in zip(rows, ok, items, strict=True)
    ]


def _small_e(eta: float | None, kappa: float | None) -> bool:
    """e = |η + iκ| inside the small-e model, as ``check_eccentricity`` tests it (None: the
    value failed its own check)."""
    if eta is None or kappa is None or not (eta or kappa):
        return True
    return math.hypot(eta, kappa) < E_MAX


def _read_columns(docs: list[dict[str, Any]], lisa: list[dict[str, Any]]) -> dict[str, Column]:
    """Every column of the plain documents: values and which pass, by name."""
    sky = [doc["sky"] for doc in docs]
    spec = [doc.get("spectroscopy") or {} for doc in docs]
    masses = [doc.get("masses", {}) for doc in docs]
    out = {
        "name": ([doc["name"].strip() for doc in docs], np.ones(len(docs), dtype=bool)),
        "frame": choices(sky, field("sky.frame")),
        "ra": angles(sky, field("sky.ra"), hours=True),
        "dec": angles(sky, field("sky.dec"), hours=False),
        "t_ref": epochs([s["t_ref"] for s in lisa]),
        "t_ref_is": choices(lisa, field("lisa.t_ref_is"), only="midpoint"),
        "lines": choices(spec, field("spectroscopy.lines")),
        "priority": numbers(docs, field("priority")),
        "vmag": numbers(docs, field("vmag")),
        "extras": _extras(docs),
        "covariance": covariances([s.get("covariance") for s in lisa]),
    }
    for section, fields in ((lisa, _LISA_VALUES), (spec, _SPECTROSCOPY_VALUES)):
        out.update({f.name: quantities(section, f) for f in fields})
    out.update({f.name: quantities(masses, f) for f in _MASS_VALUES})
    return out


#: The columns a target is built from, in the order :func:`_target` takes them.
_ROW = (
    *("name", "ra", "dec", "t_ref", "t_obs", *PARAM_NAMES),
    *("cos_inclination", "amplitude", "psi", "distance", "covariance", "has_spectroscopy"),
    *("lines", "K1", "K2", "K_eff", "sigma_v", "priority", "vmag", "m1", "m2", "extras"),
)


assert tuple(f.name for f in dataclasses.fields(PhaseParams)) == PARAM_NAMES


def _target(row: tuple[Any, ...], path: Path) -> Target:
    """The target of a row of the columns (:data:`_ROW`), as
    :func:`~ucbplan.targets.target_from_dict` builds it (its epoch a copy of the one read)."""
    name, ra, dec, t_ref, t_obs = row[:5]
    cos_i, amplitude, psi, distance, (cov_names, cov_matrix), has_spec = row[12:18]
    lines, k1, k2, k_eff, sigma_v, priority, vmag, m1, m2, extras = row[18:]
    magnitudes, references = extras if extras is not None else (_magnitudes(vmag), {})
    return Target(
        name=name,
        source=resolved_source(path),
        ra_deg=ra,
        dec_deg=dec,
        t_ref=t_ref.copy(),
        t_obs_s=t_obs,
        params=PhaseParams(*row[5:12]),  # PARAM_NAMES, its fields' order
        cov_names=cov_names,
        cov_matrix=cov_matrix,
        cos_inclination=cos_i,
        amplitude=amplitude,
        psi=psi,
        distance_kpc=distance,
        spectroscopy=Spectroscopy(lines, k1, k2, k_eff, sigma_v) if has_spec else None,
        priority=priority,
        vmag=magnitudes.get("V"),
        m1_msun=m1,
        m2_msun=m2,
        magnitudes=magnitudes,
        references=references,
    )


def _magnitudes(vmag: float | None) -> dict[str, float]:
    """``parse_magnitudes`` of a document without ``magnitudes``: V if ``vmag`` is given."""
    return {} if vmag is None else {"V": vmag}


def _extras(docs: list[dict[str, Any]]) -> Column:
    """``magnitudes`` (with ``vmag``) and ``references`` of the documents that give them, read
    by the one-file readers themselves (None: neither given; a document they refuse fails)."""
    values: list[Any] = []
    ok = np.ones(len(docs), dtype=bool)
    for k, doc in enumerate(docs):
        value = None
        if "magnitudes" in doc or "references" in doc:
            try:
                value = (parse_magnitudes(_CTX, doc), parse_references(_CTX, doc))
            except (TargetFileError, *MALFORMED):
                ok[k] = False
        values.append(value)
    return values, ok
