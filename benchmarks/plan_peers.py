"""Peers of the plan-kernel benchmark (issue 14): naive astropy, and agreement with astroplan.

Both work on *sampled blocks*: for each target, some of the candidate blocks of
:func:`ucbplan.observing.schedule.candidate_blocks`, as UTC start, middle and end times together
with our accept/reject decision (the candidates' ``ok``).

* **naive astropy** is what a careful user with only astropy would write: per target, one batched
  ``AltAz`` transform (pressure 0, so geometric altitudes like ours) of the target, of
  ``get_sun`` and of ``get_body('moon')`` over all block start and end times, then nautical night,
  airmass and Moon separation at both ends of each block.
* **agreement**: the same blocks through astroplan's ``is_event_observable`` (block start and end,
  as the speed peer). astroplan's ``AtNightConstraint`` forces pressure 0, its
  ``AirmassConstraint`` reads ``secz`` of the observer's ``AltAz`` frame (an ``Observer``'s
  pressure defaults to 0: no refraction) and accepts 1 ≤ sec z ≤ max, as ours (alt > 0 and
  sec z ≤ max). One convention differs: ours accepts any Moon separation while the Moon is below
  the horizon; astroplan's ``MoonSeparationConstraint`` never looks at the Moon's altitude. The
  comparison applies our rule to astroplan's own quantities (``Observer.moon_altaz``) and counts
  separately the blocks that astroplan's unmodified result rejects only for that reason.
  Decisions must be identical except for blocks where a decisive quantity lies within the
  accuracy of our sky model of its limit (:data:`SKY_TOL_ARCSEC`, stated in
  :mod:`ucbplan.observing.observatory.sky`), judged with astropy's values at the block's start,
  middle and end (the samples of a 60 s block in
  :func:`ucbplan.observing.constraints.checks.evaluate_window`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from astropy import units as u
from astropy.coordinates import AltAz, EarthLocation, SkyCoord, get_body, get_sun
from astropy.time import Time
from numpy.typing import NDArray

from ucbplan.observing.constraints import ConstraintSet
from ucbplan.offline import offline

BoolArray = NDArray[np.bool_]
FloatArray = NDArray[np.float64]

#: Accuracy of our sky model against astropy's AltAz [arcsec]
#: (ucbplan/observing/observatory/sky.py): target and Sun altitudes 2″, the Moon (altitude and
#: separation) 10″.
SKY_TOL_ARCSEC = {"sun_alt": 2.0, "alt": 2.0, "moon_alt": 10.0, "moon_sep": 10.0}
#: Moon altitude [deg] below which our Moon-separation constraint always holds.
MOON_DOWN_DEG = 0.0


@dataclass(frozen=True)
class Sample:
    """Sampled blocks of one target: UTC start, middle and end, and our decision."""

    coord: SkyCoord
    start: Time
    mid: Time
    end: Time
    ok: BoolArray

    @property
    def size(self) -> int:
        """Number of blocks."""
        return int(self.ok.size)

    def pairs(self) -> Time:
        """(n, 2) start/end times, the ``times_ingress_egress`` of astroplan."""
        with offline():
            jd1 = np.stack([self.start.jd1, self.end.jd1], axis=1)
            jd2 = np.stack([self.start.jd2, self.end.jd2], axis=1)
            return Time(jd1, jd2, format="jd", scale="utc")

    def ends(self) -> Time:
        """All start times, then all end times (one flat array)."""
        with offline():
            jd1 = np.concatenate([self.start.jd1, self.end.jd1])
            jd2 = np.concatenate([self.start.jd2, self.end.jd2])
            return Time(jd1, jd2, format="jd", scale="utc")


def random_picks(sizes: Sequence[int], n_sample: int, seed: int) -> list[NDArray[np.int64]]:
    """Sorted random block indices per target, ``n_sample`` in all (the speed peers' sample)."""
    rng = np.random.default_rng(seed)
    per_target = max(n_sample // len(sizes), 1)
    out = []
    for n in sizes:
        pick = rng.choice(n, size=min(per_target, n), replace=False) if n else np.empty(0)
        out.append(np.sort(pick.astype(np.int64)))
    return out


def edge_picks(cands: Sequence[Any], per_target: int, seed: int) -> list[NDArray[np.int64]]:
    """Blocks whose decision differs from a neighbour's (next to a night, airmass or Moon limit:
    where disagreements would show), per target: every pair at a change decided by a constraint
    after the night and airmass (the Moon: rare), then a random choice up to ``per_target``."""
    rng = np.random.default_rng(seed)
    out = []
    for c, _ in cands:
        flip = np.flatnonzero(c.ok[1:] != c.ok[:-1])
        rare = (c.first_failed[flip] > 1) | (c.first_failed[flip + 1] > 1)
        keep = np.concatenate([flip[rare], flip[rare] + 1])
        rest = np.setdiff1d(np.concatenate([flip, flip + 1]), keep)
        room = max(per_target - keep.size, 0)
        if rest.size > room:
            rest = rng.choice(rest, size=room, replace=False)
        out.append(np.unique(np.concatenate([keep, rest])).astype(np.int64))
    return out


def make_samples(
    coords: Sequence[SkyCoord], cands: Sequence[Any], picks: Sequence[NDArray[np.int64]]
) -> list[Sample]:
    """:class:`Sample` of each target from its ``(Candidates, TimeAxis)`` and block indices."""
    out = []
    for k, ((c, axis), pick) in enumerate(zip(cands, picks, strict=True)):
        out.append(
            Sample(
                coord=coords[k],
                start=axis.utc(c.x_start[pick]),
                mid=axis.utc(c.x_mid[pick]),
                end=axis.utc(c.x_end[pick]),
                ok=np.asarray(c.ok[pick], dtype=bool),
            )
        )
    return out


def naive_quantities(
    location: EarthLocation, coord: SkyCoord, times: Time
) -> dict[str, FloatArray]:
    """Sun and target altitude, Moon altitude and Moon–target separation [deg] at ``times``:
    one ``AltAz`` frame (pressure 0: geometric), three transforms."""
    with offline():
        frame = AltAz(obstime=times, location=location)
        target = coord.transform_to(frame)
        sun = get_sun(times).transform_to(frame)
        moon = get_body("moon", times, location).transform_to(frame)
        return {
            "sun_alt": np.asarray(sun.alt.deg),
            "alt": np.asarray(target.alt.deg),
            "moon_alt": np.asarray(moon.alt.deg),
            "moon_sep": np.asarray(moon.separation(target).deg),
        }


def naive_accept(q: dict[str, FloatArray], cs: ConstraintSet, moon_down_ok: bool) -> BoolArray:
    """Night, airmass (1 ≤ sec z ≤ max) and Moon separation at each time; ``moon_down_ok``: also
    accept any separation while the Moon is below the horizon (our rule)."""
    assert cs.moon_sep is not None
    with np.errstate(divide="ignore"):
        secz = 1.0 / np.sin(np.radians(q["alt"]))
    ok = (q["sun_alt"] <= cs.night.sun_alt_max_deg) & (secz >= 1.0)
    ok &= secz <= cs.airmass.max_airmass
    moon = q["moon_sep"] >= cs.moon_sep.min_deg
    if moon_down_ok:
        moon |= q["moon_alt"] < MOON_DOWN_DEG
    return np.asarray(ok & moon)


def naive_blocks(location: EarthLocation, s: Sample, cs: ConstraintSet) -> BoolArray:
    """Naive-astropy decision per block: every constraint at its start and end."""
    ok = naive_accept(naive_quantities(location, s.coord, s.ends()), cs, moon_down_ok=False)
    return np.asarray(ok.reshape(2, s.size).all(axis=0))


def astroplan_constraints(cs: ConstraintSet) -> list[Any]:
    """astroplan's night, airmass and Moon-separation constraints with our limits."""
    from astroplan import AirmassConstraint, AtNightConstraint, MoonSeparationConstraint

    assert cs.moon_sep is not None
    return [
        AtNightConstraint(max_solar_altitude=cs.night.sun_alt_max_deg * u.deg),
        AirmassConstraint(max=cs.airmass.max_airmass),
        MoonSeparationConstraint(min=cs.moon_sep.min_deg * u.deg),
    ]


def astroplan_observer(location: EarthLocation, name: str) -> Any:
    """An astroplan ``Observer`` at ``location`` (pressure 0: no refraction)."""
    from astroplan import Observer

    return Observer(location=location, name=name)


def peer_rates(
    location: EarthLocation,
    samples: Sequence[Sample],
    cs: ConstraintSet,
    clock: Callable[[], float] = time.perf_counter,
) -> dict[str, float | None]:
    """Blocks/s of naive astropy and of astroplan's ``is_event_observable`` (block start and
    end, batched per target) on ``samples``, timed alternately target by target so that both
    see the same load; times are built outside the clock (``clock``: wall time by default,
    ``time.process_time`` for CPU seconds). astroplan: None if not installed."""
    try:
        from astroplan import is_event_observable
    except ImportError:
        is_event_observable = None
    observer = astroplan_observer(location, "site") if is_event_observable else None
    cons = astroplan_constraints(cs) if is_event_observable else []
    naive_s = astroplan_s = 0.0
    n = 0
    for s in samples:
        if s.size == 0:
            continue
        pairs = s.pairs()
        t0 = clock()
        naive_blocks(location, s, cs)
        t1 = clock()
        if is_event_observable is not None:
            with offline():
                is_event_observable(cons, observer, s.coord, times_ingress_egress=pairs)
        t2 = clock()
        naive_s, astroplan_s, n = naive_s + t1 - t0, astroplan_s + t2 - t1, n + s.size
    return {
        "astroplan": n / astroplan_s if is_event_observable is not None else None,
        "naive astropy": n / naive_s,
    }


def astroplan_blocks(observer: Any, s: Sample, cs: ConstraintSet) -> tuple[BoolArray, BoolArray]:
    """astroplan's decisions per block: ``is_event_observable`` as is, and with our Moon rule
    (the separation passes while the Moon is down). The rule can only rescue blocks that
    astroplan rejects with night and airmass met at both ends (its cached altitudes); for those
    each end is checked again: separation met or Moon below the horizon."""
    from astroplan import is_event_observable

    night, air, sep = astroplan_constraints(cs)
    pairs = s.pairs()
    with offline():
        plain = np.asarray(
            is_event_observable([night, air, sep], observer, s.coord, times_ingress_egress=pairs)
        ).ravel()
        rule = plain.copy()
        maybe = ~plain
        for t in (pairs[:, 0], pairs[:, 1]):
            maybe &= np.asarray(night(observer, s.coord, times=t)).ravel()
            maybe &= np.asarray(air(observer, s.coord, times=t)).ravel()
        idx = np.flatnonzero(maybe)
        if idx.size:
            rule[idx] = True
            for t in (pairs[idx, 0], pairs[idx, 1]):
                down = np.asarray(observer.moon_altaz(t).alt.deg < MOON_DOWN_DEG).ravel()
                rule[idx] &= np.asarray(sep(observer, s.coord, times=t)).ravel() | down
    return plain, rule


def three_point_quantities(location: EarthLocation, s: Sample) -> dict[str, FloatArray]:
    """:func:`naive_quantities` at each block's start, middle and end, shape (3, n)."""
    with offline():
        times = Time(
            np.concatenate([s.start.jd1, s.mid.jd1, s.end.jd1]),
            np.concatenate([s.start.jd2, s.mid.jd2, s.end.jd2]),
            format="jd",
            scale="utc",
        )
    q = naive_quantities(location, s.coord, times)
    return {k: v.reshape(3, s.size) for k, v in q.items()}


def limit_margins(q: dict[str, FloatArray], cs: ConstraintSet) -> dict[str, FloatArray]:
    """Distance [arcsec] of each decisive quantity in ``q`` from its limit (same shapes)."""
    assert cs.moon_sep is not None
    limits = {
        "sun_alt": cs.night.sun_alt_max_deg,
        "alt": float(np.degrees(np.arcsin(1.0 / cs.airmass.max_airmass))),
        "moon_alt": MOON_DOWN_DEG,
        "moon_sep": cs.moon_sep.min_deg,
    }
    return {k: np.abs(q[k] - limit) * 3600.0 for k, limit in limits.items()}


def near_limit(margins: dict[str, FloatArray]) -> BoolArray:
    """Blocks where, at any sampled time (axis 0), a decisive quantity lies within
    :data:`SKY_TOL_ARCSEC` of its limit."""
    near = np.zeros(margins["alt"].shape, dtype=bool)
    for key, m in margins.items():
        near |= m < SKY_TOL_ARCSEC[key]
    return np.asarray(near.any(axis=0))


@dataclass(frozen=True)
class Agreement:
    """Our decisions against astroplan's on the same blocks.

    Attributes
    ----------
    n : int
        Blocks compared.
    accepted : int
        Blocks we accept.
    outside : int
        Disagreements (astroplan with our Moon rule) with no quantity near a limit: must be 0.
    inside : int
        Disagreements with a decisive quantity within the sky model's accuracy of its limit.
    moon_down : int
        Blocks astroplan's unmodified ``is_event_observable`` rejects and our rule accepts (the
        Moon below the horizon, closer than the separation limit).
    naive_outside : int
        The same count as ``outside`` for naive astropy with our Moon rule.
    closest : dict
        Smallest distance [arcsec] of each decisive quantity from its limit over the blocks
        (how hard the comparison was).
    """

    n: int
    accepted: int
    outside: int
    inside: int
    moon_down: int
    naive_outside: int
    closest: dict[str, float]


def agreement(location: EarthLocation, samples: Sequence[Sample], cs: ConstraintSet) -> Agreement:
    """Compare our decisions with astroplan's (and naive astropy's) on ``samples``."""
    observer = astroplan_observer(location, "site")
    n = accepted = outside = inside = moon_down = naive_out = 0
    closest = dict.fromkeys(SKY_TOL_ARCSEC, np.inf)
    for s in samples:
        if s.size == 0:
            continue
        plain, ap = astroplan_blocks(observer, s, cs)
        q = three_point_quantities(location, s)
        ends = {k: v[[0, 2]] for k, v in q.items()}
        naive = naive_accept(ends, cs, moon_down_ok=True).all(axis=0)
        margins = limit_margins(q, cs)
        near = near_limit(margins)
        closest = {k: min(closest[k], float(margins[k].min())) for k in closest}
        differ = s.ok != ap
        n, accepted = n + s.size, accepted + int(s.ok.sum())
        outside += int(np.sum(differ & ~near))
        inside += int(np.sum(differ & near))
        moon_down += int(np.sum(ap & ~plain))
        naive_out += int(np.sum((s.ok != naive) & ~near))
    return Agreement(n, accepted, outside, inside, moon_down, naive_out, closest)
