"""The body of an ESO p2 observation block: target, constraint set, description and templates.

The fields are those of p2's OB JSON (``GET /obsBlocks/{obId}``), so that :mod:`.eso_create` can
copy them into a new OB and save it with ``saveOB``:

- ``target``: ICRS coordinates as p2 writes them (``HH:MM:SS.SSS``, ``±DD:MM:SS.SS``), equinox
  J2000, epoch 2000.0 and proper motion [arcsec/yr] (0 unless the table has it: target files carry
  no proper motion; a note says so);
- ``constraints``: the plan's airmass limit and Moon distance (parsed from the table's
  ``constraints`` metadata, e.g. ``airmass <= 2.0``) and the seeing limit (``--seeing``);
- ``obsDescription``: the OB name and a comment with the block ids and UTC mid-times ± σ (cut
  with a mark when it exceeds p2's 1000 characters);
- ``templates``: the acquisition and the science exposures with the numbers the plan used
  (one science template per run of equal exposure times, its exposure count the run's length;
  a visit that waits between exposures gets one per block, to be started at its planned time
  in visitor mode) and, with ``--instrument``, that instrument's readout mode and overheads
  from its configuration (:mod:`ucbplan.observing.precision.instruments`). ESO's template names and
  keywords differ per instrument and instrument-package version and are not in that configuration:
  they come from the user's ``--eso-templates`` file (:mod:`.eso_templates`), which gives each
  template its ``name`` and ``eso_parameters`` (keyword → value, the block's exposure time and count
  included); without it the ``name`` is null and the templates are chosen in p2 (``--create`` then
  leaves them out).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from typing import Any

from ucbplan.observing.blocks.cells import sexagesimal
from ucbplan.observing.exports.eso_templates import EsoTemplate, EsoTemplates
from ucbplan.observing.exports.text import fmt_sigma
from ucbplan.observing.precision.instruments import Instrument, get_instrument

#: Airmass limit written when the plan names none (ESO's loosest common limit).
DEFAULT_MAX_AIRMASS = 2.0
#: Moon distance written when the plan names none [deg] (ESO's default constraint set).
DEFAULT_MOON_DISTANCE_DEG = 30.0
#: Longest ``obsDescription.userComments`` p2 stores [characters].
USER_COMMENTS_MAX = 1000

_AIRMASS = re.compile(r"airmass\s*<=?\s*([0-9]+(?:\.[0-9]*)?)", re.I)
_MOON = re.compile(r"moon\s+separation\s*>=?\s*([0-9]+(?:\.[0-9]*)?)", re.I)


def _first_match(pattern: re.Pattern[str], texts: Sequence[str]) -> float | None:
    for text in texts:
        m = pattern.search(text)
        if m:
            return float(m.group(1))
    return None


def eso_constraints(
    listed: Any, seeing_arcsec: float, name: str, notes: list[str]
) -> dict[str, Any]:
    """The p2 constraint set: airmass and Moon distance from the plan's constraint texts (their
    defaults with a note when the plan names none), seeing from the option."""
    texts = [x[:200] for x in listed if isinstance(x, str)] if isinstance(listed, list) else []
    airmass = _first_match(_AIRMASS, texts)
    moon = _first_match(_MOON, texts)
    if airmass is None or moon is None:
        notes.append(
            f"ESO p2: the plan names no {'airmass' if airmass is None else 'Moon'} limit: "
            f"constraint set uses airmass <= {DEFAULT_MAX_AIRMASS:g}, Moon distance >= "
            f"{DEFAULT_MOON_DISTANCE_DEG:g} deg where missing; edit them in p2 if needed"
        )
    return {
        "name": name,
        "airmass": airmass if airmass is not None else DEFAULT_MAX_AIRMASS,
        "moonDistance": round(moon if moon is not None else DEFAULT_MOON_DISTANCE_DEG),
        "seeing": seeing_arcsec,
    }


def instrument_for(name: str | None) -> Instrument | None:
    """The instrument configuration of ``--instrument NAME`` (None without one)."""
    if name is None:
        return None
    return get_instrument(name)


def _eso(template: EsoTemplate | None, exptime_s: float, n_exp: int) -> dict[str, Any]:
    if template is None:
        return {"name": None}
    return {"name": template.name, "eso_parameters": template.values(exptime_s, n_exp)}


def _templates(
    runs: Sequence[tuple[float, int]], instrument: Instrument | None, eso: EsoTemplates | None
) -> list[dict[str, Any]]:
    """The acquisition, then one science template per run of ``(exposure time [s], count)``."""
    acq_eso = _eso(eso.acquisition if eso else None, *runs[0])
    setup: dict[str, Any] = {}
    if instrument is not None:
        setup = {
            "instrument": instrument.name,
            "readout_mode": instrument.readout_mode,
            "readout_s": instrument.readout_s,
        }
    acq = {"acquisition_s": instrument.acquisition_s} if instrument is not None else {}
    return [
        {"type": "acquisition", **acq_eso, "parameters": acq},
        *(
            {
                "type": "science",
                **_eso(eso.science if eso else None, exptime_s, n_exp),
                "parameters": {"exposure_time_s": exptime_s, "n_exp": n_exp, **setup},
            }
            for exptime_s, n_exp in runs
        ),
    ]


def user_comments(members: Sequence[tuple[str, str, float]]) -> tuple[str, int]:
    """The ``userComments`` text of an OB's blocks (block id, UTC mid-time ISO, σ [s]) and how
    many blocks it lists: all of them, or, when p2's :data:`USER_COMMENTS_MAX` characters do not
    hold them, the first ones followed by a mark naming how many are left out and where they are
    (the OB's ``merged_visits`` in the export file)."""
    items = [f"{b} mid {t} UTC +/-{fmt_sigma(s)} s" for b, t, s in members]
    text = "ucbplan: " + "; ".join(items)
    if len(text) <= USER_COMMENTS_MAX:
        return text, len(items)
    for k in range(len(items) - 1, -1, -1):
        mark = (
            f"; [cut: {len(items) - k} more of {len(items)} blocks in merged_visits of the "
            "ucbplan export]"
        )
        text = "ucbplan: " + "; ".join(items[:k]) + mark
        if len(text) <= USER_COMMENTS_MAX:
            return text, k
    return text[:USER_COMMENTS_MAX], 0


def ob_body(
    *,
    ob_name: str,
    target_name: str,
    ra_deg: float,
    dec_deg: float,
    constraints: Mapping[str, Any],
    comment: str,
    runs: Sequence[tuple[float, int]],
    instrument: Instrument | None,
    eso_templates: EsoTemplates | None = None,
) -> dict[str, Any]:
    """One OB's p2 fields (see the module docstring).

    Parameters
    ----------
    comment : str
        ``userComments`` (:func:`user_comments`).
    runs : sequence of (exposure time [s], count)
        The science templates, each repeating its exposure ``count`` times.
    """
    return {
        "obsDescription": {"name": ob_name, "userComments": comment},
        "target": {
            "name": target_name,
            "ra": sexagesimal(ra_deg / 15.0, 3, ":", False),
            "dec": sexagesimal(dec_deg, 2, ":", True),
            "equinox": "J2000",
            "epoch": 2000.0,
            "properMotionRa": 0.0,
            "properMotionDec": 0.0,
        },
        "constraints": dict(constraints),
        "templates": _templates(runs, instrument, eso_templates),
    }
