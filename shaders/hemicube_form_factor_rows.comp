#version 430
// Sums the delta form factors of the pixels that show each patch: row i of F
// for every hemi-cube tile of the batch. Weights are fixed point (2^31 = 1) so
// integer atomics make the sums exact and order-independent.
#include "bindings"
layout(local_size_x = 16, local_size_y = 16, local_size_z = 1) in;

layout(binding = TEXTURE_ITEM_BUFFER) uniform usampler2D item_buffer;
layout(std430, binding = STORAGE_DELTA_FORM_FACTORS) readonly buffer DeltaFormFactors { uint delta_form_factor[]; };
layout(std430, binding = STORAGE_FORM_FACTOR_ROWS) buffer Rows { uint row[]; };

uniform ivec2 tile_size;
uniform int tiles_per_row;
uniform int slots;
uniform int row_length;  // patches + 1: the last column sums the backs of patches

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    int slot = int(gl_GlobalInvocationID.z);
    if (pixel.x >= tile_size.x || pixel.y >= tile_size.y || slot >= slots) {
        return;
    }
    ivec2 origin = ivec2(slot % tiles_per_row, slot / tiles_per_row) * tile_size;
    uint item = texelFetch(item_buffer, origin + pixel, 0).r;
    if (item != 0u) {
        atomicAdd(row[slot * row_length + int(item) - 1], delta_form_factor[pixel.y * tile_size.x + pixel.x]);
    }
}
