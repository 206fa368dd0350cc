"""Shared models and compiled flows for the test suite.

Compiling a model's kernels costs ~40 s the first time (numba caches them on disk
afterwards), so the suite uses the two paper models and only two small models of
its own.  Everything else is done by changing parameter values, which does not
recompile.
"""

from __future__ import annotations

import functools
import os
from pathlib import Path

#: The suite compiles into a kernel cache of its own (kept between runs, beside the tests), never into
#: the user's ($SALTATION_CACHE_DIR or ~/.cache/saltation): set before anything compiles, and inherited
#: by the command-line runs the tests start.  SALTATION_TEST_CACHE_DIR chooses another folder.
TEST_CACHE = Path(os.environ.get("SALTATION_TEST_CACHE_DIR") or Path(__file__).parents[1] / ".test-kernel-cache")
os.environ["SALTATION_CACHE_DIR"] = str(TEST_CACHE.resolve())

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Tolerances, Transition  # noqa: E402
from saltation.models import block_on_belt, trilinear  # noqa: E402

RISING, FALLING = Crossing.RISING, Crossing.FALLING

#: Tight tolerances for reference integrations (finite differences, closed forms).
TIGHT = Tolerances(rtol=1e-13, atol=1e-15)


def pytest_addoption(parser):
    parser.addoption("--thorough", action="store_true", default=False,
                     help="also run the literature corpus's thorough steps (longer branches, finer sweeps)")


#: the models users wrote from the docs, beside the checkout (CI clones the repository with ../shared beside it)
TRIAL_MODELS = Path(__file__).parents[2] / "shared" / "trial-models"


