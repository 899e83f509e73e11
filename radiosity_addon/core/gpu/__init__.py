"""OpenGL for the core: contexts, the resource owner and program cache, shaders and bindings."""

from .bindings import FORM_FACTOR_ONE, SHOT_ENERGY_ONE, image_unit, storage, texture_unit, uniform_block
from .context import MAX_WORK_GROUPS, REQUIRED_GL, create_context, work_groups
from .resources import GPU, Resources, open_gpu, render, render_indirect

__all__ = ["FORM_FACTOR_ONE", "GPU", "MAX_WORK_GROUPS", "SHOT_ENERGY_ONE", "REQUIRED_GL", "Resources", "create_context", "image_unit", "open_gpu", "render", "render_indirect",
           "storage", "texture_unit", "uniform_block", "work_groups"]
