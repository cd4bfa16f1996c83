"""Read and validate a target file into a :class:`~ucbplan.targets.model.Target`.

``load_target`` validates once, section by section, against the schema
(:mod:`ucbplan.targets.schema`). A ``lisa`` section gives parameters referenced to the *midpoint*
of the LISA observation (paper Sec. 4.1; ``docs/method.md``, "Phase model"); a ``timing``
section (exactly one of the two) is converted to the same phase model at its epoch T0 by
:mod:`ucbplan.core.timing`. Every validation failure is a one-line
:class:`~ucbplan.errors.TargetFileError`: ``file: field: expected …, got …``.
"""

from __future__ import annotations

import os
import unicodedata
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import Any

import numpy as np
from astropy import units as u
from astropy.time import TimeDelta
from numpy.typing import NDArray

from ucbplan.core.constants import L_B
from ucbplan.core.params import PARAM_NAMES, PhaseParams, shift_jacobian, shift_reference
from ucbplan.errors import SchemaError, TargetFileError, shorten
from ucbplan.inputs import load_yaml
from ucbplan.targets.covariance import batched_checks, parse_covariance
from ucbplan.targets.model import Spectroscopy, Target
from ucbplan.targets.samples import with_samples_covariance
from ucbplan.targets.schema import EPHEMERIS_KINDS, field, section_fields
from ucbplan.targets.sections import (
    CONTROL,
    Ephemeris,
    check_eccentricity,
    check_section,
    each_quantity,
    mapping,
    names,
    number,
    quantities,
)
from ucbplan.targets.timing_section import parse_magnitudes, parse_references, parse_timing
from ucbplan.targets.values import (
    Ctx,
    check_keys,
    one_line,
    parse_angle,
    parse_choice,
    parse_epoch,
)

FloatArray = NDArray[np.float64]

_PHASE_MODEL = tuple(field(f"lisa.{n}") for n in PARAM_NAMES)
_T_OBS = (field("lisa.t_obs"),)
_SPECTROSCOPY_VALUES = tuple(f for f in section_fields("spectroscopy") if f.kind == "quantity")
_LISA_EXTRAS = tuple(
    field(f"lisa.{n}") for n in ("cos_inclination", "amplitude", "psi", "distance")
)
#: Longest target name [characters] (names go into starlists, headers and file names).
MAX_NAME_CHARS = 200
#: Powers of 1/s in the unit of each rate that a TCB → TDB conversion rescales.
_TCB_POWER = {"f_gw": 1, "fdot": 2, "fddot": 3, "omega_dot": 1}


def load_target(path: Path | str) -> Target:
    """Read and validate a target YAML file (strictly, see :func:`ucbplan.inputs.load_yaml`).

    Raises
    ------
    TargetFileError
        One line naming the file, the field path, what was expected and how to fix it.
    """
    path = Path(path)
    label = Ctx(path).label
    try:
        doc = load_yaml(path, "target file")
    except SchemaError as exc:
        msg = str(exc)
        if len(msg) > 300 and msg.startswith(str(path)):  # a long path: its name is enough
            msg = label + msg[len(str(path)) :]
        raise TargetFileError(one_line(msg)) from None
    except RecursionError:
        raise TargetFileError(
            one_line(f"{label}: <top>: nested too deeply to be a target file; check the brackets")
        ) from None
    except (OSError, ValueError, UnicodeError):
        raise TargetFileError(
            one_line(f"{shorten(str(path))}: cannot open; check the path")
        ) from None
    return target_from_dict(doc, path)


#: Folders already resolved, inside one call loading many target files (:func:`load_targets`,
#: :func:`~ucbplan.targets.columnwise.load_target_files`); None outside one: a lone target
#: file is resolved whole, as ``Path.resolve`` does it.
_FOLDERS: ContextVar[dict[str, Path] | None] = ContextVar("ucbplan_target_folders", default=None)


def resolved_source(path: Path) -> Path:
    """``path.resolve()``; inside a call that loads many files each folder is resolved once
    (the file itself, unless a symbolic link, adds only its name)."""
    folders = _FOLDERS.get()
    name = path.name
    if folders is None or name in ("", ".", "..") or os.path.islink(path):
        return path.resolve()
    key = os.path.dirname(path)  # one key per folder as written ("" for ".")
    folder = folders.get(key)
    if folder is None:
        folder = folders[key] = path.parent.resolve()
    return folder / name


