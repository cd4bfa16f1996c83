"""Vectorised blocks-table and visit code against the per-element way (issue 14).

Each vectorised function is compared with a reference that works one element at a time with
astropy scalars (what the code did before), on inputs chosen for the edge cases: DST changes in
three zones, times whose stored Julian-date split is not astropy's normal one, microsecond
rounding at a second boundary, a leap second, visits given out of time order with equal ends.
Equality is exact (tolerance 0): outputs are promised byte-identical.
"""

from __future__ import annotations

import io
import random
from datetime import UTC, datetime, timedelta
from zoneinfo import ZoneInfo

import astropy.units as u
import numpy as np
import pytest
from astropy.table import MaskedColumn, Table
from astropy.time import Time, TimeDelta

from ucbplan.observing.blocks import accounting
from ucbplan.observing.blocks import cells as tableformat
from ucbplan.observing.blocks import ecsv_header as ecsvheader
from ucbplan.observing.blocks import make as tablemake
from ucbplan.observing.blocks import write as tablewrite
from ucbplan.observing.blocks.accounting import visit_summaries
from ucbplan.observing.blocks.arrays import jd_parts, time_array
from ucbplan.observing.blocks.block import Block
from ucbplan.observing.blocks.cells import local_datetimes
from ucbplan.observing.blocks.write import table_to_json_rows, write_table
from ucbplan.offline import offline

pytestmark = pytest.mark.filterwarnings("ignore::erfa.ErfaWarning")

ZONES = ("Europe/Madrid", "America/Santiago", "Pacific/Auckland")


def _transitions(zone: str, year: int) -> list[datetime]:
    """UTC instants (to the second) at which ``zone`` changes its offset in ``year``."""
    tz = ZoneInfo(zone)
    out = []
    t = datetime(year, 1, 1, tzinfo=UTC)
    while t.year == year:
        nxt = t + timedelta(hours=1)
        if t.astimezone(tz).utcoffset() != nxt.astimezone(tz).utcoffset():
            lo, hi = t, nxt
            while hi - lo > timedelta(seconds=1):
                mid = lo + (hi - lo) / 2
                same = mid.astimezone(tz).utcoffset() == lo.astimezone(tz).utcoffset()
                lo, hi = (mid, hi) if same else (lo, mid)
            out.append(hi)
        t = nxt
    return out


def _scalars(iso: list[str], scale: str = "utc") -> list[Time]:
    """Scalar Times cut from one array Time, as the planner makes the blocks' times."""
    with offline():
        times = Time(iso, scale=scale)
    return [times[i] for i in range(len(times))]


def _dst_times(zone: str) -> list[Time]:
    """Times every 7 min 13.4 s over ±2 h around each 2040 DST change of ``zone``, and the
    last whole second before and the first after each change."""
    iso = []
    for change in _transitions(zone, 2040):
        for k in range(-17, 18):
            iso.append((change + k * timedelta(seconds=433.4)).strftime("%Y-%m-%dT%H:%M:%S.%f"))
        for s in (-1, 0, 1):
            iso.append((change + timedelta(seconds=s)).strftime("%Y-%m-%dT%H:%M:%S"))
    return _scalars(iso)


def _reference_local(times: list[Time], zones: list[str]) -> list[datetime]:
    """The per-element way: one astropy ``to_datetime`` per time."""
    return [
        t.utc.to_datetime(timezone=UTC).astimezone(ZoneInfo(z))
        for t, z in zip(times, zones, strict=True)
    ]


def test_dst_changes_found_in_each_zone() -> None:
    # Madrid: the EU rule, last Sundays of March and October at 01:00 UTC
    assert _transitions("Europe/Madrid", 2040) == [
        datetime(2040, 3, 25, 1, tzinfo=UTC),
        datetime(2040, 10, 28, 1, tzinfo=UTC),
    ]
    assert all(len(_transitions(z, 2040)) == 2 for z in ZONES)


@pytest.mark.parametrize("zone", ZONES)
def test_local_times_across_dst_match_per_element(zone: str) -> None:
    times = _dst_times(zone)
    zones = [zone] * len(times)
    with offline():
        got = local_datetimes(times, zones)
        ref = _reference_local(times, zones)
        got_iso = tableformat.local_iso(times, zones)
    assert got == ref
    assert [d.utcoffset() for d in got] == [d.utcoffset() for d in ref]
    assert list(got_iso) == [d.isoformat(timespec="seconds") for d in ref]
    assert len({d.utcoffset() for d in got}) == 2  # both sides of every change are sampled