def trial_model(name: str):
    """The module ``../shared/trial-models/NAME.py`` (the test is skipped where it is not beside the checkout)."""
    import importlib.util

    path = TRIAL_MODELS / f"{name}.py"
    if not path.exists():
        pytest.skip(f"{path} is not beside the checkout")
    spec = importlib.util.spec_from_file_location(f"trial_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def oscillator_system() -> PiecewiseSystem:
    """``x'' = -w^2 x - g`` with a wall at ``x = a`` and a floor at ``x = 0``.

    * ``below`` / ``above``: the same field on either side of the wall, switching
      both ways without reset (event location; closed form ``x = R sin(w t)``).
    * ``ball``: bounces on the floor with restitution ``e`` (``v -> -e v``); with
      ``w = 0, g = 1`` a Zeno bouncing ball.
    * ``root``: field ``[v, -sqrt(x)]``, which is NaN for ``x < 0``.

    ``ball`` and ``root`` are reached only by passing ``mode0``; the domains of
    ``below`` and ``above`` leave the wall ``x = a`` itself uncovered.  With
    ``gap > 0`` the domain of ``above`` starts beyond the wall: the model's
    domains and transitions disagree.
    """
    field = ["v", "-w**2*x - g"]
    return PiecewiseSystem(
        name="test_oscillator",
        states=["x", "v"],
        parameters={"w": 1.0, "a": 0.5, "g": 0.0, "e": 0.5, "gap": 0.0},
        modes=[
            Mode("below", field, domain=["x - a < 0"]),
            Mode("above", field, domain=["x - a - gap > 0"]),
            Mode("ball", field, domain=["x - a < 0"]),
            Mode("root", ["v", "-sqrt(x)"], domain=["x - a < 0"]),
        ],
        surfaces={"wall": "x - a", "floor": "x"},
        transitions=[
            Transition("below", "wall", RISING, "above"),
            Transition("above", "wall", FALLING, "below"),
            Transition("ball", "floor", FALLING, "ball", reset=["x", "-e*v"]),
        ],
    )


def filippov_system() -> PiecewiseSystem:
    """A planar Filippov system with an attracting sliding motion on ``y = 0``.

    ``above`` (y > 0): ``[1, -1]``; ``below`` (y < 0): ``[2, 1 - x + q sin(omega t + phi)]``.
    Both fields push into ``y = 0`` while ``x < 1 + q sin(omega t + phi)``; the sliding
    motion leaves into ``below`` where that field turns tangent.  For ``q = 0``
    everything is in closed form (see test_sliding.py).
    """
    return PiecewiseSystem(
        name="test_filippov",
        states=["x", "y"],
        parameters={"q": 0.0, "omega": 1.0, "phi": 0.0},
        modes=[
            Mode("above", ["1", "-1"], domain=["y > 0"]),
            Mode("below", ["2", "1 - x + q*sin(omega*t + phi)"], domain=["y < 0"]),
        ],
        surfaces={"s": "y"},
        transitions=[
            Transition("above", "s", FALLING, "below"),
            Transition("below", "s", RISING, "above"),
        ],
        period="2*pi/omega",
    )


@pytest.fixture(scope="session", autouse=True)
def _models_compiled_in_parallel() -> None:
    """On an empty kernel cache, compile the models most tests share at once, one process each, instead
    of one after another as the tests first use them (models already cached are skipped)."""
    from saltation.engine.precompile import compile_in_parallel
    from saltation.models import bouncing_ball, chain, friction_oscillator, impact_oscillator
    from saltation.apps.paper import smoothed_block_on_belt

    compile_in_parallel(
        [trilinear(), block_on_belt(), oscillator_system(), filippov_system(), chain(1), chain(2), impact_oscillator(),
         bouncing_ball(), smoothed_block_on_belt(), friction_oscillator()]
    )


@pytest.fixture(autouse=True)
def _every_branch_holds_its_invariants(request, monkeypatch):
    """Every branch a test computes (every :class:`~saltation.branches.continuation.Continuation`) is checked
    after the test against the invariants of :func:`saltation.branches.check.check_branch`: the trivial
    multiplier at 1, every change of stability covered by a special point of the right kind, honest
    brackets, no silent stop.  A test that builds a branch to see it break one marks itself
    ``unchecked_branches``.  With ``SALTATION_BRANCH_CHECK_REPORT=FILE`` the violations are appended to
    FILE instead of failing the test."""
    from saltation.branches import continuation as cont

    made = []
    original = cont.Continuation.__init__

    @functools.wraps(original)
    def recording(self, *args, **kwargs):
        original(self, *args, **kwargs)
        made.append(self.branch)

    recording.__kwdefaults__ = original.__kwdefaults__  # functools.wraps does not copy them
    monkeypatch.setattr(cont.Continuation, "__init__", recording)
    yield
    if request.node.get_closest_marker("unchecked_branches") is not None:
        return
    broken = [(b, b.check()) for b in made if b.points]
    broken = [(b, c) for b, c in broken if not c.ok]
    if not broken:
        return
    text = "\n".join(f"{b.model} in {b.parameter_name} ({len(b.points)} points):\n{c}" for b, c in broken)
    report = os.environ.get("SALTATION_BRANCH_CHECK_REPORT")
    if report:
        with open(report, "a") as fh:
            fh.write(f"## {request.node.nodeid}\n{text}\n")
        return
    pytest.fail(f"a computed branch breaks its invariants:\n{text}", pytrace=False)


@pytest.fixture(scope="session")
def trilinear_flow() -> Flow:
    return Flow(trilinear())


@pytest.fixture(scope="session")
def belt_flow() -> Flow:
    return Flow(block_on_belt())


@pytest.fixture(scope="session")
def oscillator_flow() -> Flow:
    return Flow(oscillator_system())


@pytest.fixture(scope="session")
def filippov_flow() -> Flow:
    return Flow(filippov_system())


def central_difference_jacobian(fun, x0, h):
    """Jacobian of ``fun`` at ``x0`` by central differences with steps ``h`` (scalar or per component)."""
    x0 = np.asarray(x0, dtype=float)
    h = np.broadcast_to(np.asarray(h, dtype=float), x0.shape)
    cols = []
    for j in range(x0.size):
        e = np.zeros_like(x0)
        e[j] = h[j]
        cols.append((np.asarray(fun(x0 + e)) - np.asarray(fun(x0 - e))) / (2 * h[j]))
    return np.column_stack(cols)


# -- periodic orbits of the paper models (shared by several test files) -----------------

@pytest.fixture(scope="session")
def contact_orbit(trilinear_flow):
    """The trilinear orbit at omega = 1.0: contact with both supports, four events per period."""
    from saltation.orbits.shooting import find_periodic_orbit

    p = trilinear_flow.parameters({"omega": 1.0})
    guess = trilinear_flow.run([0.0, 0.0], 0.0, 50 * 2 * np.pi, p).x1  # transient
    return find_periodic_orbit(trilinear_flow, guess, parameters={"omega": 1.0})


def stick_slip_orbit(belt_flow, eta=None):
    """The stable stick-slip cycle, from a transient started in the stick band."""
    from saltation.orbits.shooting import find_periodic_orbit

    overrides = {} if eta is None else {"eta": eta}
    p = belt_flow.parameters(overrides)
    guess = belt_flow.run([0.0, 1.0], 0.0, 30.0, p).x1
    return find_periodic_orbit(belt_flow, guess, parameters=overrides, period=6.5)


def unstable_orbit(belt_flow, eta=None):
    """The infinitely unstable cycle, by shooting in backward time."""
    from saltation.orbits.shooting import find_periodic_orbit

    overrides = {} if eta is None else {"eta": eta}
    return find_periodic_orbit(belt_flow, [1.0, -0.95], parameters=overrides, period=6.3, backward=True)


@pytest.fixture(scope="session")
def stable_cycle(belt_flow):
    return stick_slip_orbit(belt_flow)


@pytest.fixture(scope="session")
def unstable_cycle(belt_flow):
    return unstable_orbit(belt_flow)


# -- hypothesis profiles (the property suites, e.g. tests/orbits/test_degenerate_orbits.py) ------
# "ci", the default: few examples per property and no deadline (a first call may compile a model),
# so that each property file runs in well under a minute.  "thorough" draws many more:
#     HYPOTHESIS_PROFILE=thorough python -m pytest tests/orbits/test_degenerate_orbits.py
try:
    from hypothesis import HealthCheck
    from hypothesis import settings as _hypothesis_settings
except ImportError:  # hypothesis comes with the test extra; without it only the property suites fail
    pass
else:
    # (a failure prints its @reproduce_failure blob; the example database, .hypothesis/, ignores itself in git)
    # "ci" draws the same examples on every run (derandomize): a CI result that does not depend on the
    # day; "thorough" draws new ones each time, and is where new failures are looked for
    _hypothesis_settings.register_profile(
        "ci", max_examples=50, deadline=None, print_blob=True, derandomize=True,
        suppress_health_check=[HealthCheck.too_slow],
    )
    _hypothesis_settings.register_profile(
        "thorough", max_examples=1000, deadline=None, print_blob=True, suppress_health_check=[HealthCheck.too_slow]
    )
    import os as _os

    _hypothesis_settings.load_profile(_os.environ.get("HYPOTHESIS_PROFILE", "ci"))
