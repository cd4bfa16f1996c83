"""Shared helpers, builders and bad-input corpora of the test suite.

Imported as ``support.<topic>``; ``pythonpath = ["tests"]`` in pyproject.toml
puts tests/ on sys.path.

One bad-input corpus per input surface, ``support/bad_<surface>.py`` (the cases
as data, each with a phrase of its one-line error), run by one test module:
target files (bad_targets → targets/test_target_bad_input.py), velocity files
(bad_velocities → reduce/test_velocity_bad_input.py), CLI option values
(bad_options → cli/test_option_bad_input.py), observed files and observing logs
(bad_observed → observing/precision/test_observed_bad_input.py), blocks tables
given to export (bad_blocks → observing/exports/test_exports_hardening.py) and
eclipse-time input (bad_eclipse_times → timing/test_eclipse_times_bad_input.py).
"""
