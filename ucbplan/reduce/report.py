"""Turn a :class:`~ucbplan.reduce.Reduction` into a report dict, JSON/YAML, rich text, an EM prior.

Every quantity is ``{"value", "sigma", "unit"}``; Monte-Carlo quantities add ``lo``/``hi`` (16/84 %
percentiles, value = median). Upper limits add ``upper_limit`` (|x̂| + 2σ) when |x̂| < 2σ.
The keys are documented in docs/commands.md ("ucbplan reduce" → "Report keys").
"""

from __future__ import annotations

import math
from json.encoder import encode_basestring_ascii
from typing import IO, TYPE_CHECKING, Any

import numpy as np

from ucbplan._version import __version__
from ucbplan.core.constants import DAY_S, RSUN_M

if TYPE_CHECKING:
    from ucbplan.reduce.drifts import Pair
    from ucbplan.reduce.masses import Summary
    from ucbplan.reduce.pipeline import Reduction

#: Units of the Monte-Carlo quantities (astropy unit strings), after conversion in :func:`_mc`.
MC_UNITS: dict[str, tuple[str, float]] = {
    "K1": ("km / s", 1.0),
    "K2": ("km / s", 1.0),
    "gamma1": ("km / s", 1.0),
    "gamma2": ("km / s", 1.0),
    "q": ("", 1.0),
    "M1": ("solMass", 1.0),
    "M2": ("solMass", 1.0),
    "M_tot": ("solMass", 1.0),
    "M_c": ("solMass", 1.0),
    "a": ("solRad", 1.0 / RSUN_M),
    "P_b": ("s", 1.0),
    "n_b": ("rad / s", 1.0),
    "e": ("", 1.0),
    "sin_i": ("", 1.0),
    "omega_dot_GR": ("rad / s", 1.0),
    "omega_dot_remainder": ("rad / s", 1.0),
    "M_tot_omega_dot": ("solMass", 1.0),
    "M_c_fdot": ("solMass", 1.0),
    "fdot_GW_only": ("Hz / s", 1.0),
    "fdot_minus_GW_only": ("Hz / s", 1.0),
    "distance": ("kpc", 1.0),
    "gamma_diff": ("km / s", 1.0),
    "redshift_orbital": ("km / s", 1.0),
    "redshift_grav": ("km / s", 1.0),
    "redshift_grav_model": ("km / s", 1.0),
    "redshift_grav_minus_model": ("km / s", 1.0),
    "R1": ("solRad", 1.0),
    "R2": ("solRad", 1.0),
    "mass_function": ("solMass", 1.0),
}


def _num(x: float | np.floating[Any]) -> float | None:
    """JSON-safe float (None for NaN/inf)."""
    x = float(x)
    return x if math.isfinite(x) else None


def _q(value: float, sigma: float, unit: str, **extra: Any) -> dict[str, Any]:
    out: dict[str, Any] = {"value": _num(value), "sigma": _num(sigma), "unit": unit}
    for k, v in extra.items():
        out[k] = _num(v) if isinstance(v, float | int | np.floating) else v
    return out


def _mc(name: str, s: Summary) -> dict[str, Any]:
    unit, scale = MC_UNITS.get(name, ("", 1.0))
    return _q(s.value * scale, s.sigma * scale, unit, lo=s.lo * scale, hi=s.hi * scale)


def _upper(value: float, sigma: float) -> float | None:
    if not (math.isfinite(value) and math.isfinite(sigma)):
        return None
    return abs(value) + 2.0 * sigma if abs(value) < 2.0 * sigma else None


