"""The reference pages' generated parts, made from the code each time the docs are built (never copied by hand).

A reference page holds a marker, ``<!-- generated: NAME -->``, on a line of its own; at ``source-read`` Sphinx
hands the page's Markdown here and the marker is replaced by what :data:`GENERATORS` makes of the code:

- ``cli``: every command and subcommand from the argparse parsers ``executive`` itself builds (``executive.cli.build_parser``);
- ``commands``: the commands, one line each, linked to their part of ``cli`` (for a page at the top of docs/);
- ``exit_codes``: the exit codes every command shares (``executive.cli.EXIT_CODES``);
- ``guards``: each guard's debounce and what it does with no reading or a stale one, from the node catalogue;
- ``mission``: every field of the mission file from its JSON schema, as ``executive schema`` prints it (the pydantic model's);
- ``nodes``: the node catalogue, as ``executive behaviours --json`` prints it;
- ``blackboard``: the documented blackboard keys (``executive.world.blackboard.KEYS``) by namespace.

Each generator returns MyST Markdown, so a test can call it without Sphinx (tests/docs/test_reference.py).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import re
from collections.abc import Callable, Iterator
from typing import Any

MARKER = re.compile(r"^<!-- generated: (\w+) -->$", re.M)

#: A field name's suffix -> its unit (the model names its units so: ``leg_timeout_s``, ``acceptance_radius_m``).
UNITS = {
    "_m_s": "m/s", "_deg_s": "deg/s", "_m": "m", "_s": "s", "_deg": "deg", "_pct": "%", "_hz": "Hz", "_wh": "Wh", "_v": "V",
    "_a": "A", "_ms": "ms", "_cm": "cm", "_mah": "mAh", "_w": "W", "_km": "km",
}  # fmt: skip


def cell(text: Any) -> str:
    """``text`` for a Markdown table cell: one line, ``|`` escaped, and outside code spans ``*``, ``<`` and ``>`` too."""
    parts = re.split(r"(`+[^`]*`+)", " ".join(str(text).split()))
    out = []
    for part in parts:
        if part.startswith("`"):
            out.append(part.replace("|", "\\|"))
        else:
            out.append(re.sub(r"([|*<>\[\]_])", r"\\\1", part))
    return "".join(out)


def table(header: tuple[str, ...], rows: list[tuple[Any, ...]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell(c) for c in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def code(text: Any) -> str:
    text = str(text)
    fence = "``" if "`" in text else "`"
    return f"{fence}{text}{fence}" if text else ""


# -- the command line -------------------------------------------------------------------------------------------------------------------


def _subcommands(parser: argparse.ArgumentParser) -> Iterator[tuple[str, str, argparse.ArgumentParser]]:
    """(name, one-line help, parser) of each subcommand of ``parser``, aliases once."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {choice.dest: choice.help or "" for choice in action._choices_actions}
            seen: set[int] = set()
            for name, sub in action.choices.items():
                if id(sub) not in seen:
                    seen.add(id(sub))
                    yield name, helps.get(name, ""), sub


def _arguments(parser: argparse.ArgumentParser) -> list[tuple[str, str, str]]:
    formatter = parser._get_formatter()
    rows = []
    for action in parser._actions:
        if action.help == argparse.SUPPRESS or isinstance(action, argparse._HelpAction | argparse._SubParsersAction):
            continue
        if action.option_strings:
            metavar = "" if action.nargs == 0 else " " + formatter._format_args(action, action.dest.upper())
            name = ", ".join(f"{o}{metavar}" for o in action.option_strings)
        else:
            name = formatter._format_args(action, action.metavar or action.dest)
        default = action.default
        shown = "" if default in (None, False, argparse.SUPPRESS) or action.nargs == 0 or "%(default)" in (action.help or "") else default
        if isinstance(shown, list | tuple):
            shown = " ".join(map(str, shown))
        rows.append((code(name), formatter._expand_help(action) if action.help else "", code(shown) if shown != "" else ""))
    return rows


