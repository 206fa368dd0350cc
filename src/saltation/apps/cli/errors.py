"""The program's name and the two errors of a subcommand, each with its exit status."""

from __future__ import annotations

from saltation.errors import SaltationError

PROG = "saltation"


class UsageError(SaltationError, ValueError):
    """The command line is malformed (exit status 2)."""


class CommandError(SaltationError, RuntimeError):
    """A subcommand could not do its job (exit status 1)."""
