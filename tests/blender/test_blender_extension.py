"""The packaged extension: build (as `make extension` does), validate, install into an isolated Blender
user directory, enable, and bake with the installed copy."""

from __future__ import annotations

import os
import subprocess
import sys
import zipfile

import blender_support as support

sys.path.insert(0, str(support.ROOT / "tools"))
import build_extension  # noqa: E402

INSTALL_AND_BAKE = r"""
import sys, bpy
zip_path, sample = sys.argv[1], sys.argv[2]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default", enable_on_install=True)
import addon_utils
assert "bl_ext.user_default.radiosity_baker" in {m.__name__ for m in addon_utils.modules()}, "not installed"
assert hasattr(bpy.types.Scene, "radiosity"), "scene.radiosity missing"
assert hasattr(bpy.types, "RADIOSITY_OT_bake") and hasattr(bpy.types, "RENDER_PT_radiosity_bake")
bpy.ops.wm.open_mainfile(filepath=sample)
settings = bpy.context.scene.radiosity
settings.method, settings.subdivision, settings.hemicube_resolution = "hemicube", 1, 32
assert bpy.ops.radiosity.bake() == {"FINISHED"}
from bl_ext.user_default.radiosity_baker.radiosity_addon import blender as installed
print("INSTALLED-FROM", installed.__file__)
print("IMAGES", sorted(i.name for i in bpy.data.images))
"""


def test_extension_builds_validates_installs_and_bakes(tmp_path):
    dist = tmp_path / "dist"
    build = subprocess.run([sys.executable, str(support.ROOT / "tools/build_extension.py"), "--output-dir", str(dist)],
                           capture_output=True, text=True, timeout=600)
    assert build.returncode == 0, build.stdout + build.stderr
    zips = sorted(p.name for p in dist.glob("*.zip"))
    assert zips == ["radiosity_baker-0.1.0-linux_x64.zip", "radiosity_baker-0.1.0-macos_arm64.zip",
                    "radiosity_baker-0.1.0-windows_x64.zip"]
    linux_zip = dist / "radiosity_baker-0.1.0-linux_x64.zip"
    names = zipfile.ZipFile(linux_zip).namelist()
    assert "blender_manifest.toml" in names and "__init__.py" in names and "LICENSE" in names  # GPL-3.0: its text ships
    assert any(n.startswith("shaders/") and n.endswith(".comp") for n in names)
    for package in ("moderngl", "glcontext"):  # cp311, cp313 and cp314: Blender 4.2 to Debian's 5.2
        assert sorted(n.split("-")[2] for n in names if n.startswith(f"wheels/{package}-")) == \
            ["cp311", "cp313", "cp314"]
    assert build_extension.check_zip(linux_zip) == []
    assert not any(n.startswith(("tests/", "sample_blends/", "tools/", "docs/", ".", "bench/"))
                   or "__pycache__" in n or n.endswith(".md") for n in names)  # only what users need ships
    shipped = {n for n in names if n.startswith("radiosity_addon/")}
    assert {n for n in shipped if not n.endswith(".json")} == \
        {p.relative_to(support.ROOT).as_posix() for p in (support.ROOT / "radiosity_addon").rglob("*.py")
         if "__pycache__" not in p.parts}  # every module, and nothing beside the code but bundled scenes
    assert any(n.startswith("shaders/include/") for n in names)
    assert not any(n.startswith("wheels/numpy") for n in names)

    user = tmp_path / "blender-user"
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(user), PYTHONPATH="")
    installed = subprocess.run([sys.executable, "-c", INSTALL_AND_BAKE, str(linux_zip), str(support.CORNELL)],
                               capture_output=True, text=True, timeout=300, env=env, cwd=tmp_path)
    assert installed.returncode == 0, installed.stdout[-3000:] + installed.stderr[-3000:]
    assert str(user) in installed.stdout.split("INSTALLED-FROM", 1)[1].splitlines()[0]
    assert "floor_lightmap" in installed.stdout.split("IMAGES", 1)[1]


def test_a_zip_without_a_wheel_for_one_of_its_pythons_is_refused(tmp_path):
    """make extension's check: each platform's zip holds each requirement for each Python."""
    wheels = [f"wheels/{package}-{version}-{tag}-{tag}-win_amd64.whl"
              for package, version in (("moderngl", "5.13.0"), ("glcontext", "3.1.0"))
              for tag in ("cp311", "cp313", "cp314")]
    def zip_with(held, listed):
        archive = tmp_path / f"{len(held)}-{len(listed)}.zip"
        with zipfile.ZipFile(archive, "w") as zipped:
            generated = ", ".join(f'"./{w}"' for w in listed)
            zipped.writestr("blender_manifest.toml", f'id = "x"\n[build.generated]\nplatforms = ["windows-x64"]\n'
                                                     f"wheels = [{generated}]\n")
            for wheel in held:
                zipped.writestr(wheel, b"")
        return build_extension.check_zip(archive)

    assert zip_with(wheels, wheels) == []
    assert zip_with(wheels[1:], wheels[1:]) == ["holds 0 moderngl wheel(s) for Python 3.11 on windows-x64"]
    assert zip_with(wheels[:-1], wheels) == [f"lists ./{wheels[-1]} but does not hold it",
                                             "holds 0 glcontext wheel(s) for Python 3.14 on windows-x64"]
