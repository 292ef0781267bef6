"""Load a mission file: YAML -> :class:`Mission`, every problem located as ``FILE:LINE:COL: FIELD: message``.

The YAML is composed into a node graph first (with limits against alias bombs and deep nesting),
each value's path is mapped to its node, and only then is the graph constructed and validated, so
that every pydantic and cross-field error points at the line and column of the offending value.
:func:`load_model` does the same for any strict pydantic model (the simulator's fault files).
"""

from __future__ import annotations

import copy
import difflib
import math
import os
import re
import threading
from collections.abc import Callable, Iterator
from typing import Any, Literal, NoReturn, TypeVar, cast, get_args, get_origin

import yaml
from pydantic import BaseModel, ValidationError, WithJsonSchema
from pydantic.fields import FieldInfo

from executive.mission.errors import FieldError, MissionError, Path, format_path
from executive.mission.model import Mission, mission_model
from executive.mission.rules import cross_field_errors

MAX_BYTES = 1 << 20  # a mission file is small; refuse anything bigger before parsing
MAX_ALIASES = 100
MAX_DEPTH = 64  # nested mappings/sequences, the root mapping being level 1
MAX_VALUES = 1_000_000  # nodes after expanding aliases; 1 MiB of YAML without aliases holds fewer
#: Files read lately kept (:func:`_read`): how many, the most characters in all (a document and its node index take ~50 bytes a
#: character: ~6 MB), and in one file (a mission is a few thousand).
READ_KEPT = 32
READ_KEPT_CHARS = 1 << 17
READ_KEPT_MAX_CHARS = 1 << 15

M = TypeVar("M", bound=BaseModel)
#: Rules between fields of a validated model: (path of the offending value, why) for each problem.
Checks = Callable[[M], list[tuple[Path, str]]]

_MERGE_TAG = "tag:yaml.org,2002:merge"
_LINE_BREAK = re.compile("\r\n|[\r\n\x85\u2028\u2029]")  # what YAML counts as the end of a line
_EXPONENT_WITHOUT_DOT_OR_SIGN = re.compile(r"[-+]?([0-9]+\.?[0-9]*|\.[0-9]+)[eE][-+]?[0-9]+")  # what YAML 1.1 reads as a string

#: YAML tags -> what a value with the tag must be (messages of values the tag cannot hold).
_TAG_KINDS = {
    "tag:yaml.org,2002:int": "an integer",
    "tag:yaml.org,2002:float": "a number",
    "tag:yaml.org,2002:bool": "a boolean",
    "tag:yaml.org,2002:timestamp": "a timestamp",
    "tag:yaml.org,2002:binary": "base64 binary",
}

#: pydantic type errors -> what the file should have had there.
_EXPECTED = {
    "float_type": "a number",
    "int_type": "an integer",
    "string_type": "a string",
    "bool_type": "true or false",
    "model_type": "a mapping",
    "model_attributes_type": "a mapping",
    "dict_type": "a mapping",
    "list_type": "a list",
    "invalid_key": "a string key",
}


