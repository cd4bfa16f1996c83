"""What a fit writes: the JSON report and the timing target file.

The JSON report gives each parameter as ``{value, sigma, unit}`` (T0's value a full-precision
``"BJD_TDB …"`` string, its σ in seconds), the covariance (T0 in seconds), χ², dof, the
reference, outliers, clipped rows, notes and every point's O − C.

The target file is the ``timing:`` kind of target:

    name: …
    sky: {ra: "…", dec: "…"}
    timing:
      t0: "BJD_TDB 2458305.682788600000"
      t0_marks: primary_eclipse
      period: "414.7915404000 s"
      pdot: -2.373e-11
      covariance: {parameters: [t0, period, pdot], matrix: [[…]]}   # s², s², 1 (t0 in s)
      source: "ucbplan ephemeris fit of FILE (N times, chi2/dof=…)"

with name, sky (and masses, spectroscopy, magnitudes) copied from ``--like TARGET.yaml`` or
given as ``--name/--ra/--dec``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import IO, Any

import yaml

from ucbplan.core.timing_epochs import format_bjd
from ucbplan.errors import InputError, InputFileError, shorten
from ucbplan.inputs import load_yaml
from ucbplan.timing.eclipse_table import EclipseTimes
from ucbplan.timing.fit import COV_UNITS, UNITS, EphemerisFit

MODEL = (
    "t(n) = T0 + P*n + P*Pdot*n^2/2 (+ P^2*Pddot*n^3/6); n = cycles since T0, integer at primary "
    "and half-integer at secondary eclipses; times BJD_TDB"
)
#: Fields copied from ``--like`` besides name and sky.
COPIED_FIELDS = ("masses", "spectroscopy", "magnitudes")


def _period_text(p: float, sigma: float) -> str:
    """P in seconds with ~3 digits beyond its σ (never fewer than 7 decimals)."""
    decimals = 7
    if sigma > 0 and math.isfinite(sigma):
        decimals = max(decimals, 2 - math.floor(math.log10(sigma)))
    return f"{p:.{min(decimals, 15)}f} s"


def fit_report(fit: EphemerisFit, times: EclipseTimes) -> dict[str, Any]:
    """The JSON document of a fit (see the module notes)."""
    sig = fit.sigmas
    params: dict[str, Any] = {
        "t0": {"value": format_bjd(fit.t0_jd), "sigma": float(sig[0]), "unit": "s"}
    }
    for i in range(1, fit.terms):
        params[fit.names[i]] = {
            "value": float(fit.values[i]),
            "sigma": float(sig[i]),
            "unit": UNITS[i],
        }
    points = _points(fit, times)
    by_row = {p["row"]: p for p in points}
    return {
        "source": fit.source,
        "model": MODEL,
        "n_points": times.n,
        "n_used": fit.n_used,
        "terms": fit.terms,
        "parameters": params,
        "covariance": {
            "parameters": list(fit.names),
            "units": list(COV_UNITS[: fit.terms]),
            "matrix": fit.cov.tolist(),
        },
        "chi2": fit.chi2,
        "dof": fit.dof,
        "chi2_per_dof": fit.chi2 / fit.dof if fit.dof > 0 else None,
        "sigma_scale": fit.sigma_scale,
        "rescaled": fit.rescaled,
        "reference": {
            "t0_marks": "primary_eclipse",
            "t0_cycle": fit.t0_cycle,
            "weighted_mean_cycle": fit.weighted_mean_cycle,
            "cycles": fit.cycles_origin,
            "note": "t0 is the primary eclipse (integer cycle) nearest the weighted mean epoch; "
            "cycles below count from it",
        },
        "outliers": [by_row[r] for r in fit.outliers],
        "clipped": [by_row[r] for r in fit.clipped],
        "notes": list(fit.notes),
        "points": points,
    }


def _points(fit: EphemerisFit, times: EclipseTimes) -> list[dict[str, Any]]:
    """One JSON record per measured time: row, epoch, kind, cycle, O − C, σ, z, used."""
    return [
        {
            "row": int(times.rows[i]),
            "bjd_tdb": str(times.jd[i]),
            "kind": "secondary" if times.secondary[i] else "primary",
            "cycle": float(fit.nu[i]),
            "o_minus_c_s": float(fit.o_minus_c_s[i]),
            "sigma_s": float(times.sigma_s[i]),
            "z": float(fit.z[i]),
            "used": bool(fit.used[i]),
        }
        for i in range(times.n)
    ]


def identity(
    like: Path | Mapping[str, Any] | None, name: str | None, ra: str | None, dec: str | None
) -> dict[str, Any]:
    """Name, sky (and masses, spectroscopy, magnitudes) of the target to write.

    From ``like`` (a target YAML, or the document itself) with ``name``/``ra``/``dec``
    overriding it.

    Raises
    ------
    InputError
        No name or sky position, or an unreadable sky position.
    """
    out: dict[str, Any] = {}
    if like is not None:
        doc = like if isinstance(like, Mapping) else load_yaml(like, "target file")
        if not isinstance(doc, Mapping):
            raise InputFileError(
                f"{getattr(like, 'name', like)}: expected a target file (a mapping), got "
                f"{type(doc).__name__}"
            )
        for key in ("name", "sky", *COPIED_FIELDS):
            if key in doc:
                out[key] = doc[key]
    if name is not None:
        if not name.strip() or len(name) > 200 or not name.isprintable():
            raise InputError(
                f"name: expected a printable name of 1–200 characters, got {shorten(name, 60)}"
            )
        out["name"] = name.strip()
    if ra is not None or dec is not None:
        if ra is None or dec is None:
            raise InputError("ra/dec: give both (ICRS), e.g. `ra` 15h39m32.16s `dec` +50d27m38.8s")
        _check_angle("ra", ra, hours=True)
        _check_angle("dec", dec, hours=False)
        out["sky"] = {"ra": ra.strip(), "dec": dec.strip()}
    missing = [k for k in ("name", "sky") if k not in out]
    if missing:
        raise InputError(
            f"-o: the timing target needs {' and '.join(missing)}; pass `like` TARGET.yaml (copies "
            "name, sky, masses, spectroscopy, magnitudes) or `name`, `ra`, `dec`"
        )
    if not isinstance(out["sky"], Mapping):
        raise InputError(
            f"like: sky: expected a mapping {{ra, dec}}, got {shorten(out['sky'], 60)}"
        )
    return out


def _check_angle(option: str, text: str, hours: bool) -> None:
    from astropy import units as u
    from astropy.coordinates import Angle

    s = text.strip()
    try:
        if any(c.isalpha() for c in s):
            a = Angle(s)
        else:
            a = Angle(s, unit=(u.hourangle if hours and (":" in s or " " in s) else u.deg))
        deg = float(a.to_value(u.deg))
    except (ValueError, TypeError, u.UnitsError):
        example = "15h39m32.16s or 234.884" if hours else "+50d27m38.8s or 50.4608"
        raise InputError(
            f"{option}: expected an angle like {example}, got {shorten(text, 60)}"
        ) from None
    low, high = (0.0, 360.0) if hours else (-90.0, 90.0)
    if not (math.isfinite(deg) and low <= deg <= high):
        raise InputError(
            f"{option}: expected an angle in [{low:g}, {high:g}] deg, got {shorten(text, 60)}"
        )


def target_document(fit: EphemerisFit, ident: Mapping[str, Any], table_name: str) -> dict[str, Any]:
    """The timing target file as a mapping (see the module notes)."""
    sig = fit.sigmas
    timing: dict[str, Any] = {
        "t0": format_bjd(fit.t0_jd),
        "t0_marks": "primary_eclipse",
        "period": _period_text(fit.period_s, float(sig[1])),
    }
    # a fit without Ṗ held it at 0 exactly: a target states it (a zero Ṗ claims no uncertainty)
    timing["pdot"] = float(fit.values[2]) if fit.terms > 2 else 0.0
    if fit.terms > 3:
        timing["pddot"] = float(fit.values[3])
    timing["covariance"] = {
        "parameters": list(fit.names),
        "matrix": [[float(x) for x in row] for row in fit.cov],
    }
    ratio = f"{fit.chi2 / fit.dof:.3g}" if fit.dof > 0 else "n/a"
    rescale = ", sigmas rescaled" if fit.rescaled else ""
    timing["source"] = (
        f"ucbplan ephemeris fit of {table_name} ({fit.n_used} times, chi2/dof={ratio}{rescale})"
    )
    doc: dict[str, Any] = {"name": ident["name"], "sky": dict(ident["sky"])}
    for key in COPIED_FIELDS:
        if key in ident:
            doc[key] = ident[key]
    doc["timing"] = timing
    return doc


def write_yaml(doc: Mapping[str, Any], handle: IO[str]) -> None:
    """Write ``doc`` as block YAML (short lists inline), keys in order."""
    handle.write("# timing target written by ucbplan ephemeris fit; covariance units: t0 in s\n")
    yaml.safe_dump(
        dict(doc), handle, sort_keys=False, allow_unicode=True, default_flow_style=None, width=100
    )
