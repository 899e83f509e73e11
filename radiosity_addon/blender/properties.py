"""Bake settings stored in the .blend: `scene.radiosity` and `object.radiosity`."""

from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty, StringProperty

from ..core import DEFAULT_QUALITY, MAX_LIGHTMAP_SIZE, PATCH_SIZE, TEXEL_DENSITY, LightmapSettings, SolveSettings
from .options import BakeOptions

_DEFAULTS = SolveSettings()  # what the panel starts with: the default preset
_OPTIONS = BakeOptions()

METHOD_ITEMS = [
    ("auto", "Auto", "The method the cost model predicts faster for this scene (the report says why)"),
    ("progressive", "Progressive", "Progressive refinement on the GPU: shoots the brightest patches first"),
    ("hemicube", "Hemi-cube", "The hemi-cube method (the dissertation's original): hemi-cube form factors"
                              " and a linear solve (memory grows with patches squared)"),
]
SOLVER_ITEMS = [
    ("jacobi-gpu", "Jacobi (GPU)", "Jacobi iterations in a compute shader"),
    ("jacobi-cpu", "Jacobi (CPU)", "Jacobi iterations with numpy"),
    ("gauss-seidel", "Gauss-Seidel (CPU)", "Gauss-Seidel iterations with numpy: about half the sweeps of Jacobi"),
]
ELEMENT_ITEMS = [(str(s), f"{s} x {s}", f"{s * s} receiving elements per patch") for s in (1, 2, 4, 8, 16)]
QUALITY_ITEMS = [
    ("draft", "Draft", "Fast: coarse patches, few refinements, a loose tolerance"),
    ("good", "Good", "The default: what the bench found the best trade of error against time"),
    ("final", "Final", "More refinement, elements and visibility resolution, a tight tolerance"),
    ("CUSTOM", "Custom", "Patch size, elements, hemi-cube resolution, solver and tolerance as set below"),
]
CONTENT_ITEMS = [
    ("light", "Light", "The light arriving at each texel: the material shows emission + Base Color x lightmap,"
                       " its textures at full resolution (what game engines multiply by albedo)"),
    ("combined", "Combined", "The outgoing radiance, as Cycles' Combined bake: textures only at the"
                             " lightmap's resolution"),
]
OUTPUT_ITEMS = [
    ("PACK", "Pack into .blend", "Keep the lightmaps inside the .blend file"),
    ("EXR", "EXR next to .blend", "Save <object>_lightmap.exr beside the saved .blend file"),
]


class RadiositySceneSettings(bpy.types.PropertyGroup):
    quality: EnumProperty(name="Quality", items=QUALITY_ITEMS, default=_DEFAULTS.quality,
                          description="What the solver's knobs are set to (each preset's measured error and time:"
                                      " the README's 'What accuracy costs')")
    method: EnumProperty(name="Method", items=METHOD_ITEMS, default=_DEFAULTS.method)
    patch_mode: EnumProperty(name="Patches", default="SIZE", items=[
        ("SIZE", "Patch Size", "Split faces into patches about Patch Size across; smaller faces stay one patch"),
        ("SUBDIVISION", "Subdivision", "Split every face N x N, however big or small"),
    ])
    patch_size: FloatProperty(name="Patch Size", min=0.001, soft_max=10.0, default=PATCH_SIZE, unit="LENGTH",
                              description="Largest patch edge: faces longer than this are split")
    subdivision: IntProperty(name="Subdivision", min=1, soft_max=16, max=64, default=4,
                             description="Each face is split N x N into patches (triangles into N² triangles)")
    elements: EnumProperty(name="Elements", items=ELEMENT_ITEMS, default=str(_DEFAULTS.elements),
                           description="Receiving elements per patch (progressive method)")
    hemicube_resolution: IntProperty(name="Hemi-cube Resolution", min=8, max=1024, step=2,
                                     default=_DEFAULTS.hemicube_res, subtype="PIXEL",
                                     description="Pixels across the hemi-cube's top face (an even number)")
    solver: EnumProperty(name="Solver", items=SOLVER_ITEMS, default=_DEFAULTS.solver,
                         description="Linear solver of the hemi-cube method")
    tolerance: FloatProperty(name="Tolerance", min=0.0, max=0.5, default=0.0, precision=6, step=0.01,
                             description="Stop when the unshot power (progressive) or the change per sweep"
                                         " (hemi-cube) falls under this fraction; 0 uses the method's default")
    texel_density: FloatProperty(name="Texel Density", min=0.0, soft_max=1024.0, default=LightmapSettings().texel_density,
                                 description="Lightmap texels per metre (objects without a resolution override);"
                                             f" 0: automatic, the quality's texel budget over the baked"
                                             f" surfaces, at least {TEXEL_DENSITY:g}")
    max_resolution: IntProperty(name="Max Resolution", min=8, max=8192, default=MAX_LIGHTMAP_SIZE, subtype="PIXEL",
                                description="Largest lightmap side in texels")
    uv_margin: FloatProperty(name="UV Margin", min=0.001, max=1.0, default=_OPTIONS.uv_margin,
                             description="Margin of the Lightmap Pack used for meshes without a 'Lightmap'"
                                         " UV map")
    output: EnumProperty(name="Output", items=OUTPUT_ITEMS, default="PACK")
    content: EnumProperty(name="Lightmap", items=CONTENT_ITEMS, default=LightmapSettings().content,
                          description="What the lightmaps hold")
    last_bake: StringProperty(name="Last Bake", default="",
                              description="What the last bake simulated and skipped (scene analysis)")
    include_unselected: BoolProperty(name="Unselected Occlude", default=_OPTIONS.include_unselected,
                                     description="Visible unselected meshes block and reflect light"
                                                 " (they get no lightmap)")

    def bake_options(self, objects) -> BakeOptions:
        """The panel's settings, and the resolution overrides of `objects`, as a plain object."""
        overrides = {obj.name: obj.radiosity.lightmap_resolution for obj in objects
                     if obj.radiosity.lightmap_resolution > 0}
        quality = DEFAULT_QUALITY if self.quality == "CUSTOM" else self.quality
        if self.quality == "CUSTOM":
            solve = SolveSettings(method=self.method, quality=quality,
                                  subdiv=self.subdivision if self.patch_mode == "SUBDIVISION" else None,
                                  patch_size=self.patch_size, elements=int(self.elements),
                                  hemicube_res=self.hemicube_resolution, solver=self.solver,
                                  tolerance=self.tolerance or None)
        else:
            solve = SolveSettings.preset(quality, method=self.method)
        lightmaps = LightmapSettings.preset(quality, texel_density=self.texel_density, max_size=self.max_resolution,
                                            resolution_overrides=overrides, content=self.content)
        return BakeOptions(solve=solve, lightmaps=lightmaps, output=self.output,
                           include_unselected=self.include_unselected, uv_margin=self.uv_margin)


class RadiosityObjectSettings(bpy.types.PropertyGroup):
    lightmap_resolution: IntProperty(name="Lightmap Resolution", min=0, max=8192, default=0, subtype="PIXEL",
                                     description="Side of this object's lightmap in texels; 0 follows the"
                                                 " scene's texel density")


CLASSES = (RadiositySceneSettings, RadiosityObjectSettings)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.radiosity = PointerProperty(type=RadiositySceneSettings)
    bpy.types.Object.radiosity = PointerProperty(type=RadiosityObjectSettings)


def unregister():
    del bpy.types.Object.radiosity
    del bpy.types.Scene.radiosity
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
