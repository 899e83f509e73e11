"""Radiosity Baker: diffuse global illumination baked into lightmaps on the GPU.

`core` is bpy-free (numpy + moderngl); `blender` is the only package that
imports bpy.
"""

__version__ = "0.1.0"
