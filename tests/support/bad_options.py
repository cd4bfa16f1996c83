"""The CLI-option bad-input corpus: option values each command refuses before any work, in one
line naming the flag (exit 2, nothing written), and the library keywords behind the `plan` flags.
Run by tests/cli/test_option_bad_input.py; the fuzzed options and values by
tests/cli/test_cli_fuzz_surfaces.py."""

from __future__ import annotations

import math
from collections.abc import Callable
from datetime import date

from hypothesis import strategies as st

from support.cli import VALUES
from support.paths import CATALOGS
from ucbplan.observing.observatory.sites import site_from_lonlat
from ucbplan.observing.schedule import PlanSettings, night_dates
from ucbplan.observing.schedule.run import parse_priorities

HM = str(CATALOGS / "hm-cnc-simulated.yaml")
INJ = str(CATALOGS / "fiducial-injection.yaml")
ECC = str(CATALOGS / "fiducial-eccentric.yaml")
TIMING = str(CATALOGS / "examples" / "synthetic-eclipsing.yaml")

#: The night the `plan` cases are planned for.
NIGHT = date(2040, 2, 15)

#: Values no numeric option accepts (non-finite, or too large for any range).
NON_FINITE: list[float] = [math.nan, math.inf, -math.inf, 3.8e239, -1e300]

#: ``--plot`` file names that are not .png/.pdf/.svg (each tried on three commands).
PLOT_NAMES: list[str] = ["oc.txt", "figs", "oc.PNGX"]

#: `population rank` options given a bad value, and the word the error must blame.
RANK_OPTIONS: list[tuple[list[str], str]] = [
    (["--goal", "q=1%,M1=2%"], "one QUANTITY=VALUE per goal"),
    (["--top", "-1"], "--top"),
    (["--sigma-ref", "abc"], "--sigma-ref"),
    (["--readout", "-30"], "--readout"),
    (["--visit", "0"], "--visit"),
    (["--overhead", "-1"], "--overhead"),
    (
        ["--sigma-ref", "10,17,600", "--visit", "100", "--exptime", "60", "--overhead", "60"],
        "--visit",
    ),
    (["--instruments-file", "missing.yaml"], "--instruments-file"),
    (["--top", "3"], "nosuch.ecsv"),  # the source itself is missing (see the test)
]

#: `population simulate` options given a bad value, and the words the error must hold.
SIMULATE_OPTIONS: list[tuple[list[str], str]] = [
    (["--walkers", "2"], "--walkers: expected a whole number in [12,"),
    (["--steps", "0"], "--steps"),
]

#: `feasibility --optical-sigma-X` suffixes, and the values each refuses.
OPTICAL_SIGMA_OPTIONS: list[str] = ["p", "pdot", "t0", "phase", "f-rel", "fdot-rel"]
OPTICAL_SIGMA_VALUES: list[str] = ["-1", "-1e-30", "inf", "1e140"]

#: (flag of the CLI, keyword of the library object, values to refuse, values to keep): the library
#: names the keyword, the CLI the flag (ucbplan.cli._flags).
SETTINGS_RANGES: list[tuple[str, str, list[float], list[float]]] = [
    ("--airmass-max", "airmass_max", [0.5, 0.999, 101.0], [1.0, 2.0, 100.0]),
    ("--moon-sep", "moon_sep_deg", [-1.0, 180.5], [0.0, 30.0, 180.0]),
    ("--moon-illum", "moon_illum_max", [-0.1, 1.01], [0.0, 0.5, 1.0]),
    ("--zenith-hole", "zenith_hole_deg", [-3.0, 46.0, 100.0], [0.0, 4.0, 45.0]),
    ("--alpha", "alpha", [0.0, -1.0, 11.0], [0.01, 1.0, 10.0]),
    ("--sigma-v", "sigma_v_kms", [0.0, -1.0, 1.1e4], [0.5, 1e4]),
    ("--k-eff", "k_eff_kms", [0.0, -5.0, 1e5], [1.0, 390.0]),
    ("--max-bin-fraction", "max_bin_fraction", [0.0, -1.0, 1.5], [0.1, 1.0]),
    ("--overhead", "overhead_s", [-5.0, 43201.0], [0.0, 300.0, 43200.0]),
]

#: ExposurePlan keywords out of range, and the flag(s) the CLI names.
EXPOSURE_PLANS: list[tuple[str, dict[str, float]]] = [
    ("--exptime", {"exptime_s": 0.0}),
    ("--exptime", {"exptime_s": 43201.0}),
    ("--exptime", {"exptime_s": 3.8e239}),  # was "Maximum allowed size exceeded"
    ("--exptime", {"exptime_s": math.nan}),
    ("--readout", {"readout_s": -1.0}),
    ("--readout", {"readout_s": 1e300}),
    ("--readout", {"readout_s": math.nan}),
    ("--n-exp", {"n_exp": 0}),
    ("--n-exp", {"n_exp": 100_000_000}),  # was a 80 GiB allocation
    ("--n-exp", {"n_exp": 2.5}),
    ("--n-exp/--exptime/--readout", {"exptime_s": 40.0, "n_exp": 2000}),
]