def test_local_times_known_madrid_offsets() -> None:
    # 2040-03-25 01:00 UTC: CET (+01:00) becomes CEST (+02:00); independent of astropy
    times = _scalars(["2040-03-25T00:59:59", "2040-03-25T01:00:00"])
    with offline():
        got = tableformat.local_iso(times, ["Europe/Madrid"] * 2)
    assert list(got) == ["2040-03-25T01:59:59+01:00", "2040-03-25T03:00:00+02:00"]


def test_local_times_mixed_zones_and_rounding_carry() -> None:
    # 0.4 µs before a second rounds up to it (astropy's µs datetime), carrying into the date
    iso = ["2040-12-31T23:59:59.9999996", "2040-06-30T11:59:59.9999994", "2040-01-01T12:00:00"]
    times = _scalars(iso)
    zones = ["Pacific/Auckland", "America/Santiago", "Europe/Madrid"]
    with offline():
        assert local_datetimes(times, zones) == _reference_local(times, zones)
    assert local_datetimes([], []) == []


def _unnormalised() -> list[Time]:
    """UTC times stored with jd1 one day early and jd2 > 1 (the same instants, not the split
    ``Time(jd1, jd2)`` makes; astropy itself always re-splits, a future version might not)."""
    with offline():
        utc = Time(
            np.full(4, 2465000.0), np.array([-0.49999, 0.1, 0.4999, 0.5]), format="jd", scale="utc"
        )
    utc._time.jd1 = utc._time.jd1 - 1.0
    utc._time.jd2 = utc._time.jd2 + 1.0
    return [utc[i] for i in range(len(utc))]


def test_time_array_keeps_the_stored_split() -> None:
    times = _unnormalised()
    jd1, jd2 = jd_parts(times)
    assert np.all(np.abs(jd2) > 0.5)  # the case the fallback exists for
    with offline():
        arr = time_array(times, "utc")
        assert np.array_equal(arr.jd1, jd1) and np.array_equal(arr.jd2, jd2)
        assert list(arr.isot) == [t.isot for t in times]
        assert local_datetimes(times, ["Europe/Madrid"] * 4) == _reference_local(
            times, ["Europe/Madrid"] * 4
        )
        tdb = _scalars(["2040-02-16T02:03:12.123456"], "tdb")
        assert time_array(tdb, "utc").isot[0] == tdb[0].utc.isot  # converted like .utc


def test_leap_second_is_refused_as_before() -> None:
    times = _scalars(["2016-12-31T23:59:60.5"])
    with offline(), pytest.raises(ValueError, match="leap second"):
        local_datetimes(times, ["UTC"])


def test_iso_columns_match_per_element() -> None:
    times = [*_dst_times("Europe/Madrid")[:10], *_unnormalised(), None]
    has = np.array([t is not None for t in times])
    with offline():
        filled = [t if t is not None else times[0] for t in times]
        got = tableformat.iso_column(time_array(filled, "utc"), has, 3)
        ref = [
            "" if t is None else Time(t.utc.jd1, t.utc.jd2, format="jd", precision=3).isot
            for t in times
        ]
        tdb = tableformat.iso_column(time_array(times[:-1], "tdb"), None, 6)
        ref_tdb = [Time(t.tdb.jd1, t.tdb.jd2, format="jd", precision=6).isot for t in times[:-1]]
    assert list(got) == ref and list(tdb) == ref_tdb


def _visit_block(target: str, visit: str, start: Time, n_exp: int, k: int) -> Block:
    with offline():
        end = start + (n_exp * 60.0 + (n_exp - 1) * 7.5) * u.s
        mid = start + (end - start) / 2
    return Block(
        target=target, block_id=f"{target}-{k:02d}", anchor="quadrature", u_star_rad=0.0,
        t_mid_utc=mid, t_start_utc=start, t_end_utc=end, t_mid_tdb_bary=mid.tdb,
        sigma_t_s=1.0, t_alt_utc=None, exptime_s=60.0, n_exp=n_exp, readout_s=7.5,
        lambda_k=0.95, lambda_kappa=0.8, smear_kms=1.0, alt_start_deg=50.0, altitude_deg=51.0,
        alt_end_deg=52.0, airmass_start=1.3, airmass=1.29, airmass_end=1.28, moon_sep_deg=90.0,
        moon_illum=0.5, ra_deg=120.0, dec_deg=15.0, night="2040-03-24",
        timezone="Europe/Madrid", period_s=321.5, visit_id=visit,
    )  # fmt: skip


