#version 430
// Direct light at lightmap resolution: every texel receiver gathers the light of one shot (a
// lamp, a sun, a piece of an emitter),
//   H += B_shooter * F(texel point -> shooter) * V,
// F and V as the shooting pass over elements computes them ("shot"). A texel carries the world
// point its centre shows (on the patch whose UV footprint holds it), its normal and its plane.
#include "bindings"
#include "constants"
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
    float f = shot_factor(texel_position[t].xyz, texel_normal[t].xyz, texel_plane[t], 0.0);
    if (f > 0.0) {
        texel_light[t] += vec4(shooter_radiosity * f, 0.0);
    }
}
