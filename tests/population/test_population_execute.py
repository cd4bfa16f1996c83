"""The executor seam's options: --cluster slurm|pbs (dask-jobqueue), --scheduler, --jobs."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from ucbplan.errors import InputError
from ucbplan.population.execute import ExecutorSpec, jobqueue_cluster_class, open_executor

ROOT = Path(__file__).resolve().parents[2]
CATALOG = ROOT / "catalogs" / "population" / "ldc-200.ecsv"


def _open(spec: ExecutorSpec) -> None:
    with open_executor(spec):
        pass


@pytest.mark.parametrize(
    ("kw", "needle"),
    [
        ({"cluster": "sge"}, "expected slurm or pbs"),
        ({"cluster": "slurm", "scheduler": "tcp://h:8786"}, "not both"),
        ({"cluster": "slurm", "jobs": 0}, "^jobs: "),
        ({"scheduler": "h:8786"}, "tcp://HOST:8786"),
        ({"workers": 0}, "^workers: "),
    ],
)
def test_bad_cluster_options_are_one_line(kw: dict[str, object], needle: str) -> None:
    with pytest.raises(InputError, match=needle) as exc:
        ExecutorSpec(**kw)  # type: ignore[arg-type]
    assert "\n" not in str(exc.value) and len(str(exc.value)) < 400


def test_missing_dask_jobqueue_is_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "dask_jobqueue", None)  # import raises ImportError
    with pytest.raises(InputError, match="pip install dask-jobqueue"):
        jobqueue_cluster_class("slurm")


def test_cluster_classes_and_an_unconfigured_cluster(monkeypatch: pytest.MonkeyPatch) -> None:
    jq = pytest.importorskip("dask_jobqueue")
    assert jobqueue_cluster_class("SLURM") is jq.SLURMCluster
    assert jobqueue_cluster_class("pbs") is jq.PBSCluster
    import dask

    # no cores/memory configured: dask-jobqueue refuses before starting anything (no network)
    with dask.config.set({"jobqueue.slurm.cores": None, "jobqueue.slurm.memory": None}):
        with pytest.raises(InputError, match=r"jobqueue\.yaml") as exc:
            _open(ExecutorSpec(cluster="slurm"))
    assert "\n" not in str(exc.value)


def test_describe() -> None:
    assert ExecutorSpec().describe() == "serial"
    assert ExecutorSpec(workers=2).describe() == "2-process pool"
    assert "slurm" in ExecutorSpec(cluster="slurm", jobs=4).describe()


def test_cli_cluster_error_exits_2_without_output(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from ucbplan.cli import app as app_module

    out = tmp_path / "f.ecsv"
    argv = ["ucbplan", "population", "forecast", str(CATALOG), "-o", str(out), "--cluster", "lsf"]
    monkeypatch.setattr(sys, "argv", argv)
    with pytest.raises(SystemExit) as exc:
        app_module.main()
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "--cluster" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()