def _visit_blocks() -> list[Block]:
    """Two targets' visits out of time order, blocks without a visit, equal visit ends."""
    rng = random.Random(3)
    base = _dst_times("Europe/Madrid")[:30]
    blocks = []
    for k, start in enumerate(base):
        target = "A" if k % 3 else "B Cnc"
        visit = "" if k % 7 == 0 else f"{target}-V{k % 4:02d}"
        blocks.append(_visit_block(target, visit, start, 1 + k % 3, k))
    blocks.append(_visit_block("A", "A-V01", base[5], 3, 99))  # same start as another
    rng.shuffle(blocks)
    return blocks


def _reference_visits(blocks: list[Block], acq_s: float, trailing: bool) -> list[tuple]:
    """The per-visit way: scalar astropy arithmetic on each visit's first and last block."""
    groups: dict[tuple[str, str], list[Block]] = {}
    for k, b in enumerate(blocks):
        groups.setdefault((b.target, b.visit_id or f"#{k}"), []).append(b)
    out = []
    for (_, vid), bs in groups.items():
        bs = sorted(bs, key=lambda b: (b.t_start_utc.jd1, b.t_start_utc.jd2))
        start, end = bs[0].t_start_utc, max((b.t_end_utc for b in bs), key=lambda t: t.jd)
        drop = 0 if trailing else 1
        readout = float(sum((b.n_exp - drop) * b.readout_s for b in bs))
        span = float((end - start).to_value("s")) + (bs[-1].readout_s if trailing else 0.0)
        shutter = float(sum(b.n_exp * b.exptime_s for b in bs))
        acq = start - TimeDelta(acq_s, format="sec")
        wall = acq_s + span
        iso = [Time(t, precision=0).utc.isot for t in (acq, start, end)]
        idle = max(0.0, wall - shutter - (acq_s + readout))
        out.append(
            (vid if not vid.startswith("#") else "", bs[0].target, bs[0].night, *iso,
             sum(b.n_exp for b in bs), shutter, acq_s + readout, idle)
        )  # fmt: skip
    return sorted(out, key=lambda v: v[3])


@pytest.mark.parametrize("trailing", [False, True])
def test_visit_summaries_match_per_visit_reference(trailing: bool) -> None:
    blocks = _visit_blocks()
    with offline():
        got = visit_summaries(blocks, 300.0, trailing)
        ref = _reference_visits(blocks, 300.0, trailing)
    fields = [
        (v.visit_id, v.target, v.night, v.acq_start_utc, v.start_utc, v.end_utc, v.exposures,
         v.shutter_s, v.overhead_s, v.idle_s)
        for v in got
    ]  # fmt: skip
    assert fields == ref
    assert visit_summaries([], 300.0, trailing) == []


def test_plan_run_computes_visits_once(monkeypatch: pytest.MonkeyPatch) -> None:
    from ucbplan.observing.schedule import run as run_module
    from ucbplan.observing.schedule.run import PlanRun

    calls = []

    def counting(*args: object) -> accounting.VisitColumns:
        calls.append(args)
        return accounting.visit_columns(*args)  # type: ignore[arg-type]

    monkeypatch.setattr(run_module, "visit_columns", counting)
    settings = type("S", (), {"visit_s": None, "overhead_s": 300.0, "plans_visits": False})()
    result = type("R", (), {"blocks": _visit_blocks()})()
    run = PlanRun([], None, [], settings, result)  # type: ignore[arg-type]
    first = run.visits()
    first.clear()  # a caller's list is its own
    assert run.visits() == run.visits() != []
    run.accounting()
    assert len(calls) == 1


def _random_meta(rng: random.Random, alphabet: str, depth: int = 0) -> object:
    kind = rng.random()
    if depth < 3 and kind < 0.2:
        return {
            "".join(rng.choice(alphabet) for _ in range(rng.randint(1, 40))) or "k": (
                _random_meta(rng, alphabet, depth + 1)
            )
            for _ in range(rng.randint(0, 4))
        }
    if depth < 3 and kind < 0.35:
        return [_random_meta(rng, alphabet, depth + 1) for _ in range(rng.randint(0, 4))]
    if kind < 0.5:
        return rng.choice([0, -3, 2**70, True, None, 0.1, 1e17, float("nan"), float("inf")])
    return "".join(rng.choice(alphabet) for _ in range(rng.choice([0, 1, 5, 40, 140, 300])))


