"""The entry point's contract: exit 0/1/2/130, one line, a traceback only with --debug."""

from __future__ import annotations

import sys
from collections.abc import Callable

import pytest
import typer

from ucbplan.cli import app as app_module
from ucbplan.errors import TargetFileError


def _run_main(monkeypatch: pytest.MonkeyPatch, raiser: Callable[[], object], *args: str) -> int:
    def fake_run() -> int:
        raiser()
        return 0

    monkeypatch.setattr(app_module, "_run", fake_run)
    monkeypatch.setattr(sys, "argv", ["ucbplan", *args])
    with pytest.raises(SystemExit) as exc:
        app_module.main()
    code = exc.value.code
    assert isinstance(code, int)
    return code


def _raise(exc: BaseException) -> Callable[[], object]:
    def f() -> object:
        raise exc

    return f


def test_user_error_is_exit_2_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    err = TargetFileError("t.yaml: lisa.f_gw: expected a frequency [Hz]\nnext line")
    assert _run_main(monkeypatch, _raise(err)) == 2
    out = capsys.readouterr().err.strip()
    assert out.count("\n") == 0 and out.startswith("error: t.yaml: lisa.f_gw")
    assert "[Hz]" in out  # rich markup did not eat the unit


def test_ctrl_c_is_130(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    assert _run_main(monkeypatch, _raise(KeyboardInterrupt())) == 130
    assert "interrupted" in capsys.readouterr().err
    assert _run_main(monkeypatch, lambda: (_ for _ in ()).throw(typer.Abort())) == 130


def test_interrupt_inside_typer_returns_130(monkeypatch: pytest.MonkeyPatch) -> None:
    """typer turns Ctrl-C into a returned 130 in non-standalone mode: main must not lose it."""
    monkeypatch.setattr(app_module, "app", lambda standalone_mode: 130)
    monkeypatch.setattr(sys, "argv", ["ucbplan", "plan"])
    with pytest.raises(SystemExit) as exc:
        app_module.main()
    assert exc.value.code == 130


def test_bug_is_exit_1_one_line_without_traceback(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    assert _run_main(monkeypatch, _raise(ZeroDivisionError("x" * 5000))) == 1
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err and err.count("\n") == 0 and len(err) < 400
    assert err.startswith("internal error: ZeroDivisionError") and "please report" in err


def test_debug_shows_the_traceback(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(app_module, "_run", _raise(ZeroDivisionError("boom")))
    monkeypatch.setattr(sys, "argv", ["ucbplan", "--debug", "plan"])
    with pytest.raises(ZeroDivisionError):
        app_module.main()


def test_os_error_is_a_user_error(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    exc = PermissionError(13, "Permission denied", "/data/t.yaml")
    assert _run_main(monkeypatch, _raise(exc)) == 2
    assert capsys.readouterr().err.strip() == (
        "error: /data/t.yaml: Permission denied; check the path and its permissions"
    )


def test_os_error_on_a_huge_path_is_one_short_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A 5000-character --out-dir (ENAMETOOLONG) is echoed shortened, not in full (issue 33)."""
    exc = OSError(36, "File name too long", "a" * 5000)
    assert _run_main(monkeypatch, _raise(exc)) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and len(err) < 400, len(err)
    assert " characters)" in err and err.endswith("check the path and its permissions")


def test_usage_error_is_one_line() -> None:
    import subprocess

    res = subprocess.run(
        # '--bogus' alone draws click's "(Possible options: --verbose)" since plan has --verbose
        [sys.executable, "-m", "ucbplan", "plan", "--bogus-flag"],
        capture_output=True,
        text=True,
    )
    assert res.returncode == 2
    assert res.stderr.strip() == (
        "error: No such option: --bogus-flag (see `python -m ucbplan plan --help`)"
    )


#: Runs the entry point ``ARGV[1]`` (``run`` or ``main``) with ``ucbplan ARGV[2:]``; an atexit
#: handler (which runs after the entry returned) reports whether the collector was frozen.
_FREEZE_PROBE = """
import atexit, gc, sys
from ucbplan.cli import app
atexit.register(lambda: print("FROZEN", gc.get_freeze_count() > 0, flush=True))
entry = getattr(app, sys.argv[1])
sys.argv = ["ucbplan", *sys.argv[2:]]
entry()
"""


@pytest.mark.parametrize(("entry", "frozen"), [("run", True), ("main", False)])
def test_only_the_process_entry_freezes_the_collector(entry: str, frozen: bool) -> None:
    """The console script (``ucbplan.cli.main`` = ``app.run``) freezes the objects it made when
    it exits, so the interpreter's shutdown does not trace them again (issue 34); ``app.main``,
    what in-process callers use, leaves the collector alone. Exit code and output are the same."""
    import subprocess

    from ucbplan import cli
    from ucbplan._version import __version__

    assert cli.main is app_module.run  # what pyproject's console script calls
    res = subprocess.run(
        [sys.executable, "-c", _FREEZE_PROBE, entry, "--version"], capture_output=True, text=True
    )
    assert res.returncode == 0, res.stderr
    assert res.stdout.splitlines() == [f"ucbplan {__version__}", f"FROZEN {frozen}"]


#: Reports whether the collector was frozen when ``run`` handed over to ``main`` (the command).
_START_PROBE = """
import gc, sys
from ucbplan.cli import app
command = app.main
def probe():
    print("AT-START", gc.get_freeze_count() > 0, flush=True)
    command()
app.main = probe
sys.argv = ["ucbplan", "--version"]
app.run()
"""


def test_the_process_entry_freezes_the_imports_before_the_command() -> None:
    """``app.run`` freezes what the imports made before the command runs, so a full collection
    during a long command does not trace the modules' objects again (issue 34)."""
    import subprocess

    res = subprocess.run([sys.executable, "-c", _START_PROBE], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert res.stdout.splitlines()[0] == "AT-START True"


#: Reports, when ``run`` hands over to ``main`` (the command), OpenBLAS's thread setting and
#: whether numpy was already loaded (OpenBLAS reads the setting once, when numpy loads it).
_BLAS_PROBE = """
import os, sys
from ucbplan.cli import app
command = app.main
def probe():
    print("BLAS", os.environ.get("OPENBLAS_NUM_THREADS"), "numpy" in sys.modules, flush=True)
    command()
app.main = probe
sys.argv = ["ucbplan", "--version"]
app.run()
"""


@pytest.mark.parametrize(("given", "seen"), [(None, "1"), ("3", "3")])
def test_the_process_entry_runs_openblas_on_one_thread_unless_told(
    given: str | None, seen: str
) -> None:
    """``app.run`` sets OpenBLAS to one thread before numpy loads (issue 34: the products are
    ≤ 9 columns wide, where a second thread only spins, ~0.1 CPU s of a semester plan, and a
    result never depends on the thread count); a user's own ``OPENBLAS_NUM_THREADS`` stays."""
    import os
    import subprocess

    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if given is not None:
        env["OPENBLAS_NUM_THREADS"] = given
    res = subprocess.run(
        [sys.executable, "-c", _BLAS_PROBE], capture_output=True, text=True, env=env
    )
    assert res.returncode == 0, res.stderr
    assert res.stdout.splitlines()[0] == f"BLAS {seen} False"


#: Reports the collector's state when ``run`` hands over to ``main`` (the command).
_GC_PROBE = """
import gc, json, sys
from ucbplan.cli import app
before = gc.get_threshold()
command = app.main
def probe():
    print(json.dumps([gc.isenabled(), gc.get_threshold(), before]), flush=True)
    command()
app.main = probe
sys.argv = ["ucbplan", "--version"]
app.run()
"""


def test_the_process_entry_keeps_the_collector_on_with_rare_full_collections() -> None:
    """``app.run`` leaves the collector on and its young generations as they were, but makes a
    full collection 100× rarer (issue 34: one of a command's few full collections re-traces
    every long-lived object its imports made, ~0.1 CPU s of a reduce of 10⁶ spectra)."""
    import json
    import subprocess

    res = subprocess.run([sys.executable, "-c", _GC_PROBE], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    enabled, during, before = json.loads(res.stdout.splitlines()[0])
    assert enabled
    assert during[:2] == before[:2]
    assert during[2] == 100 * before[2]
