"""mkdocs hooks: reference pages generated from the code at build time.

A page asks for generated text with a marker line ``<!-- ucbplan:generate NAME -->``;
:func:`on_page_markdown` replaces it with what ``GENERATORS[NAME]`` renders:

``cli``
    Every command of the typer app: help, usage, arguments and options with their help texts,
    types and defaults, read from the same click objects that ``ucbplan COMMAND --help`` prints.
``blocks-table``
    The columns of the master blocks table from :mod:`ucbplan.observing.blocks.schema` (a
    declarative column list when the module has one, else ``REQUIRED_COLUMNS``/``EXTRA_COLUMNS``
    with their unit and description maps).
``target-schema``
    The field table of :mod:`ucbplan.targets.schema` when that module exists; nothing (and no
    warning) when it does not.

The repository root is put first on ``sys.path`` before importing, so the site documents the
checked-out code rather than an installed copy. A generator that fails stops the build.

:func:`on_files` turns each notebook ``docs/tutorials/NAME.ipynb`` into a page
``tutorials/NAME.md`` (its Markdown cells as they are, its code cells as Python blocks, and the
outputs it carries), read as JSON with no Jupyter package; the notebook itself is copied beside
it for download. The test suite executes the notebooks in a Jupyter kernel with no network
(``tests/house/test_tutorial_notebooks.py``).
"""

from __future__ import annotations

import base64
import html
import importlib
import json
import re
import sys
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

from mkdocs.exceptions import PluginError
from mkdocs.structure.files import File, Files

ROOT = Path(__file__).resolve().parents[1]
MARKER = re.compile(r"<!--\s*ucbplan:generate\s+([\w-]+)\s*-->")

# Characters that Markdown or a table row would interpret, written as HTML entities instead.
_ENTITIES = {c: f"&#{ord(c)};" for c in "\\`*_{}[]#|"}


# ---------------------------------------------------------------------------------- helpers


def _import(name: str) -> ModuleType:
    """Import ``name`` from the repository (root first on ``sys.path``)."""
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    return importlib.import_module(name)


def _plain(text: str) -> str:
    """``text`` as inert inline HTML: nothing in it becomes Markdown or splits a table cell."""
    escaped = html.escape(text, quote=False)
    return "".join(_ENTITIES.get(c, c) for c in escaped).replace("\n", " ")


def _inline(text: str) -> str:
    """Like :func:`_plain`, but ```code``` spans of the source text become ``<code>``."""
    parts = text.split("`")
    if len(parts) % 2 == 0:  # unbalanced backtick: keep it literally
        return _plain(text)
    return "".join(
        f"<code>{_plain(part)}</code>" if i % 2 else _plain(part) for i, part in enumerate(parts)
    )


def _code(text: str) -> str:
    return f"<code>{_plain(text)}</code>" if text else ""


def _paragraphs(text: str | None) -> list[str]:
    """Help text as Markdown paragraphs (click's ``\\b`` no-rewrap markers dropped)."""
    if not text:
        return []
    blocks = re.split(r"\n\s*\n", text.replace("\b", "").strip())
    return [_inline(" ".join(line.strip() for line in b.splitlines())) for b in blocks]


def _table(header: Iterable[str], rows: Iterable[Iterable[str]]) -> list[str]:
    """A Markdown table (empty cells shown as a dash) followed by a blank line."""
    head = list(header)
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(cell or "—" for cell in row) + " |" for row in rows]
    return [*lines, ""]


# ---------------------------------------------------------------------------------- CLI


def _split_label(label: str) -> tuple[str, str]:
    """``"-o, --output <path>"`` → (``"-o, --output"``, ``"<path>"``)."""
    m = re.fullmatch(r"(.*?)(?:\s+(<[^<>]*>))?", label.strip())
    assert m is not None  # the pattern matches every string
    return m.group(1), m.group(2) or ""


def _split_help(text: str) -> tuple[str, str, bool]:
    """Help text → (help, default, required) from click's trailing ``  [default: …; required]``."""
    m = re.fullmatch(r"(.*?)(?:\s{2}\[([^\[\]]*)\])?", text.strip(), flags=re.S)
    assert m is not None
    help_text, default, required = m.group(1), "", False
    for part in (m.group(2) or "").split("; "):
        if part == "required":
            required = True
        elif part.startswith("default: "):
            default = part[len("default: ") :]
        elif part:
            help_text += f" [{part}]"
    return help_text, default, required


def _flags(names: str) -> str:
    return ", ".join(_code(n.strip()) for n in re.split(r",\s*|\s+/\s+", names) if n.strip())


def _param_rows(command: Any, ctx: Any) -> tuple[list[list[str]], list[list[str]]]:
    """(argument rows, option rows) of one command, ``--help`` itself left out."""
    arguments: list[list[str]] = []
    options: list[list[str]] = []
    for param in command.get_params(ctx):
        if getattr(param, "hidden", False) or "--help" in getattr(param, "opts", ()):
            continue
        record = param.get_help_record(ctx)
        label, text = record if record else (param.human_readable_name, "")
        names, metavar = _split_label(label)
        help_text, default, required = _split_help(text)
        if param.param_type_name == "argument":
            arguments.append(
                [_code(names), _code(metavar), "yes" if required else "no", _inline(help_text)]
            )
        else:
            when = "required" if required else _code(default)
            options.append([_flags(names), _code(metavar), when, _inline(help_text)])
    return arguments, options