class _Loader(yaml.SafeLoader):
    """A SafeLoader that refuses alias bombs, recursive aliases and deep nesting while composing,
    and indexes the composed graph by value path (reporting duplicate keys)."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._aliases = 0
        self._depth = 0
        self._expanded = 0  # nodes composed so far, counting an alias as the size of what it names
        self._sizes: dict[int, int] = {}  # id(anchored node) -> its expanded size
        self.values: dict[Path, yaml.Node] = {}
        self.keys: dict[Path, yaml.Node] = {}
        self.duplicates: dict[int, tuple[Path, yaml.Node]] = {}  # id(key node) -> (path, key node): aliased mappings are walked again

    def compose_node(self, parent: yaml.Node | None, index: Any) -> yaml.Node:
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_ALIASES:
                _refuse(event, f"more than {MAX_ALIASES} aliases (refusing a possible alias bomb)")
            node = self.anchors.get(event.anchor)
            # A collection is closed (end_mark set) once composed: an alias to an open one is inside it.
            if isinstance(node, yaml.CollectionNode) and node.end_mark is None:
                _refuse(event, f"recursive alias *{event.anchor} (a value that contains itself)")
            self._expanded += self._sizes.get(id(node), 1)
            if self._expanded > MAX_VALUES:
                _refuse(event, f"aliases expand the document to more than {MAX_VALUES} values (refusing a possible alias bomb)")
            return super().compose_node(parent, index)
        collection = isinstance(event, yaml.CollectionStartEvent)
        self._depth += int(collection)
        if self._depth > MAX_DEPTH:
            _refuse(event, f"nesting deeper than {MAX_DEPTH} levels")
        before = self._expanded
        self._expanded += 1
        node = super().compose_node(parent, index)
        self._depth -= int(collection)
        if getattr(event, "anchor", None) is not None:
            self._sizes[id(node)] = self._expanded - before
        return node

    def construct_object(self, node: yaml.Node, deep: bool = False) -> Any:
        """As SafeLoader's, but a value its tag cannot hold (``!!int abc``, a 5000-digit integer) is a located error, not a crash."""
        try:
            return super().construct_object(node, deep)
        except yaml.MarkedYAMLError:
            raise
        except (ValueError, TypeError, KeyError, AttributeError, OverflowError, ArithmeticError):
            kind = _TAG_KINDS.get(node.tag, node.tag.rsplit(":", 1)[-1])
            shown = _show(node.value) if isinstance(node, yaml.ScalarNode) else "this value"
            raise yaml.constructor.ConstructorError(problem=f"cannot read {shown} as {kind}", problem_mark=node.start_mark) from None

    def index_paths(self, node: yaml.Node, path: Path = ()) -> None:
        """Map ``path`` and everything below it to nodes, as the constructor will see them."""
        if isinstance(node, yaml.CollectionNode) and len(path) >= MAX_DEPTH:  # deep only through aliases
            _refuse(node, f"nesting deeper than {MAX_DEPTH} levels (through aliases)")
        self.values[path] = node
        if isinstance(node, yaml.SequenceNode):
            for i, child in enumerate(node.value):
                self.index_paths(child, (*path, i))
        elif isinstance(node, yaml.MappingNode):
            pairs: dict[Any, tuple[yaml.Node, yaml.Node]] = {}
            for key, value in _own_pairs(node):
                name = self.construct_object(key)
                if name in pairs:
                    self.duplicates[id(key)] = ((*path, name), key)
                pairs[name] = (key, value)  # the last one wins, as in the constructor
            for key, value in _merged_pairs(node):
                pairs.setdefault(self.construct_object(key), (key, value))
            for name, (key, value) in pairs.items():
                self.keys[(*path, name)] = key
                self.index_paths(value, (*path, name))


def _refuse(at: yaml.Event | yaml.Node, problem: str) -> NoReturn:
    raise yaml.composer.ComposerError(problem=problem, problem_mark=at.start_mark)


def _own_pairs(node: yaml.MappingNode) -> Iterator[tuple[yaml.Node, yaml.Node]]:
    """Key/value nodes written in the mapping itself (hashable keys only; the constructor reports the others)."""
    return ((k, v) for k, v in node.value if isinstance(k, yaml.ScalarNode) and k.tag != _MERGE_TAG)


def _merged_pairs(node: yaml.MappingNode) -> Iterator[tuple[yaml.Node, yaml.Node]]:
    """Key/value nodes merged in with ``<<``, in the precedence order of the constructor."""
    for key, value in node.value:
        if key.tag == _MERGE_TAG:
            for merged in value.value if isinstance(value, yaml.SequenceNode) else [value]:
                if isinstance(merged, yaml.MappingNode):
                    yield from _own_pairs(merged)
                    yield from _merged_pairs(merged)


def load_mission(path: str | os.PathLike[str], checks: Checks[Mission] = cross_field_errors) -> Mission:
    """Read and validate a mission file (its schema, then ``checks``: the rules between fields); raises :class:`MissionError` listing every problem.

    Whether it can run here (its tree, plugins, instrument) is :func:`executive.admission.checks.load_mission`'s to check.
    """
    return load_model(path, Mission, checks)


def load_mission_text(text: str, filename: str, checks: Checks[Mission] = cross_field_errors) -> Mission:
    """Validate mission YAML ``text`` as :func:`load_mission` does; ``filename`` is only used to locate errors."""
    return load_model_text(text, filename, Mission, checks)


