"""The Blender side of Radiosity Baker: the only package that imports bpy.

properties (scene.radiosity, object.radiosity) -> panel (Render Properties ›
Radiosity Bake) -> operators (bake, remove bake) -> bake (transaction) ->
export / worker (solve on its own thread) / apply (images, material wiring).
"""

from . import operators, panel, properties

MODULES = (properties, operators, panel)


def register():
    for module in MODULES:
        module.register()


def unregister():
    for module in reversed(MODULES):
        module.unregister()
