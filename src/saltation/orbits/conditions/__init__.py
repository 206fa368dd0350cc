"""Special points as one periodic-orbit problem with conditions attached.

A special point of a periodic orbit is the orbit's own problem (periodicity, and for an autonomous
orbit the phase condition: :meth:`saltation.orbits.shooting.ShootingProblem.periodicity`) with extra
equations, each a :class:`Condition`, and as many parameters (or extra unknowns) freed to close the
system.  The COCO ``hspo`` idea: an orbit problem plus zero functions.

Each condition reads one shot's pieces (:class:`Shot`): the state, the fundamental solution matrix and
the parameter sensitivities at the instant it looks at, and returns its value and its exact derivatives
with respect to the unknowns and the parameters (:class:`Rows`).  The shot is split at that instant (the
second piece carries on from the first, :meth:`saltation.engine.flow.Flow.run` with ``phi0``/``psi0``), so
one integration of the period per free parameter gives the whole Jacobian.

The conditions:

* :class:`Tangency`: a grazing.  ``h(t_g, x(t_g)) = 0`` and ``L(t_g, x(t_g)) = h_x f + h_t = 0`` with the
  instant ``t_g`` an unknown, on the virtual orbit that passes the grazed surface (its transitions
  disabled).  A corner of the trilinear kind is the grazing of a contact's entry surface;
* :class:`ArrivalTangency`: crossing- and switching-sliding.  Where the orbit arrives at a surface (an
  event named by identity: its surface, the mode it arrives from and its place among such arrivals),
  the far side's field is tangent, ``L_B(t_e, x_e) = 0``;
* :class:`CubicTangency`: adding-sliding.  At an unknown instant ``tau`` of a sliding motion, the exit
  side's field is tangent with zero rate: ``L_A = 0`` and ``L_A,x f_A + L_A,t = 0``;
* :class:`MultiplierCondition`: a fold (``mu = +1``) or a period doubling (``mu = -1``), minimally
  augmented: the bordered test function of Govaerts (*Numerical Methods for Bifurcations of Dynamical
  Equilibria*, SIAM 2000) vanishes where ``M - mu I`` is singular;
* :class:`NeimarkSackerCondition`: a complex pair ``exp(+-i theta)`` on the unit circle, ``kappa = cos theta``
  an unknown: ``M^2 - 2 kappa M + I`` has a two-dimensional null space, two borders on each side.

:class:`ConditionedProblem` is the augmented problem.  It has the continuation protocol (so a
two-parameter curve is :class:`~saltation.branches.continuation.Continuation` on it) and one Newton
(:meth:`ConditionedProblem.solve`) with one accuracy estimate for every location.

Its modules:

- :mod:`~saltation.orbits.conditions.shot`: what a condition reads (:class:`Shot`, :class:`Piece`,
  :class:`Segments`) and answers (:class:`Rows`), and a solved problem (:class:`Located`);
- :mod:`~saltation.orbits.conditions.base`: the :class:`Condition` protocol and its hooks;
- :mod:`~saltation.orbits.conditions.tangency`: :class:`Tangency` and :class:`ReturnTangency`;
- :mod:`~saltation.orbits.conditions.arrival`: :class:`EventIdentity`, :class:`ArrivalTangency` and
  :class:`CubicTangency` (sliding bifurcations);
- :mod:`~saltation.orbits.conditions.multiplier`: :class:`MultiplierCondition`;
- :mod:`~saltation.orbits.conditions.neimark_sacker`: :class:`NeimarkSackerCondition`;
- :mod:`~saltation.orbits.conditions.conditioned`: :class:`ConditionedProblem`, its layout, shots,
  single-shooting equations and Newton;
- :mod:`~saltation.orbits.conditions.segmented`: its equations under multiple shooting;
- :mod:`~saltation.orbits.conditions.joining`: consecutive trajectories as one (:func:`join`).
"""

from saltation._moved import forward_names
from saltation.orbits.conditions.arrival import (
    ArrivalTangency,
    CubicTangency,
    EventIdentity,
)
from saltation.orbits.conditions.base import Condition
from saltation.orbits.conditions.conditioned import ConditionedProblem
from saltation.orbits.conditions.joining import _joined as _joined
from saltation.orbits.conditions.joining import join
from saltation.orbits.conditions.multiplier import MultiplierCondition
from saltation.orbits.conditions.neimark_sacker import NeimarkSackerCondition
from saltation.orbits.conditions.shot import Located, Piece, Rows, Shot
from saltation.orbits.conditions.tangency import ReturnTangency, Tangency

__all__ = [
    "ArrivalTangency", "Condition", "ConditionedProblem", "CubicTangency", "EventIdentity", "Located",
    "MultiplierCondition", "NeimarkSackerCondition", "Piece", "ReturnTangency", "Rows", "Shot", "Tangency", "join",
]


# names the module held in release 0.1 and no longer imports: found where they live now, until 0.3.0
__getattr__ = forward_names(__name__, ('saltation.orbits.records', 'saltation.orbits.floquet', 'saltation.engine.flow', 'saltation.errors'))
