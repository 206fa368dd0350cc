"""A chain of masses with the trilinear contact on its last mass: a scalable benchmark.

``n`` equal masses ``m`` in a row, joined by springs ``k`` and dampers ``c``;
the first is tied to a wall by the same spring and damper and forced by
``f0 sin(omega t)``, the last carries the two supports of the trilinear spring
system at ``+-x_c`` (stiffness ``k_f``, damping ``c_f``).  The contact regions
and transitions are those of :func:`saltation.models.trilinear` with ``x, v``
replaced by the last mass's ``x_n, v_n``, so there are three modes for any
``n``; with ``n = 1`` the model *is* the trilinear system::

    m x_i'' = -k (x_i - x_{i-1}) - c (v_i - v_{i-1})
              - k (x_i - x_{i+1}) - c (v_i - v_{i+1})   (x_0 = 0, no x_{n+1} term)
              + [i = 1] f0 sin(omega t) - [i = n, in contact] (k_f (x_n -+ x_c) + c_f v_n)

The states are ``x1, ..., xn, v1, ..., vn``.  Each ``n`` is its own model
(named ``chain{n}``) with its own compiled kernels.
"""

from __future__ import annotations

import functools

from ..model import Crossing, Mode, PiecewiseSystem, Transition
from .trilinear import DEFAULTS

RISING, FALLING = Crossing.RISING, Crossing.FALLING


@functools.lru_cache(maxsize=64)  # a model is immutable: building it again (sympy) is wasted
def chain(n: int = 2, **overrides: float) -> PiecewiseSystem:
    """A chain of ``n`` masses with trilinear contacts on the last; keyword arguments override Appendix A's values."""
    if not isinstance(n, int) or isinstance(n, bool) or n < 1:
        raise ValueError(f"the chain needs a positive integer number of masses, got n={n!r}")
    params = DEFAULTS | overrides
    xs = [f"x{i}" for i in range(1, n + 1)]
    vs = [f"v{i}" for i in range(1, n + 1)]

    def internal(i: int) -> str:
        """Spring, damper and forcing forces on mass ``i`` (0-based), without the contact."""
        if i == 0:
            force = f"-k*{xs[0]} - c*{vs[0]} + f0*sin(omega*t)"  # the wall and the forcing
        else:
            force = f"-k*({xs[i]} - {xs[i - 1]}) - c*({vs[i]} - {vs[i - 1]})"
        if i < n - 1:
            force += f" - k*({xs[i]} - {xs[i + 1]}) - c*({vs[i]} - {vs[i + 1]})"
        return force

    def field(support: str | None) -> list[str]:
        """The vector field, with the support force ``support`` pushing back on the last mass."""
        acc = []
        for i in range(n):
            force = internal(i)
            if i == n - 1 and support is not None:
                force += f" - ({support})"
            acc.append(f"({force})/m")
        return vs + acc

    x, v = xs[-1], vs[-1]
    return PiecewiseSystem(
        name=f"chain{n}",
        states=xs + vs,
        parameters=params,
        modes=[
            # V+1: x_n > x_c and k_f (x_n - x_c) + c_f x_n' >= 0
            Mode("contact_1", field(f"k_f*({x} - x_c) + c_f*{v}"),
                 domain=[f"{x} - x_c > 0", f"k_f*({x} - x_c) + c_f*{v} >= 0"]),
            # V+2: x_n < -x_c and k_f (x_n + x_c) + c_f x_n' <= 0
            Mode("contact_2", field(f"k_f*({x} + x_c) + c_f*{v}"),
                 domain=[f"{x} + x_c < 0", f"k_f*({x} + x_c) + c_f*{v} <= 0"]),
            Mode("free", field(None)),
        ],
        surfaces={
            "h1a": f"{x} - x_c",
            "h1b": f"k_f*({x} - x_c) + c_f*{v}",
            "h2a": f"{x} + x_c",
            "h2b": f"k_f*({x} + x_c) + c_f*{v}",
        },
        transitions=[
            Transition("free", "h1a", RISING, "contact_1", guard=[f"k_f*({x} - x_c) + c_f*{v} >= 0"]),
            Transition("free", "h1b", RISING, "contact_1", guard=[f"{x} - x_c > 0"]),
            Transition("contact_1", "h1b", FALLING, "free"),
            Transition("contact_1", "h1a", FALLING, "free"),
            Transition("free", "h2a", FALLING, "contact_2", guard=[f"k_f*({x} + x_c) + c_f*{v} <= 0"]),
            Transition("free", "h2b", FALLING, "contact_2", guard=[f"{x} + x_c < 0"]),
            Transition("contact_2", "h2b", RISING, "free"),
            Transition("contact_2", "h2a", RISING, "free"),
        ],
        period="2*pi/omega",
    )
