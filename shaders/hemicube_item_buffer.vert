#version 430
// Hemi-cube item buffer: draws every patch into one face of one hemi-cube.
// One instance = one face of one patch's hemi-cube; its tile in the atlas is
// kept apart from the others by clip distances, so a batch of hemi-cubes is a
// single instanced draw. A flat quad surface or a grid triangle of many patches
// is drawn once: the fragment shader finds the patch under each pixel (visibility/item_geometry.py;
// LOOKUP 0 compiles a variant without it, for atlases that draw every patch).

in vec3 in_position;
in vec3 in_normal;      // the triangle's front normal
in ivec2 in_item;       // the front patch's id, and its back patch (-1 when its back is not simulated)
#if LOOKUP
in vec2 in_st;          // the unit's parameters at this corner (visibility/item_geometry.py)
in uvec4 in_cuts;       // the unit's record (item_geometry.unit_record), the same at its every vertex:
in uvec4 in_bins;       // cuts' and bins' offsets and counts, (table offset, map, g), (e, f); map
in uvec4 in_table;      // OWN_TRIANGLES for a patch drawn by its own triangles
in vec4 in_ef;
#endif

#if OPACITY
in vec2 in_opacity_uv;  // texture UVs of an alpha-cut surface (include/opacity.glsl)
in ivec4 in_opacity_rect;
#endif

in vec3 in_eye;         // per instance: hemi-cube centre
in vec3 in_right;       // face axes: right, up, forward (world space)
in vec3 in_up;
in vec3 in_forward;
in vec4 in_tile;        // tile rectangle in atlas NDC: x0, y0, x1, y1
in float in_up_min;     // -1 for the top face, 0 for the half side faces

const float GRAZING = 1e-3;  // sin^2 of it: the form factor of the band it drops, 1e-6

uniform float near;
uniform float far;
uniform uint back_item;  // what the back of a patch writes: it hides the sky but receives nothing

flat out uint item;
#if LOOKUP
flat out uvec4 unit_cuts;  // the record, flat: no fragment reads it from memory
flat out uvec4 unit_bins;
flat out uvec4 unit_table;
flat out vec4 unit_ef;
flat out uint seen_from_front;
out vec2 surface_st;    // affine over each triangle drawn (parameters, plane coordinates, weights): interpolated exactly
#endif
#if OPACITY
out vec2 opacity_uv;
flat out ivec4 opacity_rect;
#endif
out float view_depth;   // c: distance along the face's axis (linear in the triangle: interpolates exactly)
out float gl_ClipDistance[5];

void main() {
    vec3 d = in_position - in_eye;
    float a = dot(d, in_right);
    float b = dot(d, in_up);
    float c = dot(d, in_forward);

    // Keep only this face's frustum: |a| <= c, up_min c <= b <= c, c >= near.
    gl_ClipDistance[0] = c - a;
    gl_ClipDistance[1] = c + a;
    gl_ClipDistance[2] = c - b;
    gl_ClipDistance[3] = b - in_up_min * c;
    // c >= near, and above the horizon by more than GRAZING (radians, about): the receiver's own
    // plane (its surface, its back twin) lies at c ~ 0 and must never be seen, however near.
    gl_ClipDistance[4] = c - max(near, GRAZING * length(d));

    // Face coordinates (a/c, b/c) mapped to the tile, written homogeneously in c
    // so perspective-correct rasterization still holds.
    float x = in_tile.x * c + 0.5 * (a + c) * (in_tile.z - in_tile.x);
    float y = in_tile.y * c + (b - in_up_min * c) / (1.0 - in_up_min) * (in_tile.w - in_tile.y);
    // Depth is written per fragment as log(c / near) / log(far / near): the same relative precision
    // at every distance, so `near` can be far below the 4 mm between an emitter and a ceiling
    // (a projective depth would clip them apart or lose the far walls' order).
    view_depth = c;
    gl_Position = vec4(x, y, 0.0, c);
#if OPACITY
    opacity_uv = in_opacity_uv;
    opacity_rect = in_opacity_rect;
#endif

    // Item 0 means nothing is seen (sky); a back is its twin patch, or (single-sided) its own item.
    bool front = dot(in_eye - in_position, in_normal) > 0.0;
#if LOOKUP
    seen_from_front = front ? 1u : 0u;
    unit_cuts = in_cuts;
    unit_bins = in_bins;
    unit_table = in_table;
    unit_ef = in_ef;
    surface_st = in_st;
#endif
#if BACKS_HIDE
    // a lookup's buffer: an unsimulated back is its id with the BACK_OF bit (include/shot.glsl): it hides
    uint unsimulated_back = (uint(in_item.x) + 1u) | 0x80000000u;
#else
    uint unsimulated_back = back_item;  // the form factors' last column
#endif
    item = front ? uint(in_item.x) + 1u : (in_item.y >= 0 ? uint(in_item.y) + 1u : unsimulated_back);
}
