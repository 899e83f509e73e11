"""The benchmark: what accuracy costs in time, with Cycles as the peer (`python -m bench`),
and its furnished rooms with their Cycles reference (`rooms`, `blend_reference`, `compare`).

bpy is imported only by the modules that build, bake or read .blend files (`blend_*`, `cycles`,
`rooms`), lazily where the bpy-free sweep calls them; `compare`, `shapes` and `room_layout` are numpy only.
"""
