#version 430
#include "bindings"
#include "opacity"
flat in uint item;
in float view_depth;
uniform float near;
uniform float far;
uniform uint back_item;
out uint out_item;
#if OPACITY
in vec2 opacity_uv;
flat in ivec4 opacity_rect;
#endif

#if LOOKUP
flat in uvec4 unit_cuts;   // the unit's record (hemicube_item_buffer.vert): cuts s offset, count, t offset, count;
flat in uvec4 unit_bins;   // bins likewise; (table offset, map, g); (e, f) of a skewed quad's map
flat in uvec4 unit_table;
flat in vec4 unit_ef;
flat in uint seen_from_front;
in vec2 surface_st;  // (s, t) on a parallelogram; on a skewed quad the point in its plane; on a grid
                    // triangle its barycentric weights (w1, w2)

// Units drawn once (visibility/item_geometry.py: quad surfaces, grid triangles): the cut parameters; per
// bin the cut at or below its start; the patch tables; each front's back twin.
layout(std430, binding = STORAGE_LOOKUP_CUTS) readonly buffer Cuts { float cut[]; };
layout(std430, binding = STORAGE_LOOKUP_BINS) readonly buffer Bins { uint bin_cut[]; };
layout(std430, binding = STORAGE_LOOKUP_TABLE) readonly buffer Table { uint table[]; };
layout(std430, binding = STORAGE_LOOKUP_TWINS) readonly buffer Twins { int twin[]; };

const uint EMPTY_CELL = 0xFFFFFFFFu;
const uint SKEWED_QUAD = 1u;     // a record's map (visibility/item_geometry.py): 0 a parallelogram, whose
const uint GRID_TRIANGLE = 2u;   // (s, t) the vertices carry; 1 a skewed quad; 2 a grid triangle; 3 no
const uint OWN_TRIANGLES = 3u;   // lookup (a patch's own triangles)

// index i of the cell [cut[first + i], cut[first + i + 1]) holding x: the cut at or below the start of
// x's uniform bin, or the next one (a bin holds at most one cut inside it)
uint cell_of(float x, uint first, uint count, uint first_bin, uint bins) {
    uint b = uint(clamp(int(x * float(bins)), 0, int(bins) - 1));
    uint i = bin_cut[first_bin + b];
    if (i + 2u < count && cut[first + i + 1u] <= x) i += 1u;
    return i;
}

float cross2(vec2 a, vec2 b) {
    return a.x * b.y - a.y * b.x;
}

// (s, t) of the point p of a convex quad p(s, t) = e s + f t + g s t (plane coordinates, corner 0 at
// the origin, diagonal 1): v solves k2 v^2 + k1 v + k0 = 0, both roots taken stably (a parallelogram
// has k2 = 0 and the first root only), the one in [0, 1]; then s from the larger component.
vec2 inverse_bilinear(vec2 p, vec2 e, vec2 f, vec2 g) {
    float k2 = cross2(g, f);
    float k1 = cross2(e, f) + cross2(p, g);
    float k0 = cross2(p, e);
    float w = sqrt(max(k1 * k1 - 4.0 * k0 * k2, 0.0));
    float q = -0.5 * (k1 + (k1 >= 0.0 ? w : -w));
    float v = k0 / q;
    float other = q / k2;
    if (abs(other - clamp(other, 0.0, 1.0)) < abs(v - clamp(v, 0.0, 1.0))) v = other;
    vec2 d = e + g * v;
    float s = abs(d.x) >= abs(d.y) ? (p.x - f.x * v) / d.x : (p.y - f.y * v) / d.y;
    return vec2(s, v);
}

#endif

void main() {
#if OPACITY
    if (transparent_at(opacity_uv, opacity_rect)) {
        discard;
    }
#endif
    out_item = item;
#if LOOKUP
    if (unit_table.y != OWN_TRIANGLES) {
        vec2 st = surface_st;
        if (unit_table.y == SKEWED_QUAD) {
            st = inverse_bilinear(surface_st, unit_ef.xy, unit_ef.zw, uintBitsToFloat(unit_table.zw));
        } else if (unit_table.y == GRID_TRIANGLE) {  // barycentric (w1, w2) -> (w1 / (1 - w2), w2)
            st = vec2(surface_st.x / max(1.0 - surface_st.y, 1e-30), surface_st.y);
        }
        uint i = cell_of(st.x, unit_cuts.x, unit_cuts.y, unit_bins.x, unit_bins.y);
        uint j = cell_of(st.y, unit_cuts.z, unit_cuts.w, unit_bins.z, unit_bins.w);
        uint patch_id = table[unit_table.x + j * (unit_cuts.y - 1u) + i];
        if (patch_id == EMPTY_CELL) discard;
        out_item = seen_from_front != 0u ? patch_id + 1u
#if BACKS_HIDE
                 : (twin[patch_id] >= 0 ? uint(twin[patch_id]) + 1u : (patch_id + 1u) | 0x80000000u);
#else
                 : (twin[patch_id] >= 0 ? uint(twin[patch_id]) + 1u : back_item);
#endif
    }
#endif
    gl_FragDepth = clamp(log(view_depth / near) / log(far / near), 0.0, 1.0);
}
