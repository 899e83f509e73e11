"""Write radiosity_addon/core/scene/scenes/cornell-box.json from the published Cornell box data.

Geometry: the Cornell Program of Computer Graphics measurements (millimetres),
converted to metres. The published left wall is 3 mm off-plane, so it is kept
exactly as two triangles. Faces are oriented so their fronts look into the
room (walls) or out of the blocks. Reflectances are the usual RGB reduction of
the measured spectra; the light is a 13 × 10.5 cm quad 5 mm below the ceiling.
"""

import json
from pathlib import Path

import numpy as np

WHITE, RED, GREEN = [0.725, 0.71, 0.68], [0.63, 0.065, 0.05], [0.14, 0.45, 0.091]
LIGHT_EMISSION, LIGHT_REFLECTANCE = [17.0, 12.0, 4.0], [0.78, 0.78, 0.78]
ROOM_CENTRE = np.array([278.0, 274.4, 279.6])

# (object, name, reflectance, emission, vertices in mm, inside point the front must face)
A, B, C, D = [552.8, 0, 0], [549.6, 0, 559.2], [556, 548.8, 559.2], [556, 548.8, 0]
ROOM = [
    ("floor", "floor", WHITE, [[552.8, 0, 0], [0, 0, 0], [0, 0, 559.2], [549.6, 0, 559.2]]),
    ("ceiling", "ceiling", WHITE, [[556, 548.8, 0], [556, 548.8, 559.2], [0, 548.8, 559.2], [0, 548.8, 0]]),
    ("back_wall", "back_wall", WHITE, [[549.6, 0, 559.2], [0, 0, 559.2], [0, 548.8, 559.2], [556, 548.8, 559.2]]),
    ("right_wall", "right_wall", GREEN, [[0, 0, 559.2], [0, 0, 0], [0, 548.8, 0], [0, 548.8, 559.2]]),
    ("left_wall", "left_wall_lower", RED, [A, B, C]),
    ("left_wall", "left_wall_upper", RED, [A, C, D]),
]
SHORT_BLOCK = [
    [[130, 165, 65], [82, 165, 225], [240, 165, 272], [290, 165, 114]],
    [[290, 0, 114], [290, 165, 114], [240, 165, 272], [240, 0, 272]],
    [[130, 0, 65], [130, 165, 65], [290, 165, 114], [290, 0, 114]],
    [[82, 0, 225], [82, 165, 225], [130, 165, 65], [130, 0, 65]],
    [[240, 0, 272], [240, 165, 272], [82, 165, 225], [82, 0, 225]],
]
TALL_BLOCK = [
    [[423, 330, 247], [265, 330, 296], [314, 330, 456], [472, 330, 406]],
    [[423, 0, 247], [423, 330, 247], [472, 330, 406], [472, 0, 406]],
    [[472, 0, 406], [472, 330, 406], [314, 330, 456], [314, 0, 456]],
    [[314, 0, 456], [314, 330, 456], [265, 330, 296], [265, 0, 296]],
    [[265, 0, 296], [265, 330, 296], [423, 330, 247], [423, 0, 247]],
]
BLOCK_FACE_NAMES = ["top", "side_a", "side_b", "side_c", "side_d"]
LIGHT_Y = 548.8 - 5.0
LIGHT = [[343, LIGHT_Y, 227], [343, LIGHT_Y, 332], [213, LIGHT_Y, 332], [213, LIGHT_Y, 227]]
# The official camera: eye (278, 273, -800) mm looking along +z, a 35 mm lens on a
# 25 mm square film: vertical field of view 2 atan(12.5 / 35) = 39.3°.
CAMERA = {"eye": [0.278, 0.273, -0.8], "forward": [0, 0, 1], "up": [0, 1, 0],
          "fov_y_degrees": round(2 * np.degrees(np.arctan(12.5 / 35)), 4)}


def oriented(vertices, faces_towards=None, faces_away_from=None):
    v = np.asarray(vertices, dtype=float)
    normal = np.cross(v[1] - v[0], v[2] - v[0])
    centroid = v.mean(axis=0)
    wrong = (
        np.dot(faces_towards - centroid, normal) < 0
        if faces_towards is not None
        else np.dot(centroid - faces_away_from, normal) < 0
    )
    return (v[::-1] if wrong else v) / 1000.0


def surface(obj, name, reflectance, emission, vertices):
    return {
        "name": name,
        "object": obj,
        "vertices": np.round(vertices, 6).tolist(),
        "reflectance": reflectance,
        "emission": emission,
    }


def main():
    surfaces = [surface(o, n, r, [0, 0, 0], oriented(v, faces_towards=ROOM_CENTRE)) for o, n, r, v in ROOM]
    for obj, faces in (("short_block", SHORT_BLOCK), ("tall_block", TALL_BLOCK)):
        centre = np.mean([p for f in faces for p in f], axis=0)
        centre[1] = faces[0][0][1] / 2  # half height: the top face's points would bias it upward
        for face_name, face in zip(BLOCK_FACE_NAMES, faces):
            surfaces.append(surface(obj, f"{obj}_{face_name}", WHITE, [0, 0, 0], oriented(face, faces_away_from=centre)))
    light = oriented(LIGHT, faces_towards=np.array([278.0, 0.0, 279.6]))
    surfaces.append(surface("light", "light", LIGHT_REFLECTANCE, LIGHT_EMISSION, light))
    out = Path(__file__).resolve().parents[1] / "radiosity_addon/core/scene/scenes/cornell-box.json"
    out.write_text(json.dumps({"camera": CAMERA, "surfaces": surfaces}, indent=1) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
