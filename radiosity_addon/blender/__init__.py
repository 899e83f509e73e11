"""The Blender side of Radiosity Baker: the only package that imports bpy.

properties (scene.radiosity, object.radiosity) -> panel (Render Properties ›
Radiosity Bake) -> operators (bake, remove bake) -> ui_bake (the modal bake's life and every way
it ends) -> bake (transaction) -> export / worker (the solve in a child process, see
radiosity_addon/solver_process) / live_preview / apply (images, material wiring).
"""

from . import operators, panel, properties

MODULES = (properties, operators, panel)


def register():
    for module in MODULES:
        module.register()


def unregister():
    for module in reversed(MODULES):
        module.unregister()
