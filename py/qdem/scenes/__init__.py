"""qdem.scenes: ready-made scenes built on the public API - the seed paper's
shogi pieces and domino lines (shogi).  The top layer: nothing in qdem
imports it."""
from . import shogi

__all__ = ["shogi"]