def load_model(path: str | os.PathLike[str], model: type[M], checks: Checks[M] | None = None, what: str = "mission") -> M:
    """Read a YAML file and validate it as ``model`` (then ``checks``); raises :class:`MissionError` listing every problem.

    ``what`` names the kind of file in messages (``a {what} file``, ``({what})`` for the whole document).
    """
    name = os.fsdecode(path)
    try:
        with open(path, "rb") as stream:
            _check_size(name, os.fstat(stream.fileno()).st_size, what)
            data = stream.read(MAX_BYTES + 1)  # the size may lie (a pipe) or change
    except OSError as exc:
        raise MissionError([_located(name, None, "(file)", exc.strerror or str(exc))]) from None
    _check_size(name, len(data), what)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        before = data[: exc.start].decode("utf-8", "replace")
        raise MissionError([_located_after(name, before, "(file)", f"not UTF-8 text: byte 0x{data[exc.start]:02x} at offset {exc.start}")]) from None
    return load_model_text(text, name, model, checks, what)


def load_model_text(text: str, filename: str, model: type[M], checks: Checks[M] | None = None, what: str = "mission") -> M:
    """Validate YAML ``text`` as ``model`` (then ``checks``); ``filename`` is only used to locate errors."""
    _check_size(filename, len(text.encode("utf-8", "surrogatepass")), what)
    data, loader = _read(text, filename, what)
    if model is Mission:  # with the options section its plugin tree declares
        model = cast("type[M]", mission_model(data))

    def error(path: Path, message: str, node: yaml.Node | None = None) -> FieldError:
        """Located at ``node``, else at the value of ``path`` or of its nearest enclosing value in the file."""
        node = node or next(loader.values[path[:n]] for n in range(len(path), -1, -1) if path[:n] in loader.values)
        number = _waypoint_number(data, path) if what == "mission" else ""  # after the message: FIELD stays one token for tools
        return _located(filename, node.start_mark, format_path(path) if path else f"({what})", message + number)

    errors = [error(path, "duplicate key (an earlier one is ignored)", key) for path, key in loader.duplicates.values()]
    try:
        result = model.model_validate(data)
    except ValidationError as exc:
        for e in exc.errors(include_url=False):
            path = _file_path(e["loc"], data, missing=e["type"] == "missing")
            if e["type"] in ("union_tag_invalid", "union_tag_not_found"):  # name the tag field, not the whole mapping
                path = (*path, e["ctx"]["discriminator"].strip("'"))
            key = loader.keys.get(path) if e["type"] in ("extra_forbidden", "invalid_key") else None
            if key is not None and e["type"] == "invalid_key":
                path = (*path[:-1], key.value)  # 'on: 1' has the key True: name it as written
            errors.append(error(path, _message(e, key or loader.values.get(path), model), key))
        if checks is not None:  # the rules between fields too, on the values that are valid: every error in one pass
            errors += [error(path, message) for path, message in _checks_on_the_valid_part(data, model, checks)]
        raise MissionError(errors) from None
    errors += [error(path, message) for path, message in (checks(result) if checks else [])]
    if errors:
        raise MissionError(errors)
    return result


def _waypoint_number(data: object, path: Path) -> str:
    """`` (waypoint 7, 'far')`` for an error in ``waypoints[6]``: the path locates the YAML, a person counts from 1 by name."""
    if len(path) < 2 or path[0] != "waypoints" or not isinstance(path[1], int) or isinstance(path[1], bool):
        return ""
    waypoints = data.get("waypoints") if isinstance(data, dict) else None
    item = waypoints[path[1]] if isinstance(waypoints, list) and 0 <= path[1] < len(waypoints) else None
    name = item.get("name") if isinstance(item, dict) and path[2:3] != ("name",) else None  # not a name that is itself refused
    return f" (waypoint {path[1] + 1}" + (f", {name!r}" if isinstance(name, str) and name else "") + ")"


#: Passes of leaving out what pydantic refuses before the rules between fields give up.
_MAX_PRUNING_PASSES = 8
#: pydantic errors that name a field missing from its mapping: the mapping itself cannot be kept.
_MISSING = frozenset({"missing", "union_tag_not_found"})


