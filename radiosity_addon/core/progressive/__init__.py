"""Progressive refinement: shooter selection through residual mipmaps, the energy ledger, the method."""

from .ledger import EnergyLedger, ambient_term
from .method import ProgressiveDetails, ProgressiveWork, solve_progressive
from .selection import SELECTION_DTYPE, Selection, Selector

__all__ = ["EnergyLedger", "ProgressiveDetails", "ProgressiveWork", "SELECTION_DTYPE", "Selection", "Selector",
           "ambient_term", "solve_progressive"]
