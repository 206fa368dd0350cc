"""Consecutive trajectories as one: the segments of a multiple shot, the two pieces of a split shot."""

from saltation.engine.trajectory import continued as _joined  # noqa: F401  (the name its callers use)
from saltation.engine.trajectory import join

__all__ = ["join"]
