"""Write ``engine_reference.json``: results of the paper's two models, for tests/engine/test_engine.py.

The reference was written by the per-model kernels that the shared engine
replaced (the revision before it, run with ``PYTHONPATH`` pointing at that
revision's ``src``); the engine must reproduce it to 1e-12.  Run by hand::

    PYTHONPATH=<old checkout>/src python tests/data/engine_reference.py

(It calls ``Flow.run(..., parameter=0)``, the name of ``sensitivity`` in that revision.)
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from saltation import Flow, Tolerances
from saltation.models import block_on_belt, trilinear
from saltation.apps.paper import block_on_belt_diagram, trilinear_diagram

RUNS = [  # model, parameters, initial state, span, tolerances (None: the defaults)
    ("trilinear", {"omega": 1.3}, [1.5, 0.3], 6.0, None),
    ("trilinear", {"omega": 1.3}, [1.5, 0.3], 6.0, {"exact_affine": False}),
    ("trilinear", {"omega": 0.9}, [2.0, -0.5], -5.0, None),
    ("block_on_belt", {}, [2.0, 0.0], 10.0, None),
    ("block_on_belt", {}, [0.4, 1.0], -4.0, None),
]


def trajectories() -> list[dict]:
    out = []
    for name, pars, x0, span, tol in RUNS:
        flow = Flow({"trilinear": trilinear, "block_on_belt": block_on_belt}[name]())
        p = flow.parameters(pars)
        tr = flow.run(x0, 0.0, span, p, variational=True, parameter=0, tolerances=Tolerances(**tol) if tol else None)
        out.append({
            "x1": tr.x1.tolist(), "monodromy": tr.monodromy.tolist(), "sensitivity": tr.parameter_sensitivity.tolist(),
            "event_times": [e.t for e in tr.events], "event_surfaces": [e.surface for e in tr.events],
        })
    return out


def special_points() -> dict[str, list[dict]]:
    branches = {"fig3": [trilinear_diagram()], "fig7": list(block_on_belt_diagram().branches)}
    return {
        fig: [
            {"kind": sp.kind.value, "parameter": sp.parameter,
             "multipliers": [[z.real, z.imag] for z in (sp.multipliers if sp.multipliers is not None else [])]}
            for b in bs for sp in b.special_points
        ]
        for fig, bs in branches.items()
    }


if __name__ == "__main__":
    data = {"runs": RUNS, "trajectories": trajectories(), "special_points": special_points()}
    path = Path(__file__).with_name("engine_reference.json")
    path.write_text(json.dumps(data, indent=1) + "\n")
    print(f"wrote {path}")
