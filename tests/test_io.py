"""The one output writer: atomic, exclusive without --overwrite, regular files only, umask mode."""

from __future__ import annotations

import os
import stat
import threading
from pathlib import Path
from typing import IO, Any

import pytest

from ucbplan.errors import InputError, OutputError, OutputExistsError
from ucbplan.io import output_format, write_file_set, write_output


def _text(s: str) -> Any:
    def w(h: IO[str]) -> None:
        h.write(s)

    return w


def test_writes_and_refuses_overwrite(tmp_path: Path) -> None:
    out = tmp_path / "a.txt"
    write_output(out, _text("one"))
    with pytest.raises(OutputExistsError):
        write_output(out, _text("two"))
    assert out.read_text() == "one"
    write_output(out, _text("two"), overwrite=True)
    assert out.read_text() == "two"


def test_failed_writer_leaves_nothing(tmp_path: Path) -> None:
    out = tmp_path / "a.txt"

    def bad(h: IO[str]) -> None:
        h.write("partial")
        raise RuntimeError("boom")

    with pytest.raises(RuntimeError):
        write_output(out, bad)
    assert list(tmp_path.iterdir()) == []
    write_output(out, _text("old"))
    with pytest.raises(RuntimeError):
        write_output(out, bad, overwrite=True)
    assert out.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"]


def test_mode_follows_umask(tmp_path: Path) -> None:
    old = os.umask(0o022)
    try:
        write_output(tmp_path / "a", _text("x"))
        os.umask(0o077)
        write_output(tmp_path / "b", _text("x"))
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a").stat().st_mode) == 0o644
    assert stat.S_IMODE((tmp_path / "b").stat().st_mode) == 0o600


def test_refuses_directories_and_devices(tmp_path: Path) -> None:
    with pytest.raises(OutputError, match="folder"):
        write_output(tmp_path, _text("x"), overwrite=True)
    with pytest.raises(OutputError, match="not a regular file"):
        write_output(Path("/dev/null"), _text("x"), overwrite=True)
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)  # the device node is untouched
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with pytest.raises(OutputError, match="not a regular file"):
        write_output(fifo, _text("x"), overwrite=True)


def test_missing_and_read_only_folder(tmp_path: Path) -> None:
    with pytest.raises(OutputError, match="does not exist"):
        write_output(tmp_path / "nope" / "a.txt", _text("x"))
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        if os.access(ro, os.W_OK):  # root ignores permissions: emulate the OS's answer

            def denied(h: IO[str]) -> None:
                raise PermissionError(13, "Permission denied")

            with pytest.raises(OutputError, match="not writable"):
                write_output(ro / "a.txt", denied)
        else:
            with pytest.raises(OutputError, match="not writable"):
                write_output(ro / "a.txt", _text("x"))
        assert list(ro.iterdir()) == []
    finally:
        ro.chmod(0o755)


def test_concurrent_new_file_writers_exactly_one_wins(tmp_path: Path) -> None:
    out = tmp_path / "plan.ecsv"
    barrier = threading.Barrier(8)
    results: list[str] = []

    def run(i: int) -> None:
        def w(h: IO[str]) -> None:
            barrier.wait()  # everybody has passed the existence check before anybody commits
            h.write(f"writer {i}")

        try:
            write_output(out, w)
            results.append("ok")
        except OutputExistsError:
            results.append("exists")

    threads = [threading.Thread(target=run, args=(i,)) for i in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(results) == ["exists"] * 7 + ["ok"]
    assert out.read_text().startswith("writer ")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.ecsv"]


def test_file_set_is_all_or_nothing(tmp_path: Path) -> None:
    a, b = tmp_path / "post.yaml", tmp_path / "post.samples.ecsv"
    b.write_text("someone else's")
    with pytest.raises(OutputExistsError):
        write_file_set({a: _text("A"), b: _text("B")})
    assert not a.exists() and b.read_text() == "someone else's"

    def bad(h: IO[str]) -> None:
        raise RuntimeError("interrupted")

    with pytest.raises(RuntimeError):
        write_file_set({a: _text("A"), tmp_path / "c": bad})
    assert not a.exists()
    (tmp_path / "sub").mkdir()
    with pytest.raises(OutputError, match="same file"):
        write_file_set({a: _text("A"), tmp_path / "sub" / ".." / "post.yaml": _text("B")})


def test_output_format_rule() -> None:
    allowed = ("table", "json", "ecsv", "csv")
    assert output_format(Path("x.json"), None, allowed, "table") == "json"
    assert output_format(Path("x.dat"), None, allowed, "ecsv") == "ecsv"
    assert output_format(None, None, allowed, "table") == "table"
    assert output_format(Path("x.ecsv"), "ecsv", allowed, "table") == "ecsv"
    with pytest.raises(InputError, match="suffix says json"):
        output_format(Path("x.json"), "ecsv", allowed, "table")
    with pytest.raises(InputError, match="expected one of"):
        output_format(None, "xml", allowed, "table")


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full")
def test_full_disk_is_one_line(tmp_path: Path) -> None:
    # /dev/full as a *folder* cannot be used; emulate ENOSPC through the writer instead
    def full(h: IO[str]) -> None:
        raise OSError(28, "No space left on device")

    with pytest.raises(OutputError, match="no space left"):
        write_output(tmp_path / "a.txt", full)
    assert list(tmp_path.iterdir()) == []