@contextmanager
def many_files() -> Iterator[None]:
    """The scope of :data:`_FOLDERS`: one call loading many target files."""
    token = _FOLDERS.set({})
    try:
        yield
    finally:
        _FOLDERS.reset(token)


def _file_key(path: Path | str) -> tuple[int, int] | str:
    """What makes two paths the same file: device and inode (links, ``./a`` vs ``a``)."""
    try:
        st = os.stat(path)
    except OSError:
        return str(Path(path).absolute())
    return file_key(st)


def file_key(st: os.stat_result) -> tuple[int, int]:
    """The key of :func:`check_distinct_files` of a file's ``os.stat`` result."""
    return (st.st_dev, st.st_ino)


def check_distinct_files(
    paths: Sequence[Path | str], keys: Sequence[tuple[int, int] | None] = ()
) -> None:
    """Refuse a target file given twice (also through another path to it): the first half of
    the one rule for a repeated target (:func:`load_targets`).

    ``keys``: each path's :func:`file_key` where its ``os.stat`` is at hand (None, or none
    given: the path is looked up here).

    Raises
    ------
    TargetFileError
        One line naming both paths.
    """
    files: dict[tuple[int, int] | str, int] = {}
    for k, path in enumerate(paths):  # as given: a Path is built only for the message
        key = keys[k] if k < len(keys) else None
        first = files.setdefault(_file_key(path) if key is None else key, k)
        if first != k:
            raise TargetFileError(
                f"{Path(paths[first])}, {Path(path)}: the same target file twice; give each "
                "target once"
            )


def load_targets(
    paths: Sequence[Path | str], ident: Callable[[str], str] = lambda name: name
) -> list[Target]:
    """Read several target files, each target once: the one rule for a repeated target.

    Parameters
    ----------
    paths : sequence of path
        Target YAML files, in order.
    ident : callable, optional
        Maps a target name to what must be unique (the planner passes its block-id slug, so
        that ``HM Cnc`` and ``HM-Cnc`` are one target there).

    Raises
    ------
    TargetFileError
        As :func:`load_target`, or a file given twice, or two files naming the same target:
        one line naming both files.
    """
    check_distinct_files(paths)
    with many_files():
        return _load_each_once(paths, ident)


def _load_each_once(paths: Sequence[Path | str], ident: Callable[[str], str]) -> list[Target]:
    """:func:`load_targets` after the files are known distinct."""
    names: dict[str, tuple[Path, str]] = {}
    out = []
    for raw in paths:
        path = raw if isinstance(raw, Path) else Path(raw)  # a Path is not parsed again
        target = load_target(path)
        key = ident(target.name)
        if key in names:
            other, name = names[key]
            same = shorten(name, 40)
            if name != target.name:
                same += f" / {shorten(target.name, 40)}"
            raise TargetFileError(
                f"{other}, {path}: both are target {same}; give each target once or rename one "
                "(name:)"
            )
        names[key] = (path, target.name)
        out.append(target)
    return out


def target_from_dict(doc: Any, path: Path | None = None) -> Target:
    """Validate a parsed target document (see :func:`load_target`).

    ``path`` names the file in messages and anchors a relative ``lisa.samples``.
    """
    ctx = Ctx(path)
    if not isinstance(doc, Mapping):
        raise ctx.fail(
            "<top>", f"expected a YAML mapping with name, sky and lisa, got {_kind(doc)}"
        )
    check_keys(ctx, "", doc, _TOP)
    with ctx.reading("name", "a name"):
        name = _parse_name(ctx, doc.get("name"))
    with ctx.reading("sky", "a sky position"):
        ra, dec = _parse_sky(ctx, doc)
    kind = _ephemeris_kind(ctx, doc)
    eph = _parse_ephemeris(ctx, doc, kind, path)
    with ctx.reading("spectroscopy", "spectroscopy defaults"):
        spectroscopy = _parse_spectroscopy(ctx, doc.get("spectroscopy"))
    priority = number(ctx, doc, field("priority"))
    with ctx.reading("magnitudes", "magnitudes"):
        magnitudes = parse_magnitudes(ctx, doc)
    with ctx.reading("references", "references"):
        references = parse_references(ctx, doc)
    with ctx.reading("masses", "masses"):
        masses = _parse_masses(ctx, doc)
    target = Target(
        name=name,
        source=resolved_source(path) if path is not None else None,
        ra_deg=ra,
        dec_deg=dec,
        t_ref=eph.t_ref,
        t_obs_s=eph.t_obs_s,
        params=eph.params,
        cov_names=eph.cov_names,
        cov_matrix=eph.cov_matrix,
        cos_inclination=eph.extras["cos_inclination"],
        amplitude=eph.extras["amplitude"],
        psi=eph.extras["psi"],
        distance_kpc=eph.extras["distance"],
        spectroscopy=spectroscopy,
        samples=eph.samples,
        priority=priority,
        vmag=magnitudes.get("V"),
        m1_msun=masses.get("m1"),
        m2_msun=masses.get("m2"),
        ref_shift_s=eph.ref_shift_s,
        notes={"t_ref_converted_from": eph.converted} if eph.converted else {},
        kind=kind,
        timing=eph.timing,
        magnitudes=magnitudes,
        references=references,
    )
    return with_samples_covariance(target)


