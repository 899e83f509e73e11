"""The benchmark: what accuracy costs in time, with Cycles as the peer (`python -m radiosity_addon bench`).

bpy-free except `reference`, which calls `radiosity_addon.blender.cycles_reference` lazily.
"""
