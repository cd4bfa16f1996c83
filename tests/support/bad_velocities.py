"""The velocity-file bad-input corpus: each way a velocity table can be wrong, with a phrase of its
one-line error (naming the row and the column). Run by tests/reduce/test_velocity_bad_input.py."""

from __future__ import annotations

from support.reduce import HEADER, JD

#: CSV tables (text) the reader refuses, and a phrase of the error.
CSV_TABLES: list[tuple[str, str]] = [
    (HEADER + f"{JD},30,abc,15,1,15,A\n", "row 1, column 'v1'"),
    (HEADER + f"{JD},30,1,15,1,15,A\n{JD},30,1,0,1,15,A\n", "row 2, column 'sigma_v1'"),
    (HEADER + f"{JD},30,1,15,1,-3,A\n", "row 1, column 'sigma_v2'"),
    (HEADER + f"{JD},30,nan,15,1,15,A\n", "row 1, column 'v1'"),
    (HEADER + f"{JD},30,1,15,1,A\n", "row 1 (line 2)"),
    (HEADER + f"{JD},-5,1,15,1,15,A\n", "row 1, column 'exptime_s'"),
    ("bjd_tdb,exptime_s,v1,sigma_v1,v2,sigma_v2,colour\n", "column 'colour'"),
    ("bjd_utc,exptime_s,v,sigma_v\n", "column 'bjd_utc'"),
    ("bjd_tdb,exptime_s,v1,v2,sigma_v2\n", "sigma_v1"),
    ("bjd_tdb,v,sigma_v\n", "exptime_s"),
    (HEADER, "no data rows"),
    ("", "empty velocity file"),
]

#: CSV tables found by issue 11's hardening (blank cells, overflows, repeated columns).
CSV_TABLES_MORE: list[tuple[str, str]] = [
    (HEADER + f"{JD},30,,15,1,15,A\n", "row 1, column 'v1': blank cell"),
    (HEADER + f"{JD},30,1,15,1,15,\n", "row 1, column 'session': blank cell"),
    (HEADER + f"{JD},30,1,15,1e400,15,A\n", "row 1, column 'v2'"),
    (HEADER + f"{JD},30,3e5,15,1,15,A\n", "speed of light"),
    (HEADER + "1e300,30,1,15,1,15,A\n", "row 1, column 'bjd_tdb'"),
    (HEADER + f"{'9' * 5000},30,1,15,1,15,A\n", "characters"),
    ("bjd_tdb,exptime_s,v1,sigma_v1,V1,sigma_v2\n", "column 'v1': appears twice"),
    ("bjd_tdb,exptime_s,v,sigma_v,exptime_s\n", "column 'exptime_s': appears twice"),
]

#: ECSV data rows (columns bjd_tdb v sigma_v exptime_s) the reader refuses, and a phrase of the
#: error.
ECSV_ROWS: list[tuple[list[str], str]] = [
    ([f'{JD} "" 15 30', f"{JD + 0.01} 2 15 30"], "row 1, column 'v': blank cell"),
    ([f"{JD} 1 15 30", f'{JD + 0.01} 2 15 ""'], "row 2, column 'exptime_s': blank cell"),
    ([f"{JD} 1 15 30", f"{JD + 0.01} inf 15 30"], "row 2, column 'v'"),
    ([f"{JD} 1 -15 30", f"{JD + 0.01} 1 15 30"], "row 1, column 'sigma_v'"),
]
