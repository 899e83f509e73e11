"""`python -m radiosity_addon bake FILE.blend`: EXRs, a saved .blend that reopens with the lightmaps shown."""

from __future__ import annotations

import os
import subprocess
import sys

import blender_support as support

PYTHON = sys.executable


def run_cli(*args, cwd=support.ROOT):
    env = dict(os.environ, BLENDER_USER_RESOURCES=os.environ["BLENDER_USER_RESOURCES"])
    return subprocess.run([PYTHON, "-m", "radiosity_addon", *args], capture_output=True, text=True, cwd=cwd,
                          env=env, timeout=300)


REOPEN_CHECK = r"""
import sys, bpy, numpy as np
bpy.ops.wm.open_mainfile(filepath=sys.argv[1])
shown = {}
for obj in (o for o in bpy.data.objects if o.type == "MESH"):
    image = bpy.data.images[obj.name + "_lightmap"]
    pixels = np.empty(image.size[0] * image.size[1] * 4, np.float32)
    image.pixels.foreach_get(pixels)
    for slot in obj.material_slots:
        tree = slot.material.node_tree
        output = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial" and n.is_active_output)
        emission = output.inputs["Surface"].links[0].from_node
        stack, shown_images = [emission], []
        while stack:  # the lightmap image upstream of the emission (through a light lightmap's arithmetic)
            node = stack.pop()
            shown_images += [node.image] if node.bl_idname == "ShaderNodeTexImage" and node.get("radiosity_baker") else []
            stack += [link.from_node for socket in node.inputs for link in socket.links]
        assert shown_images == [image], (obj.name, shown_images)
    shown[obj.name] = (image.filepath, float(pixels.reshape(-1, 4)[:, :3].max()))
print("SHOWN", shown)
"""


def test_headless_bake_writes_exrs_and_a_blend_that_reopens_with_lightmaps(tmp_path):
    out_dir = tmp_path / "lightmaps"
    saved = tmp_path / "baked" / "cornell_baked.blend"
    result = run_cli("bake", str(support.CORNELL), "--output-dir", str(out_dir), "--save-as", str(saved),
                     "--method", "hemicube", "--subdiv", "2", "--hemicube-res", "32", "--texel-density", "32",
                     "--quiet")
    assert result.returncode == 0, result.stderr
    assert "baked 8 object(s)" in result.stdout
    names = ["back_wall", "ceiling", "floor", "left_wall", "light", "right_wall", "short_block", "tall_block"]
    assert sorted(p.name for p in out_dir.glob("*.exr")) == [f"{name}_lightmap.exr" for name in names]
    assert saved.is_file()

    # a fresh process, as a user opening the file would
    check = subprocess.run([PYTHON, "-c", REOPEN_CHECK, str(saved)], capture_output=True, text=True, timeout=120,
                           env=dict(os.environ))
    assert check.returncode == 0, check.stderr[-2000:]
    shown = eval(check.stdout.split("SHOWN", 1)[1].strip())
    assert sorted(shown) == names
    for name, (filepath, brightest) in shown.items():
        assert filepath.endswith(f"{name}_lightmap.exr"), filepath
        assert brightest > 0, f"{name}: the reopened lightmap is black"


def test_headless_bake_of_selected_objects_packs_into_the_saved_file(tmp_path):
    saved = tmp_path / "room_baked.blend"
    result = run_cli("bake", str(support.ROOM), "--objects", "Room,Table", "--save-as", str(saved),
                     "--method", "hemicube", "--subdiv", "1", "--hemicube-res", "32", "--texel-density", "16",
                     "--quiet")
    assert result.returncode == 0, result.stderr
    assert "baked 2 object(s)" in result.stdout
    assert not list(tmp_path.glob("*.exr"))


def test_headless_user_errors_are_one_line(tmp_path):
    cases = [
        (["bake", str(tmp_path / "missing.blend"), "--save-as", str(tmp_path / "x.blend")], "does not exist"),
        (["bake", str(support.CORNELL)], "--output-dir"),
        (["bake", str(support.CORNELL), "--objects", "nope", "--save-as", str(tmp_path / "x.blend")],
         "no object named 'nope'"),
    ]
    for args, expected in cases:
        result = run_cli(*args)
        assert result.returncode == 2, (args, result.stderr)
        errors = [line for line in result.stderr.splitlines() if line.startswith("error:")]
        assert len(errors) == 1 and expected in errors[0], result.stderr
        assert "Traceback" not in result.stderr
