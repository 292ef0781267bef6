"""The module names of 0.1 keep importing for one release (issue 41): the same module, with a DeprecationWarning."""

from __future__ import annotations

import importlib
import importlib.util
import sys

import pytest

import executive


@pytest.mark.parametrize("old", sorted(executive.MOVED))
def test_an_old_module_name_is_the_moved_module_with_a_warning(old: str) -> None:
    sys.modules.pop(f"executive.{old}", None)
    with pytest.warns(DeprecationWarning, match=f"executive.{old} moved to executive.{executive.MOVED[old]}"):
        module = importlib.import_module(f"executive.{old}")
    assert module is importlib.import_module(f"executive.{executive.MOVED[old]}")
    assert module.__spec__.name == f"executive.{executive.MOVED[old]}"  # the moved module keeps its own spec


def test_names_of_the_modules_that_became_packages_are_forwarded_with_a_warning() -> None:
    from executive.admission.checks import refusals
    from executive.runtime.loop import Runtime

    with pytest.warns(DeprecationWarning, match="executive.runtime.Runtime moved to executive.runtime.loop.Runtime"):
        from executive.runtime import Runtime as old_runtime
    with pytest.warns(DeprecationWarning, match="executive.admission.refusals moved"):
        from executive.admission import refusals as old_refusals
    assert (old_runtime, old_refusals) == (Runtime, refusals)
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        executive.runtime.nothing  # noqa: B018


def test_the_old_names_are_the_ones_that_moved() -> None:
    """Every old name is gone from where it was (a shim, not a copy) and its new home exists."""
    here = executive._HERE
    for old, new in executive.MOVED.items():
        assert not (here / f"{old.replace('.', '/')}.py").exists()
        assert not (here / old.replace(".", "/") / "__init__.py").exists()
        assert importlib.util.find_spec(f"executive.{new}") is not None


@pytest.mark.parametrize("old", sorted(executive.RENAMED))
def test_a_renamed_name_is_the_new_one_with_a_warning(old: str) -> None:
    """One name for one thing (0.2): ``executive.world.state.Sample`` (a finished sample) is ``SampleRecord``, apart from the Sample action."""
    module, _, name = old.rpartition(".")
    new = executive.RENAMED[old]
    with pytest.warns(DeprecationWarning, match=rf"executive\.{old} moved to executive\.{module}\.{new} \(0\.2\)"):
        found = getattr(importlib.import_module(f"executive.{module}"), name)
    assert found is getattr(importlib.import_module(f"executive.{module}"), new)
    assert found.__name__ == new  # the class itself, under its new name


def test_the_old_name_of_a_sample_record_imports_with_a_warning_and_a_typo_still_fails() -> None:
    from executive.behaviours.sampling import Sample as SampleAction
    from executive.world.state import SampleRecord

    with pytest.warns(DeprecationWarning, match="executive.world.state.Sample moved to executive.world.state.SampleRecord"):
        from executive.world.state import Sample
    assert Sample is SampleRecord and Sample is not SampleAction
    with pytest.raises(ImportError):
        from executive.world.state import Sampel  # noqa: F401