def cli_reference() -> str:
    """Every command and subcommand of ``executive``: usage, description and arguments, from its argparse parsers."""
    from executive.cli import build_parser

    def page(words: list[str], summary: str, parser: argparse.ArgumentParser, level: int) -> Iterator[str]:
        parser.formatter_class = lambda prog: argparse.HelpFormatter(prog, width=110)
        yield f"{'#' * level} `{' '.join(words)}`\n"
        about = parser.description or summary
        if about:
            yield about.strip() + "\n"
        yield f"```text\n{parser.format_usage().strip()}\n```\n"
        if level == 2:  # the root's epilog, as a table
            yield "Exit codes, the same for every command:\n\n" + exit_codes_table()
        rows = _arguments(parser)
        if rows:
            yield table(("argument", "what it does", "default"), rows)
        subs = list(_subcommands(parser))
        if subs and level >= 3:
            yield table(("subcommand", "what it does"), [(code(" ".join([*words, n])), h) for n, h, _ in subs])
        for name, help_, sub in subs:
            yield from page([*words, name], help_, sub, min(level + 1, 4))

    root = build_parser()
    return "\n".join(page(["executive"], "", root, 2))


def commands_table() -> str:
    """Each command of ``executive``, its one-line help and a link to its part of the command line reference (for pages in docs/)."""
    from executive.cli import build_parser

    rows = []
    for name, help_, _ in _subcommands(build_parser()):
        rows.append((f"[`executive {name}`](reference/cli.md#executive-{name})", help_))
    header = "| command | what it does |\n|---|---|\n"
    return header + "".join(f"| {link} | {cell(help_)} |\n" for link, help_ in rows)


def exit_codes_table() -> str:
    """The exit codes every command shares (``executive.cli.EXIT_CODES``)."""
    from executive.cli import EXIT_CODES

    return table(("code", "meaning"), [(code_, meaning) for code_, meaning in EXIT_CODES.items()])


# -- the mission file -------------------------------------------------------------------------------------------------------------------


def mission_schema() -> dict[str, Any]:
    """The JSON schema ``executive schema`` prints."""
    from executive.cli import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["schema"]) == 0, "executive schema failed"
    return json.loads(out.getvalue())


def _type(prop: dict[str, Any]) -> str:
    if "$ref" in prop:
        name = prop["$ref"].rsplit("/", 1)[-1]
        return f"[{name}](#{name.lower()})" if not name.startswith("TreeNode") else "a tree node (node catalogue)"
    if "const" in prop:
        return code(json.dumps(prop["const"]))
    if "enum" in prop:
        return " | ".join(code(json.dumps(v)) for v in prop["enum"])
    if "anyOf" in prop:
        return " or ".join(_type(p) for p in prop["anyOf"])
    if prop.get("type") == "array":
        return f"list of {_type(prop.get('items', {}))}"
    if prop.get("type") == "object" and "additionalProperties" in prop and isinstance(prop["additionalProperties"], dict):
        return f"mapping to {_type(prop['additionalProperties'])}"
    return {"number": "number", "integer": "integer", "string": "text", "boolean": "true/false", "null": "null", "object": "mapping"}.get(
        prop.get("type", ""), "any"
    )


def _bounds(prop: dict[str, Any]) -> str:
    said = []
    for key, sign in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="), ("exclusiveMaximum", "<"), ("minItems", "items >="),
                      ("maxItems", "items <="), ("minLength", "length >="), ("maxLength", "length <="), ("pattern", "matches")):  # fmt: skip
        if key in prop:
            said.append(f"{sign} {prop[key]}")
    for option in prop.get("anyOf", ()):
        said += [b for b in _bounds(option).split(", ") if b]
    return ", ".join(said)


def unit(field: str) -> str:
    return next((u for suffix, u in sorted(UNITS.items(), key=lambda kv: -len(kv[0])) if field.endswith(suffix)), "")


def _fields(model: dict[str, Any]) -> str:
    required = set(model.get("required", ()))
    rows = []
    for name, prop in model.get("properties", {}).items():
        default = code(json.dumps(prop["default"], ensure_ascii=False)) if "default" in prop else "required" if name in required else ""
        about = prop.get("description", "")
        if bounds := _bounds(prop):
            about = f"{about} ({bounds})" if about else bounds
        rows.append((code(name), _type(prop), unit(name), default, about))
    return table(("field", "type", "unit", "default", "what it is"), rows)


