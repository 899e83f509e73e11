#version 430
// Direct light at lightmap resolution: every texel receiver gathers the light of a batch of shots
// (lamps, suns, pieces of emitters),
//   H += sum_k B_k * F(texel point -> shooter k) * V,
// F and V as the shooting pass over elements computes them ("shot"). A texel carries the world
// point its centre shows (on the patch whose UV footprint holds it), its normal and its plane.
// The pieces of one emitting polygon (a group) are there for their visibility and their own
// radiosity B_k (an emitter's reflected light is not uniform): the group sends
//   F(texel -> whole polygon) * sum_k w_k V_k B_k / sum_k w_k,  w_k = F_disk(texel -> piece k),
// Lambert's exact factor once per polygon instead of once per piece (the costly part), exact
// wherever all or none of the pieces are seen and B is uniform, the penumbra weighted piece by piece.
// SHOT_COLUMNS 1: no light is gathered; each shot's factor F * V is written on its own, to column
// column_offset + k of the texel's row (hemicube/bright_columns.py: a column of F per shot).
#ifndef SHOT_COLUMNS
#define SHOT_COLUMNS 0
#endif
#include "bindings"
#include "constants"
#include "kernels"
#include "shot"
layout(local_size_x = 64) in;

layout(std430, binding = STORAGE_TEXEL_POSITION) readonly buffer Position { vec4 texel_position[]; };
layout(std430, binding = STORAGE_TEXEL_NORMAL) readonly buffer Normal { vec4 texel_normal[]; };
layout(std430, binding = STORAGE_TEXEL_PLANE) readonly buffer TexelPlane { int texel_plane[]; };
layout(std430, binding = STORAGE_TEXEL_LIGHT) buffer Light { vec4 texel_light[]; };

#if SHOT_COLUMNS
layout(std430, binding = STORAGE_TEXEL_COLUMNS) writeonly buffer Columns { float texel_columns[]; };
uniform int column_offset;
uniform int column_stride;
#endif

uniform int texel_count;
uniform int single_count;  // shots [0, single_count) are not pieces of a group
uniform int group_count;  // groups of pieces after them (group_corner: corners, .w of the first two: first, end)

void main() {
    // rows of work groups beyond 65535 (the portable limit per dimension) go to y
    int t = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
    if (t >= texel_count) {
        return;
    }
    vec3 x = texel_position[t].xyz;
    vec3 n = texel_normal[t].xyz;
    int plane = texel_plane[t];
    vec3 gathered = vec3(0.0);
    // the shots that are not pieces of a group come first (TexelReceivers orders them so), each
    // with its own factor; separate loops, so that no lane runs the other's code
    for (int k = 0; k < single_count; ++k) {
#if SHOT_COLUMNS
        texel_columns[t * column_stride + column_offset + k] = shot_factor(k, x, n, plane, 0.0);
#else
        gathered += shots[k].radiosity.rgb * shot_factor(k, x, n, plane, 0.0);
#endif
    }
    for (int g = 0; g < group_count; ++g) {
        int first = int(group_corner[4 * g].w), end = int(group_corner[4 * g + 1].w);
        vec3 seen = vec3(0.0);
        float weights = 0.0;
        for (int k = first; k < end; ++k) {
            float w = disk_form_factor(shots[k].eye_area.xyz, shots[k].normal_w.xyz, shots[k].eye_area.w, x, n);
            if (w > 0.0) {
                weights += w;
                seen += shot_sees(k, x, n, plane) ? w * shots[k].radiosity.rgb : vec3(0.0);
            }
        }
        vec3 polygon[4] = vec3[4](group_corner[4 * g].xyz, group_corner[4 * g + 1].xyz, group_corner[4 * g + 2].xyz,
                                  group_corner[4 * g + 3].xyz);
        gathered += polygon_form_factor(polygon, x, n) * (seen / max(weights, 1e-30));
    }
    if (gathered != vec3(0.0)) {
        texel_light[t] += vec4(gathered, 0.0);
    }
}