def _command_section(name: str, command: Any, ctx: Any, level: int = 2) -> list[str]:
    """The section of one command; a group (``ephemeris``, ``population``) lists its commands."""
    out = [f"{'#' * level} `ucbplan {name}`", ""]
    for para in _paragraphs(command.help):
        out += [para, ""]
    usage = command.get_usage(ctx).removeprefix("Usage:").strip()
    out += ["```text", usage, "```", ""]
    arguments, options = _param_rows(command, ctx)
    if arguments:
        out += ["**Arguments**", ""]
        out += _table(["argument", "value", "required", "description"], arguments)
    if options:
        out += ["**Options**", ""]
        out += _table(["option", "value", "default", "description"], options)
    for sub_name in getattr(command, "list_commands", lambda _ctx: [])(ctx):
        sub = command.get_command(ctx, sub_name)
        if sub is None or sub.hidden:
            continue
        sub_ctx = sub.context_class(sub, info_name=sub_name, parent=ctx)
        out += _command_section(f"{name} {sub_name}", sub, sub_ctx, level + 1)
    return out


def cli_reference() -> str:
    """Markdown for every command of ``ucbplan.cli.app.app``, in registration order."""
    typer_main = _import("typer.main")
    app = _import("ucbplan.cli.app").app
    group = typer_main.get_command(app)
    ctx = group.context_class(group, info_name="ucbplan")
    out = [*_paragraphs(group.help), ""]
    usage = group.get_usage(ctx).removeprefix("Usage:").strip()
    out += ["```text", usage, "```", ""]
    _, options = _param_rows(group, ctx)
    if options:
        out += _table(["option", "value", "default", "description"], options)
    names = [n for n in group.list_commands(ctx) if not group.get_command(ctx, n).hidden]
    out += ["Commands: " + ", ".join(f"[`{n}`](#ucbplan-{n})" for n in names) + ".", ""]
    for name in names:
        command = group.get_command(ctx, name)
        sub = command.context_class(command, info_name=name, parent=ctx)
        out += _command_section(name, command, sub)
    return "\n".join(out)


# ---------------------------------------------------------------------------- blocks table


def _text(value: Any) -> str:
    """A unit, dtype or description as text (``""`` for None; types by their name)."""
    if value is None:
        return ""
    return str(value.__name__) if isinstance(value, type) else str(value)


def _declared_columns(module: ModuleType, names: list[str]) -> list[tuple[str, str, str, str]]:
    """(name, unit, dtype, description) from the module's declarative column list, if any.

    Any module-level tuple, list or mapping of records with a ``name`` and a ``description`` (or
    ``doc``) counts; the one naming most of ``names`` wins. Empty when there is none.
    """
    best: list[Any] = []
    for value in vars(module).values():
        if isinstance(value, str) or not isinstance(value, tuple | list | Mapping):
            continue
        items = list(value.values()) if isinstance(value, Mapping) else list(value)
        if items and all(
            hasattr(c, "name") and (hasattr(c, "description") or hasattr(c, "doc")) for c in items
        ):
            covered = len({str(c.name) for c in items} & set(names))
            if covered > len({str(c.name) for c in best} & set(names)):
                best = items
    return [
        (
            str(c.name),
            _text(getattr(c, "unit", None)),
            _text(getattr(c, "dtype", None)),
            _text(getattr(c, "description", None) or getattr(c, "doc", None)),
        )
        for c in best
    ]


def _listed_columns(module: ModuleType) -> list[tuple[str, str, str, str]]:
    """(name, unit, dtype, description) from the column tuples and their unit/description maps."""
    units: Mapping[str, str] = getattr(module, "_UNITS", {})
    descriptions: Mapping[str, str] = getattr(module, "_DESCRIPTIONS", {})
    names = [*module.REQUIRED_COLUMNS, *getattr(module, "EXTRA_COLUMNS", ())]
    return [(n, units.get(n, ""), "", descriptions.get(n, "")) for n in names]


def blocks_table() -> str:
    """Markdown tables of the master blocks table's required and further columns."""
    module = _import("ucbplan.observing.blocks.schema")
    listed = [*module.REQUIRED_COLUMNS, *getattr(module, "EXTRA_COLUMNS", ())]
    columns = _declared_columns(module, listed) or _listed_columns(module)
    missing = sorted(set(listed) - {c[0] for c in columns})
    if missing:
        raise PluginError(f"blocks-table: columns {missing} are listed but not declared")
    required = set(module.REQUIRED_COLUMNS)
    with_dtype = any(c[2] for c in columns)
    header = ["column", "unit", *(["type"] if with_dtype else []), "description"]

    def rows(keep: Callable[[str], bool]) -> list[list[str]]:
        return [
            [_code(n), _plain(u), *([_code(d)] if with_dtype else []), _inline(text)]
            for n, u, d, text in columns
            if keep(n)
        ]

    out = ["### Required columns", "", "Every table has these, in this order.", ""]
    out += _table(header, rows(lambda n: n in required))
    out += ["### Further columns", "", "Always written, after the required ones.", ""]
    out += _table(header, rows(lambda n: n not in required))
    return "\n".join(out)


