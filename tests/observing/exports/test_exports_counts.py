"""Issue 31: every export asks the observatory for exactly what was planned.

Plans of targeted and back-to-back visits, a multi-night goal, a LISA target, a timing target at
Keck, La Palma and Cerro Pachón, sessions of two-exposure blocks and a ``--service-mode`` plan
are exported to every format; each file is read back by its format's own rules (JSON documents
as the OCS, Gemini and p2 read them, the ESO OBs through p2api to a fake p2, the calendar with
icalendar, the schedule with astroplan) and its exposure count and shutter time compared with
the blocks table. The first tests are the issue's own lines (they failed before the fix).
"""

from __future__ import annotations

import itertools
import json
import re
import socket
import warnings
from datetime import datetime, timedelta
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from astropy import units as u
from astropy.table import Table
from astropy.time import Time
from support.cli import run_cli
from support.eso_p2 import TEMPLATES_YAML

import ucbplan
from ucbplan.observing.exports import ExportOptions, export_blocks
from ucbplan.observing.exports.astroplan_schedule import to_astroplan
from ucbplan.observing.exports.eso_ob import USER_COMMENTS_MAX
from ucbplan.observing.exports.queue import ServiceModeError
from ucbplan.observing.observatory.sites import get_site

CATALOGS = Path(__file__).resolve().parents[3] / "catalogs"
HM = str(CATALOGS / "hm-cnc-simulated.yaml")
TIMING = str(CATALOGS / "examples" / "synthetic-eclipsing.yaml")
LISA = str(CATALOGS / "fiducial-injection.yaml")
XSH = {"sigma_v_kms": "30km/s@300s", "instrument": "xshooter-vis"}
#: name → (target file, site, nights, plan options)
PLANS: dict[str, tuple[str, str, int, dict[str, Any]]] = {
    "targeted": (HM, "paranal", 1, {"visit": "1h", **XSH}),
    "untargeted": (HM, "paranal", 1, {"visit": "1h", "cadence": "untargeted", **XSH}),
    "goal-3-nights": (HM, "paranal", 3, {"goal": "sigma_K=8km/s", **XSH}),
    "service": (HM, "paranal", 1, {"visit": "1h", "service_mode": True, **XSH}),
    "phase-locked": (
        HM,
        "paranal",
        1,
        {"visit": "1h", "readout_s": 10.0, "cadence": "phase-locked", "allow_smeared": True},
    ),
    "lisa": (LISA, "paranal", 1, {"visit": "1h", **XSH}),
    "sessions": (HM, "paranal", 1, {"n_exp": 2, "exptime_s": 30.0, "sessions_per_night": 2}),
    "timing-keck": (
        TIMING,
        "keck",
        1,
        {"visit": "1h", "sigma_v_kms": "30km/s@300s", "instrument": "esi", "overhead_s": 600},
    ),
    "timing-lapalma": (
        TIMING,
        "lapalma",
        1,
        {
            "visit": "1h",
            "sigma_v_kms": "30km/s@300s",
            "instrument": "isis",
            "overhead_s": 600,
            "readout_s": 30,
        },
    ),
    "timing-gmos-s": (
        TIMING,
        "gemini-south",
        1,
        {"visit": "1h", "sigma_v_kms": "30km/s@300s", "instrument": "gmos-s", "overhead_s": 600},
    ),
}
FORCE = ExportOptions(force=True)
_CACHE: dict[str, Table] = {}

pytestmark = [
    pytest.mark.filterwarnings("ignore::ucbplan.errors.UcbplanWarning"),
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]


def planned(name: str) -> Table:
    """The blocks table of plan ``name`` (made once per session: each takes ~0.2 s)."""
    if name not in _CACHE:
        path, site, nights, options = PLANS[name]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            _CACHE[name] = ucbplan.plan(
                path, site, "2040-02-15", nights=nights, **options
            ).text_table
    return _CACHE[name]


def totals(table: Table) -> tuple[int, float]:
    """The plan's exposure count and shutter time [s]: Σ n_exp, Σ n_exp · exptime_s."""
    n_exp = np.asarray(table["n_exp"], dtype=int)
    return int(n_exp.sum()), float((n_exp * np.asarray(table["exptime_s"], dtype=float)).sum())


def doc(table: Table, to: str, options: ExportOptions = FORCE) -> dict[str, Any]:
    return json.loads(export_blocks(table, to, options).content)


