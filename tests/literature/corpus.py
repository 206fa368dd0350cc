"""The literature corpus: published models written as a user writes them from the docs, each with a reference.

A model of the corpus is one file in ``tests/literature/models/`` that defines ``CASE``, a
:class:`LiteratureCase`: the model (a function returning a :class:`~saltation.PiecewiseSystem`, written from its
paper with the public API only), where its natural orbit is, and what an independent reference (a closed
form, matrix exponentials and ``brentq``, or a scipy integration written without saltation, in the same file)
says about it.  ``tests/literature/test_corpus.py`` takes every case through the steps a researcher takes:

1. an orbit from the most natural guess, its multipliers against the reference's (and its trivial multiplier
   at 1 if the model is autonomous);
2. a branch across the interesting range, whose special points are compared with the reference's, kind by
   kind; every branch is checked against the invariants of :func:`saltation.branches.check.check_branch`
   (``tests/conftest.py`` does that for every branch the suite computes);
3. a two-parameter curve of one special point, where one exists, against the reference's curve;
4. a sweep, checked by a function of the case;
5. Lyapunov exponents where the motion is chaotic.

A new model needs only its file.  ``pytest --thorough`` runs the steps marked ``thorough`` too (longer
branches, finer sweeps).
"""

from __future__ import annotations

import importlib.util
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

MODELS = Path(__file__).parent / "models"


@dataclass(frozen=True)
class Expected:
    """A special point the reference predicts on the branch.

    Attributes
    ----------
    kinds : tuple of str
        The :class:`~saltation.SpecialPointKind` values that name it correctly (a border collision may be
        ``grazing`` or ``nonsmooth_no_crossing`` depending on what the one-sided multipliers do; list what the
        theory allows, not what the code prints).
    value : float
        The parameter value from the reference.
    tol : float
        What the reference and the location promise together (the location's own ``accuracy`` is added).
    """

    kinds: tuple[str, ...]
    value: float
    tol: float


@dataclass(frozen=True)
class Orbit:
    """Where the natural orbit is and what the reference says of it.

    ``multipliers(parameters)`` returns the reference's Floquet multipliers (for an autonomous model,
    without the trivial one; the test removes the computed multiplier closest to 1).  ``state(parameters)``,
    if given, the orbit's state at the section (forced: at ``t0``).
    """

    parameters: Mapping[str, float]
    guess: Sequence[float]
    multipliers: Callable[[Mapping[str, float]], np.ndarray]
    period: float | None = None  # autonomous models: the period guess
    mode0: str | None = None
    t0: float = 0.0
    state: Callable[[Mapping[str, float]], np.ndarray] | None = None
    rtol: float = 1e-7  # what shooting (tol 1e-10) and the default integration promise for the multipliers


@dataclass(frozen=True)
class BranchStep:
    """A branch of the natural orbit in ``parameter`` over ``bounds``, and the special points expected on it."""

    parameter: str
    bounds: tuple[float, float]
    expected: Callable[[], Sequence[Expected]]
    ds: float = 0.02
    ds_max: float = 0.05
    max_points: int = 400
    thorough: bool = False


@dataclass(frozen=True)
class LocusStep:
    """The curve of the branch's special point of ``kind`` in ``second`` over ``bounds``, against
    ``reference(second value) -> first parameter value``, at most ``tol`` apart."""

    kind: str
    second: str
    bounds: tuple[float, float]
    reference: Callable[[float], float]
    tol: float
    thorough: bool = False


@dataclass(frozen=True)
class SweepStep:
    """A sweep of ``parameter`` over ``values`` (other settings as keyword arguments of :func:`saltation.sweep`),
    then ``check(result)`` asserts what the reference says of it."""

    parameter: str
    values: Sequence[float]
    check: Callable[[object], None]
    options: Mapping[str, object] = field(default_factory=dict)
    thorough: bool = False


@dataclass(frozen=True)
class LyapunovStep:
    """Lyapunov exponents at ``parameters`` from ``state0``; ``check(exponents)`` against the reference."""

    parameters: Mapping[str, float]
    state0: Sequence[float]
    time: float
    check: Callable[[np.ndarray], None]
    transient: float = 0.0
    mode0: str | None = None
    thorough: bool = False


@dataclass(frozen=True)
class LiteratureCase:
    """One published model of the corpus."""

    name: str
    field: str  # mechanics, power electronics, control, neuroscience, robotics, Filippov benchmark, ...
    source: str  # the publication(s) the model is written from
    model: Callable[..., object]  # keyword overrides of the defaults -> PiecewiseSystem
    orbit: Orbit
    branch: BranchStep | None = None
    locus: LocusStep | None = None
    sweep: SweepStep | None = None
    lyapunov: LyapunovStep | None = None
    #: steps the library fails today: ``{step: "what fails, and the issue"}``, run as strict expected failures
    #: (``orbit``, ``branch``, ``locus``, ``sweep``, ``lyapunov``), so that a fix shows as XPASS and fails the run
    known_failures: Mapping[str, str] = field(default_factory=dict)


def load_cases() -> list[LiteratureCase]:
    """Every ``CASE`` in ``tests/literature/models/*.py``, in file order."""
    cases = []
    for path in sorted(MODELS.glob("*.py")):
        if path.name.startswith("_"):
            continue
        spec = importlib.util.spec_from_file_location(f"literature_{path.stem}", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        cases.append(module.CASE)
    return cases
