"""The estimate of a first build against the truth: what the build's message says, and how long it took.

Run by hand (not by CI); each build takes a minute or so of both cores::

    python benchmarks/build_estimate.py paper                 # the paper's build on an empty cache
    python benchmarks/build_estimate.py trilinear chain:5     # each on an empty cache of its own
    python benchmarks/build_estimate.py --one-cache trilinear chain:5 chain:32
                                                              # one after the other in one cache: the
                                                              # later estimates come from the earlier builds
    python benchmarks/build_estimate.py functions:chain:32    # a 64-state model's functions alone

A target is ``paper`` (the engine for two states and the paper's three models, side by side, as
``saltation paper`` starts), a model of :mod:`saltation.models` with its arguments after colons
(``chain:5``), whose first :class:`~saltation.Flow` is built (its engine and functions), or
``functions:`` and a model (``functions:chain:32``), whose functions alone are compiled.  Each runs in a fresh interpreter with
``SALTATION_CACHE_DIR`` and ``NUMBA_CACHE_DIR`` in a temporary folder; the builds it made are then read
from the record in the cache (``build_times.json``): each one's kind, estimate and where it came from,
and the time it took.  The load average at start and end is printed: the numbers mean little without it.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

CHILD = """
import sys
target = sys.argv[1]
if target == "paper":
    from saltation.apps.paper import smoothed_block_on_belt
    from saltation.engine.precompile import compile_in_parallel
    from saltation.models import block_on_belt, trilinear
    compile_in_parallel((make() for make in (trilinear, block_on_belt, smoothed_block_on_belt)), dimensions=(2,))
else:
    from saltation import Flow, models
    from saltation.engine.codegen import load_model_functions
    alone = target.startswith("functions:")
    name, *args = target.removeprefix("functions:").split(":")
    model = getattr(models, name)(*map(int, args))
    load_model_functions(model) if alone else Flow(model)
"""


def run(target: str, cache: str, numba_cache: str) -> list[dict]:
    """Build ``target`` in a fresh interpreter with the given caches; the builds it recorded."""
    path = os.path.join(cache, "build_times.json")
    try:
        with open(path) as fh:
            before = len(json.load(fh)["builds"])
    except (OSError, ValueError, KeyError):
        before = 0
    env = {**os.environ, "SALTATION_CACHE_DIR": cache, "NUMBA_CACHE_DIR": numba_cache}
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", CHILD, target], env=env, check=True, timeout=900)
    print(f"{target}: the process took {time.perf_counter() - start:.1f} s", file=sys.stderr)
    with open(path) as fh:
        return json.load(fh)["builds"][before:]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("targets", nargs="+", help="paper, or a model with its arguments (chain:5)")
    parser.add_argument("--one-cache", action="store_true", help="build the targets one after the other in one cache")
    args = parser.parse_args(argv)
    print(f"cores {os.cpu_count()}, load average {os.getloadavg()}")
    print(f"{'target':<10} {'build':<16} {'estimate':>8} {'truth':>6} {'truth/est':>9} {'cores':>5} {'had':>5} "
          f"{'scale':>5}  source")
    with tempfile.TemporaryDirectory() as shared:
        for target in args.targets:
            with tempfile.TemporaryDirectory() as own:
                base = shared if args.one_cache else own
                cache, numba_cache = os.path.join(base, "saltation"), os.path.join(base, "numba")
                for b in run(target, cache, numba_cache):
                    estimate, cpu = b.get("estimate"), b.get("cpu")
                    ratio = f"{b['seconds'] / estimate:9.2f}" if estimate else f"{'-':>9}"
                    had = f"{cpu / b['seconds']:5.2f}" if cpu else f"{'-':>5}"  # the cores it used, on average
                    scale = f"{cpu / sum(b['work']):5.2f}" if cpu else f"{'-':>5}"  # processor time over work
                    print(f"{target:<10} {b['kind']:<16} {estimate or '-':>8} {b['seconds']:>6.1f} {ratio} "
                          f"{b['cores']:5.2f} {had} {scale}  {b['source']}", flush=True)
    print(f"load average at the end {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
