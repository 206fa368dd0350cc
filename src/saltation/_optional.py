"""Optional dependencies: imported where a function needs them, with an error that says how to install them.

pandas (:meth:`saltation.branches.branch.Branch.to_pandas`) and xarray (the sweeps' ``to_xarray`` and NetCDF
files) are extras of the package: ``pip install 'saltation[pandas]'`` or ``'saltation[xarray]'``.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from saltation.errors import MissingDependencyError


def require(module: str, extra: str, what: str) -> ModuleType:
    """The module ``module``, imported; or a clear error naming what needs it and the extra to install.

    Parameters
    ----------
    module : str
        The module to import (``"pandas"``, ``"xarray"``).
    extra : str
        The package's extra that installs it.
    what : str
        What needs it, for the message (``"Branch.to_pandas"``).

    Returns
    -------
    module

    Raises
    ------
    MissingDependencyError
        If the module cannot be imported.
    """
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise MissingDependencyError(
            f"{what} needs {module}, an optional dependency of saltation that is not installed "
            f"({exc}): pip install 'saltation[{extra}]'") from exc