def build_report(red: Reduction) -> dict[str, Any]:
    """The machine-readable report (JSON/YAML-ready: plain floats, lists, dicts).

    Parameters
    ----------
    red : Reduction

    Returns
    -------
    dict
        Top-level keys: metadata, ``K1``, ``K2``, ``gamma1``, ``gamma2``, ``q``, ``M1``, ``M2``,
        ``M_tot`` (None if not measurable, e.g. SB1) plus every Monte-Carlo quantity, ``fits``,
        ``wil41``, ``phase``, ``light_time``, ``drifts``, ``warnings``.
    """
    doc = _metadata(red)
    for key in ("K1", "K2", "gamma1", "gamma2", "q", "M1", "M2", "M_tot"):
        doc[key] = None  # fixes the key order; SB1 and missing masses stay None
    fits_doc: dict[str, Any] = {}
    for j in range(len(red.fits)):
        doc[f"K{j + 1}"], doc[f"gamma{j + 1}"] = _k_gamma_docs(red, j)
        fits_doc[f"star{j + 1}"] = _fit_doc(red, j)
    doc["fits"] = fits_doc
    for name, s in red.summaries.items():
        if name in ("K1", "K2", "gamma1", "gamma2"):
            continue
        doc[name] = _mc(name, s)
    if red.wilson is not None:
        doc["wil41"] = _wilson_doc(red)
    doc["phase"] = {
        "sigma_u_mean": _q(float(np.mean(red.sigma_u)), 0.0, "rad"),
        "sigma_u_max": _q(float(np.max(red.sigma_u)), 0.0, "rad"),
    }
    lt = red.light_time
    doc["light_time"] = {
        "applied": red.options.light_time,
        "max_delay": _q(lt["max_delay_s"], 0.0, "s"),
        **{k: _q(v, 0.0, "km / s") for k, v in lt.items() if k.startswith("d")},
    }
    doc["drifts"] = _drift_doc(red)
    doc["warnings"] = list(red.warnings)
    return doc


def _metadata(red: Reduction) -> dict[str, Any]:
    """Provenance and run settings: version, files, spectra, sessions, seed, options."""
    t, tab = red.target, red.table
    return {
        "ucbplan_version": __version__,
        "target": t.name,
        "target_file": str(t.source) if t.source else None,
        "velocity_file": str(tab.source) if tab.source else None,
        "lines": tab.lines,
        "n_spectra": tab.n,
        "sessions": sorted(set(tab.session)),
        "time_scale": "TDB (barycentric)",
        "seed": red.seed,
        "n_samples": red.options.n_samples,
        "light_time_applied": red.options.light_time,
        "mass_radius_model": red.options.mass_radius,
    }


def _k_gamma_docs(red: Reduction, j: int) -> tuple[dict[str, Any], dict[str, Any]]:
    """K_j and γ_j of the fit with σ = statistical ⊕ phase (⊕ attenuation for K), MC range."""
    f, star = red.fits[j], j + 1
    s_k = math.sqrt(f.sigma_K**2 + red.sigma_K_phase[j] ** 2 + red.attenuation[j] ** 2)
    s_g = math.sqrt(f.sigma_gamma**2 + red.sigma_gamma_phase[j] ** 2)
    sk, sg = red.summaries[f"K{star}"], red.summaries[f"gamma{star}"]
    k_doc = _q(
        f.K,
        s_k,
        "km / s",
        lo=sk.lo,
        hi=sk.hi,
        sigma_stat=f.sigma_K,
        sigma_stat_input=f.sigma_K_input,
        sigma_phase=red.sigma_K_phase[j],
        attenuation=red.attenuation[j],
    )
    g_doc = _q(
        f.gamma,
        s_g,
        "km / s",
        lo=sg.lo,
        hi=sg.hi,
        sigma_stat=f.sigma_gamma,
        sigma_phase=red.sigma_gamma_phase[j],
    )
    return k_doc, g_doc


def _fit_doc(red: Reduction, j: int) -> dict[str, Any]:
    """The weighted line of star j + 1: coefficients, χ², outliers, mean Λ_K."""
    line = red.fits[j].line
    w = 1.0 / red.table.sigma[j] ** 2
    lam = float((w * red.lam_k).sum() / w.sum())
    return {
        "slope": _num(line.slope),
        "intercept": _num(line.intercept),
        "cov_intercept_slope": [[_num(x) for x in r] for r in line.cov],
        "chi2": _num(line.chi2),
        "dof": line.dof,
        "rms_km_s": _num(line.rms),
        "errors_scaled_by_chi2": line.scaled,
        "sigma_scale": _num(line.scale),
        "outlier_rows": (np.flatnonzero(line.outliers) + 1).tolist(),
        "lambda_k_mean": _num(lam),
    }


def _wilson_doc(red: Reduction) -> dict[str, Any]:
    """WIL41 q and intercept, and how far q is from the Monte-Carlo K1/K2 (in σ)."""
    w41 = red.wilson
    assert w41 is not None
    out: dict[str, Any] = {
        "q": _q(w41.q, w41.sigma_q, ""),
        "gamma1_plus_q_gamma2": _q(w41.intercept, w41.sigma_intercept, "km / s"),
        "chi2": _num(w41.chi2),
        "dof": w41.dof,
    }
    if "q" in red.summaries:
        s = red.summaries["q"]
        out["q_difference_sigma"] = _num((w41.q - s.value) / math.hypot(w41.sigma_q, s.sigma))
    return out


