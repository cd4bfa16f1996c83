"""Benchmark (issue 23): what a user waits for in ``ucbplan plan``, through the CLI.

Two rows, both in CPU seconds (the machine is shared: time slices lost to other processes count
for neither side):

* **exposure-dense nights**: every observable u = 0 epoch of one target planned as its own
  exposure (``--mode u=0 --sessions 1000 --overhead 0``) and written to an ECSV blocks table;
  the marginal cost per planned block is (30 nights − 1 night) / (blocks of 30 − blocks of 1),
  i.e. records, table, header and file included, each the least of :data:`DENSE_RUNS` runs.
  Peers: astroplan's ``is_event_observable`` (batched per target, block start and end) and
  naive astropy (one ``AltAz`` transform of target, Sun and Moon) on a random sample of the
  same target's blocks, timed in CPU seconds
  alternately with each other (:func:`plan_peers.peer_rates`). They do less: they neither find
  the epochs, remove the light time, nor write anything. Goal: ≥ 100× both.
* **semester**: 10 targets × 183 nights (quadrature, the defaults) through the CLI against the
  fixed numpy workload (:mod:`benchmarks._workload`), each CLI run preceded by one workload run;
  least of two. Goal: ≤ 7.2× the workload.

Usage: ``python -m benchmarks --only plan_dense`` or ``python benchmarks/plan_dense.py``.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
import warnings
from datetime import date, timedelta
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _workload import children_cpu_s, compile_package, workload_s
from bench_plan import make_targets
from plan_peers import make_samples, peer_rates, random_picks

from ucbplan.observing.blocks.block import ExposurePlan
from ucbplan.observing.observatory.sites import get_site
from ucbplan.observing.schedule import PlanSettings, night_windows
from ucbplan.observing.schedule.candidates import prepare_runs
from ucbplan.offline import offline
from ucbplan.targets.write import write_target

REPO = Path(__file__).resolve().parents[1]
#: The exposure-dense target of :func:`bench_plan.make_targets` (~85 u = 0 exposures a night in
#: January at Paranal: "a visit holds dozens of exposures").
DENSE = 3
DENSE_OPTS = ["--mode", "u=0", "--sessions", "1000", "--overhead", "0"]
#: Runs of each dense plan, alternated (1 night, 30 nights, 1 night, ...), least of each: the
#: marginal cost is the difference of two ~1-s CPU times, and with the least of 2 the same code
#: read 40–90 µs/block on a busy 2-core machine.
DENSE_RUNS = 4
GOAL_PEER, GOAL_WORKLOAD = 100.0, 7.2


def cli(files: list[Path], n_nights: int, out: Path, opts: list[str]) -> tuple[float, int]:
    """(CPU s of ``ucbplan plan`` in a fresh process, blocks written) to the ECSV ``out``."""
    cmd = [sys.executable, "-m", "ucbplan", "plan", *map(str, files), "--site", "paranal"]
    cmd += ["--night", "2040-01-01", "--nights", str(n_nights), *opts]
    cmd += ["-o", str(out), "--overwrite"]
    compile_package()
    c0 = children_cpu_s()
    subprocess.run(cmd, check=True, capture_output=True, cwd=REPO)
    cpu = children_cpu_s() - c0
    rows = sum(1 for line in out.read_text().splitlines() if not line.startswith("#")) - 1
    return cpu, rows


def peer_samples(n_sample: int) -> list:  # type: ignore[type-arg]
    """A random sample of the dense target's candidate u = 0 blocks (30 nights)."""
    target = make_targets(10)[DENSE]
    nights = [date(2040, 1, 1) + timedelta(days=k) for k in range(30)]
    settings = PlanSettings(mode="u=0", exposure=ExposurePlan(60.0))
    site = get_site("paranal")
    frame, runs, _ = prepare_runs([target], site, night_windows(site, nights), settings)
    picks = random_picks([runs[0].cand.x_mid.size], n_sample, seed=3)
    return make_samples([target.coord], [(runs[0].cand, frame.axis)], picks)


