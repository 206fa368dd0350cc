"""Smoothing a piecewise-smooth model: the classical regularization the paper warns about.

:func:`regularize` turns a :class:`~saltation.model.system.PiecewiseSystem` into a
smooth one with a single mode.  Every switching is smoothed through the
modes' domains, the same rule that chooses the initial mode (the first mode,
in declaration order, whose conditions all hold):

* a condition ``c > 0`` (or ``c >= 0``) becomes the sigmoid
  ``sigma(c / epsilon) = (1 + tanh(c / epsilon)) / 2``, and a mode's domain
  the product ``s_m`` of its conditions' sigmoids (1 without conditions);
* first match becomes ``W_1 = s_1``, ``W_2 = (1 - s_1) s_2``, ...,
  ``W_m = s_m prod_{l<m} (1 - s_l)``;
* the field is ``f = sum_m W_m f_m``.

The width ``epsilon`` is a parameter of the new model (one compilation serves
every width).  Switching that depends on the mode, not on the state alone
(hysteresis: contact made at one surface and lost at another), becomes the
region of the domains; resets (impacts) have no such smoothing and are refused.

As the paper argues (and ``saltation paper`` shows for the block on a belt), a
smoothed model follows the stable branches, but an infinitely unstable orbit
becomes extremely unstable in the smoothed model, and continuation in forward
time never reaches it: backward-time shooting of the discontinuous model does.
"""

from __future__ import annotations

import sympy as sp

from saltation.errors import ModelError
from saltation.model.system import Mode, PiecewiseSystem


def regularize(system: PiecewiseSystem, epsilon: float, *, name: str | None = None, parameter: str = "epsilon") -> PiecewiseSystem:
    """A smooth, single-mode version of ``system`` with smoothing width ``epsilon``.

    Parameters
    ----------
    system : PiecewiseSystem
        The discontinuous model, without resets.
    epsilon : float
        Default width of the sigmoids (a parameter of the result, named ``parameter``).
    name : str, optional
        Name of the result (default ``<name>_smooth``).
    parameter : str
        Name of the width parameter in the result.

    Returns
    -------
    PiecewiseSystem
        One mode, ``smooth``, with the field ``sum_m W_m f_m``, no surfaces and no transitions; the
        parameters of ``system`` plus ``parameter``, and its forcing period.

    Raises
    ------
    ModelError
        If a transition has a reset, ``epsilon`` is not positive, or ``parameter``
        is already a name of the model.

    References
    ----------
    Sotomayor and Teixeira (1998), "Regularization of discontinuous vector fields", in Magalhaes et al.
    (eds.), *International Conference on Differential Equations* (Equadiff 95, Lisboa 1995), World
    Scientific, 207-223.
    Leine and Van Campen, "Fold bifurcations in discontinuous systems" (on what smoothing loses).
    """
    if not epsilon > 0:
        raise ModelError(f"regularize: epsilon must be positive, got {epsilon!r}")
    for k, g in enumerate(system.resets):
        if g is not None:
            tr = system.transitions[k]
            raise ModelError(
                f"regularize: transition {k} ({tr.label}) has a reset map (an impact); a reset has no smooth "
                "version through the domains: model the contact as compliant instead"
            )
    if parameter in system.parameter_names or parameter in system.state_names or parameter == "t":
        raise ModelError(f"regularize: {parameter!r} is already a name of model {system.name!r}; choose another parameter")
    eps = sp.Symbol(parameter, real=True, positive=True)
    weights = []
    remaining = sp.Integer(1)
    for conditions in system.domains:
        s_m = sp.Integer(1)
        for c in conditions:
            s_m *= (1 + sp.tanh(c.expr / eps)) / 2
        weights.append(remaining * s_m)
        remaining = remaining * (1 - s_m)
    if remaining != 0:
        # states in no domain: the initial-mode rule has no mode there either; their weight goes to the last mode
        weights[-1] = weights[-1] + remaining
    field = [sp.Integer(0)] * system.n
    for w, f in zip(weights, system.fields):
        field = [a + w * b for a, b in zip(field, f)]
    parameters = dict(system.defaults) | {parameter: float(epsilon)}
    return PiecewiseSystem(
        name=name or f"{system.name}_smooth",
        states=list(system.state_names),
        parameters=parameters,
        modes=[Mode("smooth", field)],
        surfaces={},
        transitions=[],
        period=system.period_expr,
    )


__all__ = ["regularize"]
