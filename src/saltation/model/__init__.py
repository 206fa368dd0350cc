"""Layer 1, the model: piecewise-smooth systems as mathematics.

Nothing here integrates; every other layer depends on this one.  Its modules:

- :mod:`~saltation.model.system`: modes, switching surfaces, transitions and resets, written as sympy
  expressions (:class:`PiecewiseSystem`);
- :mod:`~saltation.model.nonsmooth`: ``sign``, ``Abs``, ... in a field turned into modes and surfaces;
- :mod:`~saltation.model.contacts`: impacts that stick, continued as the motion constrained to their surface;
- :mod:`~saltation.model.sides`: each mode's field read on its own side of its surfaces (contact laws with
  fractional powers);
- :mod:`~saltation.model.regularize`: the smoothed model the paper warns about;
- :mod:`~saltation.model.symmetry`: a model's symmetry, ``x -> S x`` with a shift of half a period;
- :mod:`~saltation.model.labels`: how plots write a model's names.
"""

__all__ = ["TIME", "Crossing", "Mode", "PiecewiseSystem", "Symmetry", "Transition"]

#: the package's names and the modules that define them (imported on first use: sympy loads with them)
_HOME_OF = {"Symmetry": "saltation.model.symmetry", **dict.fromkeys(("TIME", "Crossing", "Mode", "PiecewiseSystem",
                                                                    "Transition"), "saltation.model.system")}


def __getattr__(name: str):
    """The package's names, imported on first use; and the other names of the flat layout's
    ``saltation.model`` (now :mod:`saltation.model.system`), with a warning."""
    import importlib

    if name in _HOME_OF:
        value = getattr(importlib.import_module(_HOME_OF[name]), name)
        globals()[name] = value
        return value
    if name.startswith("__"):
        raise AttributeError(f"module 'saltation.model' has no attribute {name!r}")
    system = importlib.import_module("saltation.model.system")
    if not hasattr(system, name):
        raise AttributeError(f"module 'saltation.model' has no attribute {name!r}")
    import warnings

    warnings.warn(f"saltation.model.{name} has moved to saltation.model.system.{name}", DeprecationWarning, stacklevel=2)
    return getattr(system, name)


def __dir__() -> list[str]:
    return sorted({*globals(), *_HOME_OF})
