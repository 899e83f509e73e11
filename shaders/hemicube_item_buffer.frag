#version 430
#include "bindings"
flat in uint item;
flat in int lookup;
flat in uint seen_from_front;
in vec3 world_position;
in float view_depth;
uniform float near;
uniform float far;
uniform uint back_item;
out uint out_item;

// Surfaces drawn once (visibility/item_geometry.py): per surface its plane frame, corners and cut
// offsets; the cut parameters; the patch table; each front patch's back twin.
layout(std430, binding = STORAGE_LOOKUP_SURFACES) readonly buffer Surfaces { uvec4 surface_record[]; };
layout(std430, binding = STORAGE_LOOKUP_CUTS) readonly buffer Cuts { float cut[]; };
layout(std430, binding = STORAGE_LOOKUP_TABLE) readonly buffer Table { uint table_offset_and_patch[]; };
layout(std430, binding = STORAGE_LOOKUP_TWINS) readonly buffer Twins { int twin[]; };

const int RECORD = 6;  // vec4s per surface
const uint NO_PATCH = 0xFFFFFFFFu;

vec4 record(int k) { return uintBitsToFloat(surface_record[k]); }

float cross2(vec2 a, vec2 b) { return a.x * b.y - a.y * b.x; }

// (s, t) of point p in the planar quad q0 = 0, q1, q2, q3 (bilinear map, corners counter-clockwise):
// the root of the quadratic in t that goes to the linear solution as the quad becomes a parallelogram.
vec2 inverse_bilinear(vec2 p, vec2 q1, vec2 q2, vec2 q3) {
    vec2 e = q1, f = q3, g = q2 - q1 - q3, h = p;
    float k2 = cross2(g, f);
    float k1 = cross2(e, f) + cross2(h, g);
    float k0 = cross2(h, e);
    float root = sqrt(max(k1 * k1 - 4.0 * k0 * k2, 0.0));
    float q = -0.5 * (k1 + (k1 >= 0.0 ? root : -root));
    float t = q != 0.0 ? k0 / q : 0.0;
    if ((t < -1e-3 || t > 1.0 + 1e-3) && k2 != 0.0) t = q / k2;  // the other root
    vec2 along = e + g * t;
    float s = dot(h - f * t, along) / dot(along, along);
    return vec2(s, t);
}

// index i of the cell [cut[first + i], cut[first + i + 1]) holding x (clamped to the cells)
int cell_of(float x, uint first, uint count) {
    int low = 0, high = int(count) - 2;
    while (low < high) {
        int middle = (low + high + 1) >> 1;
        if (cut[first + uint(middle)] <= x) low = middle; else high = middle - 1;
    }
    return low;
}

void main() {
    out_item = item;
    if (lookup >= 0) {
        int base = lookup * RECORD;
        vec3 d = world_position - record(base).xyz;
        vec2 p = vec2(dot(d, record(base + 1).xyz), dot(d, record(base + 2).xyz));
        vec4 q12 = record(base + 3);
        vec2 st = inverse_bilinear(p, q12.xy, q12.zw, record(base + 4).xy);
        uvec4 cuts = surface_record[base + 5];
        int i = cell_of(st.x, cuts.x, cuts.y);
        int j = cell_of(st.y, cuts.z, cuts.w);
        uint table_start = table_offset_and_patch[lookup];
        uint patch_id = table_offset_and_patch[uint(table_start) + uint(j) * (cuts.y - 1u) + uint(i)];
        if (patch_id == NO_PATCH) discard;
        out_item = seen_from_front != 0u ? patch_id + 1u
                 : (twin[patch_id] >= 0 ? uint(twin[patch_id]) + 1u : back_item);
    }
    gl_FragDepth = clamp(log(view_depth / near) / log(far / near), 0.0, 1.0);
}
