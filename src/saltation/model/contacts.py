"""Contacts that stick: a plastic impact continued as a motion constrained to the moving surface.

A ball that lands on a vibrating table with no rebound (restitution ``e = 0``) does not leave it at
once: it moves with the table, held by the contact force, until that force changes sign, where the
table's deceleration reaches ``g``.  Declared by one flag on the impact, ``Transition(...,
sticks=True)``, the model gets, for that impact from mode ``S`` to mode ``T`` on surface ``h``:

* a mode ``T@h`` (*stuck*), whose field is ``T``'s field with the contact force added along the
  contact direction ``b``: ``f_c = f + lambda b``, ``lambda`` the force that keeps the relative
  acceleration zero, ``L^2 h = (Lh)_x (f + lambda b) + (Lh)_t = 0`` with ``Lh = h_x f + h_t`` the
  relative velocity.  ``b`` is the state the reset changes (the velocity of an impact), or given
  (``sticks=[b_1, ..., b_n]``);
* a surface ``h@release``: the contact force ``N = -sigma ((Lh)_x f + (Lh)_t)`` (``sigma = +1`` for an
  impact where ``h`` falls, the motion kept on ``h >= 0``; ``-1`` where it rises); the contact holds
  while ``N > 0``;
* the impact into ``T@h`` where it leaves no relative velocity and the force holds it (guards on the
  state after the reset: ``N > 0`` and ``|Lh| <= 1e-9 (1 + |x|)``, :data:`ON_SURFACE`), the impact as
  written where it does not and the state arrives at a relative velocity (one that reaches the surface
  at none, as where the contact releases it, touches it and goes on); and the release ``T@h -> T``
  where ``N`` falls through zero, with no reset.  ``T``'s other transitions leave ``T@h`` as well.
  The initial mode of a state on the surface at no relative velocity where the force holds it (to the
  same resolution) is ``T@h``.

Both are ordinary transitions, so eq. (9) gives their saltation matrices: the landing's is singular
(the reset forgets the velocity: a multiplier 0), the release's is the identity (``f_c = f`` where
``lambda = 0``).  A restitution ``e > 0`` ends in the same sticking phase after infinitely many impacts
of decreasing height (complete chatter): the integrator jumps to their accumulation point and goes on
in ``T@h`` (:mod:`saltation.engine.chatter`; :func:`sticking_twins` pairs each impact with the transition
into its stuck mode).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import sympy as sp

from saltation.errors import ModelError

__all__ = ["ON_SURFACE", "Sticking", "expand_sticking", "sticking_twins"]

#: a state within this distance of a sticking surface (relative to ``1 + |x|``), at a relative velocity as small, is
#: on the surface: the stuck mode is its initial mode
ON_SURFACE = 1e-9


@dataclass(frozen=True)
class Sticking:
    """What one ``sticks=True`` impact added to the model.

    Attributes
    ----------
    mode : str
        The stuck mode, ``"<target>@<surface>"``.
    release : str
        The surface where the contact force vanishes, ``"<surface>@release"``.
    force : sympy expression
        The contact force ``N(t, x)`` (per unit of the contact direction), positive while the contact holds.
    direction : tuple of sympy expressions
        The contact direction ``b``.
    """

    mode: str
    release: str
    force: sp.Expr
    direction: tuple[sp.Expr, ...]


def expand_sticking(modes: Sequence, surfaces: dict, transitions: Sequence, parse, x: Sequence[sp.Symbol],
                    t: sp.Symbol, records: tuple) -> tuple[list, dict, list, dict[str, Sticking]]:
    """Modes, surfaces and transitions with each ``sticks=True`` impact expanded (see the module's text).

    Parameters
    ----------
    modes, surfaces, transitions
        As given to :class:`saltation.model.system.PiecewiseSystem`.
    parse : callable
        ``parse(value, where)``: a sympy expression of an expression the user wrote.
    x : sequence of sympy symbols
        The states.
    t : sympy symbol
        Time.
    records : tuple
        The model's ``(Mode, Transition, Crossing)`` (passed in, so that this module does not import the one
        that calls it).

    Returns
    -------
    tuple
        The modes, surfaces and transitions with the stuck modes, release surfaces and their transitions
        added, and ``{stuck mode: Sticking}``.  A model without ``sticks=True`` comes back unchanged.

    Raises
    ------
    ModelError
        A sticking impact without a reset, with a direction ``EITHER``, onto a surface that does not exist,
        whose contact direction is not determined or cannot hold the state on the surface.
    """
    Mode, Transition, Crossing = records
    if not isinstance(transitions, Sequence) or not any(getattr(tr, "sticks", False) is not False
                                                        for tr in transitions):
        return list(modes), dict(surfaces), list(transitions), {}
    by_name = {m.name: m for m in modes if isinstance(m, Mode)}
    x = list(x)
    new_surfaces, new_transitions, added, stuck_modes = dict(surfaces), [], {}, []
    for k, tr in enumerate(transitions):
        if not isinstance(tr, Transition) or tr.sticks is False:
            new_transitions.append(tr)
            continue
        where = f"transition {k} ({tr.source} -> {tr.target}, sticks)"
        sticking, stuck, release = _sticking(tr, where, by_name, surfaces, parse, x, t, (Mode, Transition, Crossing))
        name = sticking.mode
        if name not in by_name:
            by_name[name] = stuck
            stuck_modes.append(stuck)
            if sticking.force.free_symbols & {*x, t}:  # (a constant force never changes sign: no release)
                new_surfaces[sticking.release] = sticking.force
                new_transitions.append(release)
            for other in transitions:  # the target's other ways out leave the stuck motion too
                if isinstance(other, Transition) and other.source == tr.target and other.surface != tr.surface:
                    new_transitions.append(Transition(name, other.surface, other.direction, other.target,
                                                      reset=other.reset, guard=other.guard))
            added[name] = sticking
        g = [parse(e, f"{where} reset component {i}") for i, e in enumerate(tr.reset)]
        after = dict(zip(x, g))
        speed = _relative_speed(by_name[tr.target], surfaces[tr.surface], parse, x, t, where)
        force_after = sticking.force.xreplace(after)
        resolution = ON_SURFACE**2 * (1 + sum((xi**2 for xi in x), sp.Integer(0)))
        left = resolution - sp.expand(speed.xreplace(after)) ** 2  # >= 0: no relative velocity after the reset
        sticks = _guard(tr.guard, sp.StrictGreaterThan(force_after, 0), sp.GreaterThan(left, 0))
        if sticks is not None:
            new_transitions.append(Transition(tr.source, tr.surface, tr.direction, name, reset=tr.reset, guard=sticks))
        # the impact as written where it does not stick, and only at a relative velocity (a state that reaches
        # the surface at none, as where the contact releases it, touches it and goes on)
        bounces = _guard(tr.guard, sp.StrictLessThan(sp.Min(force_after, left), 0),
                         sp.StrictGreaterThan(speed**2 - resolution, 0))
        if bounces is not None:
            new_transitions.append(Transition(tr.source, tr.surface, tr.direction, tr.target, reset=tr.reset,
                                              guard=bounces))
    new_modes = [by_name[m.name] if isinstance(m, Mode) else m for m in modes] + stuck_modes
    return new_modes, new_surfaces, new_transitions, added


def sticking_twins(system) -> dict[int, int]:
    """The impacts that can stick, each with its sticking twin: ``{impact: twin}``.

    The twin of an impact from mode ``S`` to mode ``T`` on surface ``h`` is the transition from ``S`` on ``h``,
    in the same direction, into the stuck mode ``T@h`` that ``sticks=True`` added; the impact's repetitions
    may accumulate into it (complete chatter, :mod:`saltation.engine.chatter`).

    Parameters
    ----------
    system : PiecewiseSystem
        The model (one without ``sticking``, such as compiled callables, has none).

    Returns
    -------
    dict of int to int
        Indices of the transitions.
    """
    stuck = getattr(system, "sticking", None) or {}
    if not stuck:
        return {}
    transitions = system.transitions
    twins = {}
    for k, tr in enumerate(transitions):
        name = f"{tr.target}@{tr.surface}"
        if system.resets[k] is None or tr.target in stuck or name not in stuck:
            continue
        for j, other in enumerate(transitions):
            if (other.source == tr.source and other.surface == tr.surface and other.target == name
                    and int(other.direction) == int(tr.direction)):
                twins[k] = j
                break
    return twins


def _relative_speed(mode, indicator, parse, x, t, where: str) -> sp.Expr:
    """``Lh = h_x f + h_t`` along ``mode``'s field."""
    h = parse(indicator, f"{where}: its surface")
    f = [parse(e, f"{where}: mode {mode.name!r} field component {i}") for i, e in enumerate(mode.field)]
    return sp.expand(sum((sp.diff(h, xi) * fi for xi, fi in zip(x, f)), sp.diff(h, t)))