def _pyyaml_ecsv(table: Table) -> str:
    buf = io.StringIO()
    table.write(buf, format="ascii.ecsv")  # astropy's own writer (PyYAML's emitter)
    return buf.getvalue()


def _ours(table: Table, fmt: str = "ecsv") -> str:
    buf = io.StringIO()
    write_table(table, buf, fmt)
    return buf.getvalue()


@pytest.mark.parametrize("seed", range(40))
def test_ecsv_header_bytes_as_astropy_writes_them(seed: int) -> None:
    rng = random.Random(seed)
    ascii_text = "abcXYZ019 _-.:,#'\"!&*?|>%@`[]{}=+/\\~" + "  "
    other = ascii_text + "\n\té σΛ★\x85\u2028\ufeff"
    alphabet = ascii_text if seed % 2 else other  # odd seeds: libyaml, even: mostly not
    meta = {f"key{k}": _random_meta(rng, alphabet) for k in range(rng.randint(1, 6))}
    if seed % 4 == 0:
        meta[""] = "empty key"  # libyaml writes empty keys otherwise than PyYAML
    table = Table({"a": [1.5, float("nan")], "b": ["x y", ""]}, meta=meta)
    table["a"].unit = "km / s"
    table["a"].description = "a speed: the 'fast' one"
    assert ecsvheader.header_safe(table) == bool(seed % 2)
    assert _ours(table) == _pyyaml_ecsv(table)


def _random_visit(rng: random.Random, alphabet: str) -> dict[object, object]:
    """A visit record: mostly a plan's keys and plain values, sometimes (one in seven) a key or
    value of another kind or text of ``alphabet``."""
    keys: list[object] = ["visit_id", "target", "night", "exposures", "shutter_s"]
    plain = ["UCB03-20400101-V01", "2040-01-02", 1, 2.5, -0.0, "HM Cnc", "a_b-c.d"]
    odd = [float("nan"), True, None, np.float64(1.5), "", "x: y", "'q'"]
    odd.append("".join(rng.choice(alphabet) for _ in range(rng.randint(1, 12))))
    if rng.random() < 6 / 7:
        return {k: rng.choice(plain) for k in keys}
    keys[rng.randrange(len(keys))] = rng.choice([1, 2.5, None, "", "a b", "é", "k"])
    return {k: rng.choice(plain + odd) for k in keys}


@pytest.mark.parametrize("seed", range(30))
def test_plan_visits_and_reasons_of_any_kind_as_astropy_writes_them(seed: int) -> None:
    """A plan's ``visits`` and ``not_planned`` are written apart only when their own paths know
    every value; otherwise (keys that do not sort, text libyaml writes otherwise, NaN, numpy
    scalars) the header is written as astropy writes it."""
    rng = random.Random(seed)
    alphabet = "abcXYZ019 _-.:'" + ("" if seed % 3 else "é\n\x85")
    visits = [_random_visit(rng, alphabet) for _ in range(rng.randint(1, 12))]
    why = rng.choice(["never up", "", "a: b", "é", 3, "moon"])
    reasons = {"T": {"2040-01-01": {why: rng.choice([1, 2.5, "x", None])}}}
    meta = {"visits": visits, "not_planned": reasons, "other": _random_meta(rng, alphabet)}
    table = Table({"a": [1.5, 2.0]}, meta=meta)
    assert _ours(table) == _pyyaml_ecsv(table)


@pytest.mark.parametrize("seed", range(20))
def test_visit_lists_checked_at_once_as_one_by_one(seed: int) -> None:
    """A list of flat records (a plan's visits) is checked joined: the same answer as the
    recursive check of each record."""
    rng = random.Random(seed)
    alphabet = "abcXYZ019 _-.:" + ("" if seed % 3 else "é\n\x85")
    records = [
        {
            rng.choice(["a", "b", "key c", "" if seed % 5 == 0 else "d"]): rng.choice(
                [1, 2.5, None, True, "".join(rng.choice(alphabet) for _ in range(5))]
            )
            for _ in range(rng.randint(1, 4))
        }
        for _ in range(rng.randint(1, 30))
    ]
    expected = all(ecsvheader._libyaml_safe(r) for r in records)
    assert ecsvheader.flat_records_safe(records) is expected
    assert ecsvheader._libyaml_safe({"visits": records}) is expected


