#version 430
#include "bindings"
flat in uint item;
in float view_depth;
uniform float near;
uniform float far;
uniform uint back_item;
out uint out_item;

#if LOOKUP
flat in int lookup;
flat in uint seen_from_front;
in vec2 surface_st;

// Surfaces drawn once (visibility/item_geometry.py): per surface its cut, bin and table offsets; the
// cut parameters; per bin the cut at or below its start; the patch tables; each front's back twin.
layout(std430, binding = STORAGE_LOOKUP_SURFACES) readonly buffer Surfaces { uvec4 surface_record[]; };
layout(std430, binding = STORAGE_LOOKUP_CUTS) readonly buffer Cuts { float cut[]; };
layout(std430, binding = STORAGE_LOOKUP_BINS) readonly buffer Bins { uint bin_cut[]; };
layout(std430, binding = STORAGE_LOOKUP_TABLE) readonly buffer Table { uint table[]; };
layout(std430, binding = STORAGE_LOOKUP_TWINS) readonly buffer Twins { int twin[]; };

const int RECORD = 3;  // uvec4s per surface
const uint EMPTY_CELL = 0xFFFFFFFFu;

// index i of the cell [cut[first + i], cut[first + i + 1]) holding x: the cut at or below the start of
// x's uniform bin, or the next one (a bin holds at most one cut inside it)
uint cell_of(float x, uint first, uint count, uint first_bin, uint bins) {
    uint b = uint(clamp(int(x * float(bins)), 0, int(bins) - 1));
    uint i = bin_cut[first_bin + b];
    if (i + 2u < count && cut[first + i + 1u] <= x) i += 1u;
    return i;
}

#endif

void main() {
    out_item = item;
#if LOOKUP
    if (lookup >= 0) {
        uvec4 cuts = surface_record[lookup * RECORD];
        uvec4 bins = surface_record[lookup * RECORD + 1];
        uint i = cell_of(surface_st.x, cuts.x, cuts.y, bins.x, bins.y);
        uint j = cell_of(surface_st.y, cuts.z, cuts.w, bins.z, bins.w);
        uint patch_id = table[surface_record[lookup * RECORD + 2].x + j * (cuts.y - 1u) + i];
        if (patch_id == EMPTY_CELL) discard;
        out_item = seen_from_front != 0u ? patch_id + 1u
                 : (twin[patch_id] >= 0 ? uint(twin[patch_id]) + 1u : back_item);
    }
#endif
    gl_FragDepth = clamp(log(view_depth / near) / log(far / near), 0.0, 1.0);
}
