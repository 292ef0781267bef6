"""Drawings of a behaviour tree for a person: Unicode text with box-drawing lines, and Graphviz DOT.

Each node is drawn with a glyph for its kind (sequence, selector, parallel, decorator, leaf) and,
once it has ticked, one for its status. In DOT every node has its own id (``n0``, ``n1``...), its
name only in the quoted label: two nodes of one name, or names with ``:`` or quotes, stay apart.
"""

from __future__ import annotations

from collections.abc import Iterator

import py_trees
from py_trees.common import Status

from executive.tree.ticks import STATUS_SYMBOLS

KIND_GLYPHS = {"sequence": "→", "selector": "?", "parallel": "⇉", "decorator": "◇", "leaf": "•"}
#: Graphviz shape and fill per kind (py_trees' own palette, so its users recognise it).
DOT_STYLE = {
    "sequence": ("box", "orange"),
    "selector": ("octagon", "cyan"),
    "parallel": ("parallelogram", "gold"),
    "decorator": ("ellipse", "ghostwhite"),
    "leaf": ("ellipse", "gray"),
}
DOT_STATUS_COLOUR = {Status.SUCCESS: "green", Status.FAILURE: "red", Status.RUNNING: "blue"}


def kind(node: py_trees.behaviour.Behaviour) -> str:
    """``sequence``, ``selector``, ``parallel``, ``decorator`` or ``leaf``."""
    if isinstance(node, py_trees.composites.Sequence):
        return "sequence"
    if isinstance(node, py_trees.composites.Selector):
        return "selector"
    if isinstance(node, py_trees.composites.Parallel):
        return "parallel"
    if isinstance(node, py_trees.decorators.Decorator):
        return "decorator"
    return "leaf"


def unicode_tree(root: py_trees.behaviour.Behaviour, *, show_status: bool = False) -> str:
    """The tree as indented text: ``├─``/``└─`` lines, a kind glyph per node; with ``show_status``, a status glyph and the feedback."""
    return "\n".join(_unicode_lines(root, "", "", show_status))


def _unicode_lines(node: py_trees.behaviour.Behaviour, lead: str, child_lead: str, show_status: bool) -> Iterator[str]:
    status = f"{STATUS_SYMBOLS[node.status]} " if show_status else ""
    feedback = f" — {node.feedback_message}" if show_status and node.feedback_message and node.status != Status.INVALID else ""
    yield f"{lead}{status}{KIND_GLYPHS[kind(node)]} {node.name}{feedback}"
    children = list(node.children)
    for i, child in enumerate(children):
        last = i == len(children) - 1
        yield from _unicode_lines(child, child_lead + ("└─ " if last else "├─ "), child_lead + ("   " if last else "│  "), show_status)


def _quoted(text: str) -> str:
    """A DOT string literal."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def dot_graph(root: py_trees.behaviour.Behaviour, name: str, *, show_status: bool = False) -> str:
    """The tree as a Graphviz digraph named ``name``; with ``show_status``, each ticked node outlined in its status's colour."""
    lines = [
        f"digraph {_quoted(name)} {{",
        "  ordering=out;",
        '  graph [fontname="sans-serif"];',
        '  node [fontname="sans-serif", fontsize=9, style=filled];',
    ]
    ids: dict[int, str] = {}
    nodes = list(_preorder(root))
    for node in nodes:
        ids[id(node)] = node_id = f"n{len(ids)}"
        shape, fill = DOT_STYLE[kind(node)]
        outline = f", color={DOT_STATUS_COLOUR[node.status]}, penwidth=2" if show_status and node.status in DOT_STATUS_COLOUR else ""
        lines.append(f"  {node_id} [label={_quoted(node.name)}, shape={shape}, fillcolor={fill}{outline}];")
    for node in nodes:
        lines += [f"  {ids[id(node)]} -> {ids[id(child)]};" for child in node.children]
    lines.append("}")
    return "\n".join(lines) + "\n"


def _preorder(node: py_trees.behaviour.Behaviour) -> Iterator[py_trees.behaviour.Behaviour]:
    yield node
    for child in node.children:
        yield from _preorder(child)