def _checks_on_the_valid_part(data: dict[str, Any], model: type[M], checks: Checks[M]) -> list[tuple[Path, str]]:
    """``checks`` run on ``data`` without its invalid values (paths in ``data``), so that one pass reports every error.

    Each value pydantic refuses is left out (a field then takes its default); a mapping that then
    lacks a required field is left out whole (a list item is dropped, its siblings keep their
    paths). A rule's error about a value left out, about what held it (a mapping or a list that
    lost it), or judged by one (its message names it) is not reported: it would judge a value
    that is not the file's. Nothing when the document itself
    cannot be kept.
    """
    dropped: set[Path] = set()
    for _ in range(_MAX_PRUNING_PASSES):
        pruned, kept = _without(data, dropped)
        try:
            result = model.model_validate(pruned)
        except ValidationError as exc:
            refused = set()
            for e in exc.errors(include_url=False):
                path = _file_path(e["loc"], pruned, missing=e["type"] == "missing")
                path = _original_path(path[:-1] if e["type"] in _MISSING else path, kept)
                if not path:
                    return _whatever_it_is(data, model, checks, e["loc"][:1] if e["type"] in _MISSING else ())
                refused.add(path)
            if refused <= dropped:
                return []
            dropped |= refused
            continue
        found = []
        for path, message in checks(result):
            original = _original_path(path, kept)
            if any(_related(original, d) or format_path(d) in message for d in dropped):
                continue  # about a value left out or what holds it, or judged by one (its message names it)
            found.append((original, message))
        return found
    return []


def _whatever_it_is(data: dict[str, Any], model: type[M], checks: Checks[M], field: tuple[Any, ...]) -> list[tuple[Path, str]]:
    """The rules' errors that hold whatever a refused required field of a few choices (``vehicle: boats``) would have been.

    The document cannot be kept without it; each of its choices stands in for it in turn, and an error
    found with every one of them (``tree: unknown tree 'waypoint'``) is the file's. Nothing for any other field.
    """
    name = field[0] if len(field) == 1 and isinstance(field[0], str) else None
    choices = _field_choices(model.model_fields[name]) if name in model.model_fields else ()
    if not choices or name not in data:
        return []
    common: list[tuple[Path, str]] | None = None
    for choice in choices:
        found = _checks_on_the_valid_part({**data, name: choice}, model, checks)
        common = found if common is None else [error for error in common if error in found]
    return common or []


def _field_choices(field: FieldInfo) -> tuple[Any, ...]:
    """A field's few choices: its ``Literal[...]``'s values, or the ``enum`` its schema says (``vehicle:``: a plugin may add kinds)."""
    schemas = [meta.json_schema for meta in field.metadata if isinstance(meta, WithJsonSchema) and isinstance(meta.json_schema, dict)]
    enum = next((tuple(schema["enum"]) for schema in schemas if 0 < len(schema.get("enum", ())) <= 8), ())
    return _literal_choices(field.annotation) or enum


def _literal_choices(annotation: Any) -> tuple[Any, ...]:
    """The values of a ``Literal[...]`` annotation (a few of them), else none."""
    values = get_args(annotation) if get_origin(annotation) is Literal else ()
    return values if 0 < len(values) <= 8 else ()


def _without(value: Any, dropped: set[Path], path: Path = ()) -> tuple[Any, dict[Path, list[int]]]:
    """A copy of ``value`` without the values at ``dropped``, and for each list the indices (in ``value``) of the items kept."""
    kept: dict[Path, list[int]] = {}
    if isinstance(value, dict):
        copy = {}
        for key, item in value.items():
            if (*path, key) not in dropped:
                copy[key], below = _without(item, dropped, (*path, key))
                kept |= below
        return copy, kept
    if isinstance(value, list):
        indices = [i for i in range(len(value)) if (*path, i) not in dropped]
        kept[path] = indices
        items = []
        for i in indices:
            item, below = _without(value[i], dropped, (*path, i))
            items.append(item)
            kept |= below
        return items, kept
    return value, kept


def _original_path(path: Path, kept: dict[Path, list[int]]) -> Path:
    """A path in the pruned copy as a path in the original document."""
    original: list[int | str] = []
    for part in path:
        indices = kept.get(tuple(original))
        if indices is not None and isinstance(part, int) and 0 <= part < len(indices):
            part = indices[part]
        original.append(part)
    return tuple(original)


