"""Fixtures of the export tests: ``fake_p2``, a local fake of ESO's p2 server (support/eso_p2)."""

from __future__ import annotations

from support.eso_p2 import fake_p2

__all__ = ["fake_p2"]
