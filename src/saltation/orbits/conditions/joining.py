"""Consecutive trajectories as one: the segments of a multiple shot, the two pieces of a split shot."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from saltation.engine.flow import Trajectory


def join(segs: Sequence[Trajectory]) -> Trajectory:
    """One trajectory from consecutive segments.

    Their events in order, the product of their transfer matrices as its monodromy (assembled: its
    eigenvalues are not the multipliers' best values).

    Parameters
    ----------
    segs : sequence of Trajectory
        Consecutive segments, with their transfer matrices.

    Returns
    -------
    Trajectory
        From the first segment's start to the last one's end, without parameter sensitivity or dense
        output.

    Raises
    ------
    IndexError
        If ``segs`` is empty.
    """
    first, last = segs[0], segs[-1]
    logs = [seg.event_log for seg in segs]
    event_log = tuple(np.concatenate([log[k] for log in logs]) for k in range(len(first.event_log)))
    M = first.monodromy
    for seg in segs[1:]:
        M = seg.monodromy @ M
    return replace(
        first, t1=last.t1, x1=last.x1, mode1=last.mode1, event_log=event_log, monodromy=M,
        parameter_sensitivity=None, x_min=np.min([s.x_min for s in segs], axis=0),
        x_max=np.max([s.x_max for s in segs], axis=0), sliding_at_end=last.sliding_at_end,
        velocity_end=last.velocity_end, n_steps=sum(s.n_steps for s in segs),
        n_rejected=sum(s.n_rejected for s in segs), _steps=None,
    )


def _joined(a: Trajectory, b: Trajectory) -> Trajectory:
    """Two consecutive pieces as one trajectory: ``b`` carried on from ``a`` (its matrices include ``a``'s)."""

    event_log = tuple(np.concatenate([x, y]) for x, y in zip(a.event_log, b.event_log))
    return replace(b, t0=a.t0, x0=a.x0, mode0=a.mode0, event_log=event_log, x_min=np.minimum(a.x_min, b.x_min),
                   x_max=np.maximum(a.x_max, b.x_max), n_steps=a.n_steps + b.n_steps,
                   n_rejected=a.n_rejected + b.n_rejected, _steps=None)


__all__ = ["join"]
