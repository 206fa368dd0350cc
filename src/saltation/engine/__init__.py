"""Layer 2, the engine: a model's compiled functions and the event-driven integrator.

:mod:`~saltation.engine.codegen` writes a model's functions and the engine (from the template
``_kernel_source.py``, with the layouts of ``_contract.py``) and caches them per machine;
:mod:`~saltation.engine.flow` (:class:`~saltation.engine.flow.Flow`) integrates forward and backward
in time, event by event, with the fundamental solution matrix jumped by the saltation matrix of
eq. (9) at every event; :mod:`~saltation.engine.affine` (the exact flow of affine modes),
:mod:`~saltation.engine.compiled` (models given as compiled callables) and
:mod:`~saltation.engine.precompile` (compiling several at once).  Depends on the model layer only.
"""