def _parse_ephemeris(ctx: Ctx, doc: Mapping[str, Any], kind: str, path: Path | None) -> Ephemeris:
    """The ``lisa`` or ``timing`` section (``kind``), read."""
    if kind == "lisa":
        with ctx.reading("lisa", "the LISA posterior summary"):
            return _parse_lisa(ctx, doc.get("lisa"), path)
    with ctx.reading("timing", "a timing ephemeris"):
        return parse_timing(ctx, doc["timing"])


def _ephemeris_kind(ctx: Ctx, doc: Mapping[str, Any]) -> str:
    """``"lisa"`` or ``"timing"``: exactly one of the two sections must be given."""
    given = [k for k in EPHEMERIS_KINDS if k in doc]
    if len(given) == 1:
        return given[0]
    if given:
        raise ctx.fail(
            "lisa/timing",
            "give exactly one of lisa (a LISA posterior) and timing (an optical/X-ray timing "
            "ephemeris), not both; keep the other in a second target file",
        )
    raise ctx.fail(
        "lisa",
        f"missing; add lisa: {field('lisa').example} (a LISA posterior) or timing: "
        f"{field('timing').example} (a timing ephemeris)",
    )


# ---------------------------------------------------------------------------------------------
# fields and sections
# ---------------------------------------------------------------------------------------------


_TOP = names("")


def _kind(value: Any) -> str:
    if isinstance(value, list):
        return "a list"
    if value is None:
        return "an empty document"
    return f"{type(value).__name__} {shorten(value)}"


def _parse_name(ctx: Ctx, name: Any) -> str:
    """A non-empty one-line name (no control characters), at most :data:`MAX_NAME_CHARS`."""
    f = field("name")
    expect = f"expected {f.what} like {f.example}"
    if name is None:
        raise ctx.fail(f.path, f"missing; {expect}")
    if not isinstance(name, str) or not name.strip():
        raise ctx.fail(f.path, f"{expect}, got {shorten(name)}")
    if len(name) > MAX_NAME_CHARS:
        raise ctx.fail(
            f.path, f"{expect} of at most {MAX_NAME_CHARS} characters, got {shorten(name)}"
        )
    if any(unicodedata.category(c) in CONTROL for c in name):
        raise ctx.fail(
            f.path, f"{expect} on one line without control characters, got {shorten(name)}"
        )
    return name.strip()


def _parse_sky(ctx: Ctx, doc: Mapping[str, Any]) -> tuple[float, float]:
    """ICRS (ra, dec) in degrees from ``sky``: ICRS ra/dec, or galactic l/b converted."""
    f = field("sky")
    if "sky" not in doc:
        raise ctx.fail(f.path, f"missing; add sky: {f.example}")
    sky = mapping(ctx, f, doc["sky"])
    keys = set(sky)
    if {"l", "b"} & keys:
        if {"ra", "dec", "frame"} & keys:
            raise ctx.fail(f.path, "give ICRS ra, dec (with frame) or galactic l, b, not both")
        for k in ("l", "b"):
            if k not in sky:
                raise ctx.fail(f"sky.{k}", "missing; give galactic l and b together")
        lon = parse_angle(ctx, field("sky.l"), sky["l"])
        lat = parse_angle(ctx, field("sky.b"), sky["b"])
        from astropy.coordinates import SkyCoord  # imported for galactic positions only

        c = SkyCoord(l=lon * u.deg, b=lat * u.deg, frame="galactic").icrs
        return float(c.ra.deg), float(c.dec.deg)
    for k in ("ra", "dec"):
        if k not in sky:
            raise ctx.fail(f"sky.{k}", "missing; give ICRS ra and dec (or galactic l and b)")
    frame_field = field("sky.frame")
    parse_choice(ctx, frame_field, sky.get("frame", frame_field.default))
    ra = parse_angle(ctx, field("sky.ra"), sky["ra"], hours=True)
    return ra, parse_angle(ctx, field("sky.dec"), sky["dec"])


