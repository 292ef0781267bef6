"""executive: an onboard behaviour-tree mission executive for uncrewed vehicles."""

import importlib
import importlib.machinery
import importlib.util
import sys
import warnings
from collections.abc import Callable
from operator import attrgetter  # not `import operator`: the subpackage executive.operator, once imported, is this module's `operator`
from pathlib import Path
from types import MappingProxyType, ModuleType
from typing import Any

__version__ = "0.1.0"

_HERE = Path(__file__).resolve().parent
#: The built-in trees live in the repository's top-level ``trees/`` folder (the project's layout). Installed, setuptools puts
#: them inside the package as ``executive.trees`` (pyproject's package-dir); run from a checkout they are found there.
_CHECKOUT_TREES = _HERE.parent / "trees"


# The finders and the loader below are duck-typed (the import system asks for find_spec, create_module and exec_module):
# importlib.abc's base classes would cost every command's start ~10 ms (importlib.resources, tempfile...).
class _CheckoutTrees:
    """Finds ``executive.trees`` (only that name; its modules then by its path) in a checkout's ``trees/`` folder."""

    def find_spec(self, fullname: str, path: object = None, target: object = None) -> importlib.machinery.ModuleSpec | None:
        if fullname != "executive.trees":
            return None
        return importlib.util.spec_from_file_location(fullname, _CHECKOUT_TREES / "__init__.py", submodule_search_locations=[str(_CHECKOUT_TREES)])


if not (_HERE / "trees").is_dir() and (_CHECKOUT_TREES / "__init__.py").is_file():
    sys.meta_path.append(_CheckoutTrees())


#: Modules moved into the packages of their layer in 0.2 (issue 41), old name -> new, below ``executive``. The old names
#: still import, with a DeprecationWarning, for one release; ``executive.runtime`` and ``executive.admission`` became
#: packages of the same name, whose old names are forwarded by :func:`moved_attribute`.
MOVED: MappingProxyType[str, str] = MappingProxyType(
    {
        "blackboard": "world.blackboard",
        "state": "world.state",
        "vehicles": "world.vehicles",
        "geo": "world.geo",
        "frames": "world.frames",
        "geofence": "world.geofence",
        "seabed": "world.seabed",
        "clock": "world.clock",
        "mavlink_dialect": "world.dialect",
        "mission.plan_files": "mission.formats.plan_files",
        "mission.plan_reading": "mission.formats.plan_reading",
        "mission.plan_items": "mission.formats.plan_items",
        "mission.mp_zone_files": "mission.formats.mp_zone_files",
        "mode_cause": "autopilot.mode_cause",
        "target_watch": "autopilot.target_watch",
        "io.serial_sampler": "instruments.serial",
        "intervention": "operator.intervention",
        "status": "operator.status",
        "progress": "operator.progress",
        "logs": "operator.logs",
        "composition": "tree.composition",
        "catalogue": "tree.catalogue",
        "waiting": "tree.waiting",
        "mission_tree": "tree.select",
        "tree_drawing": "tree.drawing",
        "mission_schema": "tree.schema",
        "btcpp": "tree.formats.btcpp",
        "recompose": "tree.formats.recompose",
        "reach": "admission.reach",
        "assembly": "runtime.assembly",
        "services": "runtime.services",
        "pacing": "runtime.pacing",
        "journal": "observers.journal",
        "snapshots": "observers.snapshots",
        "groot2": "observers.groot2",
        "web": "observers.web",
        "mcap_messages": "observers.mcap.messages",
        "mcap_reading": "observers.mcap.reading",
        "mcap_recording": "observers.mcap.recording",
        "mcap_writer": "observers.mcap.writer",
        "mcap_report": "observers.mcap.report",
        "foxglove_live": "observers.foxglove.live",
        "foxglove_layout": "observers.foxglove.layout",
    }
)
#: The two modules that became packages of their own name: their names forwarded from the package (PEP 562).
MOVED_INTO_PACKAGE = MappingProxyType({"runtime": "runtime.loop", "admission": "admission.checks"})
#: Names renamed in 0.2 (issue 41: one name for one thing), module and old name below ``executive`` -> the new name in the same
#: module. The old name still works, with a DeprecationWarning, for one release: the module's ``__getattr__`` asks
#: :func:`moved_attribute`. A class's member that moved to another object is a :class:`MovedMember`.
RENAMED: MappingProxyType[str, str] = MappingProxyType(
    {
        "runtime.loop.Outcome": "RunOutcome",  # how a run ended; world.state.Outcome is what an acked command asks
        "world.state.Sample": "SampleRecord",  # a finished sample; behaviours.sampling.Sample is the action taking it
        "sim.Limits": "MotionLimits",  # how a simulated vehicle moves; mission.model.Limits are the mission's
        "sim.physics.vehicle.Limits": "MotionLimits",
        "mission.formats.plan_items.Source": "FileContents",  # what a plan file says; observers.web.server.Source feeds the page
        "runtime.services.Step": "FunctionService",  # a service made of a function; autopilot.asking.Step is a step asked
        "sim.ardupilot.plane.Transition": "TransitionState",  # SLT_Transition's state; mission.events.Transition is the lifecycle's
    }
)


