#version 430
// Direct light at lightmap resolution: every texel receiver gathers the light of a batch of shots
// (lamps, suns, pieces of emitters),
//   H += sum_k B_k * F(texel point -> shooter k) * V,
// F and V as the shooting pass over elements computes them ("shot"). A texel carries the world
// point its centre shows (on the patch whose UV footprint holds it), its normal and its plane.
#include "bindings"
#include "constants"
#include "kernels"
#include "shot"
layout(local_size_x = 64) in;

layout(std430, binding = STORAGE_TEXEL_POSITION) readonly buffer Position { vec4 texel_position[]; };
layout(std430, binding = STORAGE_TEXEL_NORMAL) readonly buffer Normal { vec4 texel_normal[]; };
layout(std430, binding = STORAGE_TEXEL_PLANE) readonly buffer TexelPlane { int texel_plane[]; };
layout(std430, binding = STORAGE_TEXEL_LIGHT) buffer Light { vec4 texel_light[]; };

uniform int texel_count;

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
    for (int k = 0; k < shot_count; ++k) {
        float f = shot_factor(k, x, n, plane, 0.0);
        gathered += shots[k].radiosity.rgb * f;
    }
    if (gathered != vec3(0.0)) {
        texel_light[t] += vec4(gathered, 0.0);
    }
}