def _parse_spectroscopy(ctx: Ctx, spec: Any) -> Spectroscopy | None:
    if spec is None:
        return None
    spec = mapping(ctx, field("spectroscopy"), spec)
    lines_field = field("spectroscopy.lines")
    lines = parse_choice(ctx, lines_field, spec.get("lines", lines_field.default))
    vals = each_quantity(ctx, spec, _SPECTROSCOPY_VALUES)
    return Spectroscopy(lines, vals["K1"], vals["K2"], vals["K_eff"], vals["sigma_v"])


def _parse_masses(ctx: Ctx, doc: Mapping[str, Any]) -> dict[str, float | None]:
    if "masses" not in doc:
        return {}
    masses = mapping(ctx, field("masses"), doc["masses"])
    return quantities(ctx, masses, section_fields("masses"))


# ---------------------------------------------------------------------------------------------
# the LISA section
# ---------------------------------------------------------------------------------------------


def _parse_lisa(ctx: Ctx, lisa: Any, path: Path | None) -> Ephemeris:
    """The ``lisa`` section; TCB rates are rescaled and start-referenced ones moved."""
    _check_lisa_fields(ctx, lisa)
    t_ref, converted = parse_epoch(ctx, field("lisa.t_ref"), lisa["t_ref"], lisa.get("t_ref_scale"))
    t_obs = float(each_quantity(ctx, lisa, _T_OBS)["t_obs"])
    ref_is = _reference_point(ctx, lisa)
    vals = quantities(ctx, lisa, _PHASE_MODEL)
    check_eccentricity(ctx, vals["eta"], vals["kappa"])
    names, mat = parse_covariance(ctx, lisa.get("covariance"))
    if converted == "tcb":
        vals, mat = _tcb_to_tdb(vals, names, mat)
        t_obs *= 1.0 - L_B
    params = PhaseParams(**vals)
    shift = 0.0
    if ref_is == "start":
        shift = t_obs / 2.0
        params, mat = _moved_to_midpoint(ctx, params, names, mat, shift)
        t_ref = t_ref + TimeDelta(shift, format="sec")
    return Ephemeris(
        t_ref=t_ref,
        t_obs_s=t_obs,
        params=params,
        cov_names=names,
        cov_matrix=mat,
        extras=quantities(ctx, lisa, _LISA_EXTRAS),
        samples=_samples_path(ctx, lisa, path),
        ref_shift_s=shift,
        converted=converted,
    )


def _moved_to_midpoint(
    ctx: Ctx, params: PhaseParams, names: tuple[str, ...], mat: FloatArray, shift: float
) -> tuple[PhaseParams, FloatArray]:
    """Start-referenced values moved by T_obs/2; they must stay finite, and f positive."""
    why = (
        "from the start to the midpoint of the observation (t_ref_is: start); check the "
        "magnitudes and units of f_gw, fdot, fddot and omega_dot"
    )
    try:
        with np.errstate(all="ignore"):
            moved, moved_mat = _shift_named(params, names, mat, shift)
    except (ValueError, OverflowError, ArithmeticError):
        raise ctx.fail("lisa", f"values overflow when moved {why}") from None
    if not (np.all(np.isfinite(moved.as_array())) and np.all(np.isfinite(moved_mat))):
        raise ctx.fail("lisa", f"values overflow when moved {why}")
    if moved.f_gw <= 0.0:
        raise ctx.fail(
            "lisa.f_gw", f"f_gw at the midpoint is {moved.f_gw:.4g} Hz ≤ 0 when moved {why}"
        )
    return moved, moved_mat


def _check_lisa_fields(ctx: Ctx, lisa: Any) -> None:
    """``lisa`` is a mapping of known fields with every required one present."""
    check_section(ctx, "lisa", lisa)


def _reference_point(ctx: Ctx, lisa: Mapping[str, Any]) -> str:
    """``t_ref_is``: where in the observation t_ref lies (``midpoint`` or ``start``)."""
    f = field("lisa.t_ref_is")
    return parse_choice(ctx, f, lisa.get(f.name, f.default))


