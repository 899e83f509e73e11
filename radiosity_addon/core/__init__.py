"""Radiosity Baker's core: diffuse global illumination by radiosity on the GPU, without Blender.

This is the public API; the command line, the Blender side and the benchmark use only the
names below. The packages follow the data flow (docs/architecture.md):

    scene -> (visibility, shooting) -> hemicube | progressive -> solve -> lightmap -> preview
    with gpu (contexts, the GL resource owner) and imaging (gutters, downsampling) underneath.

Scenes
------
load_scene(path_or_name, require_emitter=True) -> Scene
    path_or_name   a scene file (JSON, docs/architecture.md › Scene file) or a bundled scene's
                   name ("cornell-box").
    require_emitter  refuse a scene where nothing emits (SceneError).
scene_from_dict(data, require_emitter=True) -> Scene     the same from a parsed dict.
save_scene(scene, path)                                  writes the scene file back.
check_has_emitter(scene)                                 SceneError when nothing emits.
polygon_faults(corners, corner_count) -> masks           the polygon checks every scene passes
                                                         (zero area, not planar, not convex).
surfaces_with_material_maps(gpu, scene, {object: MaterialMap}) -> Scene
                       attaches per-texel albedo and emission (float32 (H, W, 3) each, in the
                       object's lightmap UVs at its lightmap's size) and gives every surface the
                       mean of its texels; a solve then gives every patch the mean of its own.
Scene                  arrays of surfaces (`corners`, `reflectance`, `emission`, `uv`, objects)
                       plus `extras` (lights, world, camera); `scene.surface(i)` is one of them.

Solving
-------
solve(scene, settings=None, progress=None, should_cancel=None, gpu=None, preview=None,
      preview_interval=2.0, timer=None) -> Solution
    scene          the Scene to solve.
    settings       SolveSettings (None: SolveSettings(), the default preset "good", as the
                   command line and the panel; SolveSettings(quality="draft") is the whole draft
                   preset, and any field given overrides the preset's value):
                   method "auto" | "progressive" | "hemicube"; subdiv N (every surface N x N) or, with
                   subdiv None, patch_size (scene units); elements S (S x S per patch,
                   progressive); hemicube_res; solver "gauss-seidel" (default) |
                   "jacobi-gpu" | "jacobi-cpu"; tolerance (None: the method's default); max_iterations;
                   max_shots; visibility, visibility_res, kernel, shoot_from (progressive);
                   memory_limit_bytes (the hemi-cube matrix guard); skip_unneeded (simulate
                   only the effects the scene analysis finds).
    progress       progress(fraction in [0, 1], message, details dict), called as it goes (every
                   stage reports; details["eta"]: the solve's seconds left, details["stage"]).
    should_cancel  should_cancel() -> True stops the solve with SolveCancelled.
    gpu            a GPU to run on (its program cache is reused); None: a context of its own,
                   released afterwards. Every GL object a solve makes is released when it
                   returns or raises.
    preview        preview(Solution) every `preview_interval` seconds of a progressive solve:
                   the radiosity so far plus the ambient term (Cohen et al. 1988), for display
                   only (its report is None); bake_lightmaps turns it into images. The
                   hemi-cube method has no intermediate result and never calls it.
    timer          a StageTimer to time the stages with (None: a new one); a subclass may measure
                   more per stage (the bench's scaling records peak memory).
Solution               patches, patch_radiosity (P, 3), element_radiosity (P, S, S, 3) or None,
                       report (Report: `to_dict()` is the report file, `summary_line()` the
                       panel's one line).

Lightmaps and preview
---------------------
bake_lightmaps(scene, solution, settings=None, gpu=None, objects=None, progress=None) -> {object name: Lightmap}
    settings       LightmapSettings (None: LightmapSettings(), the default preset's; quality= and
                   overrides as SolveSettings): texel_density (texels per scene unit; 0, every
                   preset's: automatic, the preset's texel_budget over the baked area), max_size,
                   resolution_overrides {object: side or (w, h)}, power_of_two, gutter, and
                   content: "light" (default) — the light H arriving, B = E + ρH, shown as
                   emission + albedo x lightmap — or "combined", B itself (per texel from the
                   material map where an object has one).
    objects        names of the objects that get a lightmap (default: all; others only
                   block and reflect light).
Lightmap               levels (RGBA float32 mip chain, alpha = coverage), filled_image() (for
                       renderers that build their own mipmaps), surfaces and their surface_uv.
lightmap_sizes(scene, settings=None, objects=None) -> {object: (width, height)}
chosen_texel_density(scene, settings, objects=None) -> texels per unit   the settings' density, or
                       where it is 0 (automatic) the preset's texel budget over the baked area.
                       the sizes bake_lightmaps will use (e.g. to bake material maps first).
lightmap_seconds(scene, sizes, settings) -> seconds  about how long bake_lightmaps takes for those sizes.
render_preview(scene, lightmaps, camera=None, width=512, height=512, supersample=2, gpu=None)
    -> Preview         the scene from `camera` (default: the scene's own, else one that frames
                       it), lit only by the lightmaps, trilinearly filtered.
save_preview(path, scene, preview, exposure=None) -> exposure   tone-mapped 8-bit PNG.
tone_map(radiance, exposure) -> uint8 sRGB; write_png(path, rgb uint8 (H, W, 3), row 0 at the top).

Building blocks (the benchmark's Table 5.1 and exact references)
-----------------------------------------------------------------
subdivide(scene, subdiv=None, patch_size=0.5) -> Patches     the patches a solve would use.
bilinear(corners, s, t) -> points                            the bilinear map of patch corners.
form_factor_matrix(gpu, patches, resolution, scene_diameter, progress=None, should_cancel=None,
                   rows=None) -> F (P x P float32)            hemi-cube form factors.
solve_linear(gpu, solver, F, reflectance, emission, Convergence(solver, tolerance, cap)) -> B
point_to_polygon(points, normals, polygons) -> (M, N)        exact unoccluded point-to-polygon
                                                             form factors (Lambert's formula).

Errors
------
USER_ERRORS = (SceneError, SolveError, SolveCancelled, GLUnavailable, FileNotFoundError): the
faults a user can cause, each with a one-line message saying what to do.
"""

