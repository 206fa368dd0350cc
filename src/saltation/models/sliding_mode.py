"""A second-order plant under sliding-mode (relay) control: a planar autonomous Filippov system.

After the classical example of variable-structure control (Utkin, *Sliding Modes in Control and
Optimization*, Springer 1992; Edwards and Spurgeon, *Sliding Mode Control: Theory and
Applications*, Taylor & Francis 1998): a mass-spring-damper ``y'' + c y' + k y = u`` is
driven by a relay of level ``U`` switched on the line ``s = 0``,

    x1' = x2,    x2' = -k x1 - c x2 + u,    u = -U sgn(s),    s = x2 + lam (x1 - r),

so as to hold the position ``x1`` at the reference ``r``.  Mode ``u_plus`` (``u = +U``) holds where
``s < 0``, mode ``u_minus`` (``u = -U``) where ``s > 0``; ``k < 0`` makes the plant unstable (an
inverted pendulum, linearised).

The rate of ``s`` along a mode's field is ``s' = u - G`` with ``G = k x1 + (c - lam) x2``: both
fields push into the line (Filippov sliding) where ``|G| < U``, with the equivalent control
``u_eq = G``.  On the line ``x2 = -lam (x1 - r)``, so the sliding motion is ``x1' = -lam (x1 - r)``
whatever the plant (the invariance of sliding modes): its rest point, the pseudo-equilibrium, is
``(r, 0)``, with the sliding eigenvalue ``-lam``, the weight ``(U - k r) / (2 U)`` of ``u_minus``'s
field (``u_eq = k r``), and admissible while the relay can hold it: ``|k r| < U``.

The regular equilibria are ``(U / k, 0)`` of ``u_plus``, admissible (in ``s < 0``) for
``r > U / k``, and ``(-U / k, 0)`` of ``u_minus``, admissible for ``r < -U / k`` (``lam > 0``).  At
``r = +-U / k`` one of them reaches the line, on the pseudo-equilibrium (boundary-equilibrium
bifurcations, Kuznetsov, Rinaldi and Gragnani, *One-parameter bifurcations in planar Filippov
systems*, Int. J. Bifurcation and Chaos 13, 2003; di Bernardo, Budd, Champneys and Kowalczyk,
*Piecewise-smooth Dynamical Systems*, Springer 2008, section 5.2).  For ``k > 0`` (a stable plant) the
equilibrium and the pseudo-equilibrium are admissible on opposite sides: it persists as the other
(``persistence``).  For ``k < 0`` the pseudo-equilibrium and both saddles are admissible for
``|r| < U / |k|``: at each end a saddle and the pseudo-node meet and disappear (``nonsmooth_fold``);
beyond, only the other saddle is left, and no rest state attracts.

Defaults (chosen for the gallery, ``k = 3, c = 0.5, U = 1, lam = 2, r = 0.2``): the pseudo-equilibrium
``(0.2, 0)`` is admissible (weight 0.2, sliding eigenvalue -2, on the sliding segment
``-1/15 < x1 < 4/15``); the plant's equilibria ``(+-1/3, 0)``, stable foci with the eigenvalues
``-0.25 +- 1.7139 i``, are virtual; the boundary equilibria lie at ``r = +-1/3``.  With ``k = -1.5``
the saddles ``(-+2/3, 0)`` (eigenvalues 1 and -1.5) meet the pseudo-node at ``r = +-2/3``.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping

from ..model import Crossing, Mode, PiecewiseSystem, Transition
from .shipped import ShippedModel

DEFAULTS = {"k": 3.0, "c": 0.5, "U": 1.0, "lam": 2.0, "r": 0.2}


@functools.lru_cache(maxsize=64)
def sliding_mode(**overrides: float) -> PiecewiseSystem:
    """The sliding-mode controlled plant; keyword arguments override ``k, c, U, lam, r``."""
    return PiecewiseSystem(
        name="sliding_mode",
        states=["x1", "x2"],
        parameters=DEFAULTS | overrides,
        modes=[
            Mode("u_plus", ["x2", "-k*x1 - c*x2 + U"], domain=["x2 + lam*(x1 - r) < 0"]),
            Mode("u_minus", ["x2", "-k*x1 - c*x2 - U"]),
        ],
        surfaces={"s": "x2 + lam*(x1 - r)"},
        transitions=[  # a region-based model: the line listed both ways
            Transition("u_plus", "s", Crossing.RISING, "u_minus"),
            Transition("u_minus", "s", Crossing.FALLING, "u_plus"),
        ],
    )


def _transient_start(p: Mapping[str, float], backward: bool) -> list[float]:
    """Off the switching line (on it, at the reference, the state rests)."""
    return [float(p["r"]) - 1.0, 0.0]


SHIPPED = ShippedModel(
    "sliding_mode",
    sliding_mode,
    "second-order plant under sliding-mode control u = -U sgn(x2 + lam (x1 - r)) (autonomous; pseudo-equilibria)",
    start=_transient_start,
)