def dense_rows(files: list[Path], tmp: Path, n_sample: int) -> list[dict[str, object]]:
    """Marginal CPU cost per planned block against astroplan and naive astropy."""
    runs = [
        (
            cli(files, 1, tmp / "one.ecsv", DENSE_OPTS),
            cli(files, 30, tmp / "month.ecsv", DENSE_OPTS),
        )
        for _ in range(DENSE_RUNS)
    ]
    one, month = min(r[0] for r in runs), min(r[1] for r in runs)
    per_us = 1e6 * (month[0] - one[0]) / (month[1] - one[1])
    samples = peer_samples(n_sample)
    rates = peer_rates(get_site("paranal").location, samples, _cs(), clock=time.process_time)
    note = (
        f"{month[1] - one[1]} more blocks in {month[0] - one[0]:.2f} CPU s (30 nights: "
        f"{month[1]} blocks, {month[0]:.2f} s; 1 night: {one[1]}, {one[0]:.2f} s), ECSV written; "
        f"peers on {sum(s.size for s in samples)} sampled blocks of the same target, CPU s"
    )
    out = []
    for peer, rate in rates.items():
        row: dict[str, object] = {
            "name": "plan, every u=0 epoch planned and written (CLI, 1 target, 30 − 1 nights), "
            f"marginal cost per block{'' if peer == 'astroplan' else ' vs naive astropy'}",
            "value": per_us,
            "unit": "µs/block (CPU)",
            "goal": f"≥ {GOAL_PEER:g}× {peer}",
            "note": note,
        }
        if rate is not None:
            ratio = 1e6 / rate / per_us
            row |= {"ratio": ratio, "peer": f"{peer} ({1e6 / rate:.0f} µs/block)"}
            row["met"] = bool(ratio >= GOAL_PEER)
        out.append(row)
    return out


def _cs():  # type: ignore[no-untyped-def]
    """The constraints astroplan is given (night, airmass, Moon; no zenith hole)."""
    return PlanSettings(exposure=ExposurePlan(60.0)).constraints(None)


def semester_row(files: list[Path], tmp: Path) -> dict[str, object]:
    """The semester through the CLI against the numpy workload, CPU s, least of two."""
    best, work, blocks = float("inf"), float("inf"), 0
    for _ in range(2):
        work = min(work, workload_s(1))
        cpu, blocks = cli(files, 183, tmp / "semester.ecsv", [])
        best = min(best, cpu)
    work = min(work, workload_s(1))
    ratio = best / work
    return {
        "name": f"semester plan via the CLI, {len(files)} targets × 183 nights (quadrature)",
        "value": best,
        "unit": "CPU s",
        "ratio": work / best,
        "peer": f"numpy workload ({work:.3f} CPU s; ours = {ratio:.2f}× it)",
        "goal": f"≤ {GOAL_WORKLOAD:g}× the workload",
        "met": bool(ratio <= GOAL_WORKLOAD),
        "note": f"fresh process, {blocks} blocks written to ECSV; least of 2 runs, each after "
        "a workload run",
    }


@offline()
def rows(quick: bool) -> list[dict[str, object]]:
    """The exposure-dense marginal cost per block and the semester, through the CLI."""
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        files = []
        for t in make_targets(10):
            files.append(tmp / f"{t.name}.yaml")
            write_target(t, files[-1])
        dense = dense_rows([files[DENSE]], tmp, 300 if quick else 1500)
        return [*dense, semester_row(files, tmp)]


if __name__ == "__main__":
    for r in rows("--quick" in sys.argv):
        ratio = f"; {r['ratio']:.3g}x {r['peer']}" if r.get("ratio") else ""
        print(f"{r['name']}: {r['value']:,.4g} {r['unit']}{ratio} (goal {r['goal']})")
