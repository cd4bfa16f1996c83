"""Fixed-u pairs: for each first epoch, the second epoch (same u★ = 0) that best measures Δκ_LISA.

Two epochs at the same argument of latitude see the same Keplerian velocity; what changes
between them is the eccentricity vector rotated by apsidal motion, Δκ_LISA (Eq.
delta_kappa_rewrite). The second night is the first observable one among the baselines with
|Δκ_LISA| ≥ 0.8 of its largest value inside T_valid, tried in order of decreasing |Δκ_LISA|.
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
from ucbplan.observing.blocks import Block
from ucbplan.observing.schedule.candidates import TargetRun
from ucbplan.observing.schedule.placement import Unplaced
from ucbplan.observing.schedule.records import slug
from ucbplan.observing.timeaxis import elapsed

if TYPE_CHECKING:
    from ucbplan.target import Target

__all__ = ["SecondEpoch", "delta_kappa", "pair_blocks"]

FloatArray = NDArray[np.float64]

#: Plans the single u★ = 0 block of one target on one night, clear of the blocks given (None if
#: nothing is observable there).
SecondEpoch = Callable[["Target", date, Sequence[Block]], Block | None]

#: Baselines considered: |Δκ_LISA| at least this fraction of its largest value inside T_valid.
_DK_FRACTION = 0.8

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


def _best_baselines(
    eta_a: float, kappa_a: float, omega_dot: float, max_days: int
) -> NDArray[np.int64]:
    """Baselines [whole days] with large |Δκ_LISA|, largest first (at most ``_MAX_TRIES``)."""
    days = np.arange(1, max_days + 1)
    dk = delta_kappa(eta_a, kappa_a, omega_dot * days * DAY_S)
    order = days[np.argsort(-np.abs(dk), kind="stable")]
    return np.asarray(order[np.abs(dk[order - 1]) >= _DK_FRACTION * np.abs(dk).max()][:_MAX_TRIES])


def _pair(
    n: int,
    first: Block,
    run: TargetRun,
    max_baseline_days: float,
    second_epoch: SecondEpoch,
    busy: Sequence[Block],
) -> tuple[list[Block], list[Unplaced]]:
    """Pair ``n`` (0-based): the first block with its second epoch clear of ``busy``, or the
    reason there is none."""
    t, p = run.target, run.target.params
    eta, kappa = ll_pair(p, np.array([run.cand.epochs.tau(first.t_mid_tdb_bary)]))
    eta_a, kappa_a = float(eta[0]), float(kappa[0])
    days_valid = elapsed(first.t_mid_tdb_bary, run.until, u.d)
    max_days = int(min(days_valid - 1, max_baseline_days))
    if max_days < 1:
        return [first], [Unplaced(t.name, first.night, "no second night inside T_valid")]
    good = _best_baselines(eta_a, kappa_a, p.omega_dot, max_days)
    night0 = date.fromisoformat(first.night)
    second = next(
        (
            b
            for d in good
            if (b := second_epoch(t, night0 + timedelta(days=int(d)), busy)) is not None
        ),
        None,
    )
    pair = f"{slug(t.name)}-P{n + 1:02d}"
    if second is None:
        reason = (
            f"no observable second epoch on the {good.size} nights with |Delta-kappa| "
            f">= {_DK_FRACTION:g} of its maximum inside T_valid"
        )
        return [replace(first, pair_id=pair)], [Unplaced(t.name, first.night, reason)]
    dt = elapsed(first.t_mid_tdb_bary, second.t_mid_tdb_bary)
    dk = float(delta_kappa(eta_a, kappa_a, np.array([p.omega_dot * dt]))[0])
    return [
        replace(first, pair_id=pair, delta_kappa=dk),
        replace(second, anchor="fixed-u-pairs", pair_id=pair, delta_kappa=dk),
    ], []


def pair_blocks(
    firsts: list[Block],
    runs: list[TargetRun],
    max_baseline_days: float,
    second_epoch: SecondEpoch,
) -> tuple[list[Block], list[Unplaced]]:
    """For each first epoch, the second epoch maximising |Δκ_LISA| inside T_valid.

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

    Returns
    -------
    blocks : list of Block
        Pairs (first, second) sharing a ``pair_id`` and their ``delta_kappa``; a first block
        without a partner stays alone.
    unplaced : list of Unplaced
        First blocks without a second epoch, and why.
    """
    out: list[Block] = []
    unplaced: list[Unplaced] = []
    by_name = {r.target.name: r for r in runs}
    seconds: list[Block] = []
    used = {b.block_id for b in firsts} | {b.session_id for b in firsts}
    for n, first in enumerate(firsts):
        run = by_name[first.target]
        busy = [*firsts, *seconds]
        blocks, missing = _pair(n, first, run, max_baseline_days, second_epoch, busy)
        blocks[1:] = [_renumbered(b, used) for b in blocks[1:]]
        out += blocks
        seconds += blocks[1:]
        unplaced += missing
    return out, unplaced


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
