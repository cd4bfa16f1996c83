"""The population commands' shared options: declared once, in every command, into one value."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
import typer

from ucbplan.cli import population as cli_population
from ucbplan.cli._population_options import (
    PARTS_OPTIONS,
    SHARED_OPTIONS,
    PopulationArgs,
    population_options,
)
from ucbplan.errors import InputError
from ucbplan.population.execute import ExecutorSpec
from ucbplan.population.runner import RunControl

SHARED = [name for name, _, _ in SHARED_OPTIONS]
PARTS = [name for name, _, _ in PARTS_OPTIONS]


def _params(name: str) -> list[str]:
    group = typer.main.get_command(cli_population.population_app)
    return [p.name for p in group.commands[name].params]  # type: ignore[attr-defined]


def test_the_value_has_one_field_per_declared_option() -> None:
    assert [f.name for f in dataclasses.fields(PopulationArgs)] == SHARED + PARTS


@pytest.mark.parametrize("command", ["forecast", "visibility", "rank", "simulate"])
def test_every_command_lists_the_shared_options_together_and_in_order(command: str) -> None:
    names = _params(command)
    want = SHARED + (PARTS if command != "rank" else [])
    start = names.index(SHARED[0])
    assert names[start : start + len(want)] == want
    assert "shared" not in names and names[-1] == "overwrite"
    if command == "rank":  # rank keeps no part files
        assert not set(PARTS) & set(names)


def test_the_values_reach_the_run_control(tmp_path: Path) -> None:
    values = {name: default for name, _, default in SHARED_OPTIONS + PARTS_OPTIONS}
    args = PopulationArgs(**{**values, "workers": 3, "chunk": 7, "resume": True})
    control = args.control(tmp_path / "p", overwrite=True)
    assert control == RunControl(tmp_path / "p", ExecutorSpec(workers=3), 7, True, True)
    with pytest.raises(InputError, match=r"^workers: ") as info:  # the CLI prints --workers
        dataclasses.replace(args, workers=0).control(tmp_path, overwrite=False)
    assert info.value.parameter == "workers"


def test_a_command_without_a_place_for_the_options_is_refused() -> None:
    def command(catalog: Path) -> None:
        """Has no ``shared`` parameter."""

    with pytest.raises(TypeError, match="shared"):
        population_options()(command)