def mission_reference(schema: dict[str, Any] | None = None) -> str:
    """Every field of the mission file, by the model that holds it: type, unit, default, bounds and description."""
    schema = mission_schema() if schema is None else schema
    parts = ["## The mission file\n", (schema.get("description") or "").strip() + "\n", _fields(schema)]
    for name, model in sorted(schema.get("$defs", {}).items()):
        if name.startswith("TreeNode") or "properties" not in model:
            continue
        parts += [f"## {name}\n", (model.get("description") or "").strip() + "\n", _fields(model)]
    return "\n".join(p for p in parts if p.strip())


# -- the node catalogue -----------------------------------------------------------------------------------------------------------------


def catalogue() -> list[dict[str, Any]]:
    """The node catalogue, as ``executive behaviours --json`` prints it."""
    from executive.cli import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["behaviours", "--json"]) == 0, "executive behaviours --json failed"
    return json.loads(out.getvalue())


def nodes_reference(nodes: list[dict[str, Any]] | None = None) -> str:
    """Every node of the catalogue by kind, with its parameters."""
    nodes = catalogue() if nodes is None else nodes
    parts = []
    kinds = list(dict.fromkeys(n["kind"] for n in nodes))
    for kind in kinds:
        parts.append(f"## {kind.capitalize()}s\n" if not kind.endswith("s") else f"## {kind.capitalize()}\n")
        for node in (n for n in nodes if n["kind"] == kind):
            parts.append(f"### {node['name']}\n")
            parts.append(f"{node.get('doc', '').strip()} ({code(node.get('origin', ''))})\n")
            rows = []
            for p in node.get("params", ()):
                if "from_mission" in p:
                    default = f"the mission's {code(p['from_mission'])}"
                elif p.get("required"):
                    default = "required"
                else:
                    default = code(json.dumps(p.get("default"), ensure_ascii=False)) if "default" in p else ""
                rows.append((code(p["name"]), p.get("type", ""), p.get("unit", ""), default, p.get("doc", "")))
            if rows:
                parts.append(table(("parameter", "type", "unit", "default", "what it is"), rows))
    return "\n".join(parts)


def guards_table(nodes: list[dict[str, Any]] | None = None) -> str:
    """Each guard of the catalogue: its debounce (hold after, resume after, the defaults) and what it does unknown or stale."""
    nodes = catalogue() if nodes is None else nodes
    rows = []
    for node in (n for n in nodes if n["kind"] == "guard"):
        defaults = {p["name"]: p.get("default") for p in node.get("params", ())}
        title = f"{defaults['name']} ({code(node['name'])})" if defaults.get("name") else code(node["name"])
        seconds = [f"{defaults[k]:g} s" if isinstance(defaults.get(k), int | float) else "" for k in ("hold_after_s", "resume_after_s")]
        rows.append((title, *seconds, node.get("unknown_or_stale", "")))
    return table(("guard", "hold after", "resume after", "no reading yet, or one older than its limit"), rows)


# -- the blackboard ---------------------------------------------------------------------------------------------------------------------


def blackboard_reference() -> str:
    """Every documented blackboard key by namespace (the module's docstring says what each namespace is)."""
    from executive.world import blackboard

    namespaces = dict(re.findall(r"^- ``(/[^`]+)``: (.+)$", blackboard.__doc__ or "", re.M))
    by_space: dict[str, list[blackboard.Key]] = {}
    for key in blackboard.KEYS.values():
        by_space.setdefault("/" + key.name.split("/")[1], []).append(key)
    parts = []
    for space, keys in by_space.items():
        parts.append(f"## `{space}`\n")
        if space in namespaces:
            parts.append(namespaces[space].strip() + "\n")
        parts.append(table(("key", "default", "written by", "what it holds"), [(code(k.name), code(repr(k.default)), k.writer, k.doc) for k in keys]))
    return "\n".join(parts)


GENERATORS: dict[str, Callable[[], str]] = {
    "cli": cli_reference,
    "commands": commands_table,
    "exit_codes": exit_codes_table,
    "guards": guards_table,
    "mission": mission_reference,
    "nodes": nodes_reference,
    "blackboard": blackboard_reference,
}


def expand(text: str) -> str:
    """``text`` with each marker replaced by its generated Markdown."""
    return MARKER.sub(lambda m: GENERATORS[m[1]](), text)


def _source_read(app: Any, docname: str, source: list[str]) -> None:
    if MARKER.search(source[0]):
        source[0] = expand(source[0])


def setup(app: Any) -> dict[str, Any]:
    app.connect("source-read", _source_read)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