#: Other `plan` options, each as the library call that must refuse it (keyword or flag named).
OTHER_PLAN_OPTIONS: list[tuple[str, Callable[[], object]]] = [
    ("sessions_per_night", lambda: PlanSettings(sessions_per_night=0)),
    ("sessions_per_night", lambda: PlanSettings(sessions_per_night=10**9)),
    ("twilight", lambda: PlanSettings(twilight="foo")),
    ("twilight", lambda: PlanSettings(twilight="x" * 5000)),
    ("--mode", lambda: PlanSettings(mode="x" * 5000)),
    ("--mode u=VALUE", lambda: PlanSettings(mode="u=1e300")),
    ("max_smear", lambda: PlanSettings(max_smear="..*sigma_v")),  # was a bare ValueError
    ("max_smear", lambda: PlanSettings(max_smear="-1")),
    ("max_smear", lambda: PlanSettings(max_smear="1e300 km/s")),
    ("max_smear", lambda: PlanSettings(max_smear="x" * 5000)),
    ("--nights", lambda: night_dates(NIGHT, 0)),
    ("--nights", lambda: night_dates(NIGHT, 100_000)),
    ("--night", lambda: night_dates("15/02/2040")),
    ("--night", lambda: night_dates("2040-02-15" * 500)),
    ("--night", lambda: night_dates("9999-12-31")),  # was OverflowError: date out of range
    ("--night", lambda: night_dates("0001-01-01")),
    ("--night", lambda: night_dates("2100-12-01", 60)),
    ("--priority", lambda: parse_priorities(["HM Cnc=nan"])),
    ("--priority", lambda: parse_priorities(["=3"])),
    ("--priority", lambda: parse_priorities(["HM Cnc"])),
    ("--priority", lambda: parse_priorities(["HM Cnc=1e400"])),
    ("--priority", lambda: parse_priorities(["HM Cnc=" + "9" * 5000])),
    ("--site-lonlat", lambda: site_from_lonlat("nan,0,0")),  # was "cannot convert NaN"
    ("--site-lonlat", lambda: site_from_lonlat("0,95,0")),
    ("--site-lonlat", lambda: site_from_lonlat("0,0,1e300")),
    ("--site-lonlat", lambda: site_from_lonlat("1," * 3000)),
]

#: `plan` arguments refused before any work (exit 2, no blocks table written).
PLAN_ARGS: list[list[str]] = [
    ["--exptime", "3.8e239"],
    ["--exptime", "1e9"],
    ["--n-exp", "100000000"],
    ["--overhead", "nan"],
    ["--moon-sep", "200"],
    ["--night", "9999-12-31"],
    ["--site-lonlat", "nan,0,0"],
    ["--k-eff", "0"],  # was silently replaced by the target file's K
]

#: Extra values that name the new surfaces' own words.
SURFACE_VALUES = st.one_of(
    VALUES,
    st.sampled_from(
        [
            "q=1%,M1=2%",
            "K1=5%",
            "M1=0.01Msun",
            "sigma_K=2km/s",
            "10,17,600",
            "1,2",
            "-70,-24,2600",
            "200,0,0",
            "360,10,0",
            "414.79 s",
            "414.79",
            "1e-30 s",
            "oc.txt",
            "figs/",
            "fors2",
            "xshooter-vis",
            "phase-table",
            "eso-p2",
            "2041A",
            "P147",
            "4yr",
            "1h",
        ]
    ),
)