def utc(text: str) -> datetime:
    return datetime.fromisoformat(text.replace(" ", "T"))


def exposure_starts(table: Table) -> list[datetime]:
    """Every planned exposure start, from the table alone (n_exp per row, readout apart)."""
    out = []
    for row in table:
        t0 = utc(str(row["t_start_utc"]))
        step = float(row["exptime_s"]) + float(row["readout_s"])
        out += [t0 + timedelta(seconds=k * step) for k in range(int(row["n_exp"]))]
    return sorted(out)


# ------------------------------------------------------------------ the issue's own lines


def test_issue_eso_ob_takes_all_20_exposures_of_the_visit() -> None:
    # was: one OB whose science template had n_exp = 1 (1 exposure of the visit's 20)
    obs = doc(planned("targeted"), "eso-p2")["obs"]
    science = [t for ob in obs for t in ob["ob"]["templates"] if t["type"] == "science"]
    assert len(obs) == 1 and sum(t["parameters"]["n_exp"] for t in science) == 20


def test_issue_eso_user_comments_are_cut_with_a_mark_and_a_note() -> None:
    # was: cut at 1000 characters mid-timestamp, 14 of 20 exposures listed, no mark
    result = export_blocks(planned("targeted"), "eso-p2", FORCE)
    (ob,) = json.loads(result.content)["obs"]
    comment = ob["ob"]["obsDescription"]["userComments"]
    listed = re.findall(r"(\S+) mid (\S+) UTC \+/-\S+ s", comment)
    assert len(comment) <= USER_COMMENTS_MAX
    assert re.search(rf"\[cut: {20 - len(listed)} more of 20 blocks in merged_visits", comment)
    assert all(utc(t) for _, t in listed)  # no timestamp cut in the middle
    assert [v["block_id"] for v in ob["merged_visits"]] == list(planned("targeted")["block_id"])
    assert any(f"userComments lists {len(listed)} of 20 blocks" in n for n in result.notes)


@pytest.mark.parametrize("to", ["lco", "gemini"])
def test_issue_back_to_back_visit_is_one_unit_of_27(to: str) -> None:
    # was: 26-27 requests/observations, each with its own acquisition, windows colliding
    d = doc(planned("untargeted"), to)
    if to == "lco":
        (request,) = d["requests"]
        (config,) = request["configurations"]
        assert config["instrument_configs"] == [{"exposure_time": 73.0, "exposure_count": 27}]
    else:
        (obs,) = d["observations"]
        assert (obs["exposure_count"], obs["exposure_time_s"]) == (27, 73.0)


@pytest.mark.parametrize(("to", "mark"), [("keck-starlist", "#"), ("ing-cat", "!")])
def test_issue_keck_and_ing_say_every_block_time_and_exposure(to: str, mark: str) -> None:
    # was: no exposure time or count and no note; ING only the first of the block times
    table = planned("timing-keck" if to == "keck-starlist" else "timing-lapalma")
    result = export_blocks(table, to, FORCE)
    text = result.content.decode("ascii")
    mids = re.findall(rf"^{re.escape(mark)} .*UTC-mid (\S+) .* exp (\d+)x(\S+) s$", text, re.M)
    assert len(mids) == len(table)
    assert any("no exposure time or count field" in n for n in result.notes)


def test_issue_to_astroplan_carries_every_exposure_and_constraint() -> None:
    # was: one block per visit (3135 s for 20 x 80 s), constraints=None
    from astroplan import AirmassConstraint, AltitudeConstraint, AtNightConstraint

    table = planned("targeted")
    blocks = to_astroplan(table, get_site("paranal")).observing_blocks
    assert len(blocks) == 20
    assert sum(b.duration.to_value(u.s) for b in blocks) == pytest.approx(1600.0)
    kinds = {type(c) for c in blocks[0].constraints}
    assert {AirmassConstraint, AltitudeConstraint, AtNightConstraint} <= kinds


# ------------------------------------------------------------- counts and shutter, every plan


@pytest.mark.parametrize("name", list(PLANS))
def test_eso_templates_add_up(name: str) -> None:
    table = planned(name)
    science = [
        t["parameters"]
        for ob in doc(table, "eso-p2")["obs"]
        for t in ob["ob"]["templates"]
        if t["type"] == "science"
    ]
    count = sum(p["n_exp"] for p in science)
    shutter = sum(p["n_exp"] * p["exposure_time_s"] for p in science)
    assert (count, shutter) == pytest.approx(totals(table))


