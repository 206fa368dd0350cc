"""Models shipped with saltation, each a short file that reads like its source."""

from .trilinear import trilinear

__all__ = ["trilinear"]
