"""Rewrite the tables of docs/architecture.md that the code can make, and check its links.

    .venv/bin/python tools/architecture_tables.py           # rewrite the blocks in docs/architecture.md
    .venv/bin/python tools/architecture_tables.py --check   # change nothing; exit 1 if out of date
    make architecture-tables

Every generated table sits between two markers, each on a line of its own,

    <!-- generated:NAME -->
    ...generated, do not edit by hand...
    <!-- /generated:NAME -->

and this tool replaces what is between them (running it twice changes nothing):

    presets   the quality presets, `QUALITY_PRESETS` of radiosity_addon/core/settings.py as
              `SolveSettings.preset(q)` and `LightmapSettings.preset(q)` give them, beside what
              `SolveSettings()` and `LightmapSettings()` hold, and each field's comment
    settings  the fields no preset sets: their defaults and comments
    layering  the core's parts in the order of the data flow: where each lives, what it holds (its
              README.md's first line, or its module docstring's first sentence) and which parts it
              may import (`ALLOWED` of tests/test_layering.py, read with `ast`: no pytest needed)

It also checks every relative link of the document: the file must exist, and a `#anchor` into a
Markdown file must be one of its headings' GitHub anchors.
Exit status: 0 done (or, with --check, up to date); 1 out of date (--check) or a broken link;
2 a marker missing or unpaired, or a block the tool does not know.
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from generated_blocks import BlocksError, update  # noqa: E402
from radiosity_addon.core import settings as settings_module  # noqa: E402

DOCUMENT = ROOT / "docs" / "architecture.md"
SETTINGS_SOURCE = ROOT / "radiosity_addon" / "core" / "settings.py"
LAYERING_TEST = ROOT / "tests" / "test_layering.py"
CORE = ROOT / "radiosity_addon" / "core"
LONGEST_SUMMARY = 170  # characters of a part's description before it is cut at a word


# -- values and comments ------------------------------------------------------------------------

def shown(value) -> str:
    """A setting's value as the table shows it."""
    if isinstance(value, bool) or value is None:
        return f"`{value}`"
    if isinstance(value, str):
        return f"`{value}`"
    if isinstance(value, int):
        return f"{value:,}".replace(",", " ")
    if isinstance(value, float):
        if value != 0 and abs(value) < 0.1:
            mantissa, exponent = f"{value:.0e}".split("e")
            return f"{mantissa}e{int(exponent)}"
        return f"{value:g}"
    return f"`{value!r}`"


def field_comments(class_name: str) -> dict[str, str]:
    """Each field of `class_name` in settings.py -> its comment: the one on its line (without a
    leading "preset"), continued on the comment lines after it while a parenthesis is open, or,
    when its line says nothing more, the comment lines right above it."""
    lines = SETTINGS_SOURCE.read_text(encoding="utf-8").splitlines()
    tree = ast.parse("\n".join(lines))
    found = [node for node in tree.body if isinstance(node, ast.ClassDef) and node.name == class_name]
    if not found:
        raise BlocksError(f"{SETTINGS_SOURCE.name} has no class {class_name}")
    comments = {}
    for node in found[0].body:
        if not (isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name)):
            continue
        row = node.lineno - 1
        own = lines[row].partition("  # ")[2].strip()
        own = re.sub(r"^preset(;\s*|\s*$|\s+(?=\())", "", own)
        below = row + 1
        while own.count("(") > own.count(")") and below < len(lines) and lines[below].strip().startswith("#"):
            own += " " + lines[below].strip().lstrip("#").strip()
            below += 1
        if not own:
            above, row_above = [], row - 1
            while row_above >= 0 and lines[row_above].strip().startswith("#"):
                above.insert(0, lines[row_above].strip().lstrip("#").strip())
                row_above -= 1
            own = " ".join(above)
        if not own and isinstance(node.value, ast.Name):  # a module constant: its comment
            own = constant_comments(lines).get(node.value.id, "")
        comments[node.target.id] = own.replace("|", "/")
    return comments


def constant_comments(lines: list[str]) -> dict[str, str]:
    """NAME -> the comment on the line of a module-level `NAME = ...` of settings.py."""
    found = (re.match(r"^([A-Z_]+)\s*=.*?  # (.+)$", line) for line in lines)
    return {match.group(1): match.group(2).strip() for match in found if match}