def _pair_doc(p: Pair) -> dict[str, Any]:
    """One fixed-u pair: ΔT, Δv_j, Δκ_spec vs Δκ_LISA and their significance, Δv_CM."""
    return {
        "alpha": p.alpha,
        "beta": p.beta,
        "u_star_rad": _num(p.u_star),
        "dT": _q(p.dT_s / DAY_S, 0.0, "d"),
        "dv": [_q(v, s, "km / s") for v, s in zip(p.dv, p.sigma_dv, strict=True)],
        "dkappa_spec": _q(p.dkappa_spec, p.sigma_dkappa_spec, ""),
        "dkappa_lisa": _q(p.dkappa_lisa, p.sigma_dkappa_lisa, ""),
        "dkappa_significance": _num(p.z_kappa),
        "dv_cm": _q(p.dv_cm, p.sigma_dv_cm, "km / s", upper_limit=_upper(p.dv_cm, p.sigma_dv_cm)),
    }


def _drift_doc(red: Reduction) -> dict[str, Any]:
    """Inter-session results: pairs, zero-crossing differences, a_los, Δκ χ², WIL41 line."""
    d = red.drift
    pairs = [_pair_doc(p) for p in d.pairs]
    out: dict[str, Any] = {"n_groups": len(red.groups), "pairs": pairs}
    if d.zero_crossing:
        out["zero_crossing"] = [
            {
                "alpha": a,
                "beta": b,
                "dT": _q(dT / DAY_S, 0.0, "d"),
                "dv_cm": _q(dv, s, "km / s", upper_limit=_upper(dv, s)),
            }
            for a, b, dT, dv, s in d.zero_crossing
        ]
    if math.isfinite(d.a_los):
        out["a_los"] = _q(
            d.a_los, d.sigma_a_los, "m / s2", upper_limit=_upper(d.a_los, d.sigma_a_los)
        )
        out["fdot_acc"] = _q(d.fdot_acc, d.sigma_fdot_acc, "Hz / s")
        s = red.summaries.get("fdot_minus_GW_only")
        if s is not None:
            rem = s.value - d.fdot_acc
            out["fdot_remainder"] = _q(rem, math.hypot(s.sigma, d.sigma_fdot_acc), "Hz / s")
    if d.n_kappa:
        out["dkappa_chi2"] = _num(d.chi2_kappa)
        out["dkappa_n"] = d.n_kappa
    if d.wil41_line is not None:
        out["wil41_differences"] = {
            "q": _q(d.q_line, d.sigma_q_line, ""),
            "dv_cm": _q(d.dv_cm_line, d.sigma_dv_cm_line, "km / s"),
        }
    return out


def em_prior(red: Reduction) -> dict[str, Any]:
    """EM prior for a later LISA analysis or ``ucbplan simulate`` (Gaussian summaries).

    Returns
    -------
    dict
        ``{"em_prior": {"target", "source", <name>: {value, sigma, unit}}}`` for q, M_tot, M1,
        M2, M_c, K1, K2 (when measured) and a_los (value/σ, or an upper limit).
    """
    rep = build_report(red)
    prior: dict[str, Any] = {"target": red.target.name, "source": f"ucbplan {__version__} reduce"}
    for key in ("q", "M_tot", "M1", "M2", "M_c", "K1", "K2"):
        q = rep.get(key)
        if q is not None:
            prior[key] = {k: q[k] for k in ("value", "sigma", "unit")}
    a = rep["drifts"].get("a_los")
    if a is not None:
        prior["a_los"] = {k: a[k] for k in ("value", "sigma", "unit", "upper_limit")}
    return {"em_prior": prior}


def write_json(doc: dict[str, Any], handle: IO[str]) -> None:
    """Write ``doc`` as indented JSON (NaN-free), the text of :func:`ucbplan.io.dump_json`
    (the fixed-u pairs through :class:`_PairText`)."""
    from ucbplan.reduce.jsontext import dumps_report

    handle.write(dumps_report(doc, {"pairs": _PairText()}))
    handle.write("\n")


