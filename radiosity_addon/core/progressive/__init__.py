"""Progressive refinement: shooters chosen in batches from the residual mipmaps, the energy ledger, the method."""

from .ledger import EnergyLedger, ambient_term
from .method import ProgressiveDetails, ProgressiveWork, solve_progressive
from .selection import BATCH_POWER_FLOOR, ResidualReader, Residuals

__all__ = ["EnergyLedger", "ProgressiveDetails", "ProgressiveWork", "BATCH_POWER_FLOOR", "ResidualReader", "Residuals",
           "ambient_term", "solve_progressive"]
