"""The scene: surfaces, lamps and world as data; loading and validation; analysis; patches."""

from .analysis import SceneEffects, analyse, check_has_emitter, effects_for, emitter_count
from .lamps import Lamp
from .load import bundled_scene_names, load_scene, save_scene, scene_from_dict
from .model import FaceNames, MaterialMap, Scene, Surface
from .opacity import OpacityMaps
from .patches import Patches, split_patches, subdivide, surface_patches
from .validate import MAX_REFLECTANCE, polygon_faults

__all__ = ["FaceNames", "Lamp", "MAX_REFLECTANCE", "MaterialMap", "OpacityMaps", "Patches", "Scene", "SceneEffects", "Surface", "analyse", "bundled_scene_names",
           "check_has_emitter", "effects_for", "emitter_count", "load_scene", "polygon_faults", "save_scene",
           "scene_from_dict", "split_patches", "subdivide", "surface_patches"]