#: Keys of a fixed-u pair's document (:func:`_pair_doc`), of its quantities and of Δv_CM.
_PAIR_KEYS = tuple(
    "alpha beta u_star_rad dT dv dkappa_spec dkappa_lisa dkappa_significance dv_cm".split()
)
_Q_KEYS = ("value", "sigma", "unit")
_LIMIT_KEYS = (*_Q_KEYS, "upper_limit")


class _PairText:
    """The JSON text of fixed-u pair documents, from one template per nesting level and number
    of components: the bytes :func:`~ucbplan.reduce.jsontext.dumps_report` writes for them
    (~8,000 pairs at 10⁶ spectra), without its walk through every key. A document of another
    shape, or with a value other than a float, None or text where those stand, is left to it."""

    def __init__(self) -> None:
        self._formats: dict[tuple[int, int], str] = {}

    def __call__(self, doc: Any, level: int) -> str | None:
        try:
            leaves = _pair_leaves(doc)
        except _NotPlain:
            return None
        key = (level, len(doc["dv"]))
        if key not in self._formats:
            self._formats[key] = _pair_format(doc, level)
        return self._formats[key] % leaves


class _NotPlain(Exception):
    """A pair document that :class:`_PairText` leaves to the general writer."""


def _pair_leaves(d: Any) -> tuple[str, ...]:
    """The text of a pair document's values, in its keys' order (raises _NotPlain)."""
    if type(d) is not dict or tuple(d) != _PAIR_KEYS or type(d["dv"]) is not list:
        raise _NotPlain
    out = [_text(d["alpha"]), _text(d["beta"]), _text(d["u_star_rad"])]
    for q in (d["dT"], *d["dv"], d["dkappa_spec"], d["dkappa_lisa"]):
        if type(q) is not dict or tuple(q) != _Q_KEYS:
            raise _NotPlain
        out += (_text(q["value"]), _text(q["sigma"]), _text(q["unit"]))
    out.append(_text(d["dkappa_significance"]))
    q = d["dv_cm"]
    if type(q) is not dict or tuple(q) != _LIMIT_KEYS:
        raise _NotPlain
    out += (_text(q["value"]), _text(q["sigma"]), _text(q["unit"]), _text(q["upper_limit"]))
    return tuple(out)


def _text(x: Any) -> str:
    """JSON text of a float (null when not finite), None or str, as the general writer's."""
    if type(x) is float:
        return float.__repr__(x) if math.isfinite(x) else "null"
    if x is None:
        return "null"
    if type(x) is str:
        return encode_basestring_ascii(x)
    raise _NotPlain


def _pair_format(doc: dict[str, Any], level: int) -> str:
    """A %-format of the text of documents shaped as ``doc`` at nesting ``level``: the general
    writer's text of ``doc`` with each value replaced by a marker, the markers made ``%s``."""
    import itertools
    import re

    from ucbplan.reduce.jsontext import dumps_report

    count = itertools.count()

    def mark(x: Any) -> Any:
        if type(x) is dict:
            return {k: mark(v) for k, v in x.items()}
        return [mark(v) for v in x] if type(x) is list else f"@{next(count)}@"

    text = dumps_report(mark(doc)).replace("\n", "\n" + "  " * level)
    return "%s".join(part.replace("%", "%%") for part in re.split(r'"@\d+@"', text))


def write_yaml(doc: dict[str, Any], handle: IO[str]) -> None:
    """Write ``doc`` as block-style YAML."""
    import yaml

    yaml.safe_dump(doc, handle, sort_keys=False, allow_unicode=True)


def _fmt(q: dict[str, Any] | None, digits: int = 4) -> str:
    if q is None or q.get("value") is None:
        return "—"
    v, s = q["value"], q.get("sigma")
    unit = q.get("unit", "")
    txt = f"{v:.{digits}g} ± {s:.2g}" if s else f"{v:.{digits}g}"
    if q.get("upper_limit") is not None:
        txt += f" (|x| < {q['upper_limit']:.2g})"
    return f"{txt} {unit}".strip()


#: Rows of the terminal table, in order (those in the report).
_TABLE_KEYS = (
    "K1",
    "K2",
    "gamma1",
    "gamma2",
    "q",
    "M1",
    "M2",
    "M_tot",
    "M_c",
    "a",
    "P_b",
    "e",
    "omega_dot_GR",
    "omega_dot_remainder",
    "M_tot_omega_dot",
    "M_c_fdot",
    "fdot_GW_only",
    "fdot_minus_GW_only",
    "distance",
    "gamma_diff",
    "redshift_orbital",
    "redshift_grav",
    "redshift_grav_model",
    "redshift_grav_minus_model",
    "mass_function",
)


