"""A differential corpus of target files: the bundled catalogs, the bad-input corpus and random
mutations of them (values swapped for tricky ones, fields dropped or added, sections replaced,
documents joined into catalogs), with a canonical snapshot of a loaded target (every field, bit
for bit) to compare two loaders by. Used by test_target_columnwise.py; also runnable against
another checkout of ucbplan (``python tests/targets/target_corpus.py DIR N SEED`` writes the
files; ``snapshot_run`` loads them).
"""

from __future__ import annotations

import copy
import dataclasses
import datetime as dt
import json
import math
import random
import sys
from pathlib import Path
from typing import Any

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))

from support.bad_targets import DOCUMENTS, LISA_FIELDS, TIMING_FIELDS, timing_with  # noqa: E402
from support.targets import BASE, ztf_j1539_doc  # noqa: E402

#: Values a mutation puts in place of a field's (valid spellings, near misses and garbage).
TRICKY: list[Any] = [
    None, "", " ", True, 0, -0.0, 1, 5.5, -1.0, 1e400, float("nan"), float("inf"), 10**400,
    "5.5", ".nan", "-.inf", "1e400 Hz", "6.2e-3 Hz", " 6.2e-3 Hz", "6.2e-3  Hz", "6.2e-3Hz",
    "6.2e-3 Hz ", "-6.2e-3 Hz", "0 Hz", "6.2e-3 mHz", "6.2e-3 km", "6.2e-3 Hz / s", "5 deg",
    "1 rad", "0.3 cycle", "2.0 kpc", "2 pc", "4 yr", "126232599.05 s", "-4 yr", "7e-16 Hz / s",
    "7e-16 Hz s-1", "7e-16 Hz/s", "1e-26 Hz / s2", "1.5 dex", "3 [Hz]", "1 solMass", "0.2 Msun",
    "390 km/s", "390 km / s", "3e5 km/s", "15 m/s", "08h06m23.2s", "25h00m00s", "8:06:23.2",
    "08 06 23.2", "121.5 deg", "-15d27m30s", "+95d00m00s", "1.5e-05 deg", "2037-01-01T00:00:00",
    "2037-01-01", "2037-01-01T00:00:00 TDB", "2037-01-01T00:00:00 (UTC)", "MJD 65059.5",
    "JD 2465059.5", "MJD 1", "2037-13-01T00:00:00", dt.date(2037, 1, 1),
    dt.datetime(2037, 1, 1, 12), "midpoint", "start", "Midpoint ", "SB1", "sb2", "SB3", "icrs",
    "J2000", "galactic", [1, 2], {"a": 1}, "x" * 150, "a\nb", "bad\x00", "Hz",
]  # fmt: skip
#: Sections a mutation may add a field to, with names that are known and unknown.
NEW_KEYS = ["vmag", "priority", "notes", "frame", "fddot", "eta", "kappa", "omega_dot", "psi",
            "amplitude", "cos_inclination", "distance", "t_ref_is", "t_ref_scale", "samples",
            "magnitudes", "references", "masses", "m1", "K_eff", "K1", "lines", "correlation",
            "l", "b", "bogus", "Name"]  # fmt: skip


def seeds() -> list[Any]:
    """The documents the mutations start from: bundled catalogs, BASE, ZTF J1539, and BASE
    variants with each covariance form."""
    docs = [yaml.safe_load(p.read_text("utf-8")) for p in sorted(ROOT.glob("catalogs/**/*.yaml"))]
    corr = copy.deepcopy(BASE)
    corr["lisa"]["covariance"] = {
        "sigma": {"phase": 0.02, "f_gw": "7.7e-12 Hz", "fdot": "4e-19 Hz / s"},
        "correlation": {"phase,fdot": -0.7},
    }
    full = copy.deepcopy(BASE)
    full["lisa"]["covariance"] = {
        "parameters": ["phase", "f_gw"],
        "matrix": [[4e-4, 1e-14], [1e-14, 5.9e-23]],
    }
    cited = copy.deepcopy(BASE) | {
        "vmag": 21.1,
        "magnitudes": {"V": 21.1, "g": 20.9},
        "references": {"lisa.f_gw": "2019Natur.571..528B", "magnitudes.g": "Gaia DR3"},
    }
    return [*docs, copy.deepcopy(BASE), ztf_j1539_doc(), corr, full, cited]


def bad_corpus() -> list[Any]:
    """Every document of the bad-input corpus (tests/support/bad_targets.py)."""
    out: list[Any] = []
    for extra, _ in LISA_FIELDS:
        doc = copy.deepcopy(BASE)
        doc["lisa"].update(extra)
        out.append(doc)
    out.extend(copy.deepcopy(doc) for doc, _ in DOCUMENTS)
    out.extend(timing_with(path, value) for path, value, _ in TIMING_FIELDS)
    return out


