"""Models written as on paper: ``sign``, ``Heaviside``, ``Abs``, ``Min`` and ``Max`` in a vector field
become modes and switching surfaces.

``x'' + c x' + k x + mu sign(x') = 0`` is a Filippov system: the field jumps where ``x'`` changes
sign.  Written with ``sign(v)`` in a mode's field, each argument ``g`` of such a function becomes a
switching surface ``g = 0`` and the mode splits into one mode per sign pattern of its arguments
(``sign(g) = +-1``, ``Heaviside(g) = 1 or 0``, ``Abs(g) = +-g``, ``Min(a, b)`` and ``Max(a, b)`` split
on ``a - b``), each with the domain ``g > 0`` or ``g <= 0`` added.  The sub-modes are joined by
transitions listed both ways, so that the integrator crosses the surface, or slides on it where both
fields push into it (Filippov's convex combination), and every crossing gets its saltation matrix
(eq. 9).  A transition the user wrote out of a split mode is written out of each of its sub-modes;
into a split mode, it enters the sub-mode whose signs hold at the event (guards on the arguments).

Expansion happens inside :class:`saltation.model.system.PiecewiseSystem`; the generated modes, surfaces and
transitions are what the system reports (``system.mode_names``...), and ``system.expansion`` says
where each came from.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import sympy as sp

from saltation.errors import ModelError

#: The functions that are expanded, and how each reads on either side of its surface.
EXPANDED = (sp.sign, sp.Heaviside, sp.Abs, sp.Min, sp.Max)


@dataclass(frozen=True)
class Expansion:
    """Where the modes, surfaces and transitions of an expanded model came from.

    Attributes
    ----------
    surfaces : dict
        Generated surface name -> its indicator (the argument whose sign switches).
    modes : dict
        Generated mode name -> ``(original mode, {surface: +1 or -1})``.
    """

    surfaces: dict[str, sp.Expr]
    modes: dict[str, tuple[str, dict[str, int]]]

    def __bool__(self) -> bool:
        return bool(self.surfaces)

    def describe(self) -> str:
        """A readable account: the surfaces and the modes each original mode became."""
        lines = [f"surface {name!r}: {g} = 0" for name, g in self.surfaces.items()]
        for name, (origin, signs) in self.modes.items():
            where = ", ".join(f"{s} {'> 0' if v > 0 else '<= 0'}" for s, v in signs.items())
            lines.append(f"mode {name!r}: {origin!r} where {where}")
        return "\n".join(lines)


def _switch_argument(f: sp.Basic, where: str = "") -> sp.Expr:
    """The argument whose sign switches a non-smooth function."""
    if isinstance(f, (sp.Min, sp.Max)):
        if len(f.args) != 2:
            raise ModelError(f"{where}: {f}: Min and Max of more than two arguments are not expanded; nest them")
        return f.args[0] - f.args[1]
    if not isinstance(f.args[0], sp.Expr):
        raise ModelError(f"{where}: {f} switches on {f.args[0]}, which is not an expression")
    return f.args[0]


def _on_side(f: sp.Basic, side: int) -> sp.Expr:
    """``f`` where its argument has the sign ``side``."""
    if isinstance(f, sp.sign):
        return sp.Integer(side)
    if isinstance(f, sp.Heaviside):
        return sp.Integer(1 if side > 0 else 0)
    if isinstance(f, sp.Abs):
        return side * f.args[0]
    a, b = f.args
    if isinstance(f, sp.Min):
        return b if side > 0 else a
    return a if side > 0 else b  # Max


def expand_nonsmooth(
    modes: Sequence, surfaces: Mapping, transitions: Sequence, parse, states: set, records: tuple
) -> tuple[list, dict, list, Expansion]:
    """Modes, surfaces and transitions with the non-smooth functions of the fields expanded.

    ``parse(value, where)`` turns a field component into a sympy expression; ``states`` are the state
    symbols (a function whose argument does not depend on them switches nowhere in state space and
    is left for the model's validation); ``records`` are the model's ``(Mode, Transition, Crossing)``
    (passed in, so that this module does not import the one that calls it).  A model without such
    functions comes back unchanged (with an empty :class:`Expansion`).
    """
    Mode, Transition, Crossing = records

    parsed = []
    for m in modes:
        field = m.field
        if isinstance(field, (str, sp.Basic)) or not isinstance(field, Sequence):
            return list(modes), dict(surfaces), list(transitions), Expansion({}, {})  # reported later
        parsed.append([parse(e, f"mode {m.name!r}, field component {i}") for i, e in enumerate(field)])
    switches = _switches(modes, parsed, set(surfaces), states)
    if not switches:
        return list(modes), dict(surfaces), list(transitions), Expansion({}, {})
    new_modes, origin, parts = _split_modes(modes, parsed, switches, Mode)
    new_transitions = _split_transitions(transitions, parts, switches, Transition, Crossing)
    new_surfaces = dict(surfaces) | {name: g for g, name in switches.items()}
    return new_modes, new_surfaces, new_transitions, Expansion({name: g for g, name in switches.items()}, origin)


def _switches(modes: Sequence, parsed: list[list[sp.Expr]], names: set, states: set) -> dict[sp.Expr, str]:
    """The arguments whose signs switch the fields' non-smooth functions, each with the name of its new
    surface (a name not among ``names``); an argument and its negative are one surface."""
    switches: dict[sp.Expr, str] = {}
    for m, field in zip(modes, parsed):
        for i, e in enumerate(field):
            for f in e.atoms(*EXPANDED):
                g = _switch_argument(f, f"mode {m.name!r}, field component {i}")
                if not g.free_symbols & states:
                    continue
                if g.atoms(*EXPANDED):
                    raise ModelError(f"mode {m.name!r}: {f} switches on {g}, itself not smooth; write the modes by hand")
                if g in switches or -g in switches:
                    continue
                name = str(g).replace(" ", "")
                while name in names:
                    name += "_"
                names.add(name)
                switches[g] = name
    return switches


def _argument_of(f: sp.Basic, switches: dict[sp.Expr, str]) -> tuple[sp.Expr, int]:
    """The switching argument of ``f`` as it is named in ``switches``, and the sign that relates them."""
    g = _switch_argument(f)
    return (g, 1) if g in switches else (-g, -1)


def _expanded(f: sp.Basic, switches: dict[sp.Expr, str]) -> bool:
    """Whether ``f`` switches on one of the generated surfaces."""
    g = _switch_argument(f)
    return g in switches or -g in switches


def _split_modes(modes: Sequence, parsed: list[list[sp.Expr]], switches: dict[sp.Expr, str], Mode) -> tuple[list, dict, dict]:
    """Each mode whose field switches, split into one mode per sign pattern of its arguments.

    Returns the modes, where each generated one came from (its mode and the signs), and each mode's
    parts as ``(name, pattern)`` (a mode that does not switch is its own part, with no pattern)."""
    new_modes, origin, parts = [], {}, {}
    for m, field in zip(modes, parsed):
        uses = sorted({_argument_of(f, switches)[0] for e in field for f in e.atoms(*EXPANDED) if _expanded(f, switches)},
                      key=str)
        if not uses:
            new_modes.append(m)
            parts[m.name] = [(m.name, {})]
            continue
        parts[m.name] = []
        for signs in itertools.product((1, -1), repeat=len(uses)):
            pattern = dict(zip(uses, signs))
            label = ",".join(f"{switches[g]}{'+' if s > 0 else '-'}" for g, s in pattern.items())
            name = f"{m.name}[{label}]"

            def side(f, pattern=pattern):
                g, flip = _argument_of(f, switches)
                return _on_side(f, pattern[g] * flip)

            new_field = [e.replace(lambda a: isinstance(a, EXPANDED) and _expanded(a, switches), side) for e in field]
            domain = list(m.domain) + [sp.StrictGreaterThan(g, 0) if s > 0 else sp.LessThan(g, 0)
                                       for g, s in pattern.items()]
            new_modes.append(Mode(name, new_field, domain=domain))
            origin[name] = (m.name, {switches[g]: s for g, s in pattern.items()})
            parts[m.name].append((name, pattern))
    return new_modes, origin, parts


def _split_transitions(transitions: Sequence, parts: dict, switches: dict[sp.Expr, str], Transition, Crossing) -> list:
    """The transitions between the parts of a mode (across each generated surface, both ways), then the
    model's own, from each part of its source to each part of its target that the event can reach."""
    new_transitions = []
    for subs in parts.values():
        for (a, pa), (b, pb) in itertools.combinations(subs, 2):
            differ = [g for g in pa if pa[g] != pb[g]]
            if len(differ) != 1:
                continue
            g = differ[0]
            hi, lo = (a, b) if pa[g] > 0 else (b, a)
            new_transitions.append(Transition(hi, switches[g], Crossing.FALLING, lo))
            new_transitions.append(Transition(lo, switches[g], Crossing.RISING, hi))
    for tr in transitions:
        if not isinstance(tr, Transition) or tr.source not in parts or tr.target not in parts:
            new_transitions.append(tr)  # reported by the model's validation
            continue
        for src, p_src in parts[tr.source]:
            for dst, p_dst in parts[tr.target]:
                if any(g in p_src and p_src[g] != s for g, s in p_dst.items()):
                    continue  # the sign of a shared argument does not change at the event
                extra = [sp.StrictGreaterThan(g, 0) if s > 0 else sp.LessThan(g, 0)
                         for g, s in p_dst.items() if g not in p_src]
                if extra and tr.reset is not None:
                    raise ModelError(f"transition {tr.source} -> {tr.target} has a reset into a mode split on "
                                     f"{[switches[g] for g in p_dst]}: write those modes by hand")
                guard = list(tr.guard) if not isinstance(tr.guard, (str, sp.Basic)) else tr.guard
                if extra and isinstance(guard, list):
                    guard = guard + extra
                new_transitions.append(Transition(src, tr.surface, tr.direction, dst, reset=tr.reset, guard=guard))
    return new_transitions
