"""The bench's outputs: accuracy_vs_time.{json,md,png}."""

from __future__ import annotations

import json
from pathlib import Path

from .metrics import pareto_front

METHOD_STYLE = {"hemicube": ("tab:blue", "o"), "progressive": ("tab:green", "s"), "cycles": ("tab:red", "^")}


def describe(settings: dict) -> str:
    return ", ".join(f"{key} {value:g}" if isinstance(value, float) else f"{key} {value}"
                     for key, value in settings.items())


def machine_line(machine: dict | None) -> str:
    if not machine:
        return ""
    load = ", ".join(f"{v:.1f}" for v in machine.get("load_average_after_sweep", ()))
    return (f"Machine: {machine.get('cpus')} CPUs, OpenGL renderer {machine.get('gl_renderer')};"
            f" 1/5/15-minute load average at the end {load} (timings are wall time on a shared machine).")


def scenes_of(rows: list[dict]) -> list[str]:
    return list(dict.fromkeys(row["scene"] for row in rows))


def mark_pareto(rows: list[dict]) -> None:
    for row in rows:
        row["pareto"] = False
    for scene in scenes_of(rows):
        for row in pareto_front([r for r in rows if r["scene"] == scene]):
            row["pareto"] = True


def write_json(path: Path, rows: list[dict], notes: dict, machine: dict | None = None) -> None:
    path.write_text(json.dumps({"rows": rows, "scenes": notes, "machine": machine}, indent=1, default=float))


def markdown(rows: list[dict], notes: dict, machine: dict | None = None) -> str:
    lines = ["# What accuracy costs: error vs time", "",
             "Error: area-weighted relative RMS of reflected radiance over the covered texels of the"
             " reflecting surfaces (a common grid of texels per surface), against the reference below,"
             " our patches/elements shown as a bilinearly filtered lightmap shows them; constant: the"
             " same shown piecewise constant; patch: means over each patch's texels (the solve's own"
             " error without the display error); worst object: its mean radiance's relative error."
             " ★ = on the scene's Pareto front (nothing is both faster and more accurate).", "", machine_line(machine), ""]
    for scene in scenes_of(rows):
        note = notes[scene]
        floor = f"; reference noise floor {note['noise_floor']:.4f}" if note.get("noise_floor") else ""
        lines += [f"## {scene}", "",
                  f"Reference: {note['reference']}, {note['texels_per_surface_side']}² texels per surface{floor}.", "",
                  "| method | settings | seconds | error | constant | patch | worst object (error) | stages (s) |",
                  "|---|---|---:|---:|---:|---:|---|---|"]
        for row in sorted((r for r in rows if r["scene"] == scene), key=lambda r: (r["method"], r["seconds"])):
            stages = ", ".join(f"{k} {v:.2f}" for k, v in row["timings"].items() if k != "total")
            star = " ★" if row.get("pareto") else ""
            extra = " | ".join(f"{row[key]:.4f}" if key in row else "—" for key in ("constant_error", "patch_error"))
            lines.append(f"| {row['method']}{star} | {describe(row['settings'])} | {row['seconds']:.2f} |"
                         f" {row['error']:.4f} | {extra} | {row['worst_object']} ({row['worst_object_error']:.4f}) | {stages} |")
        front = [r for r in sorted(rows, key=lambda r: r["seconds"]) if r["scene"] == scene and r.get("pareto")]
        lines += ["", "Pareto front: " + " → ".join(
            f"{r['method']} ({describe(r['settings'])}) {r['seconds']:.2f} s / {r['error']:.4f}" for r in front), ""]
        for skipped in note.get("skipped", []):
            lines.append(f"- skipped: {skipped}")
        lines.append("")
    return "\n".join(lines)


def plot(path: Path, rows: list[dict], notes: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = scenes_of(rows)
    figure, axes = plt.subplots(1, len(scenes), figsize=(6 * len(scenes), 4.8), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        scene_rows = [r for r in rows if r["scene"] == scene]
        for method, (color, marker) in METHOD_STYLE.items():
            points = [r for r in scene_rows if r["method"] == method]
            if not points:
                continue
            ax.scatter([r["seconds"] for r in points], [max(r["error"], 1e-6) for r in points],
                       color=color, marker=marker, alpha=0.6, label=method)
            own_front = pareto_front(points)  # one curve per method: its own best trade-offs
            ax.plot([r["seconds"] for r in own_front], [max(r["error"], 1e-6) for r in own_front], color=color)
        front = pareto_front(scene_rows)
        ax.plot([r["seconds"] for r in front], [max(r["error"], 1e-6) for r in front], "k--", linewidth=1,
                label="Pareto front")
        ax.scatter([r["seconds"] for r in front], [max(r["error"], 1e-6) for r in front], s=120,
                   facecolors="none", edgecolors="k")
        if notes[scene].get("noise_floor"):
            ax.axhline(notes[scene]["noise_floor"], color="gray", linestyle=":", label="reference noise")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("relative RMS error")
        ax.set_title(scene)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
