"""Run an independent corpus of bad inputs through the real CLI and count what went wrong.

Each case runs ``python -m ucbplan …`` in a subprocess (30 s limit) in a fresh folder that holds
one pre-existing output file. A case fails the contract when the CLI prints a traceback, hangs,
exits with a code other than 0/2/130, changes or leaves files on failure, or prints an error that
is not one line of < 400 characters. The corpus is built here from mutations unlike the in-repo
hypothesis strategies (byte-level damage, whole-file swaps, option permutations).

    python benchmarks/bad_input_corpus.py [--n 200] [--seed 1]
"""

from __future__ import annotations

import argparse
import hashlib
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


def _cases(n: int, rng: random.Random, work: Path) -> list[tuple[str, list[str]]]:
    cases: list[tuple[str, list[str]]] = []
    for k in range(n):
        case = work / f"c{k:04d}"
        case.mkdir()
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


def _snapshot(folder: Path) -> dict[str, str]:
    return {
        p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.iterdir() if p.is_file()
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
            timeout=30,
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
        last = [ln for ln in err.splitlines() if ln.startswith("error:")]
        if not last or len(last[-1]) >= 400:
            return f"error not one short line: {cmd[:3]}: {err.strip()[-200:]}"
    return None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    rng = random.Random(args.seed)
    with tempfile.TemporaryDirectory() as tmp:
        cases = _cases(args.n, rng, Path(tmp))
        with ThreadPoolExecutor(max_workers=2) as pool:
            problems = [p for p in pool.map(_run, cases) if p]
    kinds = {
        k: sum(p.startswith(k) for p in problems)
        for k in ("traceback", "hang", "exit", "files changed", "error not")
    }
    print(
        f"{args.n} bad-input cases (seed {args.seed}): "
        + ", ".join(f"{v} {k}" for k, v in kinds.items())
    )
    for p in problems[:20]:
        print("  " + p)
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