def _leaves(node: Any, path: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Paths of every value inside mappings and lists."""
    out = [path]
    if isinstance(node, dict):
        for k, v in node.items():
            out.extend(_leaves(v, (*path, k)))
    elif isinstance(node, list):
        for k, v in enumerate(node):
            out.extend(_leaves(v, (*path, k)))
    return out


def mutate(doc: Any, rng: random.Random) -> Any:
    """``doc`` with one to three random changes."""
    doc = copy.deepcopy(doc)
    for _ in range(rng.choice((1, 1, 1, 2, 3))):
        paths = _leaves(doc)
        path = rng.choice(paths[1:] or paths)
        if not path:
            return rng.choice(TRICKY)
        *parents, key = path
        node = doc
        for p in parents:
            node = node[p]
        what = rng.random()
        if what < 0.55:
            node[key] = copy.deepcopy(rng.choice(TRICKY))
        elif what < 0.7 and isinstance(node, dict):
            del node[key]
        elif isinstance(node, dict):
            node[rng.choice(NEW_KEYS)] = copy.deepcopy(rng.choice(TRICKY))
    return doc


def _perturbed(value: Any, rng: random.Random) -> Any:
    """A number, or the number of a ``"<number> <unit>"`` text, changed a little (spelled in
    one of several ways); anything else as it is."""
    if isinstance(value, float) and math.isfinite(value):
        return value * (1.0 + rng.uniform(-0.05, 0.05))
    if isinstance(value, str):
        number, space, unit = value.partition(" ")
        try:
            x = float(number)
        except ValueError:
            return value
        x *= 1.0 + rng.uniform(-0.05, 0.05)
        spelled = rng.choice((f"{x:.6g}", f"{x!r}", f"{x:e}", f"{x:.3E}"))
        return f"{spelled}{space}{unit}"
    return value


def perturb(doc: Any, rng: random.Random) -> Any:
    """``doc`` with each number (and number with a unit) changed a little: most stay valid."""
    doc = copy.deepcopy(doc)
    for path in _leaves(doc)[1:]:
        *parents, key = path
        node = doc
        for p in parents:
            node = node[p]
        node[key] = _perturbed(node[key], rng)
    return doc


def corpus(n: int, seed: int) -> tuple[list[list[Any]], list[int]]:
    """Files as lists of documents: the seeds, the bad corpus, then ``n`` random changes of the
    seeds, half of them values changed a little (mostly valid: their indices are returned too),
    half mutations; one file in ten is a catalog of two or three documents."""
    rng = random.Random(seed)
    base = seeds()
    files: list[list[Any]] = [[d] for d in [*base, *bad_corpus()]]
    likely_valid = list(range(len(base)))
    for _ in range(n):
        k = rng.choice((1,) * 9 + (rng.choice((2, 3)),))
        small = rng.random() < 0.5
        change = perturb if small else mutate
        if small:
            likely_valid.append(len(files))
        files.append([change(rng.choice(base), rng) for _ in range(k)])
    return files, likely_valid


def write_corpus(folder: Path, n: int, seed: int) -> list[Path]:
    """The corpus written to ``folder`` as YAML files (``v…`` the likely valid ones)."""
    folder.mkdir(parents=True, exist_ok=True)
    files, valid = corpus(n, seed)
    out = []
    for k, docs in enumerate(files):
        text = yaml.safe_dump_all(docs, allow_unicode=True, sort_keys=False)
        path = folder / f"{'v' if k in valid else 'c'}{k:05d}.yaml"
        path.write_text(text, "utf-8")
        out.append(path)
    return out


def groups_of(paths: list[Path], seed: int) -> list[list[int]]:
    """Random groups of the files (2 to 20), half of them of likely valid files only."""
    rng = random.Random(seed)
    valid = [k for k, p in enumerate(paths) if p.name.startswith("v")]
    return [
        rng.sample(valid if k % 2 else range(len(paths)), rng.choice((2, 5, 20)))
        for k in range(len(paths) // 4)
    ]


def snapshot(value: Any) -> Any:
    """A canonical JSON-able form of a target (or any of its fields): floats as hex, arrays as
    dtype, shape and bytes, Time as its jd1/jd2 bits, scale, format and precision."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = dataclasses.fields(value)
        return [type(value).__name__, {f.name: snapshot(getattr(value, f.name)) for f in fields}]
    if isinstance(value, float):
        return ["float", value.hex() if math.isfinite(value) else repr(value)]
    if isinstance(value, bool | int | str) or value is None:
        return [type(value).__name__, value]
    if isinstance(value, np.ndarray):
        return ["ndarray", str(value.dtype), list(value.shape), value.tobytes().hex()]
    if isinstance(value, Path):
        return ["Path", str(value)]
    if isinstance(value, tuple | list):
        return [type(value).__name__, [snapshot(v) for v in value]]
    if isinstance(value, dict):
        return ["dict", [[snapshot(k), snapshot(v)] for k, v in value.items()]]
    if type(value).__name__ == "Time":
        t = value
        bits = [np.asarray(t.jd1).tobytes().hex(), np.asarray(t.jd2).tobytes().hex()]
        return ["Time", bits, t.scale, t.format, t.precision, t.in_subfmt, t.out_subfmt]
    raise TypeError(f"no snapshot of {type(value).__name__}")


def outcome(call: Any) -> Any:
    """``["ok", snapshots of the targets (and their repr)]`` or ``["error", type, message]``."""
    from ucbplan.errors import UcbplanError

    try:
        targets = call()
    except UcbplanError as exc:
        return ["error", type(exc).__name__, str(exc)]
    return ["ok", [[repr(t), snapshot(t)] for t in targets]]


def snapshot_run(paths: list[Path], groups: list[list[int]]) -> dict[str, Any]:
    """Outcomes of ``load_target_files`` of each file alone and of each group of files."""
    from ucbplan.offline import offline
    from ucbplan.targets import load_target_files

    with offline():
        alone = [outcome(lambda p=p: load_target_files([p])) for p in paths]
        many = [outcome(lambda g=g: load_target_files([paths[k] for k in g])) for g in groups]
    return {"alone": alone, "groups": many}


if __name__ == "__main__":  # python tests/targets/target_corpus.py DIR N SEED [OUT.json]
    folder, n, seed = Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
    files = write_corpus(folder, n, seed) if not folder.exists() else sorted(folder.glob("*"))
    groups = groups_of(files, seed + 1)
    if len(sys.argv) > 4:
        Path(sys.argv[4]).write_text(json.dumps(snapshot_run(files, groups)), "utf-8")
