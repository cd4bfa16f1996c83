"""The eclipse-time bad-input corpus: each way an eclipse-time table, an initial-ephemeris file, a
period guess or an ``ephemeris fit`` option can be wrong, with a phrase of its one-line error. Run
by tests/timing/test_eclipse_times_bad_input.py (and the options by tests/timing/test_timing_fit.py,
which needs its campaign)."""

from __future__ import annotations

#: The header of an eclipse-time CSV table.
HEADER = "bjd_tdb,sigma_s,kind,cycle\n"

#: Four good rows: ZTF J1539-like primaries, cycles 0 to 3.
GOOD = [
    "2458305.6827886,2,primary,0",
    "2458305.6875891,2,primary,1",
    "2458305.6923896,2,primary,2",
    "2458305.6971901,2,primary,3",
]


def times_table(rows: list[str], header: str = HEADER) -> str:
    """An eclipse-time CSV table (text) of HEADER and ROWS."""
    return header + "\n".join(rows) + "\n"


#: (test id, table text, phrase of the error) for tables the reader refuses.
BAD_TABLES: list[tuple[str, str, str]] = [
    ("empty", "", "header"),
    ("only header", HEADER, "no data rows"),
    ("no sigma", times_table([r.split(",", 1)[0] for r in GOOD], "bjd_tdb\n"), "sigma_s"),
    ("unknown column", times_table(GOOD, "bjd_tdb,sigma,kind,cycle\n"), "did you mean 'sigma_s'"),
    ("two time columns", times_table(GOOD, "bjd_tdb,bmjd_tdb,kind,cycle\n"), "exactly one time"),
    ("duplicate column", times_table(GOOD, "bjd_tdb,sigma_s,cycle,cycle\n"), "appears twice"),
    ("blank epoch", times_table([*GOOD[:2], ",2,primary,2"]), "row 3, column 'bjd_tdb'"),
    ("text epoch", times_table([*GOOD[:2], "tomorrow,2,primary,2"]), "row 3, column 'bjd_tdb'"),
    ("MJD in bjd column", times_table([*GOOD[:2], "58305.18,2,primary,2"]), "bmjd_tdb"),
    ("nan epoch", times_table([*GOOD[:2], "nan,2,primary,2"]), "row 3"),
    (
        "negative sigma",
        times_table([*GOOD[:2], "2458305.69239,-2,primary,2"]),
        "row 3, column 'sigma_s'",
    ),
    ("zero sigma", times_table([*GOOD[:2], "2458305.69239,0,primary,2"]), "positive"),
    ("inf sigma", times_table([*GOOD[:2], "2458305.69239,inf,primary,2"]), "row 3"),
    ("bad kind", times_table([*GOOD[:2], "2458305.69239,2,tertiary,2"]), "row 3, column 'kind'"),
    ("half cycle primary", times_table([*GOOD[:2], "2458305.69239,2,primary,2.5"]), "integer"),
    (
        "integer cycle secondary",
        times_table([*GOOD[:2], "2458305.69239,2,secondary,2"]),
        "half-integer",
    ),
    (
        "cycle not a number",
        times_table([*GOOD[:2], "2458305.69239,2,primary,x"]),
        "row 3, column 'cycle'",
    ),
    ("short row", times_table([*GOOD[:2], "2458305.69239,2"]), "row 3"),
    (
        "non-monotonic cycles",
        times_table([GOOD[0], GOOD[1].replace(",1", ",5"), GOOD[2], GOOD[3]]),
        "rows 2 and 3",
    ),
]

#: Initial-ephemeris YAML documents refused, and a phrase of the error.
BAD_INITIAL_FILES: list[tuple[str, str]] = [
    ("name: x\n", "timing: missing"),
    ("timing: {t0: 'BJD_TDB 2458305.68'}\n", "timing.period"),
    ("timing: {period: '-4 s'}\n", "positive period"),
    ("timing: {period: '414 m'}\n", "period like"),
    ("timing: {period: 414, t0: 'HJD 2458305.68'}\n", "BJD_TDB"),
    ("timing: {period: 414, t0: 2458305.68}\n", "labelled"),
    ("timing: {period: 414, t0: 'BJD_UTC 2458305.68'}\n", "convert"),
    ("timing: {period: 414, pdot: fast}\n", "timing.pdot"),
]

#: ``--period`` guesses refused (the error starts "period: ").
BAD_PERIOD_GUESSES: list[str] = ["", "nan", "-1 s", "0", "1e400", "4 parsecs", "x" * 5000]

#: ``ephemeris fit`` options refused, and a phrase of the error as the command line prints it
#: (file names ending .yaml/.json/.png are placed in the test's folder).
BAD_FIT_OPTIONS: list[tuple[list[str], str]] = [
    (["-o", "t.yaml"], "needs name and sky"),
    (["-o", "t.yaml", "--name", "X", "--ra", "25h", "--dec", "0"], "--ra"),
    (["-o", "t.yaml", "--name", "X", "--ra", "10"], "give both"),
    # the library names its parameter; the command line prints the flag (cli/_flags.py)
    (["--terms", "5"], "terms: "),
    (["--clip", "0.5"], "clip: "),
    (["--clip", "nan"], "clip: "),
    (["-o", "t.json", "--format", "yaml"], "suffix"),
    (["--period", "414 s", "--initial", "x.yaml"], "not both"),
    (["-o", "same.png", "--format", "json", "--plot", "same.png"], "two different"),
]