# ---------------------------------------------------------------------------- target schema


def _field_row(field: Any) -> list[str]:
    unit = getattr(field, "unit", None)
    default = getattr(field, "default", None)
    bounds = getattr(field, "bounds", None)
    choices = getattr(field, "choices", ()) or ()
    allowed = " | ".join(choices) if choices else (str(bounds) if bounds is not None else "")
    reason = getattr(bounds, "reason", "") if bounds is not None else ""
    doc = str(getattr(field, "doc", "") or getattr(field, "what", ""))
    return [
        _code(str(field.path)),
        "yes" if getattr(field, "required", False) else "",
        _plain("dimensionless" if unit == "" else str(unit or "")),
        _code("" if default is None else str(default)),
        _plain(allowed) + (f" ({_inline(reason)})" if reason else ""),
        _code(str(getattr(field, "example", "") or "")),
        _inline(doc),
    ]


def target_schema() -> str:
    """Field table of :mod:`ucbplan.targets.schema`; empty text while that module does not exist."""
    try:
        schema = _import("ucbplan.targets.schema")
    except ModuleNotFoundError as exc:
        if exc.name == "ucbplan.targets.schema":
            return ""
        raise
    fields = getattr(schema, "FIELDS", ())
    if not fields:
        return ""
    out = [
        "## Field reference",
        "",
        "Generated from the declarative schema the parser and writer use "
        "(`ucbplan.targets.schema`). A bare number is read in the unit shown.",
        "",
    ]
    header = ["field", "required", "unit", "default", "allowed", "example", "description"]
    out += _table(header, (_field_row(f) for f in fields))
    params = getattr(schema, "COVARIANCE_PARAMETERS", ())
    extras = getattr(schema, "COVARIANCE_EXTRAS", ())
    if params:
        names = ", ".join(_code(str(p)) for p in dict.fromkeys((*params, *extras)))
        out += [f"Parameters a covariance or a samples file may name: {names}.", ""]
    return "\n".join(out)


# ----------------------------------------------------------------------------------- hook

GENERATORS: dict[str, Callable[[], str]] = {
    "cli": cli_reference,
    "blocks-table": blocks_table,
    "target-schema": target_schema,
}


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any, **kwargs: Any) -> str:
    """Replace each ``<!-- ucbplan:generate NAME -->`` marker with the generated Markdown."""

    def render(match: re.Match[str]) -> str:
        name = match.group(1)
        if name not in GENERATORS:
            raise PluginError(
                f"{page.file.src_uri}: unknown generated section {name!r}; "
                f"expected one of {', '.join(GENERATORS)}"
            )
        return GENERATORS[name]()

    return MARKER.sub(render, markdown)


# ------------------------------------------------------------------------------- notebooks


def _cell_source(cell: Mapping[str, Any]) -> str:
    source = cell.get("source", "")
    return "".join(source) if isinstance(source, list) else str(source)


def _output_markdown(output: Mapping[str, Any]) -> list[str]:
    """An output of a code cell: text in a fenced block, a PNG inline, an error's last line."""
    data = output.get("data", {})
    if "image/png" in data:
        png = "".join(data["image/png"]).replace("\n", "")
        base64.b64decode(png, validate=True)  # a broken image stops the build
        return [f'<img alt="figure" src="data:image/png;base64,{png}">', ""]
    text = output.get("text") or data.get("text/plain")
    if output.get("output_type") == "error":
        text = f"{output.get('ename')}: {output.get('evalue')}"
    if not text:
        return []
    body = "".join(text) if isinstance(text, list) else str(text)
    return ["```text", body.rstrip("\n"), "```", ""]


def notebook_markdown(path: Path) -> str:
    """The Markdown page of the notebook ``path`` (see :func:`on_files`)."""
    nb = json.loads(path.read_text(encoding="utf-8"))
    out = [
        f"*This page is the notebook [{path.name}]({path.name}), executed by the test suite.*",
        "",
    ]
    for cell in nb.get("cells", []):
        source = _cell_source(cell).rstrip("\n")
        if cell.get("cell_type") == "markdown":
            out += [source, ""]
        elif cell.get("cell_type") == "code" and source:
            out += ["```python", source, "```", ""]
            for output in cell.get("outputs", []):
                out += _output_markdown(output)
    return "\n".join(out)


def on_files(files: Files, config: Any, **kwargs: Any) -> Files:
    """Add a generated page ``tutorials/NAME.md`` for each ``docs/tutorials/NAME.ipynb``."""
    for path in sorted((ROOT / "docs" / "tutorials").glob("*.ipynb")):
        uri = f"tutorials/{path.stem}.md"
        files.append(File.generated(config, uri, content=notebook_markdown(path)))
    return files
