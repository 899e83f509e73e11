# Blender extension entry point (radiosity_baker).
#
# This file sits beside blender_manifest.toml at the repository root, so pytest
# and `python -m radiosity_addon` may import it as a package: it must import
# nothing at module level. Blender calls register()/unregister(), which load
# the add-on lazily.


def register():
    from .radiosity_addon import blender

    blender.register()


def unregister():
    from .radiosity_addon import blender

    blender.unregister()
