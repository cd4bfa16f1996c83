"""Time-scale guards: epochs are TDB at the barycentre unless the user states otherwise."""

from __future__ import annotations

import re

from astropy.time import Time

from ucbplan.errors import UcbplanError

__all__ = ["parse_tdb"]

_LABEL = re.compile(r"^(.*?)\s*\(?\b(TDB|TCB|TT|UTC|TAI)\b\)?$", flags=re.IGNORECASE)


def parse_tdb(text: str, what: str = "epoch") -> Time:
    """Parse an ISO epoch (or ``MJD x`` / ``JD x``) as TDB.

    A trailing scale label (``UTC``, ``TT``, ``TCB``, ``TAI``) is an explicit statement of the
    scale, and the epoch is converted to TDB; an unlabelled epoch is taken as TDB.

    Raises
    ------
    UcbplanError
        If the text is not an epoch.
    """
    raw = text.strip()
    scale = "tdb"
    m = _LABEL.match(raw)
    if m:
        raw, scale = m.group(1).strip(), m.group(2).lower()
    try:
        if raw.upper().startswith("MJD"):
            t = Time(float(raw[3:]), format="mjd", scale=scale)
        elif raw.upper().startswith("JD"):
            t = Time(float(raw[2:]), format="jd", scale=scale)
        else:
            t = Time(raw, scale=scale)
    except (ValueError, TypeError):
        raise UcbplanError(
            f'{what}: expected an ISO epoch like "2040-01-15T00:00:00" (TDB; append UTC to '
            f"give UTC), got {text!r}"
        ) from None
    return t.tdb
