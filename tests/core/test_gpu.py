"""The GPU layer: every GL object a solve, a lightmap bake or a preview makes is released on
success, on cancel and on a failure in any stage (moderngl's `context_gc` mode collects what
was dropped unreleased); programs are compiled once per context; bindings are named once."""

from __future__ import annotations

import gc
import re
from dataclasses import replace

import moderngl
import numpy as np
import pytest
from scenes import closed_cube, lightmap_settings, solve_settings, surface

from radiosity_addon.core import (GPU, SolveCancelled, bake_lightmaps, load_scene,
                                  render_preview, scene_from_dict, solve)
from radiosity_addon.core.gpu import bindings
from radiosity_addon.core.gpu.resources import MAX_SPARE_BYTES
from radiosity_addon.core.gpu.shaders import SHADERS_DIR

pytestmark = pytest.mark.gl  # covers every shader and pass: run again on zink (make test-zink)


class Injected(RuntimeError):
    """The failure these tests inject."""


@pytest.fixture
def watched():
    """A GPU on a fresh context in `context_gc` mode: objects dropped without release() land in
    ctx.objects (released ones leave an InvalidObject there)."""
    ctx = moderngl.create_context(standalone=True, backend="egl", require=430)
    ctx.gc_mode = "context_gc"
    gpu = GPU(ctx)
    yield gpu
    gpu.close()
    ctx.release()


def leaked(gpu) -> list[str]:
    gc.collect()
    return [type(obj).__name__ for obj in gpu.ctx.objects if type(obj).__name__ != "InvalidObject"]


def lit_room():
    """A closed grey cube lit by a point lamp, a sun through nothing and a world colour: every
    shooter kind, the sky hemi-cubes and (hemi-cube method) the direct light at the patches' points."""
    data = closed_cube(reflectance=0.5, emission=0.0)
    data["surfaces"].append(surface("block", [[0.4, 0.4, 0.3], [0.6, 0.4, 0.3], [0.6, 0.6, 0.3], [0.4, 0.6, 0.3]],
                                    0.5, 0.0))
    data["lights"] = [{"name": "bulb", "type": "point", "position": [0.5, 0.5, 0.8], "color": [1, 1, 1],
                       "power": 10.0}]
    data["world"] = {"color": [0.1, 0.1, 0.1]}
    return scene_from_dict(data)


PROGRESSIVE = solve_settings(subdiv=2, elements=2, tolerance=1e-2, visibility_res=64)
HEMICUBE = solve_settings(method="hemicube", subdiv=2, hemicube_res=16, visibility_res=64)


@pytest.mark.parametrize("settings", [PROGRESSIVE, HEMICUBE], ids=["progressive", "hemicube"])
def test_a_solve_lightmaps_and_preview_release_everything(watched, settings):
    scene = lit_room()
    solution = solve(scene, settings, gpu=watched)
    lightmaps = bake_lightmaps(scene, solution, lightmap_settings(texel_density=16), gpu=watched)
    render_preview(scene, lightmaps, width=32, height=32, gpu=watched)
    assert leaked(watched) == []
    assert len(watched.ctx.objects) > 0  # released objects passed through: the check saw them


@pytest.mark.parametrize("settings", [PROGRESSIVE, HEMICUBE], ids=["progressive", "hemicube"])
def test_a_cancelled_solve_releases_everything(watched, settings):
    """Cancelled at the second check: the progressive method's second shot, the hemi-cube method's
    first convergence check of the Jacobi sweeps (after the hemi-cubes' check)."""
    calls = []
    with pytest.raises(SolveCancelled):
        solve(load_scene("cornell-box"), replace(settings, tolerance=1e-7), gpu=watched,
              should_cancel=lambda: calls.append(1) or len(calls) >= 2)
    assert leaked(watched) == []


FAILURES = {  # stage -> (settings, object and method to break)
    "shooter selection": (PROGRESSIVE, "radiosity_addon.core.progressive.selection.ResidualReader.read"),
    "visibility": (PROGRESSIVE, "radiosity_addon.core.visibility.hemicube.HemicubeAtlas.draw"),
    "shooting pass": (PROGRESSIVE, "radiosity_addon.core.shooting.shooting_pass.ShootingPass.shoot"),
    "sky hemi-cubes": (PROGRESSIVE, "radiosity_addon.core.visibility.hemicube.HemicubeRenderer.coverage"),
    "element readback": (PROGRESSIVE, "radiosity_addon.core.shooting.elements.ElementTextures.read_light"),
    "refinement's probe": (HEMICUBE, "radiosity_addon.core.shooting.texel_pass.TexelReceivers.shoot"),
    "direct light at patch points": (replace(HEMICUBE, refinements=0),
                                     "radiosity_addon.core.shooting.texel_pass.TexelReceivers.shoot"),
    "hemi-cube rows": (HEMICUBE, "radiosity_addon.core.hemicube.form_factors.HemicubeRenderer.coverage"),
    "Jacobi sweeps": (HEMICUBE, "radiosity_addon.core.hemicube.linear_solvers.Convergence.done"),
}


@pytest.mark.parametrize("stage", FAILURES)
def test_a_failure_in_any_solve_stage_releases_everything(watched, monkeypatch, stage):
    settings, target = FAILURES[stage]

    def broken(*args, **kwargs):
        raise Injected(stage)

    monkeypatch.setattr(target, broken)
    with pytest.raises(Injected):
        solve(lit_room(), settings, gpu=watched)
    assert leaked(watched) == []


@pytest.mark.parametrize("target", ["radiosity_addon.core.lightmap.bake.mip_levels",
                                    "radiosity_addon.core.preview.render._surface_triangles"])