def preset_table(cls, part: str, extra_rows=()) -> list[str]:
    """Rows: the fields a preset sets (or in which a preset differs from the dataclass' own),
    columns: each quality's value, the dataclass' and the field's comment."""
    qualities = settings_module.QUALITIES
    presets = {quality: cls.preset(quality) for quality in qualities}
    default = cls()
    comments = field_comments(cls.__name__)
    names = [f.name for f in dataclasses.fields(cls) if f.name != "quality" and (
        any(f.name in settings_module.QUALITY_PRESETS[q].get(part, {}) for q in qualities)
        or any(getattr(presets[q], f.name) != getattr(default, f.name) for q in qualities))]
    head = f"| `{cls.__name__}` field | " + " | ".join(qualities) + f" | `{cls.__name__}()` | what it is |"
    rows = [head, "|---|" + "---:|" * (len(qualities) + 1) + "---|"]
    for name in names:
        values = [shown(getattr(presets[q], name)) for q in qualities] + [shown(getattr(default, name))]
        rows.append(f"| `{name}` | " + " | ".join(values) + f" | {comments.get(name, '')} |")
    return rows + list(extra_rows)


def matching_presets(cls, part: str) -> str:
    """One sentence: which presets `cls()` equals on the fields the presets set."""
    default = cls()
    names = {name for q in settings_module.QUALITIES for name in settings_module.QUALITY_PRESETS[q].get(part, {})}
    same = [q for q in settings_module.QUALITIES
            if all(getattr(cls.preset(q), n) == getattr(default, n) for n in names)]
    if same:
        return f"`{cls.__name__}()` holds the `{same[0]}` preset's values on these fields."
    nearest = min(settings_module.QUALITIES,
                  key=lambda q: sum(getattr(cls.preset(q), n) != getattr(default, n) for n in names))
    differ = sorted(n for n in names if getattr(cls.preset(nearest), n) != getattr(default, n))
    return (f"`{cls.__name__}()` matches no preset on these fields: it differs from `{nearest}`, the nearest,"
            f" in {', '.join(f'`{n}`' for n in differ)}.")


def block_presets() -> list[str]:
    solve, lightmaps = settings_module.SolveSettings, settings_module.LightmapSettings
    tolerances = settings_module.QUALITY_PRESETS
    default = solve()
    tolerance_rows = []
    for method, meaning in (("progressive", "the unshot power left, relative to the emitted power"),
                            ("hemicube", "the change per sweep, relative to max B")):
        own = default.tolerance if default.tolerance is not None else tolerances[default.quality]["tolerance"][method]
        values = [shown(tolerances[q]["tolerance"][method]) for q in settings_module.QUALITIES] + [shown(own)]
        tolerance_rows.append(f"| tolerance, `{method}` | " + " | ".join(values)
                              + f" | the stop when `tolerance` is None: {meaning} |")
    return (preset_table(solve, "solve", tolerance_rows) + ["", matching_presets(solve, "solve"), ""]
            + preset_table(lightmaps, "lightmaps") + ["", matching_presets(lightmaps, "lightmaps")])


def block_settings() -> list[str]:
    rows = ["| field | default | what it is |", "|---|---:|---|"]
    for cls, part in ((settings_module.SolveSettings, "solve"), (settings_module.LightmapSettings, "lightmaps")):
        default = cls()
        comments = field_comments(cls.__name__)
        preset_names = {n for q in settings_module.QUALITIES for n in settings_module.QUALITY_PRESETS[q].get(part, {})}
        for f in dataclasses.fields(cls):
            if f.name in preset_names or f.name == "quality":
                continue
            if any(getattr(cls.preset(q), f.name) != getattr(default, f.name) for q in settings_module.QUALITIES):
                continue  # in the presets' table
            rows.append(f"| `{cls.__name__}.{f.name}` | {shown(getattr(default, f.name))} | {comments.get(f.name, '')} |")
    return rows


# -- the core's layering --------------------------------------------------------------------------

def allowed_imports() -> tuple[dict[str, set], set]:
    """`ALLOWED` and `BASE` of tests/test_layering.py, evaluated from its source alone."""
    tree = ast.parse(LAYERING_TEST.read_text(encoding="utf-8"))
    values: dict[str, object] = {}
    for node in tree.body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name) \
                and node.targets[0].id in ("BASE", "ALLOWED"):
            expression = ast.Expression(node.value)
            values[node.targets[0].id] = eval(compile(expression, str(LAYERING_TEST), "eval"),  # noqa: S307
                                              {"__builtins__": {"set": set}}, dict(values))
    if "ALLOWED" not in values:
        raise BlocksError(f"{LAYERING_TEST.name} has no ALLOWED map")
    return values["ALLOWED"], values.get("BASE", set())


