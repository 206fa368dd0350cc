"""Progress bars of the library's long computations, and their off switch.

A first build of the integrator (:mod:`saltation.engine.codegen`) shows a tqdm bar on standard error where that
is a terminal or a notebook (tqdm leaves it out elsewhere).  ``SALTATION_PROGRESS=0`` in the environment, or
:func:`set_enabled` ``(False)``, turns every bar of the library off; tqdm's ``TQDM_DISABLE=1`` does too.  What
the bars show is also logged (:mod:`logging`, see the user guide's *Logging and progress*).
"""

from __future__ import annotations

import os

__all__ = ["ENVIRONMENT_VARIABLE", "bar", "enabled", "set_enabled"]

#: The environment variable whose value ``0``, ``false``, ``no`` or ``off`` turns the bars off.
ENVIRONMENT_VARIABLE = "SALTATION_PROGRESS"

_CHOICE: list[bool | None] = [None]  # set_enabled's choice; None: the environment's


def enabled() -> bool:
    """Whether the library may draw progress bars: :func:`set_enabled`'s choice, else the environment's.

    Returns
    -------
    bool
    """
    if _CHOICE[0] is not None:
        return _CHOICE[0]
    return os.environ.get(ENVIRONMENT_VARIABLE, "").strip().lower() not in ("0", "false", "no", "off")


def set_enabled(on: bool | None) -> None:
    """Turn the library's progress bars on or off for this process (None: as the environment says).

    Parameters
    ----------
    on : bool or None
        The choice.
    """
    _CHOICE[0] = None if on is None else bool(on)


def bar(description: str, total: float | None):
    """A tqdm bar on standard error that counts seconds (``total`` the estimate, or None), or None where the
    bars are off.  tqdm draws nothing where standard error is neither a terminal nor a notebook.

    Parameters
    ----------
    description : str
        What it counts.
    total : float or None
        The expected number of seconds.

    Returns
    -------
    tqdm.tqdm or None
        Advance it with ``update(seconds)``; ``close()`` it at the end.
    """
    if not enabled():
        return None
    import sys

    from tqdm.auto import tqdm

    return tqdm(total=total, desc=description, unit="s", file=sys.stderr, disable=None, leave=False,
                bar_format="{desc}: {bar} {n:.0f}/{total:.0f} s" if total else "{desc}: {n:.0f} s")
