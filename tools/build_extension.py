"""`make extension`: fetch the bundled wheels, build one zip per platform, validate each zip.

    python tools/build_extension.py [--output-dir dist]

Wheels (moderngl + glcontext for CPython 3.11 = Blender 4.2-5.0, 3.13 = Blender 5.1+ and
Debian's 4.3, 3.14 = Debian's 5.2) are downloaded into wheels/ by pip (gitignored, never
committed); numpy ships with Blender and is not bundled. The manifest's `wheels` list must
name exactly what was downloaded, so a version bump that forgets the manifest fails here,
not in Blender; and every zip must hold one wheel of each requirement for each Python on its
platform, since Blender refuses to enable an extension without wheels for its own Python.
Blender's own tool (`blender_ext.py`, carried by the bpy wheel) builds and validates.

What ships is an explicit list: the files SHIPPED matches (the entry, the licence, the package's
code and bundled scenes, the shaders), copied with the manifest and the wheels into a staging
folder that Blender's tool builds from; nothing else is there to leave out. (Blender 5.0's tool
cannot take the list as the manifest's `[build] paths`: with wheels and one zip per platform it
takes the wrong entries for the wheels.)
"""

from __future__ import annotations

import argparse
import shutil
import importlib.util
import subprocess
import sys
import tempfile
import tomllib
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WHEELS_DIR = ROOT / "wheels"
REQUIREMENTS = ("moderngl==5.13.0", "glcontext==3.1.0")
PYTHON_VERSIONS = ("3.11", "3.13", "3.14")
SHIPPED = ("__init__.py", "LICENSE", "radiosity_addon/**/*.py", "radiosity_addon/**/*.json", "shaders/**/*.*")
# Blender platform -> pip platform tags (pip picks the best wheel among them)
PLATFORM_TAGS = {
    "linux-x64": ["manylinux_2_28_x86_64", "manylinux_2_17_x86_64", "manylinux2014_x86_64",
                  "manylinux_2_5_x86_64", "manylinux1_x86_64"],
    "windows-x64": ["win_amd64"],
    "macos-arm64": ["macosx_11_0_arm64"],
}


def blender_ext_script() -> Path:
    spec = importlib.util.find_spec("bpy")
    if spec is None or spec.origin is None:
        sys.exit("error: the bpy module is needed for Blender's extension tool (make setup installs it)")
    found = sorted(Path(spec.origin).parent.glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    if not found:
        sys.exit("error: blender_ext.py not found in the bpy package")
    return found[-1]


def download_wheels(listed: set[str]) -> set[str]:
    """The wheels in wheels/, downloaded by pip unless every wheel the manifest lists is there already
    (so a build needs no network once they are)."""
    WHEELS_DIR.mkdir(exist_ok=True)
    if listed and all((ROOT / wheel).is_file() for wheel in listed):
        return {f"./wheels/{path.name}" for path in WHEELS_DIR.glob("*.whl")}
    for tags in PLATFORM_TAGS.values():
        for python in PYTHON_VERSIONS:
            command = [sys.executable, "-m", "pip", "download", "--quiet", "--disable-pip-version-check",
                       "--only-binary=:all:", "--no-deps", "--python-version", python,
                       "--dest", str(WHEELS_DIR), *[arg for tag in tags for arg in ("--platform", tag)],
                       *REQUIREMENTS]
            result = subprocess.run(command, capture_output=True, text=True)
            if result.returncode != 0:
                errors = [line for line in result.stderr.splitlines() if line.startswith("ERROR")]
                sys.exit(f"error: pip could not download the wheels for Python {python} {tags[0]}:"
                         f" {errors[0] if errors else result.stderr.strip()[-300:]}")
    return {f"./wheels/{path.name}" for path in WHEELS_DIR.glob("*.whl")}


def shipped_files() -> list[str]:
    """The files SHIPPED matches, relative to the repository, without Python's caches."""
    found = {path.relative_to(ROOT).as_posix() for pattern in SHIPPED for path in ROOT.glob(pattern)
             if path.is_file() and "__pycache__" not in path.parts}
    return sorted(found)


def stage(directory: Path) -> Path:
    """Copy what ships, the manifest and the wheels it lists into `directory`; return it."""
    manifest = tomllib.loads((ROOT / "blender_manifest.toml").read_text())
    for relative in [*shipped_files(), "blender_manifest.toml",
                     *(wheel.removeprefix("./") for wheel in manifest.get("wheels", []))]:
        target = directory / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / relative, target)
    return directory