def _related(path: Path, dropped: Path) -> bool:
    """``path`` is the value left out, inside it, or a mapping or list that lost it."""
    n = min(len(path), len(dropped))
    return path[:n] == dropped[:n]


def _file_path(loc: tuple[int | str, ...], data: Any, missing: bool = False) -> Path:
    """A pydantic error location as a path in the file: the tags pydantic inserts for a discriminated union are dropped.

    ``missing``: the location ends with a field missing from the file (never a tag).
    """
    path: list[int | str] = []
    here = data
    for i, part in enumerate(loc):
        # ('faults', 0, 'link_loss', 'direction'): 'link_loss' is no key of the fault but the value of its tag field
        last_missing = missing and i == len(loc) - 1
        if isinstance(here, dict) and part not in here:  # pydantic names a key that is no string or integer (null, 1.5, a date) by its repr
            part = next((k for k in here if not isinstance(k, str | int) and repr(k) == part), part)
        if not last_missing and isinstance(here, dict) and part not in here and any(v == part for v in here.values() if isinstance(v, str)):
            continue
        path.append(part)
        if isinstance(here, dict):
            here = here.get(part)
        elif isinstance(here, list) and isinstance(part, int) and 0 <= part < len(here):
            here = here[part]
        else:
            here = None
    return tuple(path)


def _located(file: str, mark: yaml.Mark | None, field: str, message: str) -> FieldError:
    """An error at a YAML mark (0-based), or at the start of the file."""
    return FieldError(file, mark.line + 1, mark.column + 1, field, message) if mark else FieldError(file, 1, 1, field, message)


def _located_after(file: str, before: str, field: str, message: str) -> FieldError:
    """An error right after ``before``, the text from the start of the file up to the problem (lines and columns as YAML counts them)."""
    breaks = [m.end() for m in _LINE_BREAK.finditer(before)]
    line_start = breaks[-1] if breaks else int(before.startswith("\ufeff"))  # a BOM takes no column
    return FieldError(file, len(breaks) + 1, len(before) - line_start + 1, field, message)


def _check_size(name: str, size: int, what: str) -> None:
    if size > MAX_BYTES:
        raise MissionError([_located(name, None, "(file)", f"file is {size} bytes; a {what} file may have at most {MAX_BYTES} (1 MiB)")])


_read_lately: dict[tuple[object, ...], tuple[dict[str, Any], _Loader]] = {}
_read_lock = threading.Lock()


def _read(text: str, filename: str, what: str) -> tuple[dict[str, Any], _Loader]:
    """:func:`_parse`, of a file read lately kept: a process reads one file again (``validate`` then ``run``, a test's runs), and
    PyYAML's pure-Python scanner is most of loading (~1.5 µs a character). The document is a copy each time: a caller's own.
    A file that cannot be read is read again each time (its errors are not kept).
    """
    key = (text, filename, what, MAX_ALIASES, MAX_DEPTH, MAX_VALUES)  # the limits too: what a text gives depends on them
    found = _read_lately.get(key)
    if found is None:
        found = _parse(text, filename, what)
        if len(text) <= READ_KEPT_MAX_CHARS:
            with _read_lock:
                _read_lately[key] = found
                while len(_read_lately) > READ_KEPT or sum(len(kept[0]) for kept in _read_lately) > READ_KEPT_CHARS:
                    del _read_lately[next(iter(_read_lately))]  # the oldest
    return copy.deepcopy(found[0]), found[1]


def _parse(text: str, filename: str, what: str) -> tuple[dict[str, Any], _Loader]:
    """The document's mapping and the loader holding the node index; refuses anything that is not one YAML mapping."""
    loader = None
    try:
        loader = _Loader(text)
        root = loader.get_single_node()
        if root is None:
            raise MissionError([_located(filename, None, f"({what})", "the file holds no YAML document (it is empty or only comments)")])
        loader.index_paths(root)
        data = loader.construct_document(root)
    except yaml.MarkedYAMLError as exc:
        message = f"{exc.context}, {exc.problem}" if exc.context else str(exc.problem)
        raise MissionError([_located(filename, exc.problem_mark or exc.context_mark, "(yaml)", message)]) from None
    except yaml.reader.ReaderError as exc:  # a character YAML does not allow, e.g. a control character
        raise MissionError([_located_after(filename, text[: exc.position], "(yaml)", f"character #x{exc.character:04x}: {exc.reason}")]) from None
    finally:
        if loader is not None:
            loader.dispose()
    if not isinstance(data, dict):
        raise MissionError([_located(filename, root.start_mark, f"({what})", f"expected a mapping of {what} fields, got {describe_value(data)}")])
    return data, loader


