"""What the command line knows of a shipped model, declared in the model's own file.

Each model module ends with one :class:`ShippedModel`; :data:`saltation.models.SHIPPED`
collects them by name.  Adding a model to the command line is one file and one
import line in ``saltation/models/__init__.py``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

from ..model import PiecewiseSystem


@dataclass(frozen=True)
class ShippedModel:
    """A model shipped with saltation, as the command line uses it.

    Attributes
    ----------
    name : str
        The name the command line uses (``saltation orbit NAME``).
    factory : callable
        Builds the model; takes keyword overrides of the default parameter values.
    summary : str
        One line for ``--help``.
    start : callable, optional
        ``(parameter values, backward) -> state``: where a transient starts
        when no ``--x0`` is given (zeros otherwise).
    transient_length : callable, optional
        ``parameter values -> time``: the transient's length for an autonomous
        model (forced models run a number of forcing periods).
    """

    name: str
    factory: Callable[..., PiecewiseSystem]
    summary: str
    start: Callable[[Mapping[str, float], bool], list[float]] | None = None
    transient_length: Callable[[Mapping[str, float]], float] | None = None
