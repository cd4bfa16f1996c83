"""Shared helpers, builders and bad-input corpora of the test suite.

Imported as ``support.<topic>``; ``pythonpath = ["tests"]`` in pyproject.toml
puts tests/ on sys.path.
"""