def _message(error: dict[str, Any], node: yaml.Node | None, root: type[BaseModel] = Mission) -> str:
    """A pydantic error entry as a person would say it."""
    kind, value = error["type"], error.get("input")
    if kind in ("missing", "union_tag_not_found"):
        return "required field is missing"
    if kind == "union_tag_invalid":
        tag = value.get(error["ctx"]["discriminator"].strip("'")) if isinstance(value, dict) else error["ctx"]["tag"]
        return f"{_show(tag)}: expected one of {error['ctx']['expected_tags']}"
    if kind == "extra_forbidden":
        model = _model_at(root, error["loc"][:-1])
        if model is None:
            return "unknown field"
        field = error["loc"][-1]
        close = difflib.get_close_matches(field, list(model.model_fields), n=1) if isinstance(field, str) else []
        hint = f"did you mean {close[0]}? " if close else ""
        return f"unknown field ({hint}allowed: {', '.join(model.model_fields)})"
    if kind in _EXPECTED:
        return f"expected {_EXPECTED[kind]}, got {describe_value(value)}{_yaml11_hint(node, value)}"
    message = error["msg"].removeprefix("Value error, ")
    return message if isinstance(value, list | dict) else f"{_show(value)}: {message}"


def _model_at(root: type[BaseModel], loc: tuple[Any, ...]) -> type[BaseModel] | None:
    """The model validating the mapping at pydantic location ``loc`` (lists, ``X | None`` and tagged unions see through)."""
    models = [root]
    for part in loc:
        if not isinstance(part, str):
            continue
        owners = [m for m in models if part in m.model_fields]
        if owners:
            models = [found for m in owners for found in _models_in(m.model_fields[part].annotation)]
        else:  # the tag pydantic puts in the location of a discriminated union's member
            models = [m for m in models if _has_tag(m, part)]
    return models[0] if len(models) == 1 else None


def _has_tag(model: type[BaseModel], tag: str) -> bool:
    return any(get_origin(f.annotation) is Literal and tag in get_args(f.annotation) for f in model.model_fields.values())


def _models_in(annotation: Any) -> list[type[BaseModel]]:
    """The models an annotation can hold: ``X``, ``list[X]``, ``X | Y | None``, ``Annotated[...]``."""
    if get_origin(annotation) is None and isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [model for arg in get_args(annotation) for model in _models_in(arg)]


def _show(value: Any) -> str:
    """A value as YAML spells it, shortened."""
    if isinstance(value, int) and value.bit_length() > 512:  # str() refuses integers of more than 4300 digits
        return f"{'-' if value < 0 else ''}<an integer of about {int(value.bit_length() * math.log10(2)) + 1} digits>"
    text = "null" if value is None else str(value).lower() if isinstance(value, bool) else repr(value) if isinstance(value, str) else str(value)
    return text if len(text) <= 40 else f"{text[:37]}..."


def describe_value(value: Any) -> str:
    """The YAML type and value found, e.g. ``bool true`` or ``a list``."""
    if isinstance(value, list | dict):
        return "a list" if isinstance(value, list) else "a mapping"
    kinds = {bool: "bool", int: "integer", float: "number", str: "string", type(None): ""}
    return f"{kinds.get(type(value), type(value).__name__)} {_show(value)}".strip()


def _yaml11_hint(node: yaml.Node | None, value: Any) -> str:
    """Explain the YAML 1.1 surprises: ``yes``/``off`` are booleans, ``1e3`` is a string."""
    if not isinstance(node, yaml.ScalarNode) or node.style is not None:  # quoted: the author meant a string
        return ""
    if isinstance(value, bool) and node.value.lower() not in ("true", "false"):
        return f" (YAML 1.1 reads {node.value} as a boolean)"
    if isinstance(value, str) and _EXPONENT_WITHOUT_DOT_OR_SIGN.fullmatch(value):
        return f" (YAML 1.1 reads {node.value} as a string: write a number with a dot and a signed exponent, e.g. 1.0e+3)"
    return ""