def test_meta_copied_as_deepcopy_copies_it() -> None:
    """The table's meta copy: equal, independent, and an object met twice still one object (the
    YAML header writes it once, with an alias), as ``copy.deepcopy`` makes it."""
    import copy

    shared, record = {"x": [1, 2]}, {"a": 1, "b": "t"}
    meta = {
        "one": shared,
        "two": shared,
        "visits": [record, {"a": 2, "b": None}, record],
        "other": (np.float64(1.5), [shared]),
        "nested": [[1.0, float("nan")], {"k": -0.0}],
        "flat": record,  # a flat mapping (a night's reasons) met again: one copy
    }
    ours, reference = tablemake._copy_meta(meta), copy.deepcopy(meta)
    assert repr(ours) == repr(reference)
    assert ours["flat"] is ours["visits"][0] and ours["flat"] is not record
    assert ours["one"] is ours["two"] is ours["other"][1][0] and ours["one"] is not shared
    assert ours["visits"][0] is ours["visits"][2] and ours["visits"][0] is not record
    table = Table({"a": [1.5]})
    table.meta = ours
    assert _ours(table) == _pyyaml_ecsv(Table({"a": [1.5]}, meta=meta))
    ours["visits"][1]["a"] = 5
    assert meta["visits"][1]["a"] == 2


def test_plan_table_header_uses_libyaml_when_safe(monkeypatch: pytest.MonkeyPatch) -> None:
    import yaml
    from support.blocks import block_meta, make_block
    from yaml._yaml import CEmitter

    with offline():
        table = tablemake.blocks_to_table([make_block(i) for i in range(5)], block_meta())
    assert ecsvheader.header_safe(table)
    expected = _pyyaml_ecsv(table)
    dumpers = []
    real_dump = yaml.dump

    def spy(*args: object, **kwargs: object) -> object:
        dumpers.append(kwargs.get("Dumper"))
        return real_dump(*args, **kwargs)  # type: ignore[call-overload]

    monkeypatch.setattr(yaml, "dump", spy)
    assert _ours(table) == expected
    assert len(dumpers) == 1 and issubclass(dumpers[0], CEmitter)  # type: ignore[arg-type]


def _reference_rows(table: Table) -> list[dict]:
    """The row-by-row way: ``item()`` of every cell, NaN as None."""
    rows = []
    for row in table:
        cells = {n: row[n].item() if hasattr(row[n], "item") else row[n] for n in table.colnames}
        rows.append({n: tablewrite._plain(v) for n, v in cells.items()})
    return rows


def test_json_rows_match_row_by_row() -> None:
    table = Table(
        {
            "f": [1.0, float("nan"), -0.0, 1e-300],
            "i": np.array([1, 2, 3, 2**62], dtype=np.int64),
            "s": ["a", "", "é", "x y"],
            "b": [True, False, True, False],
        }
    )
    assert table_to_json_rows(table) == _reference_rows(table)
    assert [type(v) for v in table_to_json_rows(table)[0].values()] == [float, int, str, bool]
    masked = table.copy()
    masked["m"] = MaskedColumn([1.0, 2.0, 3.0, 4.0], mask=[False, True, False, False])
    assert table_to_json_rows(masked) == _reference_rows(masked)  # row by row (masked)
    assert table_to_json_rows(table[:0]) == []


@pytest.mark.parametrize(
    ("zone", "year"),
    [
        ("America/Santiago", 2040),
        ("Europe/London", 2031),
        ("Australia/Lord_Howe", 2026),  # a half-hour change
        ("Africa/Monrovia", 1972),  # from an offset of whole seconds (-00:44:30) to GMT
        ("Asia/Kolkata", 2040),
        ("UTC", 2040),
    ],
)
def test_local_times_as_datetime_makes_them(zone: str, year: int) -> None:
    """Local ISO times (offsets found per instant, text made by arrays): as ``datetime`` and
    :mod:`zoneinfo` make them one by one, a second either side of each change of offset."""
    start = datetime(year, 1, 1, tzinfo=UTC)
    found = _transitions(zone, year)
    assert found or zone in ("Asia/Kolkata", "UTC")
    when = [start + timedelta(hours=7.2 * k, microseconds=k * 37_001) for k in range(1300)]
    for t in found:
        when += [t + timedelta(seconds=s) for s in (-1.5, -1, -0.25, 0, 0.5, 1)]
    with offline():
        utc = Time(when, scale="utc")
        ours = tableformat.local_iso(utc, [zone] * len(when)).tolist()
        ref = [
            d.isoformat(timespec="seconds") for d in tableformat._local_of(utc, [zone] * len(when))
        ]
    assert ours == ref
    assert len(set(o[19:] for o in ours)) == (1 if zone in ("Asia/Kolkata", "UTC") else 2)
