"""No network in a fresh interpreter or Jupyter kernel a test starts (the in-process tests are
kept offline by tests/conftest.py)."""

from __future__ import annotations

#: Python source to run first in the child: every socket connection is refused with OSError and
#: its arguments recorded in the list ``_attempts`` (the test asserts it stays empty).
BLOCK_SOCKETS = """
import socket
_attempts = []
def _refuse(*args, **kwargs):
    _attempts.append(args)
    raise OSError("network blocked by the test")
socket.socket.connect = _refuse
socket.create_connection = _refuse
"""