from .errors import USER_ERRORS, GLUnavailable, SceneError, SolveCancelled, SolveError
from .gpu import GPU, open_gpu
from .hemicube import form_factor_matrix, point_to_polygon, solve_linear
from .hemicube.linear_solvers import Convergence
from .lightmap import Lightmap, bake_lightmaps, chosen_texel_density, lightmap_seconds, lightmap_sizes
from .preview import Camera, Preview, render_preview, save_preview, tone_map, write_png
from .report import Report
from .scene.geometry import bilinear
from .scene import (MAX_REFLECTANCE, FaceNames, MaterialMap, OpacityMaps, Patches, Scene, Surface, bundled_scene_names, check_has_emitter, load_scene, polygon_faults,
                    save_scene, scene_from_dict, subdivide)
from .settings import (CONTENTS, DEFAULT_QUALITY, KERNELS, MAX_LIGHTMAP_SIZE, METHODS, PATCH_SIZE, QUALITIES,
                       QUALITY_PRESETS, SHOOTING_POINTS, SOLVE_METHODS, SOLVERS, TEXEL_DENSITY, VISIBILITY_VARIANTS,
                       LightmapSettings, SolveSettings)
from .solution import Solution
from .solve import solve
from .timing import StageTimer
from .uvspace import surfaces_with_material_maps

__all__ = [
    "CONTENTS", "Camera", "Convergence", "DEFAULT_QUALITY", "FaceNames", "GLUnavailable", "GPU", "KERNELS", "OpacityMaps", "Lightmap", "LightmapSettings", "MAX_REFLECTANCE", "MaterialMap",
    "MAX_LIGHTMAP_SIZE", "METHODS", "PATCH_SIZE", "Patches", "QUALITIES", "QUALITY_PRESETS", "SOLVE_METHODS", "Preview", "Report", "SHOOTING_POINTS", "SOLVERS",
    "Scene", "SceneError", "Solution", "SolveCancelled", "SolveError", "SolveSettings", "StageTimer", "Surface", "TEXEL_DENSITY",
    "USER_ERRORS", "VISIBILITY_VARIANTS", "bake_lightmaps", "bilinear", "bundled_scene_names", "check_has_emitter",
    "form_factor_matrix", "lightmap_seconds", "lightmap_sizes", "chosen_texel_density", "polygon_faults",
    "load_scene", "open_gpu", "point_to_polygon", "render_preview", "save_preview", "save_scene", "tone_map", "write_png",
    "scene_from_dict", "solve", "solve_linear", "subdivide", "surfaces_with_material_maps",
]
