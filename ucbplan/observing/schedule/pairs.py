"""Fixed-u pairs: for each first epoch, the second epoch (same u★ = 0) that best measures Δκ_LISA.

Two epochs at the same argument of latitude see the same Keplerian velocity; what changes
between them is the eccentricity vector rotated by apsidal motion, Δκ_LISA (Eq.
delta_kappa_rewrite). The second night is the first observable one among the baselines with
|Δκ_LISA| ≥ 0.8 of its largest value inside T_valid, tried in order of decreasing |Δκ_LISA|.
"""

from __future__ import annotations

from collections.abc import Callable
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

#: Plans the single u★ = 0 block of one target on one night (None if nothing is observable).
SecondEpoch = Callable[["Target", date], Block | None]

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
    n: int, first: Block, run: TargetRun, max_baseline_days: float, second_epoch: SecondEpoch
) -> tuple[list[Block], list[Unplaced]]:
    """Pair ``n`` (0-based): the first block with its second epoch, or the reason there is none."""
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
        (b for d in good if (b := second_epoch(t, night0 + timedelta(days=int(d)))) is not None),
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
        ``(target, night) -> Block or None``: plans the second epoch on one night.

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
    for n, first in enumerate(firsts):
        blocks, missing = _pair(n, first, by_name[first.target], max_baseline_days, second_epoch)
        out += blocks
        unplaced += missing
    return out, unplaced