def first_sentence(text: str) -> str:
    """The first sentence of `text`; past LONGEST_SUMMARY without its asides (dashes, brackets),
    then cut at a word."""
    text = " ".join(text.split())
    ends = [m.start() for m in re.finditer(r"\.(?=\s+[A-Z`(]|\s*$)", text)
            if not re.search(r"\b(al|e\.g|i\.e|etc)$", text[:m.start()])]
    sentence = text[:ends[0] + 1] if ends else text
    if len(sentence) > LONGEST_SUMMARY:
        sentence = re.sub(r" — [^—]*? — ", ", ", sentence)
        sentence = re.sub(r" \([^()]*\)", "", sentence)
    if len(sentence) > LONGEST_SUMMARY:
        sentence = sentence[:LONGEST_SUMMARY].rsplit(" ", 1)[0].rstrip(",;:—(") + " …"
    return sentence.replace("|", "/")


def part_summary(part: str) -> tuple[str, str]:
    """(where it lives, what it holds) of a core part."""
    folder, module = CORE / part, CORE / f"{part}.py"
    if folder.is_dir():
        readme = folder / "README.md"
        if readme.is_file():
            return f"`core/{part}/`", first_sentence(readme.read_text(encoding="utf-8").strip().splitlines()[0])
        module = folder / "__init__.py"
        where = f"`core/{part}/`"
    else:
        where = f"`core/{part}.py`"
    if not module.is_file():
        raise BlocksError(f"tests/test_layering.py names a core part '{part}' that has no folder or module")
    return where, first_sentence(ast.get_docstring(ast.parse(module.read_text(encoding="utf-8"))) or "")


def block_layering() -> list[str]:
    allowed, base = allowed_imports()
    order = list(allowed)
    rows = ["| part | where | what it holds | may import |", "|---|---|---|---|"]
    for part in order:
        imports = allowed[part]
        if base and base <= imports and part not in base:
            named = ["base"] + [other for other in order if other in imports - base]
        else:
            named = [other for other in order if other in imports]
        where, summary = part_summary(part)
        rows.append(f"| `{part}` | {where} | {summary} | {', '.join(named) or '—'} |")
    names = ", ".join(f"`{name}`" for name in order if name in base)
    return rows + ["", f"base: {names}. A part's own modules import each other freely;",
                   "the rest of the add-on and `bench/` import only `radiosity_addon.core` (its `__init__.py`)."]


BLOCKS = {"presets": block_presets, "settings": block_settings, "layering": block_layering}


# -- links ---------------------------------------------------------------------------------------

def github_anchor(heading: str) -> str:
    """The anchor GitHub gives a heading: lower case, punctuation dropped, spaces as hyphens."""
    text = re.sub(r"[`*_]|<[^>]+>", "", heading.strip()).lower()
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def anchors(path: Path) -> set[str]:
    found, seen = set(), {}
    text = re.sub(r"^```.*?^```", "", path.read_text(encoding="utf-8"), flags=re.S | re.M)
    for heading in re.findall(r"^#{1,6}\s+(.+?)\s*#*\s*$", text, flags=re.M):
        anchor = github_anchor(heading)
        count = seen.get(anchor, 0)
        seen[anchor] = count + 1
        found.add(anchor if count == 0 else f"{anchor}-{count}")
    return found


def broken_links(text: str, document: Path) -> list[str]:
    """Relative links of `text` (the document at `document`) whose file or heading is not there."""
    text = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)
    text = re.sub(r"`[^`\n]*`", "", text)
    broken = []
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if re.match(r"[a-z]+:", target):
            continue
        file_part, _, anchor = target.partition("#")
        path = (document.parent / file_part).resolve() if file_part else document
        if not path.exists():
            broken.append(f"{target}: no such file")
        elif anchor and path.suffix == ".md" and anchor not in anchors(path):
            broken.append(f"{target}: no such heading")
    return broken


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true", help="change nothing; exit 1 if the document is out of date")
    parser.add_argument("--document", type=Path, default=DOCUMENT)
    args = parser.parse_args(argv)
    document = args.document.resolve()
    return update("architecture_tables", args.document, "generated", BLOCKS, args.check, "architecture-tables",
                  problems=lambda text: [f"broken link {link}" for link in broken_links(text, document)])


if __name__ == "__main__":
    sys.exit(main())
