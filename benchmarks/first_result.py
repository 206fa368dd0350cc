"""Time to first result: how long a new model takes from a fresh process to its first periodic orbit.

Run by hand (not by CI)::

    python benchmarks/first_result.py            # two states, then chains of 16 and 32 masses
    python benchmarks/first_result.py --quick    # two states only

Every measurement is a fresh interpreter (``python -c``), wall clock, including
Python's start-up and ``import saltation``, in a kernel cache of its own (a
temporary directory):

1. the one-time build: a model's first orbit on an empty cache (the engine of
   its dimension compiles, then the model's functions);
2. a new model of that dimension (the same equations under a random name, so
   its functions are never cached), on the cache that now holds the engine:
   what a user waits for after changing a model's equations;
3. the first model again (everything cached).

The job is the same each time: 20 forcing periods of transient, then shooting;
the orbit must converge with a residual below 1e-8.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

TWO_STATES = """
import math, random
from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition, find_periodic_orbit
name = "relay_oscillator" + (f"_{{random.randrange(10**9)}}" if {fresh} else "")
system = PiecewiseSystem(
    name, states=["x", "v"], parameters={{"c": 0.2, "omega": 1.3}},
    modes=[Mode("up", ["v", "-x - 2*c*v + 0.5 + 2*cos(omega*t)"], domain=["x < 0"]),
           Mode("down", ["v", "-x - 2*c*v - 0.5 + 2*cos(omega*t)"], domain=["x >= 0"])],
    surfaces={{"s": "x"}},
    transitions=[Transition("up", "s", Crossing.RISING, "down"), Transition("down", "s", Crossing.FALLING, "up")],
    period="2*pi/omega")
{shoot}
"""

CHAIN = """
import copy, math, random
from saltation import Flow, find_periodic_orbit
from saltation.models import chain
system = chain({masses})
if {fresh}:  # the same equations under a new name: a model this cache has never seen
    system = copy.copy(system)
    system.name = f"chain{masses}_{{random.randrange(10**9)}}"
    system.__dict__.pop("fingerprint", None)
{shoot}
"""

SHOOT = """
flow = Flow(system)
p = flow.parameters()
T = 2 * math.pi / p[system.parameter_index("omega")]
x0 = flow.run([0.5] + [0.0] * (system.n - 1), 0.0, 20 * T, p).x1
orbit = find_periodic_orbit(flow, x0)
assert orbit.converged and orbit.residual_norm < 1e-8, orbit.residual_norm
"""


def _fresh_process(code: str, cache: str) -> float:
    env = dict(os.environ, SALTATION_CACHE_DIR=cache)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], env=env, check=True, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def measure(label: str, template: str, **kw: object) -> None:
    with tempfile.TemporaryDirectory() as cache:
        build = _fresh_process(template.format(fresh=False, shoot=SHOOT, **kw), cache)
        new = _fresh_process(template.format(fresh=True, shoot=SHOOT, **kw), cache)
        again = _fresh_process(template.format(fresh=False, shoot=SHOOT, **kw), cache)
    print(f"{label:<30} one-time build and first orbit {build:6.1f} s | new model {new:5.1f} s | "
          f"cached model {again:5.1f} s", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="two states only")
    args = parser.parse_args()
    measure("two states (relay oscillator)", TWO_STATES)
    if not args.quick:
        measure("32 states (chain of 16)", CHAIN, masses=16)
        measure("64 states (chain of 32)", CHAIN, masses=32)


if __name__ == "__main__":
    main()
