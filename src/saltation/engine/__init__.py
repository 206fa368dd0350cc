"""Layer 2, the engine: a model's compiled functions and the event-driven integrator.

It integrates forward and backward in time, event by event, with the fundamental solution matrix
jumped by the saltation matrix of eq. (9) at every event.  Depends on the model layer only.

Modules:

* :mod:`~saltation.engine.flow`: :class:`~saltation.engine.flow.Flow`, integration and the model's functions.
* :mod:`~saltation.engine.trajectory`: :class:`~saltation.engine.trajectory.Trajectory`, its events, a run's errors.
* :mod:`~saltation.engine.chatter`: complete chatter, impacts that accumulate where the contact sticks, jumped to their limit.
* :mod:`~saltation.engine.kernel_newton`: the engine's Newton on periodic orbits, run from a flow.
* :mod:`~saltation.engine.codegen`: writes a model's functions and the engine, and caches them per machine.
* :mod:`~saltation.engine.precompile`: compiling several models and engines at once, in parallel.
* :mod:`~saltation.engine.buildtime`: how long a first build takes on this machine (the estimate its message gives).
* :mod:`~saltation.engine.affine`: the exact flow of affine modes.
* :mod:`~saltation.engine.compiled`: models given as compiled callables.
* ``saltation.engine._contract``: the layouts and codes shared by the engine, the model functions and Python.
* ``saltation.engine._kernel_source``: the engine's source template (not imported; codegen writes and compiles it).
* ``saltation.engine._atomic``: files written whole or not at all (the cache's modules, memos and records).
* ``saltation.engine._records``: the named records the engine's step-and-event loop takes its settings and arrays in.
"""


def _no_terminal_reset_at_exit() -> None:
    """numba formats its warnings (the first comes from the engine's contract, at import) through colorama,
    whose first use registers a reset of the terminal's colours at exit: ``ESC[0m`` written to standard
    output when Python stops, by a program that printed no colour.  The engine unregisters it once its
    modules are loaded (colorama registers it once per process, so it does not come back)."""
    import atexit
    import sys

    initialise = sys.modules.get("colorama.initialise")
    if initialise is not None and hasattr(initialise, "reset_all"):
        atexit.unregister(initialise.reset_all)