#: Options fuzzed by tests/cli/test_cli_fuzz_surfaces.py with SURFACE_VALUES: (command line without
#: the option, option under test). "{NAME}" is one of that test's inputs, "{OUT}" a file and
#: "{DIR}" a new folder inside the output folder the test watches; FUZZED_SLOW start real work.
FUZZED_FAST: list[tuple[list[str], str]] = [
    (["ephemeris", "fit", "{TIMES}", "-o", "{OUT}.yaml"], "--terms"),
    (["ephemeris", "fit", "{TIMES}", "-o", "{OUT}.yaml"], "--clip"),
    (["ephemeris", "fit", "{TIMES}", "-o", "{OUT}.json"], "--plot"),
    (["ephemeris", "fit", "{TIMES}", "--format", "json"], "--period"),
    (["ephemeris", "fit", "{TIMES}", "--format", "json"], "--initial"),
    (["ephemeris", "fit", "{TIMES}", "-o", "{OUT}.yaml"], "--ra"),
    (["ephemeris", "fit", "{TIMES}", "--format", "yaml"], "--like"),
    (["feasibility", TIMING, "--format", "json"], "--optical-sigma-p"),
    (["feasibility", TIMING, "--format", "json"], "--optical-sigma-pdot"),
    (["feasibility", TIMING, "--format", "json"], "--optical-sigma-t0"),
    (["feasibility", HM, "--format", "json"], "--optical-sigma-phase"),
    (["feasibility", HM, "--format", "json"], "--optical-sigma-f-rel"),
    (["feasibility", ECC, "-o", "{OUT}.json"], "--plot"),
    (["horizon", HM, INJ, "--format", "json"], "--alpha"),
    (["horizon", HM, INJ, "--format", "json"], "--sigma-v"),
    (["horizon", HM, INJ, "-o", "{OUT}.json"], "--format"),
    (["horizon", HM, "-o", "{OUT}.json"], "--plot"),
    (["population", "rank", "{FORECAST}", "--out-dir", "{DIR}"], "--top"),
    (["population", "rank", "{FORECAST}", "--out-dir", "{DIR}"], "--goal"),
    (["population", "rank", "{FORECAST}", "--out-dir", "{DIR}"], "--sigma-ref"),
    (["population", "rank", "{FORECAST}", "--out-dir", "{DIR}"], "--readout"),
    (["population", "rank", "{FORECAST}", "--out-dir", "{DIR}"], "--overhead"),
    (["population", "rank", "{FORECAST}", "--out-dir", "{DIR}"], "--visit"),
    (["population", "rank", "{FORECAST}", "--out-dir", "{DIR}"], "--exptime"),
    (["population", "rank", "{FORECAST}", "--out-dir", "{DIR}"], "--instrument"),
    (["population", "rank", "{FORECAST}", "--out-dir", "{DIR}"], "--instruments-file"),
    (["population", "rank", "{FORECAST}", "--out-dir", "{DIR}"], "--catalog"),
    (["population", "rank", "{FORECAST}", "--out-dir", "{DIR}"], "--out-dir"),
    (["population", "simulate", "{CAT}", "-o", "{OUT}.ecsv", "--out-dir", "{TAKEN}"], "--walkers"),
    (["population", "simulate", "{CAT}", "-o", "{OUT}.ecsv", "--out-dir", "{TAKEN}"], "--steps"),
    (
        ["population", "simulate", "{CAT}", "-o", "{OUT}.ecsv", "--out-dir", "{TAKEN}"],
        "--max-steps",
    ),
    (["population", "simulate", "{CAT}", "-o", "{OUT}.ecsv", "--out-dir", "{TAKEN}"], "--seed"),
    (["export", "{BLOCKS}", "-o", "{OUT}"], "--to"),
    (["export", "{BLOCKS}", "--to", "phase-table", "-o", "{OUT}.ecsv"], "--tolerance-sigma"),
    (["export", "{BLOCKS}", "--to", "proposal", "-o", "{OUT}.csv"], "--semester"),
    (["export", "{BLOCKS}", "--to", "proposal", "-o", "{OUT}.csv"], "--acquisition"),
    (["export", "{BLOCKS}", "--to", "eso-p2", "-o", "{OUT}.json"], "--seeing"),
    (["export", "{BLOCKS}", "--to", "eso-p2", "-o", "{OUT}.json"], "--instrument"),
    (["plan", HM, "--night", "2040-02-15", "--site-lonlat", "-70,-24,2600"], "--site"),
]
FUZZED_SLOW: list[tuple[list[str], str]] = [
    (["population", "forecast", "{CAT}", "-o", "{OUT}.ecsv"], "--sigma-v"),
    (["population", "forecast", "{CAT}", "-o", "{OUT}.ecsv"], "--t-obs"),
    (["population", "forecast", "{CAT}", "-o", "{OUT}.ecsv"], "--n-bins"),
    (["population", "forecast", "{CAT}", "-o", "{OUT}.ecsv"], "--columns"),
    (["population", "visibility", "{CAT}", "-o", "{OUT}.ecsv", "--site", "paranal"], "--semester"),
    (
        ["population", "visibility", "{CAT}", "-o", "{OUT}.ecsv", "--semester", "2041A"],
        "--site-lonlat",
    ),
    (
        ["population", "visibility", "{CAT}", "-o", "{OUT}.ecsv", "--semester", "2041A"],
        "--site",
    ),
    (["plan", HM, "--site", "paranal", "--night", "2040-02-15"], "--instrument"),
    (["plan", HM, "--site", "paranal", "--night", "2040-02-15"], "--instruments-file"),
    (["plan", HM, "--site", "paranal", "--night", "2040-02-15"], "--goal"),
    (["plan", HM, "--site", "paranal", "--night", "2040-02-15"], "--visit"),
    (["plan", HM, "--site", "paranal", "--night", "2040-02-15"], "--readout"),
    (["plan", HM, "--site", "paranal", "--night", "2040-02-15"], "--plot"),
    (["plan", HM, "--night", "2040-02-15"], "--site-lonlat"),
]
