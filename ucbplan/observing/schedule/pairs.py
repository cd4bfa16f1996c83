"""Fixed-u pairs: for each first epoch, the second epoch (same u★ = 0) that best measures Δκ_LISA.

Two epochs at the same argument of latitude see the same Keplerian velocity; what changes
between them is the eccentricity vector rotated by apsidal motion, Δκ_LISA (Eq.
delta_kappa_rewrite). The second epoch is searched on the requested nights only, after the first
and inside T_valid, in order of decreasing |Δκ_LISA|; the first observable one is planned. When
the best baselines (|Δκ_LISA| ≥ 0.8 of its largest value inside T_valid, the apsidal maximum)
fall outside the nights given, the best pair inside is planned and its |Δκ_LISA| is reported as a
fraction of that optimum. A target without apsidal signal (circular orbit, ω̇ = 0) cannot be
planned as pairs: it is reported, and the other targets are planned.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from datetime import date, timedelta
from typing import TYPE_CHECKING

import numpy as np
from astropy import units as u
from numpy.typing import NDArray

from ucbplan.core.constants import DAY_S
from ucbplan.core.ephemeris import ll_pair
from ucbplan.observing.blocks.block import Block
from ucbplan.observing.observatory.time_axis import elapsed
from ucbplan.observing.schedule.candidates import TargetRun
from ucbplan.observing.schedule.placement import Unplaced
from ucbplan.observing.schedule.records import slug

if TYPE_CHECKING:
    from ucbplan.targets import Target

FloatArray = NDArray[np.float64]

#: Plans the single u★ = 0 block of one target on one night, clear of the blocks given (None if
#: nothing is observable there).
SecondEpoch = Callable[["Target", date, Sequence[Block]], Block | None]

#: Baselines with |Δκ_LISA| at least this fraction of its largest value inside T_valid count as
#: optimal; a pair below it is reported with its fraction of the optimum.
DK_FRACTION = 0.8

#: At most this many candidate nights are planned for the second epoch.
_MAX_TRIES = 12


def delta_kappa(eta_a: float, kappa_a: float, theta: NDArray[np.floating]) -> FloatArray:
    """Δκ_LISA = −2 sin(Θ/2)[κ_α sin(Θ/2) + η_α cos(Θ/2)], Θ = ω̇ ΔT.

    Notes
    -----
    Eq. delta_kappa_rewrite; |Δκ| ≤ 2e, nulls at Θ = 2πm and at ω_α + Θ/2 = mπ (the apsidal nulls
    of Fig. apsidal_signal_omega1_dependence).
    """
    h = np.asarray(theta, dtype=np.float64) / 2.0
    return np.asarray(-2.0 * np.sin(h) * (kappa_a * np.sin(h) + eta_a * np.cos(h)))


def pair_infeasible_reason(target: Target) -> str | None:
    """Why ``target`` cannot be planned as fixed-u pairs (Δκ_LISA ≡ 0), or None if it can."""
    p = target.params
    if p.omega_dot != 0.0 and p.eccentricity != 0.0:
        return None
    return (
        "Delta-kappa_LISA is 0 (circular orbit or no apsidal motion), so fixed-u pairs would "
        "only measure Delta-v_CM: plan it with --mode quadrature or u=VALUE"
    )


def pair_targets(targets: Sequence[Target], night: str) -> tuple[list[Target], list[Unplaced]]:
    """Targets that can be planned as fixed-u pairs, and the others reported (on ``night``)."""
    ok: list[Target] = []
    out: list[Unplaced] = []
    for t in targets:
        why = pair_infeasible_reason(t)
        if why is None:
            ok.append(t)
        else:
            out.append(Unplaced(t.name, night, why))
    return ok, out


def _baselines(night0: date, nights: Sequence[date], max_days: int) -> NDArray[np.int64]:
    """Baselines [whole days] from ``night0`` to the requested nights after it, ≤ ``max_days``."""
    days = sorted({(n - night0).days for n in nights})
    return np.asarray([d for d in days if 1 <= d <= max_days], dtype=np.int64)


def _ranked(
    eta_a: float, kappa_a: float, omega_dot: float, max_days: int, offered: NDArray[np.int64]
) -> tuple[NDArray[np.int64], float]:
    """Offered baselines by decreasing |Δκ_LISA| (at most ``_MAX_TRIES``) and the optimum
    max |Δκ_LISA| over every whole-day baseline inside T_valid."""
    all_days = np.arange(1, max_days + 1)
    best = float(np.abs(delta_kappa(eta_a, kappa_a, omega_dot * all_days * DAY_S)).max())
    dk = np.abs(delta_kappa(eta_a, kappa_a, omega_dot * offered * DAY_S))
    return offered[np.argsort(-dk, kind="stable")][:_MAX_TRIES], best


def _pair(
    n: int,
    first: Block,
    run: TargetRun,
    nights: Sequence[date],
    max_baseline_days: float,
    second_epoch: SecondEpoch,
    busy: Sequence[Block],
) -> tuple[list[Block], list[Unplaced], float | None]:
    """Pair ``n`` (0-based): the first block with its second epoch clear of ``busy`` (or the
    reason there is none) and the pair's |Δκ_LISA| as a fraction of the optimum."""
    t, p = run.target, run.target.params
    eta, kappa = ll_pair(p, np.array([run.cand.epochs.tau(first.t_mid_tdb_bary)]))
    eta_a, kappa_a = float(eta[0]), float(kappa[0])
    days_valid = elapsed(first.t_mid_tdb_bary, run.until, u.d)
    max_days = int(min(days_valid - 1, max_baseline_days))
    night0 = date.fromisoformat(first.night)
    offered = _baselines(night0, nights, max_days)
    pair = f"{slug(t.name)}-P{n + 1:02d}"
    if offered.size == 0:
        why = "no later night among the nights given inside T_valid for the second epoch"
        return [], [_dropped(pair, first, why)], None
    order, best = _ranked(eta_a, kappa_a, p.omega_dot, max_days, offered)
    second = next(
        (
            b
            for d in order
            if (b := second_epoch(t, night0 + timedelta(days=int(d)), busy)) is not None
        ),
        None,
    )
    if second is None:
        why = f"no observable second epoch on the {order.size} best later nights given"
        return [], [_dropped(pair, first, why)], None
    dt = elapsed(first.t_mid_tdb_bary, second.t_mid_tdb_bary)
    dk = float(delta_kappa(eta_a, kappa_a, np.array([p.omega_dot * dt]))[0])
    blocks = [
        replace(first, pair_id=pair, delta_kappa=dk),
        replace(second, anchor="fixed-u-pairs", pair_id=pair, delta_kappa=dk),
    ]
    return blocks, [], abs(dk) / best if best > 0.0 else None