def manifest_wheels() -> set[str]:
    return set(tomllib.loads((ROOT / "blender_manifest.toml").read_text()).get("wheels", []))


def check_manifest(downloaded: set[str]) -> dict:
    manifest = tomllib.loads((ROOT / "blender_manifest.toml").read_text())
    listed = set(manifest.get("wheels", []))
    missing = sorted(listed - downloaded)
    if missing:
        sys.exit(f"error: the manifest lists wheels that were not downloaded: {', '.join(missing)}")
    wanted = {w for w in downloaded if any(w.split("/")[-1].startswith(r.replace("==", "-")) for r in REQUIREMENTS)}
    unlisted = sorted(wanted - listed)
    if unlisted:
        sys.exit(f"error: blender_manifest.toml does not list these wheels: {', '.join(unlisted)}")
    return manifest


def wheel_tags(file_name: str) -> tuple[str, str, set[str]]:
    """(distribution, python tag, platform tags) of a wheel's file name (name-ver-py-abi-plat.whl)."""
    parts = file_name[:-len(".whl")].split("-")
    return parts[0].lower(), parts[-3], set(parts[-1].split("."))


def check_zip(archive: Path) -> list[str]:
    """The faults of one platform's zip: a requirement missing for one of PYTHON_VERSIONS, or a
    wheel the zip's manifest lists but does not hold."""
    with zipfile.ZipFile(archive) as zipped:
        names = zipped.namelist()
        manifest = tomllib.loads(zipped.read("blender_manifest.toml").decode())
    # a platform's zip says what it holds in [build.generated], which Blender reads over the top level
    manifest.update(manifest.get("build", {}).get("generated", {}))
    held = {name for name in names if name.startswith("wheels/") and name.endswith(".whl")}
    faults = [f"lists {wheel} but does not hold it" for wheel in manifest.get("wheels", [])
              if wheel.removeprefix("./") not in held]
    tags = [wheel_tags(name.split("/")[-1]) for name in held]
    for platform in manifest.get("platforms", []):
        accepted = set(PLATFORM_TAGS.get(platform, ()))
        for distribution in (requirement.split("==")[0] for requirement in REQUIREMENTS):
            for python in PYTHON_VERSIONS:
                python_tag = "cp" + python.replace(".", "")
                count = sum(1 for name, wheel_python, platforms in tags
                            if name == distribution and wheel_python == python_tag and platforms & accepted)
                if count != 1:
                    faults.append(f"holds {count} {distribution} wheel(s) for Python {python} on {platform}")
    return faults


def run(script: Path, *args: str) -> str:
    result = subprocess.run([sys.executable, str(script), *args], capture_output=True, text=True, cwd=ROOT)
    if result.returncode != 0:
        sys.exit(f"error: blender_ext.py {args[0]} failed:\n{result.stdout}{result.stderr}")
    return result.stdout


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output-dir", default=str(ROOT / "dist"))
    args = parser.parse_args(argv)
    script = blender_ext_script()
    manifest = check_manifest(download_wheels(manifest_wheels()))
    output = Path(args.output_dir).resolve()
    output.mkdir(parents=True, exist_ok=True)
    prefix = f"{manifest['id']}-{manifest['version']}"
    for old in output.glob(f"{prefix}-*.zip"):
        old.unlink()
    with tempfile.TemporaryDirectory() as staging:
        source = stage(Path(staging))
        run(script, "validate", str(source))
        run(script, "build", "--source-dir", str(source), "--output-dir", str(output), "--split-platforms")
    zips = sorted(output.glob(f"{prefix}-*.zip"))
    if len(zips) != len(manifest["platforms"]):
        sys.exit(f"error: expected one zip per platform ({', '.join(manifest['platforms'])}), got"
                 f" {', '.join(z.name for z in zips) or 'none'}")
    for archive in zips:
        run(script, "validate", str(archive))
        faults = check_zip(archive)
        if faults:
            sys.exit(f"error: {archive.name} {'; '.join(faults)}")
        print(f"built and validated {archive.relative_to(ROOT) if archive.is_relative_to(ROOT) else archive}"
              f" ({archive.stat().st_size // 1024} KiB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