@pytest.mark.parametrize("name", list(PLANS))
def test_lco_requests_add_up_and_never_collide(name: str) -> None:
    table = planned(name)
    requests = doc(table, "lco")["requests"]
    configs = [ic for r in requests for c in r["configurations"] for ic in c["instrument_configs"]]
    count = sum(c["exposure_count"] for c in configs)
    shutter = sum(c["exposure_count"] * c["exposure_time"] for c in configs)
    assert (count, shutter) == pytest.approx(totals(table))
    windows = [(utc(r["windows"][0]["start"]), utc(r["windows"][0]["end"])) for r in requests]
    assert all(a[1] <= b[0] for a, b in itertools.pairwise(windows))  # no overlap
    for start in exposure_starts(table):  # each planned exposure start inside one window
        assert sum(lo <= start < hi for lo, hi in windows) == 1


@pytest.mark.parametrize("name", list(PLANS))
def test_gemini_observations_add_up(name: str) -> None:
    table = planned(name)
    observations = doc(table, "gemini")["observations"]
    steps = [s for o in observations for s in o["sequence"]]
    assert sum(o["exposure_count"] for o in observations) == totals(table)[0]
    assert sum(s["repeat"] for s in steps) == totals(table)[0]
    shutter = sum(s["repeat"] * s["exposure_time_s"] for s in steps)
    assert shutter == pytest.approx(totals(table)[1])
    starts = [utc(t) for o in observations for t in o["exposure_starts_utc"]]
    assert [round(t.timestamp(), 2) for t in starts] == [
        round(t.timestamp(), 2) for t in exposure_starts(table)
    ]
    windows = []
    for o in observations:  # Gemini timing-window syntax: start, HH:MM duration, no repeat
        w = o["timing_window"]
        assert re.fullmatch(r"\d{4}-\d\d-\d\d \d\d:\d\d:00", w["start_utc"])
        hours, minutes = map(int, w["duration"].split(":"))
        lo = utc(w["start_utc"])
        windows.append((lo, lo + timedelta(minutes=60 * hours + minutes)))
        assert windows[-1][0] <= utc(o["observation_start_utc"]) <= windows[-1][1]
    assert all(a[1] <= b[0] for a, b in itertools.pairwise(windows))


@pytest.mark.parametrize("name", list(PLANS))
@pytest.mark.parametrize(("to", "mark"), [("keck-starlist", "#"), ("ing-cat", "!")])
def test_starlist_and_catalogue_comments_add_up(name: str, to: str, mark: str) -> None:
    table = planned(name)
    text = export_blocks(table, to, FORCE).content.decode("ascii")
    blocks = re.findall(rf"^{re.escape(mark)} .* exp (\d+)x(\S+) s$", text, re.M)
    count = sum(int(n) for n, _ in blocks)
    shutter = sum(int(n) * float(t) for n, t in blocks)
    assert (count, shutter) == pytest.approx(totals(table))
    totals_lines = re.findall(r"(\d+) exposures?, (\S+) s shutter in \d+ visits?", text)
    assert sum(int(n) for n, _ in totals_lines) == totals(table)[0]


@pytest.mark.parametrize("name", list(PLANS))
def test_ics_events_add_up(name: str) -> None:
    icalendar = pytest.importorskip("icalendar")
    table = planned(name)
    calendar = icalendar.Calendar.from_ical(export_blocks(table, "ics", FORCE).content)
    events = list(calendar.walk("VEVENT"))
    found = [re.search(r"(\d+) x (\S+) s;", str(e["DESCRIPTION"])) for e in events]
    count = sum(int(m.group(1)) for m in found if m)
    shutter = sum(int(m.group(1)) * float(m.group(2)) for m in found if m)
    assert len(events) == len(table) and (count, shutter) == pytest.approx(totals(table))