def _sticking(tr, where: str, by_name: dict, surfaces: dict, parse, x: list, t: sp.Symbol, records: tuple):
    """The :class:`Sticking` of one impact, its stuck mode and its release transition."""
    Mode, Transition, Crossing = records
    if tr.reset is None:
        raise ModelError(f"{where}: sticks=True needs an impact: a reset that takes the relative velocity away")
    if int(tr.direction) == 0:
        raise ModelError(f"{where}: sticks=True needs the side the contact keeps: a direction RISING or FALLING, "
                         "not EITHER")
    if tr.surface not in surfaces:
        raise ModelError(f"{where}: surface {tr.surface!r} does not exist; surfaces are {list(surfaces)}")
    if tr.target not in by_name:
        raise ModelError(f"{where}: target mode {tr.target!r} does not exist; modes are {list(by_name)}")
    target = by_name[tr.target]
    if isinstance(target.field, (str, sp.Basic)) or len(target.field) != len(x):
        raise ModelError(f"{where}: mode {tr.target!r} needs a field of {len(x)} components")
    f = [parse(e, f"mode {target.name!r}, field component {i}") for i, e in enumerate(target.field)]
    g = [parse(e, f"{where} reset component {i}") for i, e in enumerate(tr.reset)]
    b = _direction(tr, g, x, parse, where)
    speed = _relative_speed(target, surfaces[tr.surface], parse, x, t, where)
    speed_x = [sp.diff(speed, xi) for xi in x]
    free = sp.expand(sum((a * fi for a, fi in zip(speed_x, f)), sp.diff(speed, t)))  # L^2 h, free motion
    along = sp.simplify(sum((a * bi for a, bi in zip(speed_x, b)), sp.Integer(0)))
    if along == 0:
        raise ModelError(f"{where}: a force along {list(b)} does not change the relative velocity "
                         f"{speed} on surface {tr.surface!r}: it cannot hold the state there")
    lam = -free / along
    stuck_field = [sp.simplify(fi + lam * bi) for fi, bi in zip(f, b)]
    side = 1 if int(tr.direction) < 0 else -1  # a falling impact keeps h >= 0
    force = sp.simplify(-side * free)
    name = f"{tr.target}@{tr.surface}"
    release = f"{tr.surface}@release"
    # where the motion is stuck: on the surface, at no relative velocity, held (to the resolution ON_SURFACE
    # relative to the state's size), the initial mode of a state there; the free mode's domain leaves it out
    scale = ON_SURFACE**2 * (1 + sum((xi**2 for xi in x), sp.Integer(0)))
    h = parse(surfaces[tr.surface], f"{where}: its surface")
    off = (h**2 - scale, speed**2 - scale, -force)
    on_surface = _guard((), sp.GreaterThan(-off[0], 0), sp.GreaterThan(-off[1], 0), sp.StrictGreaterThan(force, 0))
    if on_surface is None:
        raise ModelError(f"{where}: the contact force {force} never holds the state on surface {tr.surface!r}")
    stuck = Mode(name, stuck_field, domain=on_surface)
    by_name[tr.target] = Mode(target.name, target.field,
                              domain=_guard(target.domain, sp.StrictGreaterThan(sp.Max(*off), 0)) or ())
    from_stuck = Transition(name, release, Crossing.FALLING, tr.target)
    return Sticking(name, release, force, tuple(b)), stuck, from_stuck


