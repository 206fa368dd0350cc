"""Write one file of each format with the saltation found on PYTHONPATH (an earlier release; see README.md).

Usage: PYTHONPATH=<old src> python write_old_formats.py <folder>
"""
import dataclasses
import sys
from pathlib import Path

import numpy as np

import saltation
from saltation import branch as B
from saltation import io

out = Path(sys.argv[1]); out.mkdir(parents=True, exist_ok=True)
pf = {f.name for f in dataclasses.fields(B.BranchPoint)}
ev = "event_labels" if "event_labels" in pf else "events"

def point(k):
    lam = 1.0 + 0.25 * k
    return B.BranchPoint(parameter=lam, state=np.array([0.5 + k / 8, -0.25]), period=2 * np.pi / lam,
                         amplitude=1.5 + k / 4, half_peak_to_peak=1.25 + k / 4,
                         multipliers=np.array([0.5 + 0.25j, 0.5 - 0.25j]), stable=True,
                         **{ev: ("hit stop", "leave stop")}, step=0.125, iterations=3)

sp = B.SpecialPoint(kind=B.SpecialPointKind.FOLD, parameter=1.375, bracket=(1.25, 1.5), accuracy=0.25, index=1,
                    state=np.array([0.625, -0.25]), period=4.5, amplitude=1.75,
                    multipliers=np.array([1.0 + 0j, 0.25 + 0j]), note="smooth fold")

def branch(label, n):
    return B.Branch(model="trilinear", parameter_name="omega", kind=B.BranchKind.PERIODIC,
                    points=[point(k) for k in range(n)], special_points=[sp],
                    stop_reason=B.StopReason.MAX_POINTS, **({"stop_reasons": [B.StopReason.MAX_POINTS]} if "stop_reasons" in {f.name for f in dataclasses.fields(B.Branch)} else {}),
                    fixed_parameters={"zeta": 0.05, "g": 2.0}, label=label)

b = branch("main", 3)
io.save_branch_json(b, out / "branch.json")
io.save_diagram_json([b, branch("second", 2)], out / "diagram.json")
io.save_branch_csv(b, out / "branch.csv")
try:
    from saltation import sweeps as S
except ImportError:
    try:
        from saltation import sweep as S
    except ImportError:
        print(sorted(p.name for p in out.iterdir())); sys.exit()
sf = {f.name for f in dataclasses.fields(S.SweepResult)}
pn = "parameter_name" if "parameter_name" in sf else "parameter"
extra = {"start": S.SweepStart.PREVIOUS} if "start" in sf else {}
s = S.SweepResult(model="trilinear", **{pn: "omega"}, values=np.array([1.0, 1.5]), counts=np.array([2, 1]),
                  parameter_points=np.array([1.0, 1.0, 1.5]), states=np.array([[0.5, -0.25], [0.75, 0.125], [0.625, 0.0]]),
                  state_names=("x", "v"), section="poincare", failures=(), settings={"periods": 4, "transient": 2}, **extra)
s.save(out / "sweep.json")
if hasattr(S, "PeriodMap"):
    mf = {f.name for f in dataclasses.fields(S.PeriodMap)}
    names = {"parameter_name": "omega", "parameter2_name": "zeta"} if "parameter_name" in mf else {"parameter": "omega", "parameter2": "zeta"}
    m = S.PeriodMap(model="trilinear", **names, values=np.array([1.0, 1.5]), values2=np.array([0.0, 0.05, 0.1]),
                    periods=np.array([[1, 2], [1, -1], [4, 1]]), max_period=8, failures=((1.5, 0.05, "no convergence"),),
                    settings={"periods": 4}, **({"start": S.SweepStart.PREVIOUS} if "start" in mf else {}))
    m.save(out / "period_map.json")
print(saltation.__file__, sorted(p.name for p in out.iterdir()))