def _quantity_table(doc: dict[str, Any]) -> Any:
    """Rich table of the fitted and Monte-Carlo quantities (value ± σ, 16–84 % range)."""
    from rich.table import Table

    tab = Table(title="Intra-session fits and masses (value ± 1σ; MC 16–84 % in brackets)")
    tab.add_column("quantity")
    tab.add_column("value")
    tab.add_column("16–84 %")
    for k in _TABLE_KEYS:
        q = doc.get(k)
        if q is None:
            continue
        rng = f"[{q['lo']:.5g}, {q['hi']:.5g}]" if q.get("lo") is not None else ""
        tab.add_row(k, _fmt(q, 6), rng)
    return tab


def _pairs_table(pairs: list[dict[str, Any]]) -> Any:
    """Rich table of the fixed-u pairs (Δκ_spec vs Δκ_LISA, Δv_CM)."""
    from rich.markup import escape
    from rich.table import Table

    pt = Table(title="Fixed-u pairs (Δκ_spec vs Δκ_LISA, Δv_CM)")
    for c in ("α → β", "u★ [rad]", "ΔT [d]", "Δκ_spec", "Δκ_LISA", "z [σ]", "Δv_CM"):
        pt.add_column(escape(c))
    for p in pairs:
        z = p["dkappa_significance"]
        pt.add_row(
            f"{p['alpha']} → {p['beta']}",
            f"{p['u_star_rad']:.3f}",
            f"{p['dT']['value']:.2f}",
            _fmt(p["dkappa_spec"], 3),
            _fmt(p["dkappa_lisa"], 3),
            "—" if z is None else f"{z:+.2f}",
            _fmt(p["dv_cm"], 3),
        )
    return pt


def _light_time_line(lt: dict[str, Any]) -> str:
    """One line: the largest light-time delay and the K, γ shifts of its correction."""
    return (
        f"Light travel time across the orbit: ≤ {lt['max_delay']['value']:.3f} s; "
        f"{'applied' if lt['applied'] else 'not applied (--light-time)'}: "
        + ", ".join(f"{k} {v['value']:+.3f} km/s" for k, v in lt.items() if k.startswith("d"))
    )


#: Most sessions named and fixed-u pairs listed on the terminal; a longer run lists the first
#: ones and says how many more the JSON/YAML report holds (rendering 10⁴ table rows takes longer
#: than the whole reduction).
MAX_TERMINAL_ROWS = 40


def _more(n: int, what: str) -> str:
    """The line that stands for the rows not printed."""
    return f"… and {n - MAX_TERMINAL_ROWS} more {what}: the full list is in the -o JSON/YAML report"


def print_report(doc: dict[str, Any], console: Any) -> None:
    """Rich terminal report (to the given console, normally stderr)."""
    sessions = doc["sessions"]
    names = ", ".join(sessions[:MAX_TERMINAL_ROWS])
    if len(sessions) > MAX_TERMINAL_ROWS:
        names += f", … ({len(sessions)} sessions)"
    console.print(
        f"[bold]{doc['target']}[/] — {doc['n_spectra']} spectra ({doc['lines']}), "
        f"sessions {names}; times TDB (barycentric)"
    )
    console.print(_quantity_table(doc))
    if "wil41" in doc:
        w = doc["wil41"]
        console.print(
            f"WIL41 v1–v2 line: q = {_fmt(w['q'])}, γ1+qγ2 = "
            f"{_fmt(w['gamma1_plus_q_gamma2'])} (χ²/dof {w['chi2']:.1f}/{w['dof']})"
        )
    console.print(_light_time_line(doc["light_time"]))
    dr = doc["drifts"]
    if dr["pairs"]:
        console.print(_pairs_table(dr["pairs"][:MAX_TERMINAL_ROWS]))
        if len(dr["pairs"]) > MAX_TERMINAL_ROWS:
            console.print(_more(len(dr["pairs"]), "fixed-u pairs"))
    for k in ("a_los", "fdot_acc", "fdot_remainder"):
        if k in dr:
            console.print(f"{k}: {_fmt(dr[k])}")
    for w in doc["warnings"]:
        console.print(f"[yellow]warning:[/] {w}")