@pytest.mark.parametrize("name", list(PLANS))
def test_astroplan_blocks_add_up_with_their_windows(name: str) -> None:
    from astroplan import TimeConstraint

    table = planned(name)
    blocks = to_astroplan(table, get_site("paranal")).observing_blocks
    assert len(blocks) == totals(table)[0]
    assert sum(b.duration.to_value(u.s) for b in blocks) == pytest.approx(totals(table)[1])
    starts = Time(exposure_starts(table), scale="utc").jd
    windows = [next(c for c in b.constraints if isinstance(c, TimeConstraint)) for b in blocks]
    lo, hi = (np.array([getattr(w, side).jd for w in windows]) for side in ("min", "max"))
    assert np.all((lo <= starts) & (starts <= hi))
    slots = np.array([b.start_time.jd for b in blocks])
    assert np.abs(slots - starts).max() * 86400.0 < 1.0


# -------------------------------------------------------------------- service mode and phase


def _strategy_share(table: Table, name: str) -> str:
    """The strategy's information per hour as a fraction of the best, from the plan's meta."""
    rows = next(iter(table.meta["planning"]["targets"].values()))["strategy"]["strategies"]
    best = max(r["info_per_hour"] for r in rows.values())
    return f"{rows[name]['info_per_hour'] / best:.0%}"


@pytest.mark.parametrize("to", ["eso-p2", "lco", "gemini"])
def test_targeted_visit_is_one_note_with_the_back_to_back_cost(to: str) -> None:
    table = planned("targeted")
    notes = [n for n in export_blocks(table, to, FORCE).notes if "service-mode queue" in n]
    assert len(notes) == 1 and "\n" not in notes[0]
    share = _strategy_share(table, "untargeted")
    assert f"untargeted 27 x 73 s, {share} of the best info/h" in notes[0]
    assert "`service_mode`" in notes[0] and "visitor mode" in notes[0]  # CLI: --service-mode
    with pytest.raises(ServiceModeError, match="`strict`: no file written"):
        export_blocks(table, to, ExportOptions(force=True, strict=True))


@pytest.mark.parametrize("name", ["untargeted", "service", "phase-locked"])
@pytest.mark.parametrize("to", ["eso-p2", "lco", "gemini"])
def test_back_to_back_visits_need_no_note(name: str, to: str) -> None:
    result = export_blocks(planned(name), to, ExportOptions(force=True, strict=True))
    assert not any("service-mode queue" in n for n in result.notes)


def test_service_mode_plans_only_back_to_back_visits() -> None:
    table = planned("service")
    strategy = next(iter(table.meta["planning"]["targets"].values()))["strategy"]["chosen"]
    assert strategy in ("phase-locked", "untargeted") and table.meta["planning"]["service_mode"]
    (ob,) = doc(table, "eso-p2")["obs"]
    science = [t for t in ob["ob"]["templates"] if t["type"] == "science"]
    assert [t["parameters"]["n_exp"] for t in science] == [len(table)]


def test_service_mode_refuses_a_cadence_that_waits() -> None:
    with pytest.raises(ucbplan.InputError, match="service_mode: `cadence=targeted` waits"):
        ucbplan.plan(HM, "paranal", "2040-02-15", cadence="targeted", service_mode=True, **XSH)


def test_an_eccentric_phase_locked_visit_that_waits_is_noted() -> None:
    # exposures shortened for the eccentric anchors' uneven spacing wait seconds after readouts
    table = ucbplan.plan(
        str(CATALOGS / "fiducial-eccentric.yaml"),
        "paranal",
        "2040-02-15",
        visit="1h",
        readout_s=10.0,
        cadence="phase-locked",
        allow_smeared=True,
    ).text_table
    starts = [utc(str(t)) for t in table["t_start_utc"]]
    ends = [utc(str(t)) for t in table["t_end_utc"]]
    waits = [(b - a).total_seconds() - 10.0 for a, b in zip(ends, starts[1:], strict=False)]
    assert max(waits) > 1.0  # more than --service-mode allows
    (note,) = [n for n in export_blocks(table, "gemini", FORCE).notes if "queue" in n]
    assert f"wait up to {max(waits):.0f} s ({sum(waits):.0f} s in all)" in note


def test_cli_strict_exits_2_without_a_file(tmp_path: Path) -> None:
    blocks, out = tmp_path / "plan.ecsv", tmp_path / "obs.json"
    planned("targeted").write(blocks, format="ascii.ecsv")
    code, err = run_cli(
        ["export", str(blocks), "--to", "lco", "--strict", "-o", str(out), "--force"]
    )
    assert code == 2 and not out.exists()
    assert "service-mode queue" in err.splitlines()[-1] and "Traceback" not in err
    code, err = run_cli(["export", str(blocks), "--to", "lco", "-o", str(out), "--force"])
    assert code == 0 and out.exists() and "service-mode queue" in err


