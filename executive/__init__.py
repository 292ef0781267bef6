"""executive: an onboard behaviour-tree mission executive for uncrewed vehicles."""

import importlib.abc
import importlib.machinery
import importlib.util
import sys
from pathlib import Path

__version__ = "0.1.0"

_HERE = Path(__file__).resolve().parent
#: The built-in trees live in the repository's top-level ``trees/`` folder (the project's layout). Installed, setuptools puts
#: them inside the package as ``executive.trees`` (pyproject's package-dir); run from a checkout they are found there.
_CHECKOUT_TREES = _HERE.parent / "trees"


class _CheckoutTrees(importlib.abc.MetaPathFinder):
    """Finds ``executive.trees`` (only that name; its modules then by its path) in a checkout's ``trees/`` folder."""

    def find_spec(self, fullname: str, path: object = None, target: object = None) -> importlib.machinery.ModuleSpec | None:
        if fullname != "executive.trees":
            return None
        return importlib.util.spec_from_file_location(fullname, _CHECKOUT_TREES / "__init__.py", submodule_search_locations=[str(_CHECKOUT_TREES)])


if not (_HERE / "trees").is_dir() and (_CHECKOUT_TREES / "__init__.py").is_file():
    sys.meta_path.append(_CheckoutTrees())
