"""The import paths of the flat layout (release 0.1), kept working until release 0.3.0.

The modules moved into one folder per layer (see the package's docstring).  ``import
saltation.integrate`` and ``from saltation.shooting import find_periodic_orbit`` still work: a finder
on ``sys.meta_path`` gives the module at its new path under the old name, with a
``DeprecationWarning`` that names the new path.  ``saltation.model`` is now a package; its old
names are forwarded by its own ``__getattr__``.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import warnings

#: old module -> the module that replaces it
MOVED = {
    "saltation.nonsmooth": "saltation.model.nonsmooth",
    "saltation.regularize": "saltation.model.regularize",
    "saltation._contract": "saltation.engine._contract",
    "saltation.affine": "saltation.engine.affine",
    "saltation.codegen": "saltation.engine.codegen",
    "saltation.compiled": "saltation.engine.compiled",
    "saltation.integrate": "saltation.engine.flow",
    "saltation.precompile": "saltation.engine.precompile",
    "saltation.floquet": "saltation.orbits.floquet",
    "saltation.shooting": "saltation.orbits.shooting",
    "saltation.boundary": "saltation.orbits.boundary",
    "saltation.branch": "saltation.branches.branch",
    "saltation.corrector": "saltation.branches.corrector",
    "saltation.continuation": "saltation.special_points.continuation",
    "saltation.bifurcations": "saltation.special_points.detection",
    "saltation.grazing": "saltation.special_points.grazing",
    "saltation.sliding": "saltation.special_points.sliding",
    "saltation.loci": "saltation.special_points.loci",
    "saltation.branch_switching": "saltation.special_points.branch_switching",
    "saltation.plotting": "saltation.output.plotting",
    "saltation.io": "saltation.output.io",
    "saltation.cli": "saltation.apps.cli",
    "saltation.paper": "saltation.apps.paper",
    "saltation.diagram": "saltation.apps.diagram",
}


class _Alias(importlib.abc.Loader):
    def __init__(self, target: str):
        self.target = target

    def create_module(self, spec):
        warnings.warn(f"{spec.name} has moved to {self.target}; the old path goes in release 0.3.0",
                      DeprecationWarning, stacklevel=2)
        module = importlib.import_module(self.target)
        self.spec = module.__spec__  # the import machinery sets the alias's spec on it: put back below
        return module

    def exec_module(self, module) -> None:
        module.__spec__ = self.spec


class _MovedFinder(importlib.abc.MetaPathFinder):
    def find_spec(self, fullname, path=None, target=None):
        new = MOVED.get(fullname)
        if new is None:
            return None
        return importlib.machinery.ModuleSpec(fullname, _Alias(new))


def install() -> None:
    """Put the finder on ``sys.meta_path`` (once)."""
    if not any(isinstance(f, _MovedFinder) for f in sys.meta_path):
        sys.meta_path.append(_MovedFinder())


def forward_names(module: str, homes: tuple[str, ...]):
    """A module ``__getattr__`` for the names a release-0.1 module held at its top level and no longer
    defines or imports: each is looked up in the modules that hold it now (``homes``, in order), and
    returned with a ``DeprecationWarning`` naming its home (the old place goes in release 0.3.0).

    Parameters
    ----------
    module : str
        The module's name (its ``__name__``).
    homes : tuple of str
        The modules to look in, of the same layer or below.

    Returns
    -------
    callable
        ``__getattr__(name)``, which raises ``AttributeError`` for a name none of them holds.
    """

    def __getattr__(name: str):
        if not name.startswith("_"):
            for home in homes:
                found = importlib.import_module(home)
                if hasattr(found, name):
                    warnings.warn(f"{module}.{name} lives in {home}; the old place goes in release 0.3.0",
                                  DeprecationWarning, stacklevel=2)
                    return getattr(found, name)
        raise AttributeError(f"module {module!r} has no attribute {name!r}")

    return __getattr__