def test_a_failure_while_baking_lightmaps_or_rendering_the_preview_releases_everything(watched, monkeypatch, target):
    scene = lit_room()
    solution = solve(scene, HEMICUBE, gpu=watched)
    lightmaps = bake_lightmaps(scene, solution, lightmap_settings(texel_density=16), gpu=watched)
    calls = []

    def broken_on_the_second_call(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise Injected(target)
        return original(*args, **kwargs)

    module, name = target.rsplit(".", 1)
    original = getattr(__import__(module, fromlist=[name]), name)
    monkeypatch.setattr(target, broken_on_the_second_call)
    with pytest.raises(Injected):
        if "preview" in target:
            render_preview(scene, lightmaps, width=32, height=32, gpu=watched)
        else:
            bake_lightmaps(scene, solution, lightmap_settings(texel_density=16), gpu=watched)
    assert leaked(watched) == []


def test_programs_are_compiled_once_per_context(watched):
    scene = lit_room()
    solve(scene, PROGRESSIVE, gpu=watched)
    compiled = watched.program_count
    solve(scene, PROGRESSIVE, gpu=watched)
    assert watched.program_count == compiled > 0


def test_binding_names_are_unique_per_pass_and_every_shader_name_is_defined():
    for group, slots in bindings.STORAGE_GROUPS.items():
        assert len(set(slots.values())) == len(slots), f"{group}: two buffers share a binding point"
        assert max(slots.values()) < 8, f"{group}: beyond OpenGL 4.3's guaranteed 8 storage bindings"
        assert all(bindings.STORAGE[name] == slot for name, slot in slots.items()), f"{group}: a name moved slot"
    defined = set(re.findall(r"#define (\w+)", bindings.glsl()))
    sources = " ".join(p.read_text() for p in SHADERS_DIR.rglob("*") if p.is_file())
    used = set(re.findall(r"\b((?:STORAGE|TEXTURE|IMAGE)_[A-Z_]+)\b", sources))
    assert used and used <= defined, used - defined


def test_scratch_targets_pass_from_scope_to_scope_and_leave_results_unchanged(watched):
    """The visibility atlases and maps a closed scope gave back are what the next solve draws
    into (no fresh allocation), they hold stale pixels then, and the solve is the same bit for bit."""
    scene = lit_room()
    settings = replace(HEMICUBE, refinements=2)
    first = solve(scene, settings, gpu=watched)
    kept = {id(obj) for obj in watched.spares}
    assert kept and 0 < watched.spare_bytes <= MAX_SPARE_BYTES
    second = solve(scene, settings, gpu=watched)
    assert {id(obj) for obj in watched.spares} == kept
    np.testing.assert_array_equal(first.patch_radiosity, second.patch_radiosity)
    assert leaked(watched) == []


def test_a_spares_warm_up_keeps_only_its_programs_and_changes_no_result(watched, monkeypatch):
    """solver_process.child.warm_up: the bundled box solved and baked on the spare's context; what
    stays is the compiled programs (no kept maps, no pooled targets), a solve after it is the
    same bit for bit, and a warm-up that fails leaves the context as usable."""
    from radiosity_addon.solver_process import child

    scene = lit_room()
    settings = replace(HEMICUBE, refinements=2)
    with GPU() as cold:
        expected = solve(scene, settings, gpu=cold)
    assert child.warm_up(watched)
    assert watched.program_count > 0 and watched.kept_count == 0 and watched.spare_bytes == 0
    assert leaked(watched) == []
    np.testing.assert_array_equal(solve(scene, settings, gpu=watched).patch_radiosity, expected.patch_radiosity)

    def failing(*args, **kwargs):
        raise Injected("warm-up")

    with GPU() as other:
        monkeypatch.setattr(child.core, "bake_lightmaps", failing)  # after the solve made its maps
        assert not child.warm_up(other)
        assert other.kept_count == 0 and other.spare_bytes == 0
        monkeypatch.undo()
        np.testing.assert_array_equal(solve(scene, settings, gpu=other).patch_radiosity, expected.patch_radiosity)


def test_an_opengl_too_old_says_what_was_found_and_what_is_needed():
    """A macOS-like driver (OpenGL 4.1, no compute shaders): the one-line error names the version and
    renderer found and the version needed, not a library to install (the libraries are there)."""
    import os
    import subprocess
    import sys
    env = {**os.environ, "MESA_GL_VERSION_OVERRIDE": "4.1",
           "MESA_EXTENSION_OVERRIDE": "-GL_ARB_compute_shader -GL_ARB_shader_storage_buffer_object"
                                      " -GL_ARB_multi_draw_indirect -GL_ARB_shader_image_load_store"}
    probe = ("from radiosity_addon.core import GLUnavailable\n"
             "from radiosity_addon.core.gpu.context import create_context\n"
             "try:\n    create_context()\nexcept GLUnavailable as error:\n    print(error)\n")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, timeout=60,
                          cwd=str(SHADERS_DIR.parent))
    message = done.stdout.strip()
    assert re.match(r"this machine offers OpenGL 4\.1 \(.+\); the bake needs OpenGL 4\.3", message), done
    assert "apt-get" not in message and "\n" not in message


def test_an_opengl_error_fails_the_gpu_that_made_it():
    """The tests run with the driver's log on (conftest): an error is raised when its GPU closes,
    one line naming it; a GPU closing on an exception of its own does not hide that exception."""
    from radiosity_addon.core.gpu.debug import GLReportedProblem
    invalid_capability = 0x1234
    with pytest.raises(GLReportedProblem, match="GL_INVALID_ENUM"):
        with GPU() as gpu:
            gpu.ctx.enable_direct(invalid_capability)
    with pytest.raises(Injected):
        with GPU() as gpu:
            gpu.ctx.enable_direct(invalid_capability)
            raise Injected()