def _guard(given, *added) -> tuple | None:
    """A transition's guard with conditions added; the ones sympy finds always true left out, and None where
    one is always false (the transition never fires)."""
    kept = []
    for c in added:
        if c is sp.true:
            continue
        if c is sp.false:
            return None
        kept.append(c)
    return (*_conditions(given), *kept)


def _conditions(domain) -> tuple:
    """A mode's domain as a tuple (a single condition given as a string is refused later, by the model)."""
    return tuple(domain) if isinstance(domain, Sequence) and not isinstance(domain, str) else (domain,)


def _direction(tr, g: list, x: list, parse, where: str) -> list[sp.Expr]:
    """The contact direction: given, or the one state the reset changes."""
    if tr.sticks is not True:
        given = tr.sticks
        if isinstance(given, (str, sp.Basic)) or not isinstance(given, Sequence) or len(given) != len(x):
            raise ModelError(f"{where}: sticks is True or the contact direction, one expression per state "
                             f"({len(x)}), got {given!r}")
        return [parse(e, f"{where} contact direction component {i}") for i, e in enumerate(given)]
    changed = [i for i, (gi, xi) in enumerate(zip(g, x)) if sp.simplify(gi - xi) != 0]
    if len(changed) != 1:
        raise ModelError(f"{where}: the reset changes {len(changed)} states, so the direction of the contact force "
                         "is not determined; give it: sticks=[b_1, ..., b_n], one expression per state")
    return [sp.Integer(1 if i == changed[0] else 0) for i in range(len(x))]