def _samples_path(ctx: Ctx, lisa: Mapping[str, Any], path: Path | None) -> Path | None:
    """``lisa.samples`` resolved next to the target file (it must exist)."""
    f = field("lisa.samples")
    if f.name not in lisa:
        return None
    name = lisa[f.name]
    if not isinstance(name, str) or not name.strip() or len(name) > 1000:
        raise ctx.fail(f.path, f"expected {f.what} like {f.example}, got {shorten(name)}")
    base = path.parent if path is not None else Path(".")
    try:
        samples = (base / name).resolve()
        found = samples.is_file()
    except (OSError, ValueError, UnicodeError):
        found = False
    if not found:
        raise ctx.fail(
            f.path, f"file {shorten(name)} not found next to the target file (or not a file)"
        )
    return samples


# ---------------------------------------------------------------------------------------------
# time scale and reference epoch
# ---------------------------------------------------------------------------------------------


def _tcb_to_tdb(
    vals: dict[str, float], names: tuple[str, ...], mat: FloatArray
) -> tuple[dict[str, float], FloatArray]:
    """Rescale rates from TCB to TDB seconds: a quantity per TCB second^n gains (1 − L_B)^−n."""
    out = dict(vals)
    scale = np.ones(len(names))
    for key, n in _TCB_POWER.items():
        out[key] = vals[key] / (1.0 - L_B) ** n
        if key in names:
            scale[names.index(key)] = 1.0 / (1.0 - L_B) ** n
    return out, mat * np.outer(scale, scale)


def _shift_named(
    p: PhaseParams, names: tuple[str, ...], mat: FloatArray, dt: float
) -> tuple[PhaseParams, FloatArray]:
    """Shift parameters and the named covariance by ``dt`` [s] (extras like cos ι unchanged)."""
    new_p, _ = shift_reference(p, np.zeros((7, 7)), dt)
    if not names:
        return new_p, mat
    j7 = shift_jacobian(p, dt)
    j = np.eye(len(names))
    for a, na in enumerate(names):
        for b, nb in enumerate(names):
            if na in PARAM_NAMES and nb in PARAM_NAMES:
                j[a, b] = j7[PARAM_NAMES.index(na), PARAM_NAMES.index(nb)]
    # parameters absent from the covariance are exact: their columns do not matter
    new = j @ mat @ j.T
    return new_p, 0.5 * (new + new.T)


def load_target_documents(path: Path | str) -> list[Target]:
    """Every target of a YAML file: one target file, or a catalog of several target documents
    separated by ``---`` lines (each validated as :func:`load_target` does one).

    Raises
    ------
    TargetFileError
        One line naming the file, the document (``document 3``) of a catalog, the field path,
        what was expected and how to fix it; a file with no document.
    """
    path = Path(path)
    return targets_of_documents(read_documents(path), path)


def read_documents(path: Path) -> list[Any]:
    """The documents of a target file or catalog, parsed (empty ones dropped), unvalidated.

    Raises
    ------
    TargetFileError
        As :func:`load_target_documents` for a file that cannot be read or has no document.
    """
    try:
        docs = load_yaml(path, "target file", documents=True)
    except SchemaError as exc:
        msg = str(exc)
        if len(msg) > 300 and msg.startswith(str(path)):  # a long path: its name is enough
            msg = Ctx(path).label + msg[len(str(path)) :]
        raise TargetFileError(one_line(msg)) from None
    except RecursionError:
        raise TargetFileError(
            one_line(
                f"{Ctx(path).label}: <top>: nested too deeply to be a target file; "
                "check the brackets"
            )
        ) from None
    except (OSError, ValueError, UnicodeError):
        raise TargetFileError(
            one_line(f"{shorten(str(path))}: cannot open; check the path")
        ) from None
    docs = [d for d in docs if d is not None]
    if not docs:
        raise TargetFileError(one_line(f"{Ctx(path).label}: no target in this file; add one"))
    return docs


def targets_of_documents(docs: list[Any], path: Path) -> list[Target]:
    """The targets of a file's documents (:func:`read_documents`), each validated in turn as
    :func:`load_target` does one; a catalog's errors name their document.

    Raises
    ------
    TargetFileError
        As :func:`load_target_documents`.
    """
    if len(docs) == 1:
        return [target_from_dict(docs[0], path)]
    out = []
    for k, doc in enumerate(docs, start=1):
        try:
            with batched_checks():  # checked with its document, so its errors name it
                out.append(target_from_dict(doc, path))
        except TargetFileError as exc:
            label = Ctx(path).label
            msg = str(exc)
            msg = msg[len(label) :] if msg.startswith(label) else ": " + msg
            raise TargetFileError(one_line(f"{label} (document {k}){msg}")) from None
    return out
