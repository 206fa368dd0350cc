"""Layer 1, the model: piecewise-smooth systems as mathematics.

Nothing here integrates; every other layer depends on this one.  Its modules:

- :mod:`~saltation.model.system`: modes, switching surfaces, transitions and resets, written as sympy
  expressions (:class:`PiecewiseSystem`);
- :mod:`~saltation.model.nonsmooth`: ``sign``, ``Abs``, ... in a field turned into modes and surfaces;
- :mod:`~saltation.model.regularize`: the smoothed model the paper warns about;
- :mod:`~saltation.model.symmetry`: a model's symmetry, ``x -> S x`` with a shift of half a period;
- :mod:`~saltation.model.labels`: how plots write a model's names.
"""

from saltation.model.symmetry import Symmetry
from saltation.model.system import TIME, Crossing, Mode, PiecewiseSystem, Transition

__all__ = ["TIME", "Crossing", "Mode", "PiecewiseSystem", "Symmetry", "Transition"]


def __getattr__(name: str):
    """The other names of the flat layout's ``saltation.model`` (now :mod:`saltation.model.system`)."""
    from saltation.model import system

    if name.startswith("__") or not hasattr(system, name):
        raise AttributeError(f"module 'saltation.model' has no attribute {name!r}")
    import warnings

    warnings.warn(f"saltation.model.{name} has moved to saltation.model.system.{name}", DeprecationWarning, stacklevel=2)
    return getattr(system, name)
