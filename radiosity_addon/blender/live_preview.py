"""The lightmaps of a progressive bake while it runs, shown through the objects' materials, so the
viewport (Material Preview or Rendered) shows the light building up; and the way back.

The solver process sends the radiosity so far plus the ambient term (display only) every couple
of seconds. The first snapshot makes one float image per object, named "<object>_lightmap
(baking)", and shows it: an object without a bake gets the bake's usual wiring, an object that
shows an earlier bake has only its lightmap node pointed at the new image. Later snapshots only
refresh the pixels. A cancel or failure takes all of it back exactly (`take_back`); a finished
bake wires its final images first and then drops these (`release`). Objects in neither state
(wired by hand, half restored) get no preview, so taking it back can never lose anything.
"""

from __future__ import annotations

import bpy
import numpy as np

from . import apply
from .tags import ADDED_SLOT, ORIGINAL_OUTPUT, ORIGINAL_SLOTS, is_ours, lightmap_image_name

PREVIEW_SUFFIX = " (baking)"


def lightmap_node(material):
    """The add-on's Image Texture node in a material it wired, else None."""
    tree = material.node_tree if material is not None else None
    node = tree.nodes.get(apply.NODE_NAMES["image"]) if tree is not None else None
    return node if node is not None and is_ours(node) else None


def shows_a_bake(obj) -> bool:
    materials = [slot.material for slot in obj.material_slots]
    return bool(materials) and all(m is not None and m.get(ORIGINAL_OUTPUT) is not None and lightmap_node(m)
                                   for m in materials)


def shows_no_bake(obj) -> bool:
    return ORIGINAL_SLOTS not in obj and ADDED_SLOT not in obj and not any(
        slot.material is not None and slot.material.get(ORIGINAL_OUTPUT) is not None for slot in obj.material_slots)


def set_pixels(image, rgba: np.ndarray) -> None:
    image.pixels.foreach_set(np.ascontiguousarray(rgba, dtype=np.float32).ravel())
    image.update()  # the viewport uploads the new pixels on its next redraw


class LivePreview:
    def __init__(self, objects, content: str = "combined", diffuse_factors: dict | None = None):
        self.objects = list(objects)
        self.content, self.diffuse_factors = content, diffuse_factors  # shown the way the final images will be
        self.images: dict = {}  # object name -> its preview image
        self.rewired: list = []  # objects that got the bake's wiring for the preview
        self.pointed: list = []  # (lightmap node, the image it showed before)

    def show(self, snapshot: dict) -> None:
        """Show a snapshot (object name -> float32 RGBA); the first one sets the wiring up."""
        if self.images:
            for name, image in self.images.items():
                if tuple(image.size) == snapshot[name].shape[1::-1]:
                    set_pixels(image, snapshot[name])
            return
        for obj in self.objects:
            rgba = snapshot[obj.name]
            previously = shows_a_bake(obj)
            if not previously and not shows_no_bake(obj):
                continue
            height, width = rgba.shape[:2]
            image = bpy.data.images.new(lightmap_image_name(obj.name) + PREVIEW_SUFFIX, width, height, alpha=True,
                                        float_buffer=True)
            image.alpha_mode = "CHANNEL_PACKED"  # coverage lives in alpha, as in the final images
            set_pixels(image, rgba)
            self.images[obj.name] = image
            if previously:
                for material in {slot.material.name: slot.material for slot in obj.material_slots}.values():
                    node = lightmap_node(material)
                    self.pointed.append((node, node.image))
                    node.image = image
            else:
                apply.show_lightmaps([obj], {obj.name: image}, self.content, self.diffuse_factors)
                self.rewired.append(obj)

    def release(self) -> None:
        """The final images are shown now: drop the preview's."""
        for image in self.images.values():
            bpy.data.images.remove(image)
        self.images, self.rewired, self.pointed = {}, [], []

    def take_back(self) -> None:
        """Leave the objects as they were before the first snapshot."""
        for node, image in self.pointed:
            node.image = image
        for obj in self.rewired:
            apply.remove_bake(obj, shading_only=True)
        self.release()
