"""Target files (YAML): a LISA posterior summary plus sky position and spectroscopy defaults.

``load_target`` validates once and returns a frozen :class:`Target` whose parameters are always
referenced to the *midpoint* of the LISA observation (Sec. 4.1). Every validation failure is a
one-line :class:`~ucbplan.errors.TargetFileError`: ``file: field: expected …, got …``.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from astropy import units as u
from astropy.coordinates import Angle, SkyCoord
from astropy.time import Time, TimeDelta
from numpy.typing import NDArray

from ucbplan.core.constants import E_MAX, L_B
from ucbplan.core.params import (
    PARAM_NAMES,
    PARAM_UNITS,
    PhaseParams,
    shift_columns,
    shift_reference,
)
from ucbplan.errors import TargetFileError

__all__ = [
    "PARAM_NAMES",
    "PhaseParams",
    "Spectroscopy",
    "Target",
    "load_samples",
    "load_target",
    "shift_reference",
    "target_to_dict",
    "write_target",
]

FloatArray = NDArray[np.float64]


_EXAMPLES = {
    "phase": '5.500397 (rad) or "5.5 rad"',
    "f_gw": '"6.2204944286e-3 Hz"',
    "fdot": '"7.07e-16 Hz / s"',
    "fddot": '"-1.07e-26 Hz / s2"',
    "eta": "0.0068 (dimensionless)",
    "kappa": "0.0068 (dimensionless)",
    "omega_dot": '"1.498e-6 rad / s"',
    "t_obs": '"126232599.05 s" or "4 yr"',
    "cos_inclination": "0.67 (dimensionless, in [-1, 1])",
    "amplitude": "4.9e-22 (dimensionless strain)",
    "psi": '0.339 (rad) or "19.4 deg"',
    "distance": '"2.0 kpc"',
    "K1": '"585 km/s"',
    "K2": '"713 km/s"',
    "K_eff": '"390 km/s"',
    "sigma_v": '"15 km/s"',
    "m1": '"0.347 solMass"',
    "m2": '"0.285 solMass"',
}
_KIND = {
    "phase": "a phase",
    "f_gw": "a frequency",
    "fdot": "a frequency derivative",
    "fddot": "a second frequency derivative",
    "eta": "a dimensionless number",
    "kappa": "a dimensionless number",
    "omega_dot": "an angular rate",
    "t_obs": "a duration",
    "cos_inclination": "a dimensionless number",
    "amplitude": "a dimensionless strain",
    "psi": "an angle",
    "distance": "a distance",
    "K1": "a velocity",
    "K2": "a velocity",
    "K_eff": "a velocity",
    "sigma_v": "a velocity",
    "m1": "a mass",
    "m2": "a mass",
}
_UNITS: dict[str, str] = dict(PARAM_UNITS) | {
    "t_obs": "s",
    "cos_inclination": "",
    "amplitude": "",
    "psi": "rad",
    "distance": "kpc",
    "K1": "km / s",
    "K2": "km / s",
    "K_eff": "km / s",
    "sigma_v": "km / s",
    "m1": "solMass",
    "m2": "solMass",
}
_LISA_KEYS = {
    "t_ref",
    "t_ref_scale",
    "t_obs",
    "t_ref_is",
    *PARAM_NAMES,
    "cos_inclination",
    "amplitude",
    "psi",
    "distance",
    "covariance",
    "samples",
}
_TOP_KEYS = {"name", "sky", "lisa", "spectroscopy", "priority", "vmag", "masses", "notes"}
_SPEC_KEYS = {"lines", "K1", "K2", "K_eff", "sigma_v"}
_SCALES = {"tdb", "tcb", "tt", "utc", "tai"}


@dataclass(frozen=True, slots=True)
class Spectroscopy:
    """Spectroscopy defaults used for tolerances (km/s); CLI flags override them."""

    lines: str = "SB2"
    K1_kms: float | None = None
    K2_kms: float | None = None
    K_eff_kms: float | None = None
    sigma_v_kms: float | None = None

    @property
    def k_for_tolerance(self) -> float | None:
        """K used to turn a phase error into a velocity error: K_eff, else K1+K2 (SB2) or K1."""
        if self.K_eff_kms is not None:
            return self.K_eff_kms
        if self.lines == "SB2" and self.K1_kms is not None and self.K2_kms is not None:
            return self.K1_kms + self.K2_kms
        return self.K1_kms


@dataclass(frozen=True, slots=True)
class Target:
    """A validated target, parameters referenced to the LISA observation midpoint (TDB)."""

    name: str
    source: Path | None
    ra_deg: float
    dec_deg: float
    t_ref: Time
    t_obs_s: float
    params: PhaseParams
    cov_names: tuple[str, ...]
    cov_matrix: FloatArray
    cos_inclination: float | None = None
    amplitude: float | None = None
    psi: float | None = None
    distance_kpc: float | None = None
    spectroscopy: Spectroscopy | None = None
    samples: Path | None = None
    priority: float = 1.0
    vmag: float | None = None
    m1_msun: float | None = None
    m2_msun: float | None = None
    ref_shift_s: float = 0.0
    notes: dict[str, Any] = field(default_factory=dict)

    @property
    def covariance(self) -> FloatArray:
        """Covariance (7, 7) in PARAM_NAMES order; parameters without uncertainty are zero."""
        full = np.zeros((7, 7))
        idx = [PARAM_NAMES.index(n) for n in self.cov_names if n in PARAM_NAMES]
        sub = [i for i, n in enumerate(self.cov_names) if n in PARAM_NAMES]
        full[np.ix_(idx, idx)] = self.cov_matrix[np.ix_(sub, sub)]
        return full

    @property
    def coord(self) -> SkyCoord:
        """ICRS position."""
        return SkyCoord(self.ra_deg * u.deg, self.dec_deg * u.deg, frame="icrs")

    @property
    def t_start(self) -> Time:
        """Start of the LISA observation (TDB)."""
        return self.t_ref - TimeDelta(self.t_obs_s / 2.0, format="sec")

    @property
    def t_end(self) -> Time:
        """End of the LISA observation (TDB)."""
        return self.t_ref + TimeDelta(self.t_obs_s / 2.0, format="sec")

    @property
    def period_s(self) -> float:
        """Anomalistic orbital period P_b at the reference epoch [s]."""
        return self.params.period_s

    @property
    def sha256(self) -> str | None:
        """SHA-256 of the source file (provenance), if loaded from a file."""
        if self.source is None or not self.source.exists():
            return None
        return hashlib.sha256(self.source.read_bytes()).hexdigest()

    def tau(self, t: Time) -> FloatArray:
        """Seconds since ``t_ref`` (TDB) of barycentric TDB times ``t``."""
        if t.scale != "tdb":
            raise TargetFileError(f"{self.name}: epochs must be TDB, got scale {t.scale!r}")
        out: FloatArray = np.asarray((t - self.t_ref).to_value("s"), dtype=np.float64)
        return out


# ---------------------------------------------------------------------------------------------
# parsing helpers
# ---------------------------------------------------------------------------------------------


class _Ctx:
    """Error context: file name for messages."""

    def __init__(self, path: Path | None) -> None:
        self.label = path.name if path is not None else "<target>"

    def fail(self, fieldname: str, msg: str) -> TargetFileError:
        return TargetFileError(f"{self.label}: {fieldname}: {msg}")


_NUM_RE = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*$")


def _quantity(ctx: _Ctx, path: str, key: str, value: Any) -> float:
    """Parse a bare number (in the documented unit) or an astropy quantity string → SI float."""
    unit = u.Unit(_UNITS[key])
    expect = f"expected {_KIND[key]} like {_EXAMPLES[key]}"
    if isinstance(value, bool) or value is None:
        raise ctx.fail(path, f"{expect}, got {value!r}")
    if isinstance(value, int | float):
        x = float(value)
    elif isinstance(value, str):
        text = value.strip()
        if _NUM_RE.match(text) or text.lower().lstrip("+-.") in ("nan", "inf"):
            x = float(text.replace(".nan", "nan").replace(".inf", "inf"))
        else:
            try:
                q = u.Quantity(text)
            except (TypeError, ValueError):
                raise ctx.fail(
                    path, f"{expect}, got {value!r} (not a number with a unit)"
                ) from None
            try:
                x = float(q.to_value(unit, equivalencies=u.dimensionless_angles()))
            except u.UnitConversionError:
                raise ctx.fail(path, f"{expect}, got {value!r}") from None
    else:
        raise ctx.fail(path, f"{expect}, got {type(value).__name__} {value!r}")
    if not math.isfinite(x):
        raise ctx.fail(path, f"{expect}, got non-finite value {value!r}")
    return x


def _parse_time(ctx: _Ctx, path: str, value: Any, scale_field: Any) -> tuple[Time, str | None]:
    """Parse an epoch; returns TDB Time and the scale it was converted from (None if TDB)."""
    scale_given: str | None = None
    if scale_field is not None:
        scale_given = str(scale_field).strip().lower()
        if scale_given not in _SCALES:
            raise ctx.fail(
                "lisa.t_ref_scale", f"expected one of tdb|tcb|tt|utc|tai, got {scale_field!r}"
            )
    if isinstance(value, _dt.datetime | _dt.date):
        if isinstance(value, _dt.datetime) and value.tzinfo is not None:
            raise ctx.fail(
                path,
                f"expected a TDB epoch without time zone, got {value!r}; quote the epoch and "
                "drop the offset",
            )
        text = value.isoformat()
    elif isinstance(value, str):
        text = value.strip()
    else:
        raise ctx.fail(path, f'expected an ISO epoch like "2039-01-01T00:00:00", got {value!r}')
    label: str | None = None
    m = re.match(r"^(.*?)\s*\(?\b(TDB|TCB|TT|UTC|TAI)\b\)?$", text, flags=re.IGNORECASE)
    if m:
        text, label = m.group(1).strip(), m.group(2).lower()
    if label is not None and scale_given is None and label != "tdb":
        raise ctx.fail(
            path,
            f"epochs must be TDB at the barycentre, got a {label.upper()}-labelled epoch "
            f"{value!r}; if it really is {label.upper()}, add 't_ref_scale: {label}' and "
            "ucbplan converts it explicitly",
        )
    if label is not None and scale_given is not None and label != scale_given:
        raise ctx.fail(path, f"label {label.upper()} contradicts t_ref_scale: {scale_given}")
    scale = scale_given or label or "tdb"
    import warnings

    from erfa import ErfaWarning

    try:
        with warnings.catch_warnings():
            # future UTC: leap seconds after the bundled table are unknown (TDB − UTC kept at
            # the last value); the user stated the scale, so convert with that caveat
            warnings.simplefilter("ignore", ErfaWarning)
            if text.upper().startswith("MJD"):
                t = Time(float(text[3:]), format="mjd", scale=scale)
            elif text.upper().startswith("JD"):
                t = Time(float(text[2:]), format="jd", scale=scale)
            else:
                t = Time(text, scale=scale, format="isot" if "T" in text else None)
            tdb = t.tdb
    except (ValueError, TypeError):
        raise ctx.fail(
            path, f'expected an ISO epoch like "2039-01-01T00:00:00" (TDB), got {value!r}'
        ) from None
    return tdb, (None if scale == "tdb" else scale)


def _parse_angle(ctx: _Ctx, path: str, value: Any, is_ra: bool, check_range: bool = True) -> float:
    example = '"08h06m23.2s" or "121.5967 deg"' if is_ra else '"+15d27m30s" or "15.458 deg"'
    try:
        if isinstance(value, int | float) and not isinstance(value, bool):
            ang = Angle(float(value), unit=u.deg)
        elif isinstance(value, str):
            text = value.strip()
            if _NUM_RE.match(text):
                ang = Angle(float(text), unit=u.deg)
            elif ":" in text or (" " in text and not re.search(r"[a-zA-Z]", text)):
                ang = Angle(text, unit=u.hourangle if is_ra else u.deg)
            else:
                ang = Angle(text)
        else:
            raise ValueError
        deg = float(ang.to_value(u.deg))
    except (ValueError, TypeError, u.UnitsError):
        raise ctx.fail(path, f"expected an angle like {example}, got {value!r}") from None
    if not math.isfinite(deg):
        raise ctx.fail(path, f"expected a finite angle like {example}, got {value!r}")
    if not check_range:
        return deg
    if is_ra:
        if not 0.0 <= deg < 360.0:
            raise ctx.fail(path, f"right ascension must be in [0h, 24h), got {value!r}")
    elif not -90.0 <= deg <= 90.0:
        raise ctx.fail(path, f"declination must be in [-90, +90] deg, got {value!r}")
    return deg


def _parse_sky(ctx: _Ctx, sky: Any) -> tuple[float, float]:
    if not isinstance(sky, Mapping):
        raise ctx.fail("sky", 'expected a mapping like {ra: "08h06m23.2s", dec: "+15d27m30s"}')
    keys = set(sky)
    if {"l", "b"} <= keys and not ({"ra", "dec"} & keys):
        lon = _parse_angle(ctx, "sky.l", sky["l"], is_ra=False, check_range=False)
        lat = _parse_angle(ctx, "sky.b", sky["b"], is_ra=False)
        c = SkyCoord(l=lon * u.deg, b=lat * u.deg, frame="galactic").icrs
        return float(c.ra.deg), float(c.dec.deg)
    unknown = keys - {"ra", "dec", "frame"}
    if unknown:
        raise ctx.fail(f"sky.{sorted(unknown)[0]}", "unknown field; expected ra, dec (or l, b)")
    for k in ("ra", "dec"):
        if k not in sky:
            raise ctx.fail(f"sky.{k}", "missing; give ICRS ra and dec")
    frame = str(sky.get("frame", "icrs")).lower()
    if frame not in ("icrs", "j2000", "fk5"):
        raise ctx.fail("sky.frame", f"expected icrs, got {frame!r}")
    return _parse_angle(ctx, "sky.ra", sky["ra"], True), _parse_angle(
        ctx, "sky.dec", sky["dec"], False
    )


_COV_EXTRA = ("cos_inclination", "amplitude", "psi")
_COV_ALLOWED = (*PARAM_NAMES, *_COV_EXTRA)


def _parse_covariance(ctx: _Ctx, cov: Any) -> tuple[tuple[str, ...], FloatArray]:
    if cov is None:
        return (), np.zeros((0, 0))
    if not isinstance(cov, Mapping):
        raise ctx.fail("lisa.covariance", "expected a mapping with parameters+matrix or sigma")
    if "matrix" in cov:
        names = cov.get("parameters")
        if not isinstance(names, list) or not names:
            raise ctx.fail("lisa.covariance.parameters", "expected a list of parameter names")
        names_t = tuple(str(n) for n in names)
        for n in names_t:
            if n not in _COV_ALLOWED:
                raise ctx.fail(
                    "lisa.covariance.parameters",
                    f"unknown parameter {n!r}; expected some of {', '.join(_COV_ALLOWED)}",
                )
        if len(set(names_t)) != len(names_t):
            raise ctx.fail("lisa.covariance.parameters", "parameter names repeat")
        mat_raw = cov["matrix"]
        try:
            mat = np.array(
                [[_to_float(x) for x in row] for row in mat_raw], dtype=np.float64, ndmin=2
            )
        except (TypeError, ValueError):
            raise ctx.fail(
                "lisa.covariance.matrix", "expected a square list of lists of numbers"
            ) from None
        size = len(names_t)
        if mat.shape != (size, size):
            raise ctx.fail(
                "lisa.covariance.matrix",
                f"expected a {size}×{size} matrix, got shape {mat.shape}",
            )
    elif "sigma" in cov:
        sig = cov["sigma"]
        if not isinstance(sig, Mapping) or not sig:
            raise ctx.fail("lisa.covariance.sigma", "expected a mapping parameter: sigma")
        names_t = tuple(str(n) for n in sig)
        sigmas = []
        for n in names_t:
            if n not in _COV_ALLOWED:
                raise ctx.fail(
                    f"lisa.covariance.sigma.{n}",
                    f"unknown parameter; expected some of {', '.join(_COV_ALLOWED)}",
                )
            s = _quantity(ctx, f"lisa.covariance.sigma.{n}", n, sig[n])
            if s < 0:
                raise ctx.fail(f"lisa.covariance.sigma.{n}", f"must be ≥ 0, got {sig[n]!r}")
            sigmas.append(s)
        corr = np.eye(len(names_t))
        for key, rho_raw in _iter_correlations(ctx, cov.get("correlation")):
            a, b = key
            if a not in names_t or b not in names_t or a == b:
                raise ctx.fail(
                    f"lisa.covariance.correlation.{a},{b}",
                    f"names must be two different parameters of sigma ({', '.join(names_t)})",
                )
            rho = _to_float(rho_raw)
            if not (math.isfinite(rho) and -1.0 <= rho <= 1.0):
                raise ctx.fail(
                    f"lisa.covariance.correlation.{a},{b}",
                    f"expected ρ in [-1, 1], got {rho_raw!r}",
                )
            i, j = names_t.index(a), names_t.index(b)
            corr[i, j] = corr[j, i] = rho
        sv = np.array(sigmas)
        mat = corr * np.outer(sv, sv)
    else:
        raise ctx.fail(
            "lisa.covariance", "expected either 'parameters'+'matrix' or 'sigma' (+ 'correlation')"
        )
    _check_psd(ctx, mat)
    return names_t, mat


def _iter_correlations(ctx: _Ctx, corr: Any) -> list[tuple[tuple[str, str], Any]]:
    if corr is None:
        return []
    out: list[tuple[tuple[str, str], Any]] = []
    if isinstance(corr, Mapping):
        for key, val in corr.items():
            parts = [s for s in re.split(r"[,\s]+", str(key).strip("()[] ")) if s]
            if len(parts) != 2:
                raise ctx.fail(
                    f"lisa.covariance.correlation.{key}",
                    'expected a key naming two parameters, like "phase,fdot": -0.7',
                )
            out.append(((parts[0], parts[1]), val))
    elif isinstance(corr, list):
        for item in corr:
            if not (isinstance(item, list) and len(item) == 3):
                raise ctx.fail(
                    "lisa.covariance.correlation", "expected entries like [phase, fdot, -0.7]"
                )
            out.append(((str(item[0]), str(item[1])), item[2]))
    else:
        raise ctx.fail(
            "lisa.covariance.correlation", 'expected a mapping like {"phase,fdot": -0.7}'
        )
    return out


def _to_float(x: Any) -> float:
    if isinstance(x, bool):
        raise ValueError("boolean")
    if isinstance(x, int | float):
        return float(x)
    if isinstance(x, str) and _NUM_RE.match(x):
        return float(x)
    raise ValueError(f"not a number: {x!r}")


def _check_psd(ctx: _Ctx, mat: FloatArray) -> None:
    if not np.all(np.isfinite(mat)):
        raise ctx.fail("lisa.covariance", "contains non-finite values")
    scale = np.sqrt(np.abs(np.diag(mat)))
    if np.any(np.diag(mat) < 0):
        raise ctx.fail("lisa.covariance", "negative variance on the diagonal")
    asym = np.abs(mat - mat.T)
    tol = 1e-9 * np.outer(scale, scale) + 1e-300
    if np.any(asym > tol):
        raise ctx.fail("lisa.covariance", "matrix is not symmetric; check the off-diagonal entries")
    safe = np.where(scale > 0, scale, 1.0)
    corr = mat / np.outer(safe, safe)
    eig = np.linalg.eigvalsh(0.5 * (corr + corr.T))
    if eig.size and eig.min() < -1e-9:
        raise ctx.fail(
            "lisa.covariance",
            f"matrix is not positive semi-definite (smallest correlation eigenvalue "
            f"{eig.min():.3g}); export the full posterior covariance again",
        )


# ---------------------------------------------------------------------------------------------
# loading
# ---------------------------------------------------------------------------------------------


def load_target(path: Path | str) -> Target:
    """Read and validate a target YAML file (``yaml.safe_load`` only).

    Raises
    ------
    TargetFileError
        One line naming the file, the field path, what was expected and how to fix it.
    """
    path = Path(path)
    ctx = _Ctx(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise TargetFileError(f"{path}: file not found; check the path") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise TargetFileError(f"{path}: cannot read target file ({exc})") from None
    try:
        doc = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise TargetFileError(f"{ctx.label}: not valid YAML{where}; fix the syntax") from None
    return target_from_dict(doc, path)


def target_from_dict(doc: Any, path: Path | None = None) -> Target:
    """Validate a parsed target document (see :func:`load_target`)."""
    ctx = _Ctx(path)
    if not isinstance(doc, Mapping):
        raise ctx.fail("<top>", "expected a YAML mapping with name, sky and lisa")
    unknown = set(doc) - _TOP_KEYS
    if unknown:
        raise ctx.fail(
            sorted(unknown)[0], f"unknown field; expected some of {', '.join(sorted(_TOP_KEYS))}"
        )
    name = doc.get("name")
    if not isinstance(name, str) or not name.strip():
        raise ctx.fail("name", 'expected a non-empty string like "HM Cnc"')
    if "sky" not in doc:
        raise ctx.fail("sky", 'missing; add sky: {ra: "08h06m23.2s", dec: "+15d27m30s"}')
    ra, dec = _parse_sky(ctx, doc["sky"])
    lisa = doc.get("lisa")
    if not isinstance(lisa, Mapping):
        raise ctx.fail("lisa", "missing or not a mapping; see the README target-file format")
    unknown = set(lisa) - _LISA_KEYS
    if unknown:
        raise ctx.fail(
            f"lisa.{sorted(unknown)[0]}",
            f"unknown field; expected some of {', '.join(sorted(_LISA_KEYS))}",
        )
    for req in ("t_ref", "t_obs", "phase", "f_gw", "fdot"):
        if req not in lisa:
            raise ctx.fail(
                f"lisa.{req}", f"missing; expected {_EXAMPLES.get(req, 'an ISO TDB epoch')}"
            )
    t_ref, converted = _parse_time(ctx, "lisa.t_ref", lisa["t_ref"], lisa.get("t_ref_scale"))
    t_obs = _quantity(ctx, "lisa.t_obs", "t_obs", lisa["t_obs"])
    if t_obs <= 0:
        raise ctx.fail("lisa.t_obs", f"must be positive, got {lisa['t_obs']!r}")
    ref_is = str(lisa.get("t_ref_is", "midpoint")).strip().lower()
    if ref_is not in ("midpoint", "start"):
        raise ctx.fail("lisa.t_ref_is", f"expected 'midpoint' or 'start', got {ref_is!r}")
    vals = {n: _quantity(ctx, f"lisa.{n}", n, lisa[n]) if n in lisa else 0.0 for n in PARAM_NAMES}
    if vals["f_gw"] <= 0:
        raise ctx.fail("lisa.f_gw", f"must be positive, got {lisa['f_gw']!r}")
    ecc = math.hypot(vals["eta"], vals["kappa"])
    if ecc >= E_MAX:
        raise ctx.fail(
            "lisa.eta/kappa",
            f"e = |η + iκ| = {ecc:.4g} ≥ {E_MAX}: outside the small-e (first-order) model of the "
            "paper; ucbplan cannot schedule such orbits",
        )
    names, mat = _parse_covariance(ctx, lisa.get("covariance"))
    if converted == "tcb":
        vals, mat = _tcb_to_tdb(vals, names, mat)
        t_obs *= 1.0 - L_B
    p = PhaseParams(**vals)
    shift = 0.0
    if ref_is == "start":
        shift = t_obs / 2.0
        p, mat = _shift_named(p, names, mat, shift)
        t_ref = t_ref + TimeDelta(shift, format="sec")
    extras: dict[str, float | None] = {}
    for key in ("cos_inclination", "amplitude", "psi", "distance"):
        extras[key] = _quantity(ctx, f"lisa.{key}", key, lisa[key]) if key in lisa else None
    ci = extras["cos_inclination"]
    if ci is not None and not -1.0 <= ci <= 1.0:
        raise ctx.fail("lisa.cos_inclination", f"expected a value in [-1, 1], got {ci}")
    for key in ("amplitude", "distance"):
        val = extras[key]
        if val is not None and val <= 0:
            raise ctx.fail(f"lisa.{key}", f"must be positive, got {lisa[key]!r}")
    samples = None
    if "samples" in lisa:
        if not isinstance(lisa["samples"], str):
            raise ctx.fail("lisa.samples", "expected a file name like posterior.ecsv")
        base = path.parent if path is not None else Path(".")
        samples = (base / lisa["samples"]).resolve()
        if not samples.exists():
            raise ctx.fail(
                "lisa.samples", f"file {lisa['samples']!r} not found next to the target file"
            )
    spec = _parse_spectroscopy(ctx, doc.get("spectroscopy"))
    priority = 1.0
    if "priority" in doc:
        priority = _num_field(ctx, "priority", doc["priority"])
        if priority <= 0:
            raise ctx.fail("priority", f"must be positive, got {doc['priority']!r}")
    vmag = _num_field(ctx, "vmag", doc["vmag"]) if "vmag" in doc else None
    m1 = m2 = None
    if "masses" in doc:
        masses = doc["masses"]
        if not isinstance(masses, Mapping) or set(masses) - {"m1", "m2"}:
            raise ctx.fail("masses", 'expected {m1: "0.347 solMass", m2: "0.285 solMass"}')
        m1 = _quantity(ctx, "masses.m1", "m1", masses["m1"]) if "m1" in masses else None
        m2 = _quantity(ctx, "masses.m2", "m2", masses["m2"]) if "m2" in masses else None
    notes = {"t_ref_converted_from": converted} if converted else {}
    return Target(
        name=name.strip(),
        source=path.resolve() if path is not None else None,
        ra_deg=ra,
        dec_deg=dec,
        t_ref=t_ref,
        t_obs_s=t_obs,
        params=p,
        cov_names=names,
        cov_matrix=mat,
        cos_inclination=ci,
        amplitude=extras["amplitude"],
        psi=extras["psi"],
        distance_kpc=extras["distance"],
        spectroscopy=spec,
        samples=samples,
        priority=priority,
        vmag=vmag,
        m1_msun=m1,
        m2_msun=m2,
        ref_shift_s=shift,
        notes=notes,
    )


def _num_field(ctx: _Ctx, path: str, value: Any) -> float:
    try:
        x = _to_float(value)
    except ValueError:
        raise ctx.fail(path, f"expected a number, got {value!r}") from None
    if not math.isfinite(x):
        raise ctx.fail(path, f"expected a finite number, got {value!r}")
    return x


def _parse_spectroscopy(ctx: _Ctx, spec: Any) -> Spectroscopy | None:
    if spec is None:
        return None
    if not isinstance(spec, Mapping):
        raise ctx.fail("spectroscopy", "expected a mapping with lines, K1, K2, sigma_v")
    unknown = set(spec) - _SPEC_KEYS
    if unknown:
        raise ctx.fail(
            f"spectroscopy.{sorted(unknown)[0]}",
            f"unknown field; expected some of {', '.join(sorted(_SPEC_KEYS))}",
        )
    lines = str(spec.get("lines", "SB2")).upper()
    if lines not in ("SB1", "SB2"):
        raise ctx.fail("spectroscopy.lines", f"expected SB1 or SB2, got {spec.get('lines')!r}")
    vals: dict[str, float | None] = {}
    for key in ("K1", "K2", "K_eff", "sigma_v"):
        if key in spec:
            v = _quantity(ctx, f"spectroscopy.{key}", key, spec[key])
            if v <= 0:
                raise ctx.fail(f"spectroscopy.{key}", f"must be positive, got {spec[key]!r}")
            vals[key] = v
        else:
            vals[key] = None
    return Spectroscopy(lines, vals["K1"], vals["K2"], vals["K_eff"], vals["sigma_v"])


def _shift_named(
    p: PhaseParams, names: tuple[str, ...], mat: FloatArray, dt: float
) -> tuple[PhaseParams, FloatArray]:
    """Shift parameters and the named covariance (extras like cos ι are unchanged)."""
    from ucbplan.core.params import shift_jacobian

    new_p, _ = shift_reference(p, np.zeros((7, 7)), dt)
    if not names:
        return new_p, mat
    j7 = shift_jacobian(p, dt)
    n = len(names)
    j = np.eye(n)
    for a, na in enumerate(names):
        for b, nb in enumerate(names):
            if na in PARAM_NAMES and nb in PARAM_NAMES:
                j[a, b] = j7[PARAM_NAMES.index(na), PARAM_NAMES.index(nb)]
    # parameters absent from the covariance are exact: their columns do not matter
    new = j @ mat @ j.T
    return new_p, 0.5 * (new + new.T)


def _tcb_to_tdb(
    vals: dict[str, float], names: tuple[str, ...], mat: FloatArray
) -> tuple[dict[str, float], FloatArray]:
    """Rescale rates from TCB to TDB seconds: a quantity per TCB second^n gains (1 − L_B)^−n."""
    power = {"f_gw": 1, "fdot": 2, "fddot": 3, "omega_dot": 1}
    out = dict(vals)
    scale = np.ones(len(names))
    for key, n in power.items():
        out[key] = vals[key] / (1.0 - L_B) ** n
        if key in names:
            scale[names.index(key)] = 1.0 / (1.0 - L_B) ** n
    return out, mat * np.outer(scale, scale)


# ---------------------------------------------------------------------------------------------
# writing
# ---------------------------------------------------------------------------------------------


def target_to_dict(t: Target) -> dict[str, Any]:
    """YAML-ready dict in the documented schema (parameters at the midpoint, bare SI numbers)."""
    lisa: dict[str, Any] = {
        "t_ref": t.t_ref.tdb.isot,
        "t_obs": f"{t.t_obs_s!r} s",
        "t_ref_is": "midpoint",
    }
    for n in PARAM_NAMES:
        unit = PARAM_UNITS[n]
        v = getattr(t.params, n)
        lisa[n] = float(v) if not unit or unit == "rad" else f"{v!r} {unit}"
    for key, val in (
        ("cos_inclination", t.cos_inclination),
        ("amplitude", t.amplitude),
        ("psi", t.psi),
    ):
        if val is not None:
            lisa[key] = float(val)
    if t.distance_kpc is not None:
        lisa["distance"] = f"{t.distance_kpc!r} kpc"
    if t.cov_names:
        lisa["covariance"] = {
            "parameters": list(t.cov_names),
            "matrix": [[float(x) for x in row] for row in t.cov_matrix],
        }
    if t.samples is not None:
        base = t.source.parent if t.source is not None else Path(".")
        try:
            lisa["samples"] = str(t.samples.relative_to(base.resolve()))
        except ValueError:
            lisa["samples"] = str(t.samples)
    doc: dict[str, Any] = {
        "name": t.name,
        "sky": {"ra": f"{t.ra_deg!r} deg", "dec": f"{t.dec_deg!r} deg"},
        "lisa": lisa,
    }
    if t.priority != 1.0:
        doc["priority"] = t.priority
    if t.vmag is not None:
        doc["vmag"] = t.vmag
    if t.m1_msun is not None or t.m2_msun is not None:
        doc["masses"] = {
            k: f"{v!r} solMass" for k, v in (("m1", t.m1_msun), ("m2", t.m2_msun)) if v is not None
        }
    if t.spectroscopy is not None:
        s = t.spectroscopy
        spec: dict[str, Any] = {"lines": s.lines}
        for key, v in (
            ("K1", s.K1_kms),
            ("K2", s.K2_kms),
            ("K_eff", s.K_eff_kms),
            ("sigma_v", s.sigma_v_kms),
        ):
            if v is not None:
                spec[key] = f"{v!r} km / s"
        doc["spectroscopy"] = spec
    return doc


def write_target(t: Target, path: Path, overwrite: bool = False, header: str = "") -> None:
    """Write ``t`` as YAML atomically (refuses to overwrite unless ``overwrite``)."""
    from ucbplan.io import write_output

    doc = target_to_dict(t)
    if t.samples is not None:
        try:
            doc["lisa"]["samples"] = str(t.samples.resolve().relative_to(path.parent.resolve()))
        except ValueError:
            doc["lisa"]["samples"] = str(t.samples.resolve())

    def _write(handle: Any) -> None:
        if header:
            for line in header.splitlines():
                handle.write(f"# {line}\n")
        yaml.safe_dump(doc, handle, sort_keys=False, allow_unicode=True, width=100)

    write_output(path, _write, overwrite=overwrite)


def load_samples(t: Target) -> dict[str, FloatArray]:
    """Posterior samples referenced to ``t.t_ref`` (the midpoint), columns named like parameters.

    The samples file must be referenced to the same epoch as the target file's ``t_ref`` as
    written (``t_ref_is``); samples of a start-referenced file are shifted to the midpoint.

    Raises
    ------
    TargetFileError
        If the file cannot be read or lacks the parameters the target has.
    """
    if t.samples is None:
        return {}
    from astropy.table import Table

    try:
        tab = Table.read(t.samples, format="ascii.ecsv" if t.samples.suffix == ".ecsv" else None)
    except Exception as exc:  # astropy raises many types for unreadable tables
        raise TargetFileError(f"{t.samples.name}: cannot read posterior samples ({exc})") from None
    cols = {n: np.asarray(tab[n], dtype=np.float64) for n in tab.colnames if n in _COV_ALLOWED}
    if not cols:
        raise TargetFileError(
            f"{t.samples.name}: no parameter columns; expected columns named "
            f"{', '.join(PARAM_NAMES)}"
        )
    if t.ref_shift_s:
        base = {n: getattr(t.params, n) for n in PARAM_NAMES}
        cols = shift_columns(cols, t.ref_shift_s, defaults=base)
    return cols
