"""Probe for a compile-once engine: numba first-class functions (run by hand, in a fresh process).

An engine compiled with an explicit signature whose first argument is a
``numba.types.FunctionType`` is cached once, and takes any model function
compiled with that signature without compiling again.  This script writes a
tiny engine and two models into a temporary directory, runs them in two fresh
interpreters (cold, then warm cache), and prints the import and first-call
times, the engine's compiled signatures (one), and the cost of the indirect
call against the same loop with the field written inline.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

ENGINE = '''
import numpy as np
from numba import njit, types

FIELD = types.void(types.int64, types.float64, types.float64[::1], types.float64[::1], types.float64[::1])

@njit(types.float64(types.FunctionType(FIELD), types.float64[::1], types.float64[::1], types.int64), cache=True)
def engine(field, x, p, nsteps):
    n = x.shape[0]
    k1 = np.zeros(n)
    y = x.copy()
    for s in range(nsteps):
        field(0, s * 1e-3, y, p, k1)
        for i in range(n):
            y[i] += 1e-3 * k1[i]
    return y[0]

@njit(cache=True)
def inline(x, p, nsteps):
    n = x.shape[0]
    k1 = np.zeros(n)
    y = x.copy()
    for s in range(nsteps):
        k1[0] = y[1]
        k1[1] = -p[0] * y[0]
        for i in range(n):
            y[i] += 1e-3 * k1[i]
    return y[0]
'''

MODELS = '''
from numba import njit
from engine import FIELD

@njit(FIELD, cache=True)
def oscillator(mode, t, x, p, out):
    out[0] = x[1]
    out[1] = -p[0] * x[0]

@njit(FIELD, cache=True)
def duffing(mode, t, x, p, out):
    out[0] = x[1]
    out[1] = -p[0] * x[0] - x[0] ** 3
'''

RUN = '''
import time
t0 = time.perf_counter()
import timeit
import numpy as np
from engine import engine, inline
from models import duffing, oscillator
t1 = time.perf_counter()
x, p = np.array([1.0, 0.0]), np.array([1.0])
engine(oscillator, x, p, 10)
t2 = time.perf_counter()
engine(duffing, x, p, 10)
t3 = time.perf_counter()
inline(x, p, 10)
print(f"import and compile {t1 - t0:.2f} s, first model {t2 - t1:.4f} s, second model {t3 - t2:.4f} s")
print(f"engine signatures: {len(engine.signatures)}")
steps = 200000
ind = min(timeit.repeat(lambda: engine(oscillator, x, p, steps), number=1, repeat=5)) / steps * 1e9
inl = min(timeit.repeat(lambda: inline(x, p, steps), number=1, repeat=5)) / steps * 1e9
print(f"per step: indirect call {ind:.2f} ns, field inline {inl:.2f} ns")
'''


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        for name, text in (("engine.py", ENGINE), ("models.py", MODELS), ("run.py", RUN)):
            (d / name).write_text(textwrap.dedent(text))
        env = {"NUMBA_CACHE_DIR": str(d / "cache"), "PATH": "/usr/bin:/bin"}
        for label in ("cold cache", "warm cache"):
            out = subprocess.run([sys.executable, "run.py"], cwd=d, env=env, capture_output=True, text=True, check=True)
            print(f"-- {label}\n{out.stdout}", end="")


if __name__ == "__main__":
    main()
