"""Where a subcommand starts: a transient with the shipped model's hints, a period estimate, and the first
point of a branch (a periodic orbit or an equilibrium) with its problem."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

import argparse

from saltation.apps.cli.errors import CommandError
from saltation.apps.cli.options import check_mode0
from saltation.errors import StartGuessError


def transient(flow, name: str, p: np.ndarray, state: np.ndarray | None, *, t0: float, backward: bool,
              mode0: str | None = None):
    """A transient in the direction of integration (:func:`saltation.orbits.start.transient`) from the
    shipped model's start state and with its length, in the mode ``mode0`` (``--mode0``; by default the
    model's domains give it); returns (trajectory, start state).  An autonomous model without a start state
    starts where its transient oscillates (:func:`saltation.orbits.start.oscillating_transient`: the origin,
    then unit states)."""
    import numpy as np

    system = flow.system
    values = dict(zip(system.parameter_names, map(float, p)))
    from saltation.models import SHIPPED
    from saltation.orbits import start as start_guesses

    length_fn = SHIPPED[name].transient_length if name in SHIPPED else None
    length = length_fn(values) if (length_fn and system.is_autonomous) else None
    start = SHIPPED[name].start if name in SHIPPED else None
    if state is None and start is None and system.is_autonomous:
        try:
            traj, _ = start_guesses.oscillating_transient(flow, p, t0=t0, backward=backward, length=length,
                                                          mode0=mode0)
        except StartGuessError as exc:
            raise CommandError(f"{exc}; give a starting guess with --x0 and --period") from None
        return traj, traj.x0
    if state is None:
        state = np.array(start(values, backward) if start else np.zeros(system.n), dtype=float)
    try:
        traj = start_guesses.transient(flow, p, state, t0=t0, backward=backward, length=length, mode0=mode0)
    except StartGuessError as exc:
        raise CommandError(f"{exc}; give a starting guess with --x0") from None
    return traj, state


def estimate_period(traj) -> float:
    """Period estimate from a transient of an autonomous model (:func:`saltation.orbits.start.estimate_period`).

    Raises
    ------
    CommandError
        If the transient shows no oscillation (e.g. it settles to an equilibrium).
    """
    try:
        from saltation.orbits import start as start_guesses

        return start_guesses.estimate_period(traj)
    except StartGuessError as exc:
        raise CommandError(f"{exc}; give --period and a guess --x0") from None


def periodic_start(args: argparse.Namespace, flow, overrides: dict[str, float], p: np.ndarray, x0: np.ndarray | None):
    """The shooting problem over ``--param`` and its first unknowns: a periodic orbit from ``--x0`` (or
    the end of a transient) and ``--period`` (or an estimate), forward or ``--backward``, starting in
    ``--mode0`` where it is given (and then every point of the branch)."""
    import numpy as np

    from saltation.orbits.multiple import MultipleShootingProblem
    from saltation.orbits.single import ShootingProblem
    from saltation.orbits.start import find_periodic_orbit

    system = flow.system
    period = args.period if system.is_autonomous else None  # checked by the caller (check_start_period)
    mode0 = check_mode0(args, system)
    if x0 is None or (system.is_autonomous and period is None):
        traj, _ = transient(flow, args.model, p, x0, t0=0.0, backward=args.backward, mode0=mode0)
        if x0 is None:  # the guess is the transient's end, in the mode it ends in
            x0, mode0 = traj.x1.copy(), None if mode0 is None else traj.mode1
        if system.is_autonomous and period is None:
            period = estimate_period(traj)
    segments = getattr(args, "segments", 1)
    orbit = find_periodic_orbit(flow, x0, parameters=overrides, period=period, backward=args.backward,
                                segments=segments, mode0=mode0)
    # a named start mode is kept along the branch: the orbit's own (its state may have moved off a surface)
    problem = ShootingProblem(flow, overrides, continuation_parameter=args.param, backward=args.backward,
                              mode0=None if mode0 is None else orbit.mode0)
    if segments > 1:  # multiple shooting: the unknowns are the orbit's nodes (and its period)
        nodes = np.asarray(orbit.nodes, dtype=float).ravel()
        return MultipleShootingProblem(problem, segments), (np.append(nodes, orbit.period) if system.is_autonomous
                                                            else nodes)
    return problem, problem.pack(orbit.state0, orbit.period if system.is_autonomous else None)


def equilibrium_start(which: str, flow, overrides: dict, parameter: str, x0, start: float):
    """The problem and first point of an equilibrium branch: ``which`` is a mode (its equilibria) or
    ``sliding:SURFACE`` (pseudo-equilibria), ``x0`` the guess (the origin when None)."""
    import numpy as np

    from saltation.orbits.equilibria import EquilibriumProblem

    guess = x0 if x0 is not None else np.zeros(flow.system.n)
    if which.startswith("sliding:"):
        from saltation.orbits.pseudo_equilibria import (
            PseudoEquilibriumProblem,
            find_pseudo_equilibrium,
        )

        surface = which.partition(":")[2]
        first = find_pseudo_equilibrium(flow, surface, guess, parameters=flow.parameters(overrides))
        problem = PseudoEquilibriumProblem(flow, surface, first.modes, overrides, continuation_parameter=parameter)
        return problem, PseudoEquilibriumProblem.unknowns(first)
    problem = EquilibriumProblem(flow, which, overrides, continuation_parameter=parameter)
    return problem, problem.solve(guess, start).state


def branch_start(args: argparse.Namespace, flow, overrides: dict, p: np.ndarray, x0: np.ndarray | None,
                 start: float):
    """The problem and first unknowns of the branch a command line asks for: of ``--equilibrium``
    (:func:`equilibrium_start`) or of periodic orbits (:func:`periodic_start`), at ``--param`` = ``start``."""

    if args.equilibrium is not None:
        return equilibrium_start(args.equilibrium, flow, overrides, args.param, x0, start)
    return periodic_start(args, flow, overrides, p, x0)
