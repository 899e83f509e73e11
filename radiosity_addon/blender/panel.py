"""Render Properties › Radiosity Bake."""

from __future__ import annotations

import textwrap

import bpy

from . import operators, ui_bake

# Blender draws labels on one line and cuts them: long lines are wrapped here, at a width from the
# region's, with a conservative glyph width (the real-Blender tests measure the lines with blf)
GLYPH_WIDTH = 6.5  # pixels per character of the UI font at scale 1 (its average is about 5.7)
LABEL_MARGIN = 50.0  # pixels of the region's width a label cannot use (panel padding, icon)
SEPARATOR = " · "


def fitted(text: str, region_width: float, ui_scale: float = 1.0) -> list[str]:
    """`text` as lines that fit a label in a region this wide: broken at ' · ' where it can be."""
    chars = max(12, int((region_width - LABEL_MARGIN * ui_scale) / (GLYPH_WIDTH * ui_scale)))
    lines: list[str] = []
    for piece in text.split(SEPARATOR):
        if lines and len(lines[-1]) + len(SEPARATOR) + len(piece) <= chars:
            lines[-1] += SEPARATOR + piece
        else:
            lines.extend(textwrap.wrap(piece, chars) or [""])
    return lines


def sentence(text: str) -> str:
    return text[:1].upper() + text[1:]


def draw_lines(layout, context, text: str, icon: str) -> None:
    region = context.region
    width = region.width if region is not None else 300
    column = layout.column(align=True)
    for number, line in enumerate(fitted(text, width, context.preferences.system.ui_scale)):
        column.label(text=line, icon=icon if number == 0 else "BLANK1")


def draw_progress(layout, bake) -> None:
    clock = bake.worker_clock
    if bake.plan is not None and bake.plan.worker.cancelled:
        layout.progress(factor=clock.fraction(), text="Cancelling...")
        return
    layout.progress(factor=clock.fraction(), text=clock.bar_text())
    layout.label(text=sentence(clock.stage_text()), icon="TIME")
    layout.label(text="Esc cancels", icon="CANCEL")


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

        bake = ui_bake.running
        if bake is not None:
            draw_progress(layout, bake)
        else:
            row = layout.row()
            row.scale_y = 1.5
            row.operator("radiosity.bake", text="Bake", icon="RENDER_STILL")
            reason = operators.refusal(context)
            if reason is not None:  # the button is greyed out; say why without a tooltip
                draw_lines(layout, context, sentence(reason), "INFO")

        column = layout.column()
        column.enabled = bake is None
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
        if settings.texel_density == 0:  # the last bake's summary says what it chose
            column.label(text="Texel density: automatic")
        column.prop(settings, "max_resolution")
        column.prop(settings, "uv_margin")
        column.prop(settings, "output")
        obj = context.active_object
        if obj is not None and obj.type == "MESH":
            column.prop(obj.radiosity, "lightmap_resolution", text=f"{obj.name} Resolution")

        layout.operator("radiosity.remove_bake", icon="LOOP_BACK")
        if settings.last_bake:  # what the scene analysis let the last bake skip
            draw_lines(layout, context, settings.last_bake, "INFO")


CLASSES = (RENDER_PT_radiosity_bake,)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
