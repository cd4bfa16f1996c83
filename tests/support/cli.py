"""Run the command line in this process and judge its outcome: the CLI tests' one runner."""

from __future__ import annotations

import contextlib
import io
import sys

from hypothesis import strategies as st

from ucbplan.cli import app as app_module

VALUES = st.one_of(
    st.integers(-(10**12), 10**12).map(str),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.sampled_from(
        [
            "nan",
            "-inf",
            "1e400",
            "0",
            "-0",
            "",
            " ",
            "1,2",
            "0x10",
            "١٢",
            "5 km/s",
            "1h",
            "u=",
            "u=nan",
            "table",
            "json",
            "2040-13-45",
            "9999-01-01",
            "0001-01-01",
            "/dev/null",
            "/",
            ".",
            "paranal",
            "x" * 5000,
            "\x00",
            "é",
            "--help",
        ]
    ),
    st.text(max_size=40),
)


def run_main(args: list[str]) -> tuple[int, str, str]:
    """Run ``ucbplan ARGS`` through the real entry point in this process: exit code, stdout,
    stderr (the one in-process runner of the CLI fuzz tests)."""
    err, out = io.StringIO(), io.StringIO()
    old = sys.argv
    sys.argv = ["ucbplan", *args]
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            try:
                app_module.main()
                code = 0
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 1
    finally:
        sys.argv = old
    return code, out.getvalue(), err.getvalue()


def run_cli(args: list[str]) -> tuple[int, str]:
    """Run ``ucbplan ARGS`` through the real entry point in this process: exit code, stderr."""
    code, _, err = run_main(args)
    return code, err


def check_outcome(code: int, err: str) -> None:
    assert code in (0, 2, 130), f"exit {code}: {err[-600:]}"
    assert "Traceback" not in err, err[-2000:]
    if code == 2:
        lines = [ln for ln in err.splitlines() if ln.strip()]
        last = lines[-1] if lines else ""
        assert len(last) < 400, f"{len(last)} characters: {last[:300]}"