def test_cli_plan_service_mode(tmp_path: Path) -> None:
    out = tmp_path / "plan.ecsv"
    args = ["plan", HM, "--night", "2040-02-15", "--site", "paranal", "--visit", "1h"]
    args += ["--sigma-v", "30km/s@300s", "--instrument", "xshooter-vis", "--service-mode"]
    code, err = run_cli([*args, "-o", str(out)])
    assert code == 0, err
    assert Table.read(out).meta["planning"]["service_mode"] is True


# ------------------------------------------------------------------- read back by their tools


def test_to_astroplan_needs_no_network_and_astroplan_confirms_the_plan(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from astroplan import TimeConstraint, is_event_observable

    def refuse(*args: Any, **kwargs: Any) -> None:
        raise OSError("network blocked by the test")

    monkeypatch.setattr(socket.socket, "connect", refuse)
    table = planned("untargeted")
    schedule = to_astroplan(table, get_site("paranal"))
    for block in schedule.observing_blocks[:: len(table) // 3]:
        # astroplan itself evaluates the translated constraints at the planned exposure
        times = Time([block.start_time, block.end_time])
        others = [c for c in block.constraints if not isinstance(c, TimeConstraint)]
        assert len(others) == 4  # night, airmass, zenith hole, Moon separation
        assert is_event_observable(block.constraints, schedule.observer, block.target, times).all()


@pytest.mark.parametrize("name", ["targeted", "untargeted", "goal-3-nights", "sessions"])
def test_p2api_receives_every_exposure(name: str, tmp_path: Path, fake_p2: Any) -> None:
    from ucbplan.observing.exports.eso_create import connect, create_from_export

    path = tmp_path / "templates.yaml"
    path.write_text(TEMPLATES_YAML, encoding="utf-8")
    table = planned(name)
    content = export_blocks(table, "eso-p2", ExportOptions(eso_templates=str(path))).content
    create_from_export(content, 42, dry_run=False, connection=connect("demo", "52052", "secret"))
    sent = [
        {p["name"]: p["value"] for p in tpl["parameters"]}
        for _, tpl in fake_p2.templates.values()
        if tpl["templateName"] == "XSHOOTER_slt_obs_Stare"
    ]
    count = sum(v["SEQ.NEXPO"] for v in sent)
    shutter = sum(v["SEQ.NEXPO"] * v["DET.WIN1.UIT1"] for v in sent)
    assert len(fake_p2.obs) == len({*table["visit_id"]}) or name == "sessions"
    assert (count, shutter) == pytest.approx(totals(table))


def test_lco_group_name_is_cut_with_a_note() -> None:
    table = planned("untargeted").copy()
    table["target"] = table["target"].astype("U80")
    table["target"] = "A target whose name is far longer than fifty characters allow"
    result = export_blocks(table, "lco", FORCE)
    assert len(json.loads(result.content)["name"]) == 50
    assert any("request group name cut to 50 characters" in n for n in result.notes)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"sigma_v_kms": 30.0}, "service_mode: expected `visit=DURATION`"),
        (
            {"visit": "1h", "readout_s": 10.0, "cadence": "phase-locked"},
            "phase-locked 80.5 s exposures .* wait 70.2 s after each readout",
        ),
    ],
)
def test_service_mode_refuses_what_a_queue_cannot_run(
    options: dict[str, Any], message: str
) -> None:
    with pytest.raises(ucbplan.InputError, match=message):
        ucbplan.plan(HM, "paranal", "2040-02-15", service_mode=True, **options)


def test_service_mode_without_a_sigma_law_plans_back_to_back() -> None:
    table = ucbplan.plan(
        HM, "paranal", "2040-02-15", visit="1h", readout_s=10.0, service_mode=True
    ).text_table
    starts = [utc(str(t)) for t in table["t_start_utc"]]
    ends = [utc(str(t)) for t in table["t_end_utc"]]
    gaps = [(b - a).total_seconds() for a, b in zip(ends, starts[1:], strict=False)]
    assert max(gaps) == pytest.approx(10.0, abs=0.05)  # only the readout between exposures
    assert not any("service-mode queue" in n for n in export_blocks(table, "lco", FORCE).notes)
