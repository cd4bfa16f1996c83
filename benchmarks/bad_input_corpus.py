"""Run an independent corpus of bad inputs through the real CLI and count what went wrong.

Each case runs ``python -m ucbplan …`` in a subprocess (30 s limit, 120 s for population) in
a fresh folder that holds one pre-existing output file. A case fails the contract when the CLI
prints a traceback, hangs, exits with a code other than 0/2/130, changes or leaves files or
folders on failure, or prints an error that is not one message of < 400 characters (a long
message may wrap with a hanging indent on a terminal) as its last output. The corpus is built
here from mutations unlike the in-repo hypothesis strategies (byte-level damage, whole-file
swaps, option permutations).

    python benchmarks/bad_input_corpus.py [--n 200] [--seed 1] [--surface core|new|all]

``--surface new`` draws only from the newer surfaces (eclipse-time fits, population commands,
the exports, several targets per horizon, the newer plan and feasibility options); a run that
succeeds and prints JSON must print valid JSON (no NaN).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import random
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CAT = ROOT / "catalogs"
TARGETS = [
    CAT / "hm-cnc-simulated.yaml",
    CAT / "fiducial-eccentric.yaml",
    CAT / "examples" / "synthetic-eclipsing.yaml",
]
VELOCITIES = CAT / "fiducial-eccentric-velocities.csv"


def _damage(data: bytes, rng: random.Random) -> bytes:
    kind = rng.choice(["flip", "cut", "dup", "insert", "latin1", "swap"])
    b = bytearray(data)
    if kind == "flip" and b:
        for _ in range(rng.randint(1, 5)):
            b[rng.randrange(len(b))] = rng.randrange(256)
    elif kind == "cut":
        b = b[: rng.randrange(len(b) + 1)]
    elif kind == "dup":
        i = rng.randrange(len(b) + 1)
        b = b[:i] + b[i : i + rng.randint(1, 200)] * rng.randint(2, 50) + b[i:]
    elif kind == "insert":
        junk = rng.choice(
            [
                b"\x00",
                b"&a [*a, *a]",
                b": :",
                b"\t",
                b"nan",
                b"1e999",
                b"\xff\xfe",
                b"\n  - x",
                b"'",
                b'"',
                b"---\n",
                "Ωμέγα".encode(),
            ]
        )
        i = rng.randrange(len(b) + 1)
        b = b[:i] + junk + b[i:]
    elif kind == "latin1":
        b = bytes(b).decode("utf-8", "replace").encode("latin-1", "replace")
    else:
        lines = bytes(b).split(b"\n")
        rng.shuffle(lines)
        b = bytearray(b"\n".join(lines))
    return bytes(b)


def _cases(n: int, rng: random.Random, work: Path, surface: str) -> list[tuple[str, list[str]]]:
    cases: list[tuple[str, list[str]]] = []
    base = _base_inputs(work) if surface != "core" else {}
    for k in range(n):
        case = work / f"c{k:04d}"
        case.mkdir()
        if surface == "new" or (surface == "all" and rng.random() < 0.5):
            (case / "existing.json").write_text("keep me\n")
            cases.append((str(case), _new_case(rng, case, base)))
            continue
        target = case / "t.yaml"
        target.write_bytes(_damage(rng.choice(TARGETS).read_bytes(), rng))
        vel = case / "v.csv"
        vel.write_bytes(
            _damage(VELOCITIES.read_bytes(), rng) if rng.random() < 0.7 else VELOCITIES.read_bytes()
        )
        (case / "existing.json").write_text("keep me\n")
        good = str(rng.choice(TARGETS))
        cmd = rng.choice(
            [
                ["validate", str(target)],
                ["horizon", str(target), "-o", str(case / "existing.json")],
                ["horizon", str(target), "-o", str(case / "h.json")],
                [
                    "ephemeris",
                    str(target),
                    "--start",
                    "2040-01-01T00:00",
                    "--end",
                    "2040-01-01T00:30",
                ],
                [
                    "plan",
                    str(target),
                    "--site",
                    "paranal",
                    "--night",
                    "2040-02-15",
                    "-o",
                    str(case / "b.ecsv"),
                ],
                [
                    "reduce",
                    good if rng.random() < 0.5 else str(target),
                    str(vel),
                    "--samples",
                    "300",
                    "-o",
                    str(case / "r.json"),
                ],
                ["feasibility", str(target), "-o", str(case / "f.json")],
                [
                    "plan",
                    good,
                    "--site",
                    rng.choice(["paranal", "nowhere", "", "keck"]),
                    "--night",
                    rng.choice(["2040-02-15", "2040-02-30", "0", "2040-02-15T00:00"]),
                    "--exptime",
                    rng.choice(["60", "-1", "nan", "1e300", "abc"]),
                    "-o",
                    str(case),
                ],
            ]
        )
        cases.append((str(case), cmd))
    return cases


TIMES_GOOD = "bjd_tdb,sigma_s,kind\n" + "".join(
    f"{2458305.6827886 + (n * 414.7915404) / 86400:.10f},2,primary\n"
    for n in (0, 1, 2, 3, 4, 5, 6, 7, 208, 209, 210, 211, 624, 625, 626, 1456, 1457, 1458)
)


def _base_inputs(work: Path) -> dict[str, Path]:
    """Good inputs made once with the real CLI: a 2-source catalog, its forecast, blocks."""
    base = work / "base"
    base.mkdir()
    cat = base / "c2.ecsv"
    lines = (CAT / "population" / "ldc-200.ecsv").read_text().splitlines()
    header = [ln for ln in lines if ln.startswith("#")]
    body = [ln for ln in lines if not ln.startswith("#")]
    cat.write_text("\n".join([*header, *body[:3]]) + "\n")
    forecast, blocks = base / "f.ecsv", base / "b.ecsv"
    for cmd in (
        ["population", "forecast", str(cat), "-o", str(forecast)],
        ["plan", str(TARGETS[0]), "--site", "paranal", "--night", "2040-02-15", "-o", str(blocks)],
    ):
        subprocess.run([sys.executable, "-m", "ucbplan", *cmd], check=True, capture_output=True)
    times = base / "times.csv"
    times.write_text(TIMES_GOOD)
    return {"cat": cat, "forecast": forecast, "blocks": blocks, "times": times}


def _pick(rng: random.Random, *values: str) -> str:
    return rng.choice(values)


def _new_case(rng: random.Random, case: Path, base: dict[str, Path]) -> list[str]:
    """One command line on the newer surfaces, with damaged files or doubtful options."""
    files = {}
    for name, path in base.items():
        damaged = case / f"{name}{path.suffix}"
        data = path.read_bytes()
        damaged.write_bytes(_damage(data, rng) if rng.random() < 0.6 else data)
        files[name] = str(damaged)
    target = case / "t.yaml"
    target.write_bytes(_damage(rng.choice(TARGETS).read_bytes(), rng))
    good = str(rng.choice(TARGETS))
    num = ("1", "0", "-1", "nan", "1e300", "abc", "2.5", "200", "360", "-30")
    return rng.choice(
        [
            ["ephemeris", "fit", files["times"], "-o", str(case / _pick(rng, "f.yaml", "f.json"))],
            ["ephemeris", "fit", files["times"], "--period", _pick(rng, "414.79 s", "1 s", "x")],
            [
                "ephemeris",
                "fit",
                files["times"],
                "--plot",
                str(case / _pick(rng, "o.png", "o.txt", "figs")),
            ],
            ["ephemeris", "fit", files["times"], "--terms", _pick(rng, *num), "--format", "json"],
            ["population", "forecast", files["cat"], "-o", str(case / "f.ecsv")],
            [
                "population",
                "rank",
                files["forecast"],
                "--out-dir",
                str(case / "r"),
                _pick(rng, "--goal", "--top", "--readout", "--visit", "--sigma-ref"),
                _pick(rng, *num, "q=1%,M1=2%", "K1=5%", "10,17,600"),
            ],
            ["population", "rank", files["cat"], "--out-dir", str(case / "r" / "deep")],
            [
                "population",
                "simulate",
                files["cat"],
                "-o",
                str(case / "s.ecsv"),
                "--out-dir",
                str(case / "sd"),
                "--steps",
                _pick(rng, "0", "5", "-1"),
                "--walkers",
                _pick(rng, "2", "12", "x"),
            ],
            [
                "population",
                "visibility",
                files["cat"],
                "-o",
                str(case / "v.ecsv"),
                "--semester",
                _pick(rng, "2041A", "2041C", "P147"),
                "--site-lonlat",
                _pick(rng, "200,0,0", "1,2", "-70,-24,2600"),
            ],
            [
                "export",
                files["blocks"],
                "--to",
                _pick(rng, "phase-table", "eso-p2", "proposal", "ics", "lco", "gemini", "x"),
                "-o",
                str(case / _pick(rng, "e.out", "existing.json")),
            ],
            [
                "horizon",
                str(target),
                good,
                _pick(rng, good, str(case), str(target)),
                "--format",
                _pick(rng, "json", "csv", "ecsv"),
            ],
            ["horizon", good, str(target), "-o", str(case / "h.json")],
            [
                "plan",
                good,
                _pick(rng, good, str(target)),
                "--site",
                "paranal",
                "--night",
                "2040-02-15",
                "-o",
                str(case / "b.ecsv"),
            ],
            [
                "plan",
                good,
                "--site",
                "paranal",
                "--site-lonlat",
                "-70,-24,2600",
                "--night",
                "2040-02-15",
            ],
            [
                "plan",
                good,
                "--site",
                "paranal",
                "--night",
                "2040-02-15",
                "--instruments-file",
                str(case / "missing.yaml"),
            ],
            [
                "feasibility",
                _pick(rng, good, str(target)),
                _pick(rng, "--optical-sigma-p", "--optical-sigma-pdot", "--optical-sigma-phase"),
                _pick(rng, *num),
                "--plot",
                str(case / _pick(rng, "f.png", "f.txt")),
            ],
        ]
    )


def _snapshot(folder: Path) -> dict[str, str]:
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        if p.is_file()
        else "folder"
        for p in folder.rglob("*")
    }


def _run(case: tuple[str, list[str]]) -> str | None:
    folder, cmd = Path(case[0]), case[1]
    before = _snapshot(folder)
    env = {**os.environ, "COLUMNS": "100"}
    try:
        res = subprocess.run(
            [sys.executable, "-m", "ucbplan", *cmd],
            capture_output=True,
            text=True,
            timeout=120 if cmd[0] == "population" else 30,  # per-source work: minutes, not s
            cwd=folder,
            env=env,
        )
    except subprocess.TimeoutExpired:
        return f"hang: {cmd[:3]}"
    err = res.stderr
    if "Traceback" in err:
        return f"traceback: {cmd[:3]}: {err.strip().splitlines()[-1][:200]}"
    if res.returncode not in (0, 2, 130):
        return f"exit {res.returncode}: {cmd[:3]}: {err.strip()[-200:]}"
    if res.returncode != 0:
        after = _snapshot(folder)
        if after != before:
            return f"files changed on failure: {cmd[:3]}: {sorted(set(after) ^ set(before))}"
        lines = _messages(err)
        errors = [ln for ln in lines if ln.startswith("error:")]
        if len(errors) != 1 or lines[-1] != errors[0] or len(errors[0]) >= 400:
            return f"error not one short line: {cmd[:3]}: {err.strip()[-200:]}"
    elif res.stdout.lstrip().startswith(("{", "[")):
        try:
            json.loads(res.stdout, parse_constant=_no_constant)
        except ValueError as exc:
            return f"invalid JSON on stdout: {cmd[:3]}: {exc}"
    return None


def _messages(err: str) -> list[str]:
    """Stderr as messages: a line indented under the one before (the terminal's hanging indent
    of a long message) continues it."""
    out: list[str] = []
    for line in err.splitlines():
        if line.startswith(" ") and line.strip() and out:
            out[-1] += " " + line.strip()
        elif line.strip():
            out.append(line)
    return out


def _no_constant(token: str) -> None:
    raise ValueError(f"non-standard token {token}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--surface", choices=("core", "new", "all"), default="all")
    args = ap.parse_args()
    rng = random.Random(args.seed)
    with tempfile.TemporaryDirectory() as tmp:
        cases = _cases(args.n, rng, Path(tmp), args.surface)
        with ThreadPoolExecutor(max_workers=2) as pool:
            problems = [p for p in pool.map(_run, cases) if p]
    kinds = {
        k: sum(p.startswith(k) for p in problems)
        for k in ("traceback", "hang", "exit", "files changed", "error not", "invalid JSON")
    }
    print(
        f"{args.n} bad-input cases (seed {args.seed}, {args.surface} surfaces): "
        + ", ".join(f"{v} {k}" for k, v in kinds.items())
    )
    for p in problems[:20]:
        print("  " + p)
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
