"""Library errors name Python parameters, never flags; the CLI renders them as its flags.

The library (everything outside ``ucbplan.cli``) writes a parameter bare at the start of a
message (``max_visit: …``) or between backticks elsewhere (``lengthen `visit```); the command
line turns both into the flags its user typed (``ucbplan.cli._flags``), so every CLI error line
stays as it was while a Python caller reads the names of the keywords it passed.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterator
from pathlib import Path

import click
import pytest
import typer

from ucbplan.cli._flags import FALSE_FLAGS, PARAMETERS, cli_message, flag_of
from ucbplan.cli.app import app

LIBRARY = Path(__file__).resolve().parents[2] / "ucbplan"

#: Calls whose first string argument names the parameter an error will be about.
_NAMING_CALLS = re.compile(r"^(_?check_\w+|parse_\w+|_positive|_check_\w+)$")


def _strings(node: ast.AST) -> Iterator[ast.Constant]:
    for sub in ast.walk(node):
        if isinstance(sub, ast.Constant) and isinstance(sub.value, str):
            yield sub


def _message_strings(tree: ast.AST) -> Iterator[ast.Constant]:
    """The string constants that end up in an error message: those of each ``raise``, the
    first argument of a ``check_*`` / ``parse_*`` call (the name it reports) and the default
    of an ``option`` / ``what`` parameter."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Raise) and node.exc is not None:
            yield from _strings(node.exc)
        elif isinstance(node, ast.Call) and node.args:
            func = node.func
            name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
            if _NAMING_CALLS.match(name):
                yield from _strings(node.args[0])
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            args = node.args.args + node.args.kwonlyargs
            defaults = [*node.args.defaults, *node.args.kw_defaults]
            for arg, default in zip(args[len(args) - len(defaults) :], defaults, strict=True):
                if arg.arg in ("option", "what") and default is not None:
                    yield from _strings(default)


def flags_in(source: str) -> list[str]:
    """The message strings of ``source`` that contain a flag (``--``)."""
    return [c.value for c in _message_strings(ast.parse(source)) if "--" in c.value]


def _library_files() -> list[Path]:
    return [p for p in sorted(LIBRARY.rglob("*.py")) if "cli" not in p.relative_to(LIBRARY).parts]


def test_the_scan_finds_a_planted_flag() -> None:
    planted = """
def f(x, option="--visit"):
    check_range("--max-visit", x, 0, 1)
    if x:
        raise InputError(f"--goal: expected {x}; lengthen --visit")
    raise InputError("visit: fine")
"""
    found = ["--visit", "--max-visit", "--goal: expected ", "; lengthen --visit"]
    assert flags_in(planted) == found
    assert flags_in("raise InputError(f'visit: lengthen `visit` {x}')") == []


def test_no_library_error_names_a_flag() -> None:
    found = [
        f"{path.relative_to(LIBRARY.parent)}: {text!r}"
        for path in _library_files()
        for text in flags_in(path.read_text(encoding="utf-8"))
    ]
    assert found == [], "\n".join(found)


def test_every_quoted_name_in_a_library_error_is_a_known_parameter() -> None:
    quoted = re.compile(r"`([a-z_][a-z0-9_]*)(?:=[^`]*)?`")
    unknown = {
        f"{path.name}: {m.group(1)}"
        for path in _library_files()
        for c in _message_strings(ast.parse(path.read_text(encoding="utf-8")))
        for m in quoted.finditer(c.value)
        if m.group(1) not in PARAMETERS
    }
    assert unknown == set()


def _all_flags() -> set[str]:
    command = typer.main.get_command(app)
    flags: set[str] = set()

    def walk(cmd: click.Command) -> None:
        for param in cmd.params:
            flags.update(param.opts + param.secondary_opts)
        for sub in getattr(cmd, "commands", {}).values():
            walk(sub)

    walk(command)
    return flags


def test_every_parameter_renders_as_a_flag_of_the_command_line() -> None:
    flags = _all_flags()
    missing = {n: flag_of(n) for n in PARAMETERS if flag_of(n) not in flags}
    missing |= {n: f for n, f in FALSE_FLAGS.items() if f not in flags}
    assert missing == {}


@pytest.mark.parametrize(
    ("python", "cli"),
    [
        ("max_visit: expected a duration", "--max-visit: expected a duration"),
        ("n_exp/exptime/readout: the block lasts", "--n-exp/--exptime/--readout: the block lasts"),
        ("cadence phase-locked: no exposure", "--cadence phase-locked: no exposure"),
        ("x.yaml: `resume`: file not found", "x.yaml: --resume: file not found"),
        ("pass `overwrite=True` or `site` NAME", "pass --overwrite or --site NAME"),
        ("pass `sigma_v=30km/s@600s`", "pass --sigma-v 30km/s@600s"),
        ("`dry_run=False`: no p2 connection", "--no-dry-run: no p2 connection"),
        ("overhead_s: expected seconds", "--overhead: expected seconds"),
        # not parameters: left as written
        ("sky: expected a mapping", "sky: expected a mapping"),
        ("x: `reduce` divides it out", "x: `reduce` divides it out"),
        ("hm.yaml: timing: missing", "hm.yaml: timing: missing"),
        ("(`Plan.write` to a .json path)", "(`ucbplan plan --format json`)"),
    ],
)
def test_cli_message_renders_parameters_as_flags(python: str, cli: str) -> None:
    assert cli_message(python) == cli


@pytest.mark.parametrize("value", ["0\n", "a\rb", "tab\there", "nul\x00", "esc\x1b[31m"])
def test_a_control_character_in_a_user_value_never_breaks_the_one_line(
    value: str, tmp_path: Path
) -> None:
    """Found by hypothesis (tests/api/test_plan_result.py::test_methods_take_any_value): a file
    name ``"0\\n"`` put a raw newline into two messages (the figure suffix check and the blocks
    table reader), so the "one line" promise broke. Every ucbplan error escapes them."""
    from ucbplan.errors import InputError, UcbplanError
    from ucbplan.observing.blocks.read import read_blocks
    from ucbplan.plotting import figure_format

    for make in (lambda: figure_format(Path(value)), lambda: read_blocks(tmp_path / value)):
        with pytest.raises(UcbplanError) as info:
            make()
        text = str(info.value)
        assert text.isprintable() and "\n" not in text, text
    assert str(InputError("x: got 'a'\nb")) == "x: got 'a'\\nb"
    assert str(InputError("σ_v ≤ 5 km/s … ok")) == "σ_v ≤ 5 km/s … ok"  # printable text kept
