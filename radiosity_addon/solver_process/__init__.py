"""The solve in a process of its own (bpy-free), so a bake can never freeze or crash Blender.

The Blender side (`blender/worker.py`) writes a job folder (`protocol.write_job`) and starts
`child.main` in Blender's own Python with the extension's path and its own `sys.path`. The child
solves, lays out the lightmaps and writes them as files; it talks through a private copy of its
stdout (JSON lines: progress, previews, the result or the error) and ends when its stdin closes.
A cancel kills it.
"""
