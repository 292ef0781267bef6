"""A blackboard client's get and set (its own functions, not py_trees' methods) read and write as py_trees' own do, on the client's board."""

from __future__ import annotations

import py_trees
import pytest
from py_trees.blackboard import Blackboard

from executive.world import blackboard


def test_get_and_set_are_py_trees_reads_and_writes() -> None:
    writer = blackboard.writer("test writer", ["/vehicle/armed", "/link/up"])
    reader = blackboard.reader("test reader", ["/vehicle/armed"])
    assert writer.set("/vehicle/armed", True) is True
    assert reader.get("/vehicle/armed") is True is py_trees.blackboard.Client.get(reader, "/vehicle/armed")
    assert writer.set("/vehicle/armed", False, overwrite=False) is False  # py_trees' answer: there already
    assert blackboard.value("/vehicle/armed") is True
    with pytest.raises(AttributeError, match="does not have read/write access"):
        reader.get("/link/up")  # not registered by this client: py_trees' error
    with pytest.raises(AttributeError, match="does not have write access"):
        reader.set("/vehicle/armed", False)  # read access only: py_trees' error
    assert blackboard.value("/vehicle/armed") is True


def test_with_the_activity_stream_on_each_access_is_in_it() -> None:
    writer = blackboard.writer("test writer", ["/vehicle/armed"])
    Blackboard.enable_activity_stream()
    try:
        writer.set("/vehicle/armed", True)
        assert writer.get("/vehicle/armed") is True
        stream = Blackboard.activity_stream
        assert stream is not None
        assert [(item.key, item.activity_type) for item in stream.data][-2:] == [("/vehicle/armed", "WRITE"), ("/vehicle/armed", "READ")]
    finally:
        Blackboard.disable_activity_stream()


def test_a_client_keeps_the_board_current_when_it_was_made() -> None:
    first = blackboard.for_runtime("first vehicle")
    writer = blackboard.writer("first writer", ["/vehicle/armed"])
    first.runtime = "first vehicle"  # taken: the next runtime gets a board of its own
    second = blackboard.for_runtime("second vehicle")
    assert blackboard.current() is second
    writer.set("/vehicle/armed", True)
    assert writer.get("/vehicle/armed") is True
    assert first.value("/vehicle/armed") is True and second.value("/vehicle/armed") is not True
