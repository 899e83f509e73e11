"""The hemi-cube method: form factors (hemi-cubes or the analytic kernel), linear solvers."""

from .analytic import point_to_polygon, unoccluded_form_factor_matrix
from .form_factors import check_memory, form_factor_matrix
from .linear_solvers import Convergence, solve_linear
from .method import HemicubeDetails, HemicubeWork, solve_hemicube

__all__ = ["Convergence", "HemicubeDetails", "HemicubeWork", "check_memory", "form_factor_matrix",
           "point_to_polygon", "solve_hemicube", "solve_linear", "unoccluded_form_factor_matrix"]
