"""The engine is compiled once and shared by every model; its results are those of the per-model kernels
it replaced."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Tolerances, Transition
from saltation.engine.codegen import (
    SPECIALIZED_DIMENSIONS,
    engine_dimension,
    engine_source,
    model_source,
)
from saltation.models import block_on_belt, trilinear
from saltation.apps.paper import block_on_belt_diagram, trilinear_diagram

REFERENCE = json.loads((Path(__file__).parents[1] / "data" / "engine_reference.json").read_text())


def _relay(name: str, gain: str) -> PiecewiseSystem:
    return PiecewiseSystem(
        name, states=["x", "v"], parameters={"c": 0.05, "omega": 1.3},
        modes=[Mode("up", ["v", f"-x - 2*c*v + {gain} + 0.3*cos(omega*t)"], domain=["x < 0"]),
               Mode("down", ["v", f"-x - 2*c*v - {gain} + 0.3*cos(omega*t)"], domain=["x >= 0"])],
        surfaces={"s": "x"},
        transitions=[Transition("up", "s", Crossing.RISING, "down"), Transition("down", "s", Crossing.FALLING, "up")],
        period="2*pi/omega",
    )


def test_two_models_share_one_compiled_engine(trilinear_flow):
    """A second model of the same dimension runs on the engine the first compiled: the same module, one
    compiled signature of each entry point, and one of the step and of the event search inside it (a
    compilation per model would add a signature: the model's functions would be part of the types)."""
    first = Flow(_relay("test_engine_relay_a", "1"))
    second = Flow(_relay("test_engine_relay_b", "0.5"))
    for flow in (first, second, trilinear_flow):
        flow.run([0.3, 0.0], 0.0, 20.0, flow.parameters(), variational=True, sensitivity=0)
    engine = first._engine
    assert second._engine is engine and trilinear_flow._engine is engine
    assert first._model[0] is not second._model[0]  # two models, two sets of functions
    for entry in (engine.integrate_kernel, engine.correct_periodic):
        assert len(entry.signatures) == 1
    for helper in (engine._rk_step, engine._bracket_root, engine._exact_step):
        assert len(helper.overloads) <= 1


def test_dimensions_share_engines_as_documented():
    assert [engine_dimension(n) for n in (1, 2, 3, 4, 5, 64)] == [1, 2, 3, 4, 0, 0]
    assert list(SPECIALIZED_DIMENSIONS) == [1, 2, 3, 4]
    # nothing of a model in the engine's source, nothing of the engine in a model's
    assert "vector_field(" not in engine_source(2).replace("model[VECTOR_FIELD](", "")
    assert "def integrate_kernel" not in model_source(trilinear())


@pytest.mark.slow  # compiles the engine for models above the specialised sizes
def test_a_model_of_more_states_than_specialized_runs_on_the_shared_engine():
    """Five states (the chain's engine with N_STATE = 0, the dimension read from the arrays): the
    monodromy of a linear mode against expm(A T), which the exact flow does not use here (DOP853)."""
    import scipy.linalg

    A = np.array([[0, 1, 0, 0, 0], [-2, -0.1, 1, 0, 0], [0, 0, 0, 1, 0], [1, 0, -2, -0.1, 1], [0, 0, 0, 0, -0.5]], float)
    fields = [" + ".join(f"({A[i, j]})*x{j}" for j in range(5) if A[i, j]) for i in range(5)]
    system = PiecewiseSystem(
        "test_engine_five_states", states=[f"x{i}" for i in range(5)], parameters={"a": 1.0},
        modes=[Mode("only", [f"a*({f})" for f in fields])], surfaces={"never": "x0 - 100"}, transitions=[],
    )
    flow = Flow(system, Tolerances(exact_affine=False, rtol=1e-12, atol=1e-14))
    assert engine_dimension(system.n) == 0
    tr = flow.run([0.1, 0.2, -0.1, 0.0, 0.3], 0.0, 3.0, flow.parameters(), variational=True)
    # DOP853 at rtol 1e-12 over three time units, with |expm(A T)| of order one: errors of order 1e-11
    np.testing.assert_allclose(tr.monodromy, scipy.linalg.expm(A * 3.0), rtol=0, atol=1e-10)


@pytest.mark.parametrize("k", range(len(REFERENCE["trajectories"])))
def test_trajectories_equal_those_of_the_per_model_kernels(k):
    name, pars, x0, span, tol = REFERENCE["runs"][k]
    ref = REFERENCE["trajectories"][k]
    flow = Flow({"trilinear": trilinear, "block_on_belt": block_on_belt}[name]())
    tr = flow.run(x0, 0.0, span, flow.parameters(pars), variational=True, sensitivity=0,
                  tolerances=Tolerances(**tol) if tol else None)
    assert [e.surface for e in tr.events] == ref["event_surfaces"]
    np.testing.assert_allclose([e.t for e in tr.events], ref["event_times"], rtol=0, atol=1e-12)
    for key, value in (("x1", tr.x1), ("monodromy", tr.monodromy), ("sensitivity", tr.parameter_sensitivity)):
        np.testing.assert_allclose(value, ref[key], rtol=0, atol=1e-12, err_msg=key)


@pytest.mark.parametrize("figure", ["fig3", "fig7"])
def test_special_points_equal_those_of_the_per_model_kernels(figure):
    points = trilinear_diagram().special_points if figure == "fig3" else block_on_belt_diagram().special_points
    ref = REFERENCE["special_points"][figure]
    assert [sp.kind.value for sp in points] == [r["kind"] for r in ref]
    for sp, r in zip(points, ref):
        # the same point, located to its own accuracy: since the recording, a shooting guess next to a
        # switching surface starts from the middle of its longest stretch between events (the unstable
        # branch of Fig. 7 starts in the stick band's border), so the bisection path, and the located
        # parameter within its bracket, differ; everything else is the recorded result
        assert abs(sp.parameter - r["parameter"]) <= sp.accuracy
        got = [] if sp.multipliers is None else [[z.real, z.imag] for z in sp.multipliers]
        np.testing.assert_allclose(got, r["multipliers"], rtol=0, atol=1e-12)


def test_a_flow_pickles_as_its_model_and_tolerances(trilinear_flow):
    """A flow sent to another process (a worker, a Dask task) carries its model, not the addresses of
    this process's compiled functions; the copy integrates the same trajectory, to the bit."""
    import pickle

    copy = pickle.loads(pickle.dumps(trilinear_flow))
    assert copy.system.fingerprint == trilinear_flow.system.fingerprint and copy.tolerances == trilinear_flow.tolerances
    p = trilinear_flow.parameters({"omega": 1.3})
    a = trilinear_flow.run([1.5, 0.3], 0.0, 6.0, p, variational=True)
    b = copy.run([1.5, 0.3], 0.0, 6.0, p, variational=True)
    np.testing.assert_array_equal(a.x1, b.x1)
    np.testing.assert_array_equal(a.monodromy, b.monodromy)


def test_integrations_in_threads_equal_serial_ones(trilinear_flow):
    """The engine releases the GIL (its entry points are nogil) and shares no state between calls:
    integrations and Newton solves run in threads give the serial results, to the bit."""
    from concurrent.futures import ThreadPoolExecutor

    from saltation import find_periodic_orbit

    omegas = [0.8, 1.0, 1.2, 1.4]

    def job(w):
        p = trilinear_flow.parameters({"omega": w})
        tr = trilinear_flow.run([1.5, 0.3], 0.0, 12.0, p, variational=True, sensitivity=0)
        orbit = find_periodic_orbit(trilinear_flow, [0.5, 0.5], parameters={"omega": w})
        return np.concatenate([tr.x1, tr.monodromy.ravel(), tr.parameter_sensitivity, orbit.state0])

    serial = [job(w) for w in omegas]
    with ThreadPoolExecutor(2) as pool:
        threaded = list(pool.map(job, omegas))
    for a, b in zip(serial, threaded):
        np.testing.assert_array_equal(a, b)


def test_the_sensitivity_is_asked_for_by_index_or_name(trilinear_flow):
    """``Flow.run(sensitivity=...)`` takes the parameter's index or its name, and gives the same
    ``dx/dp``; the integration of virtual orbits (``disabled``) keeps it too."""
    p = trilinear_flow.parameters({"omega": 1.3})
    k = trilinear_flow.system.parameter_index("omega")
    by_index = trilinear_flow.run([1.5, 0.3], 0.0, 6.0, p, variational=True, sensitivity=k)
    by_name = trilinear_flow.run([1.5, 0.3], 0.0, 6.0, p, variational=True, sensitivity="omega")
    np.testing.assert_array_equal(by_index.parameter_sensitivity, by_name.parameter_sensitivity)
    # a virtual orbit (contact 1 never entered): dx/d omega against central differences (the modes are
    # affine and stepped exactly, so the differences are good to about 1e-9 with h = 1e-5)
    virtual = trilinear_flow.run([1.5, 0.3], 0.0, 6.0, p, variational=True, sensitivity="omega", disabled=[0, 1])
    h, shifted = 1e-5, []
    for sign in (1, -1):
        q = p.copy()
        q[k] += sign * h
        shifted.append(trilinear_flow.run([1.5, 0.3], 0.0, 6.0, q, disabled=[0, 1]).x1)
    np.testing.assert_allclose(virtual.parameter_sensitivity, (shifted[0] - shifted[1]) / (2 * h), rtol=0, atol=1e-7)
    with pytest.raises(Exception, match="unknown parameter"):
        trilinear_flow.run([1.5, 0.3], 0.0, 6.0, p, variational=True, sensitivity="omeg")
