"""Render Properties › Radiosity Bake."""

from __future__ import annotations

import bpy

from . import operators


class RENDER_PT_radiosity_bake(bpy.types.Panel):
    bl_label = "Radiosity Bake"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        settings = context.scene.radiosity

        plan = operators.running
        if plan is not None:
            progress = plan.worker.snapshot()
            layout.progress(factor=progress.fraction, text=f"{100 * progress.fraction:.0f}% {progress.message}")
            layout.label(text="Esc cancels", icon="CANCEL")
        else:
            row = layout.row()
            row.scale_y = 1.5
            row.operator("radiosity.bake", text="Bake", icon="RENDER_STILL")

        column = layout.column()
        column.enabled = plan is None
        column.prop(settings, "quality")
        column.prop(settings, "method")
        if settings.quality == "CUSTOM":  # the presets set these knobs themselves
            column.prop(settings, "patch_mode")
            column.prop(settings, "patch_size" if settings.patch_mode == "SIZE" else "subdivision")
            if settings.method != "hemicube":
                column.prop(settings, "elements")
            if settings.method != "progressive":
                column.prop(settings, "hemicube_resolution")
                column.prop(settings, "solver")
            column.prop(settings, "tolerance")
        column.prop(settings, "include_unselected")

        column.separator()
        column.prop(settings, "content")
        column.prop(settings, "texel_density")
        column.prop(settings, "max_resolution")
        column.prop(settings, "uv_margin")
        column.prop(settings, "output")
        obj = context.active_object
        if obj is not None and obj.type == "MESH":
            column.prop(obj.radiosity, "lightmap_resolution", text=f"{obj.name} Resolution")

        layout.operator("radiosity.remove_bake", icon="LOOP_BACK")
        if settings.last_bake:  # what the scene analysis let the last bake skip
            layout.label(text=settings.last_bake, icon="INFO")


CLASSES = (RENDER_PT_radiosity_bake,)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
