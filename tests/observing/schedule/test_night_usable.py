"""A run's usable candidates and reasons found for all its nights at once (issue 34): the same,
index for index and word for word, as one night at a time; the sky model's evaluations on
many windows at once are bit for bit those of each window on its own."""

from __future__ import annotations

from datetime import date, timedelta
from pathlib import Path

import numpy as np
import pytest

from ucbplan.observing.observatory.sites import get_site
from ucbplan.observing.schedule import plan_settings
from ucbplan.observing.schedule.candidates import prepare_runs
from ucbplan.observing.schedule.nights import night_spans, night_windows
from ucbplan.observing.schedule.placement import NightSun, at_once, night_usable
from ucbplan.targets import load_target

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]

ROOT = Path(__file__).resolve().parents[3]
HM = ROOT / "catalogs" / "hm-cnc-simulated.yaml"


@pytest.fixture(scope="module")
def planned(tmp_path_factory: pytest.TempPathFactory) -> tuple:
    """HM Cnc, and a copy at dec +80 that never rises at Paranal, over 12 nights."""
    polar = tmp_path_factory.mktemp("polar") / "polar.yaml"
    text = HM.read_text().replace('dec: "+15d27m30s"', 'dec: "+80d00m00s"')
    polar.write_text(text.replace("name: HM Cnc (simulated)", "name: Polar"))
    targets = [load_target(HM), load_target(polar)]
    site = get_site("paranal")
    settings = plan_settings(sigma_v_kms=5.0, k_eff_kms=400)
    windows = night_windows(site, [date(2040, 2, 10) + timedelta(days=k) for k in range(12)])
    frame, runs, _ = prepare_runs(targets, site, windows, settings)
    return frame, runs, settings, night_spans(windows, frame.axis)


def test_all_nights_at_once_are_each_night_alone(planned: tuple) -> None:
    frame, runs, settings, spans = planned
    sun = NightSun(frame, [(sp.x0, sp.x1) for sp in spans])
    kinds = set()
    for run in runs:
        for span in spans:
            alone = night_usable(run, span, frame, settings)  # this night's own Sun
            together = night_usable(run, span, frame, settings, sun)
            if isinstance(alone, str):
                assert together == alone
                kinds.add(alone.split(" ")[0])
            else:
                assert isinstance(together, np.ndarray) and together.dtype == alone.dtype
                assert together.tolist() == alone.tolist()
                kinds.add("usable")
    assert kinds == {"usable", "never"}  # both kinds of night compared


def test_sky_at_once_is_bit_for_bit_each_window(planned: tuple) -> None:
    frame = planned[0]
    sky = frame.sky
    rng = np.random.default_rng(34)
    x = np.sort(rng.uniform(0.0, frame.span_x[1], 3000))
    parts = np.split(x, np.sort(rng.choice(np.arange(1, x.size), 200, replace=False)))
    parts += [x[:1], x[5:7], x[:0]]  # one point, two, none
    for f in (
        sky.sun_alt_deg,
        lambda t: sky.target_alt_deg(1, t),
        lambda t: frame.constraints.night.ok(sky, 0, t),
    ):
        got = at_once(f, parts)
        assert len(got) == len(parts)
        for part, value in zip(parts, got, strict=True):
            assert value.tobytes() == np.asarray(f(part)).tobytes()


def test_session_partners_same_anchor_is_numpys_isclose() -> None:
    """The next block at the same anchor is skipped where u★ differs by 0 mod 2π within
    1e-6 rad: |·| <= 1e-6 is np.isclose(·, 0, atol=1e-6) (issue 34), at and around the edge,
    for NaN and the full turn."""
    from types import SimpleNamespace

    from ucbplan.core.constants import TWO_PI
    from ucbplan.observing.schedule.candidates import session_partners

    rng = np.random.default_rng(7)
    n = 4000
    x_start = np.sort(rng.uniform(0.0, 1e6, n))
    edge = [0.0, -0.0, 1e-6, -1e-6, np.nextafter(1e-6, 1.0), TWO_PI, np.nan, np.pi]
    u = np.concatenate([rng.choice(edge, n // 2), rng.normal(0.0, 2e-6, n - n // 2)])
    c = SimpleNamespace(
        x_start=x_start,
        x_mid=x_start,
        x_end=x_start + rng.uniform(0.0, 400.0, n),
        u_star=u,
        ok=rng.random(n) < 0.8,
        airmass_mid=rng.uniform(1.0, 2.0, n),
    )
    nxt, _, _ = session_partners(c, paired=True)  # type: ignore[arg-type]
    ref = np.minimum(np.searchsorted(c.x_start, c.x_end, side="left"), n - 1)
    with np.errstate(invalid="ignore"):
        same = np.isclose(np.mod(u[ref] - u, TWO_PI), 0.0, atol=1e-6)
    ref = np.minimum(np.where(same, ref + 1, ref), n - 1)
    assert 0 < same.sum() < n and np.array_equal(nxt, ref)
