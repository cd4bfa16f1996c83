"""The window on an observation's start (ESO p2, LCO): block start − acquisition ± k·σ_t."""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime, timedelta

from ucbplan.observing.exports.interface import ExportOptions

#: What a note on a minute-rounded window (ESO p2, Gemini) offers when the window no longer
#: fixes the orbital phase (docs/exports.md).
ROUNDING_REMEDY = (
    "plan exposures covering the window and select in `reduce`, or re-plan back to back with "
    "`service_mode` (no start phase to keep)"
)

# Time window on the OB start (ESO p2, LCO)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class ObStartWindow:
    """Window on an observation's start: the block start minus the acquisition, ± half-width.

    Attributes
    ----------
    ob_start : datetime
        Nominal OB start, t_start − acquisition (UTC).
    half_width_s : float
        max(k·σ_t, floor) [s].
    lo, hi : datetime
        ob_start ∓ half_width (UTC, µs resolution, not rounded).
    """

    ob_start: datetime
    half_width_s: float
    lo: datetime
    hi: datetime


def ob_start_window(
    start: datetime, acquisition: float, sigma_s: float, options: ExportOptions
) -> ObStartWindow:
    """Window on the OB start of a block starting at ``start`` (UTC).

    Parameters
    ----------
    start : datetime
        Block start (first exposure starts), UTC.
    acquisition : float
        Acquisition overhead before the first exposure [s].
    sigma_s : float
        1σ timing uncertainty of the block [s].
    options : ExportOptions
        ``tolerance_sigma`` (k) and ``tolerance_floor_s`` of the half-width max(k·σ_t, floor).
    """
    half = max(options.tolerance_sigma * sigma_s, options.tolerance_floor_s)
    ob_start = start - timedelta(seconds=acquisition)
    return ObStartWindow(
        ob_start=ob_start,
        half_width_s=half,
        lo=ob_start - timedelta(seconds=half),
        hi=ob_start + timedelta(seconds=half),
    )


def floor_minute(t: datetime) -> datetime:
    """``t`` rounded down to the whole minute (windows written to the minute widen outwards)."""
    return t.replace(second=0, microsecond=0)


def ceil_minute(t: datetime) -> datetime:
    """``t`` rounded up to the whole minute."""
    base = floor_minute(t)
    return base if base == t else base + timedelta(minutes=1)
