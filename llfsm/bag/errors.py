"""The one exception of the bag package: what the command line prints as one line."""

from __future__ import annotations


class BagError(Exception):
    """A bag that cannot be written, read or played; the message names the bag and the cause."""