def _warn_moved(old: str, new: str, stacklevel: int = 3) -> None:
    warnings.warn(f"{old} moved to {new} (0.2); the old name goes in 0.3", DeprecationWarning, stacklevel=stacklevel)


class _MovedModule:
    """Loads an old module name as the module now at its new name (the same module object)."""

    def __init__(self, new: str) -> None:
        self._new = new
        self._spec: importlib.machinery.ModuleSpec | None = None

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        module = importlib.import_module(self._new)
        self._spec = module.__spec__
        return module

    def exec_module(self, module: ModuleType) -> None:
        module.__spec__ = self._spec  # the import system set the old name's spec on it


class _MovedModules:
    def find_spec(self, fullname: str, path: object = None, target: object = None) -> importlib.machinery.ModuleSpec | None:
        old = fullname.removeprefix("executive.")
        if fullname == old or old not in MOVED:
            return None
        new = f"executive.{MOVED[old]}"
        _warn_moved(fullname, new)
        return importlib.machinery.ModuleSpec(fullname, _MovedModule(new))


def moved_attribute(package: str, name: str) -> object:
    """An old name of module ``package``, with a DeprecationWarning: called by the module's ``__getattr__`` (PEP 562).

    A name in :data:`RENAMED` is the module's new name (``executive.world.state.Sample``: ``SampleRecord``); a module that
    became a package forwards the names of the module it was (``executive.runtime``'s ``Runtime``).
    """
    old = package.removeprefix("executive.")
    if f"{old}.{name}" in RENAMED:
        new_name = RENAMED[f"{old}.{name}"]
        _warn_moved(f"{package}.{name}", f"{package}.{new_name}", stacklevel=4)
        return getattr(sys.modules[package], new_name)
    if old not in MOVED_INTO_PACKAGE:
        raise AttributeError(f"module {package!r} has no attribute {name!r}")
    new = f"executive.{MOVED_INTO_PACKAGE[old]}"
    module = importlib.import_module(new)
    if name.startswith("__") or not hasattr(module, name):
        raise AttributeError(f"module {package!r} has no attribute {name!r}")
    _warn_moved(f"{package}.{name}", f"{new}.{name}")
    return getattr(module, name)


def lazy_exports(package: str, module_of: dict[str, str]) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """A package's ``__getattr__`` and ``__dir__`` (PEP 562) for names each imported from its module on first use.

    ``module_of`` maps a name to the module of ``package`` it is in. A package imported where little of it is used (pytest's
    plugin loads :mod:`executive.testing` in xdist's controller, which runs no test; ``executive ctl`` needs only
    :mod:`executive.operator`'s status line) then costs nothing for the rest; ``dir()`` lists the names all the same.
    """

    def __getattr__(name: str) -> object:
        if name in module_of:
            return getattr(importlib.import_module(f"{package}.{module_of[name]}"), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted({*vars(sys.modules[package]), *module_of})

    return __getattr__, __dir__


class MovedMember:
    """A class's member that moved in 0.2 to another object: read at ``new``, a path from the instance (``legs.leg_index``),
    with a DeprecationWarning, for one release. ``read`` reads it when a path alone cannot (a method that now takes an argument).
    """

    def __init__(self, new: str, read: Callable[[Any], object] | None = None) -> None:
        self.new = new
        self._read = read or attrgetter(new)
        self.old = self._owner = ""

    def __set_name__(self, owner: type, name: str) -> None:
        self.old, self._owner = f"{owner.__module__}.{owner.__qualname__}.{name}", owner.__qualname__

    def __get__(self, instance: object, owner: type | None = None) -> object:
        if instance is None:
            return self
        _warn_moved(self.old, f"{self._owner}.{self.new}")
        return self._read(instance)


sys.meta_path.append(_MovedModules())
