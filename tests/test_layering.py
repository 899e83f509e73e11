"""The layout follows the data flow, and this test keeps it so (read from the source with `ast`,
function-level imports included):

- no import cycle among the core's modules;
- a core package imports only the stages before it (ALLOWED), so `scene` imports no GPU code and
  neither method imports the other;
- outside the core (command line, Blender side, benchmark) only the core's public API
  (`radiosity_addon.core`) is imported, never a core module;
- `bpy` is imported only in radiosity_addon/blender/ and the dev-only bench/;
- the shipped package imports nothing from bench/ (which the zip leaves out);
- no Python file is longer than MAX_LINES.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "radiosity_addon"
BENCH = ROOT / "bench"  # the benchmarks: beside the package, never shipped
CORE = "radiosity_addon.core"
MAX_LINES = 420

# core part -> the core parts it may import (its own modules aside)
BASE = {"errors", "settings", "timing"}
ALLOWED = {
    "errors": set(),
    "timing": set(),
    "settings": {"errors"},
    "imaging": set(),
    "gpu": {"errors"},
    "scene": {"errors", "settings", "timing"},
    "visibility": BASE | {"gpu", "scene"},
    "shooting": BASE | {"gpu", "imaging", "scene", "visibility"},
    "uvspace": BASE | {"gpu", "scene"},
    "hemicube": BASE | {"gpu", "scene", "visibility", "shooting"},
    "progressive": BASE | {"gpu", "scene", "visibility", "shooting"},
    "report": BASE | {"scene", "hemicube", "progressive"},
    "solution": BASE | {"scene", "report"},
    "refinement": BASE | {"gpu", "scene", "uvspace", "shooting"},
    "method_choice": BASE | {"scene", "visibility", "shooting", "hemicube"},
    "solve": BASE | {"gpu", "scene", "shooting", "uvspace", "hemicube", "progressive", "report", "solution",
              "refinement", "method_choice"},
    "lightmap": BASE | {"gpu", "imaging", "scene", "uvspace", "visibility", "shooting", "solution"},
    "preview": BASE | {"gpu", "scene", "lightmap"},
}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def source_files() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py")) + sorted(BENCH.rglob("*.py"))}


MODULES = source_files()


def bound_names(package: str) -> set[str]:
    """Names a package's __init__ binds (what `from package import name` may mean besides a module)."""
    path = MODULES.get(package)
    if path is None or path.name != "__init__.py":
        return set()
    names = set()
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            names.update(alias.asname or alias.name for alias in node.names)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
    return names


def imports_of(name: str, path: Path) -> set[str]:
    """Absolute names of everything `name` imports (modules, or a package's names' module)."""
    tree = ast.parse(path.read_text())
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            for alias in node.names:  # `from pkg import module` imports that module
                candidate = f"{target}.{alias.name}"
                is_module = candidate in MODULES and alias.name not in bound_names(target)
                found.add(candidate if is_module else target)
    return found


GRAPH = {name: imports_of(name, path) for name, path in MODULES.items()}


def core_part(name: str) -> str | None:
    """'scene' for radiosity_addon.core.scene.load, None for the core package itself or outside it."""
    if not name.startswith(CORE + "."):
        return None
    return name[len(CORE) + 1:].split(".")[0]


def test_no_import_cycle_in_the_core():
    core = {name: {t for t in targets if t.startswith(CORE)} for name, targets in GRAPH.items()
            if name.startswith(CORE)}
    state: dict[str, int] = {}

    def visit(name, path):
        state[name] = 1
        for target in sorted(core.get(name, ())):
            if state.get(target) == 1:
                cycle = path[path.index(target):] + [target] if target in path else [name, target]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if target in core and state.get(target) is None:
                visit(target, path + [target])
        state[name] = 2

    for name in sorted(core):
        if state.get(name) is None:
            visit(name, [name])


def test_core_parts_import_only_earlier_stages():
    assert set(ALLOWED) == {core_part(name) for name in MODULES if core_part(name)}, "a core part has no rule"
    bad = []
    for name, targets in GRAPH.items():
        part = core_part(name)
        if part is None:
            continue
        for target in targets:
            other = core_part(target)
            if target == CORE or (other is not None and other != part and other not in ALLOWED[part]):
                bad.append(f"{name} imports {target}")
    assert not bad, "; ".join(bad)


def test_outside_the_core_only_the_public_api_is_imported():
    bad = [f"{name} imports {target}" for name, targets in GRAPH.items() if not name.startswith(CORE)
           for target in targets if target.startswith(CORE + ".")]
    assert not bad, "; ".join(bad)


def test_bpy_only_in_the_blender_side_and_the_bench():
    allowed = ("radiosity_addon.blender", "bench")
    bad = [name for name, targets in GRAPH.items()
           if any(t == "bpy" or t.startswith(("bpy.", "mathutils", "bl_")) for t in targets)
           and not name.startswith(allowed)]
    assert not bad, f"bpy imported by {bad}"


def test_the_shipped_package_never_imports_the_bench():
    bad = [f"{name} imports {target}" for name, targets in GRAPH.items() if name.startswith("radiosity_addon")
           for target in targets if target == "bench" or target.startswith("bench.")]
    assert not bad, "; ".join(bad)


def test_the_extension_entry_imports_nothing_at_module_level():
    tree = ast.parse((ROOT / "__init__.py").read_text())
    assert not [node for node in tree.body if isinstance(node, (ast.Import, ast.ImportFrom))]


def test_no_python_file_is_too_long():
    files = [*PACKAGE.rglob("*.py"), *BENCH.rglob("*.py"), *(ROOT / "tests").rglob("*.py"), *(ROOT / "tools").glob("*.py")]
    long = {str(p.relative_to(ROOT)): n for p in files if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert not long, long


def test_the_checks_see_a_violation():
    """The rules fail where they should: an ALLOWED set without 'gpu' would refuse visibility."""
    assert "radiosity_addon.core.gpu" in GRAPH["radiosity_addon.core.visibility.hemisphere"]
    assert "radiosity_addon.core.scene" in GRAPH["radiosity_addon.core.shooting.lamps"]
    assert any(t.startswith("bpy") for t in GRAPH["radiosity_addon.blender.apply"])


def test_no_test_imports_the_tools():
    """tools/ are scripts for people (samples, measurements), not a library the tests lean on."""
    bad = []
    for path in (ROOT / "tests").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            bad += [f"{path.relative_to(ROOT)} imports {n}" for n in names if n == "tools" or n.startswith("tools.")]
    assert not bad, "; ".join(bad)