def _dropped(pair: str, first: Block, why: str) -> Unplaced:
    """A pair left out whole: a fixed-u pair needs both epochs (Δκ is their difference)."""
    when = first.t_mid_utc.isot[:19].replace("T", " ")
    return Unplaced(
        first.target,
        first.night,
        f"pair {pair} dropped (first epoch {when} UTC not planned alone): {why}",
    )


def _fraction_notes(fractions: dict[tuple[str, str], list[float]]) -> list[Unplaced]:
    """One note per target and first night whose pairs fall below :data:`DK_FRACTION`."""
    out = []
    for (name, night), fr in fractions.items():
        worst = min(fr)
        span = (
            f"{worst:.2f}" if f"{worst:.2f}" == f"{max(fr):.2f}" else f"{worst:.2f}-{max(fr):.2f}"
        )
        if worst < DK_FRACTION:
            out.append(
                Unplaced(
                    name,
                    night,
                    f"the best baseline (apsidal maximum of |Delta-kappa_LISA|) is outside the "
                    f"nights given; planned the best pairs inside: |Delta-kappa_LISA| = "
                    f"{span} of the optimum (add later nights to reach it)",
                )
            )
    return out


def _requested(firsts: Sequence[Block]) -> list[date]:
    """Consecutive nights from the first to the last night holding a first block."""
    days = sorted({date.fromisoformat(b.night) for b in firsts})
    if not days:
        return []
    return [days[0] + timedelta(days=k) for k in range((days[-1] - days[0]).days + 1)]


def pair_blocks(
    firsts: list[Block],
    runs: list[TargetRun],
    max_baseline_days: float,
    second_epoch: SecondEpoch,
    nights: Sequence[date] | None = None,
) -> tuple[list[Block], list[Unplaced]]:
    """For each first epoch, the second epoch on a requested night maximising |Δκ_LISA|.

    Parameters
    ----------
    firsts : list of Block
        The placed u★ = 0 blocks.
    runs : list of TargetRun
        The targets' runs (validity, epoch axes).
    max_baseline_days : float
        Longest baseline searched [d].
    second_epoch : callable
        ``(target, night, busy) -> Block or None``: plans the second epoch on one night, clear
        of the blocks ``busy`` (every first block and the second epochs chosen so far).
    nights : sequence of date, optional
        The requested nights; second epochs are planned on these only. Default: the consecutive
        nights from the first to the last night holding a first block.

    Returns
    -------
    blocks : list of Block
        Pairs (first, second) sharing a ``pair_id`` and their ``delta_kappa``; a first block
        without a partner is dropped with its pair (both epochs or neither). Block and session
        ids are unique.
    unplaced : list of Unplaced
        Pairs dropped for want of a second epoch (which, and why), targets without apsidal
        signal, and (per target and first night) pairs whose |Δκ_LISA| is below
        :data:`DK_FRACTION` of the optimum inside T_valid, with that fraction.
    """
    requested = list(nights) if nights is not None else _requested(firsts)
    by_name = {r.target.name: r for r in runs}
    bad = {r.target.name: why for r in runs if (why := pair_infeasible_reason(r.target))}
    unplaced = [Unplaced(name, firsts[0].night if firsts else "", why) for name, why in bad.items()]
    firsts = [b for b in firsts if b.target not in bad]
    out: list[Block] = []
    seconds: list[Block] = []
    fractions: dict[tuple[str, str], list[float]] = {}
    used = {b.block_id for b in firsts} | {b.session_id for b in firsts}
    for n, first in enumerate(firsts):
        busy = [*firsts, *seconds]
        blocks, missing, frac = _pair(
            n, first, by_name[first.target], requested, max_baseline_days, second_epoch, busy
        )
        blocks[1:] = [_renumbered(b, used) for b in blocks[1:]]
        out += blocks
        seconds += blocks[1:]
        unplaced += missing
        if frac is not None:
            fractions.setdefault((first.target, first.night), []).append(frac)
    return out, unplaced + _fraction_notes(fractions)


def _renumbered(block: Block, used: set[str]) -> Block:
    """``block`` with the next free ``-NN`` / ``-SNN`` numbers of its target and night.

    A second epoch is planned alone on its night, so it is numbered 01 there; another block of
    the run may already hold that identifier.
    """
    prefix = block.block_id.rsplit("-", 1)[0]
    k = 1
    while f"{prefix}-{k:02d}" in used or f"{prefix}-S{k:02d}" in used:
        k += 1
    block_id, session_id = f"{prefix}-{k:02d}", f"{prefix}-S{k:02d}"
    used.update((block_id, session_id))
    return replace(block, block_id=block_id, session_id=session_id)
