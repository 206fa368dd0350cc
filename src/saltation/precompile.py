"""Compiling the kernels of several models at once, before they are used (a cold cache only).

numba compiles a model's generated module on its first use; a process that
needs several models (the paper's figures, the test suite) compiles them in
parallel here, one fresh interpreter per model, and then loads them from the
cache.  It sits above :mod:`saltation.integrate`: a warm-up run is what
compiles.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from .codegen import is_compiled
from .integrate import Flow
from .model import PiecewiseSystem


def _compile_in_worker(system: PiecewiseSystem) -> str:
    flow = Flow(system)
    n, p = system.n, flow.parameters()
    try:
        flow.run(np.zeros(n), 0.0, 1e-3, p, variational=True, parameter=0 if system.n_params else -1)
    except Exception:  # noqa: BLE001 - compiling is what matters here, not these tiny runs
        pass
    if system.n_params:  # the corrector of continuation
        m = n + (1 if system.is_autonomous else 0)
        normal = np.zeros(m + 1)
        normal[-1] = 1.0
        phase = (np.zeros(n), np.zeros(n)) if system.is_autonomous else None
        try:
            flow.compiled_newton(
                np.zeros(m + 1), normal, p, t0=0.0, sign=1.0, lam_index=0, span=0.0, phase=phase, tol=1e-10,
                max_iter=0, max_correction=1.0, damped=False,
            )
        except Exception:  # noqa: BLE001
            pass
    return system.name


def compile_in_parallel(systems: list[PiecewiseSystem], workers: int | None = None) -> list[str]:
    """Compile the kernels of several models at once, one process per model (a cold cache only).

    Models whose kernels are cached already are skipped; each model is compiled
    in a fresh interpreter (so this is safe from any script), at most ``workers``
    (default: the number of cores) at a time, and the calling process then loads
    the kernels from the cache.  Returns the names compiled.
    """
    import pickle
    import subprocess
    from concurrent.futures import ThreadPoolExecutor

    todo = [s for s in systems if not is_compiled(s)]
    workers = min(len(todo), workers or os.cpu_count() or 1)
    if len(todo) <= 1 or workers <= 1:
        return []
    code = "import pickle, sys; from saltation.precompile import _compile_in_worker; _compile_in_worker(pickle.load(open(sys.argv[1], 'rb')))"
    with tempfile.TemporaryDirectory() as tmp:

        def compile_one(k: int) -> None:
            path = Path(tmp) / f"model{k}.pickle"
            path.write_bytes(pickle.dumps(todo[k]))
            subprocess.run([sys.executable, "-c", code, str(path)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

        with ThreadPoolExecutor(workers) as pool:
            list(pool.map(compile_one, range(len(todo))))
    return [s.name for s in todo]


__all__ = ["compile_in_parallel"]
