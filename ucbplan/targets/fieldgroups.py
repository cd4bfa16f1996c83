"""Families of target-file fields that share a shape, for the declaration in
:mod:`ucbplan.targets.schema`: phase-model parameters, spectroscopic velocities, the eccentricity
triple (η, κ, ω̇) and the covariance mapping (matrix, or σ's and correlations).
"""

from __future__ import annotations

from ucbplan.core.constants import C_KM_S, E_MAX
from ucbplan.core.params import PARAM_UNITS
from ucbplan.targets.fieldtypes import Field, Range

#: Time scales an epoch may be labelled with (``t_ref_scale``).
TIME_SCALES = ("tdb", "tcb", "tt", "utc", "tai")
_ECC_NOTE = f"e = |η + iκ| < {E_MAX} (the paper's first-order small-e model)"


def phase_field(
    name: str,
    what: str,
    example: str,
    doc: str,
    required: bool = False,
    bounds: Range | None = None,
    dimension_hint: str = "",
    section: str = "lisa",
) -> Field:
    """A phase-model parameter ``<section>.<name>`` in its core unit; optional ones default to 0."""
    return Field(
        f"{section}.{name}",
        "quantity",
        what,
        example,
        unit=PARAM_UNITS[name],
        required=required,
        default=None if required else 0.0,
        bounds=bounds,
        doc=doc,
        dimension_hint=dimension_hint,
    )


def velocity_field(name: str, example: str, doc: str, reason: str) -> Field:
    """A spectroscopy velocity ``spectroscopy.<name>`` in km/s, positive and below c."""
    return Field(
        f"spectroscopy.{name}",
        "quantity",
        "a velocity",
        example,
        unit="km / s",
        bounds=Range(
            0.0,
            C_KM_S,
            low_open=True,
            high_open=True,
            reason=f"{reason}, below the speed of light",
            error=f"must be in (0, {C_KM_S:g}) km/s, got {{raw}}",
        ),
        doc=doc,
    )


def eccentricity_fields(section: str, epoch: str) -> tuple[Field, Field, Field]:
    """η, κ (of star 1 at ``epoch``) and ω̇ of ``section``, as in the paper's LISA model."""
    return (
        phase_field(
            "eta",
            "a dimensionless number",
            "0.0068 (dimensionless)",
            f"η = e sin ω of star 1 at {epoch}; {_ECC_NOTE}",
            dimension_hint="η = e sin ω is dimensionless: give a plain number",
            section=section,
        ),
        phase_field(
            "kappa",
            "a dimensionless number",
            "0.0068 (dimensionless)",
            f"κ = e cos ω of star 1 at {epoch}; {_ECC_NOTE}",
            dimension_hint="κ = e cos ω is dimensionless: give a plain number",
            section=section,
        ),
        phase_field(
            "omega_dot",
            "an angular rate",
            '"1.498e-6 rad / s"',
            "apsidal advance rate ω̇",
            dimension_hint="give rad/s (ω̇ = 2π rad × the rate in Hz)",
            section=section,
        ),
    )


def covariance_fields(
    section: str, names: str, example: str, sigma_example: str, required: bool = False
) -> tuple[Field, ...]:
    """The covariance mapping of ``section`` (two forms, as ``lisa.covariance``)."""
    path = f"{section}.covariance"
    return (
        Field(
            path,
            "mapping",
            "a mapping",
            example,
            required=required,
            doc="covariance: parameters + matrix, or sigma (+ correlation)"
            + ("; required (horizons and σ_t need it)" if required else ""),
        ),
        Field(
            f"{path}.parameters",
            "list",
            "a list of parameter names",
            names,
            doc="names of the matrix rows, in the units of the parameters above",
        ),
        Field(
            f"{path}.matrix",
            "list",
            "a square list of lists of numbers",
            "[[5.29e-4, 0, 0], [0, 5.93e-23, 0], [0, 0, 2.17e-37]]",
            doc="symmetric positive semi-definite covariance matrix",
        ),
        Field(
            f"{path}.sigma",
            "mapping",
            "a mapping parameter: sigma",
            sigma_example,
            bounds=Range(
                0.0,
                low_open=True,
                reason="a standard deviation is positive; leave out a parameter known exactly",
                error="must be > 0, got {raw}",
            ),
            doc="marginal standard deviations, each in its parameter's unit",
        ),
        Field(
            f"{path}.correlation",
            "mapping",
            "a mapping of parameter pairs to ρ",
            '{"phase,fdot": -0.7} or [[phase, fdot, -0.7]]'
            if section == "lisa"
            else '{"period,pdot": -0.9} or [[period, pdot, -0.9]]',
            bounds=Range(
                -1.0,
                1.0,
                reason="a correlation coefficient",
                error="expected ρ in [-1, 1], got {raw}",
            ),
            doc="correlation coefficients between parameters of sigma (default 0)",
        ),
    )


def positive(reason: str) -> Range:
    """The open interval (0, inf) with its ``reason``."""
    return Range(low=0.0, low_open=True, reason=reason)
