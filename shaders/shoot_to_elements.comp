#version 430
// One shot: every receiving element gathers the light
//   dH = B_shooter_unshot * F(element point -> shooter) * V
// into its light (padded tile, gutter texels copied from the element they
// continue; B = E + rho H), and dB = rho_recv * dH into its residual (unpadded
// tile, weighted by element area so that mip means are power per patch area).
// The shooter's own residual is cleared.
// F and V come from the "shot" include: V is looked up in the shooter's hemispherical item
// buffer (the receiver looks for its own patch id, or any patch of its own plane, at its
// projected position within SEARCH_RADIUS texels: dissertation Algorithm 8), F is the exact
// point-to-polygon form factor (or the disk approximation), a lamp's or the sun's kernel, or
// the element's sky fraction (kind 3, shooter_radiosity: the world colour).
// Each work group also sums the shot's hit fraction and reflected fractions
// (per channel) of the shooter's power, added in fixed point to `energy`.
//
// Defines: ELEMENT_FORMAT, ELEMENTS, GUTTER, RECORD_VISIBILITY, INTERREFLECTION (0: nothing a
// receiver reflects can reach a reflector, so no residual), and those of "shot".
#include "bindings"
#include "constants"
#include "bilinear"
#include "shot"
layout(local_size_x = 64) in;

layout(ELEMENT_FORMAT, binding = IMAGE_LIGHT) uniform image2D light;  // rgba32f, or r32f for a grey scene
layout(ELEMENT_FORMAT, binding = IMAGE_RESIDUAL) uniform image2D residual;

layout(std430, binding = STORAGE_PATCH_CORNERS) readonly buffer Corners { vec4 corner[]; };  // 4 per patch
layout(std430, binding = STORAGE_PATCH_NORMAL_AREA) readonly buffer Patch { vec4 normal_area[]; };  // normal, area
layout(std430, binding = STORAGE_PATCH_REFLECTANCE) readonly buffer Reflectance { vec4 reflectance[]; };
layout(std430, binding = STORAGE_ELEMENT_WEIGHTS) readonly buffer ElementWeight { float element_weight[]; };  // a_e S^2 / A
layout(std430, binding = STORAGE_SHOT_ENERGY) buffer Energy { uint energy[4]; };
layout(std430, binding = STORAGE_SKY_FRACTION) readonly buffer Sky { float sky_fraction[]; };  // per element (kind 3)
#if RECORD_VISIBILITY
layout(std430, binding = STORAGE_RECORDED_VISIBILITY) writeonly buffer Visibility { float visibility_out[]; };
#endif

uniform int patch_count;
uniform int shooter_keeps_residual;  // 1: the shooter shot part of its residual (an emitter its emission)
uniform int padded_tiles_per_row;
uniform int residual_tiles_per_row;

shared vec4 partial[64];

void main() {
    const int per_patch = ELEMENTS * ELEMENTS;
    // rows of work groups beyond 65535 (the portable limit per dimension) go to y
    int e = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
    bool in_range = e < patch_count * per_patch;
    int element = min(e, patch_count * per_patch - 1);
    int p = element / per_patch;
    int j = (element % per_patch) / ELEMENTS;
    int i = element % ELEMENTS;
    vec4 shot = vec4(0.0);  // hit fraction, reflected fraction per channel

    if (in_range) {
        ivec2 residual_texel = ivec2((p % residual_tiles_per_row) * ELEMENTS + i,
                                     (p / residual_tiles_per_row) * ELEMENTS + j);
        if (p == shooter_patch) {
            // the shot is cleared from the shooter's residual: all of it, or only what it shot
            vec4 kept = shooter_keeps_residual != 0
                      ? imageLoad(residual, residual_texel) - vec4(element_weight[element] * shooter_radiosity, 0.0)
                      : vec4(0.0);
            imageStore(residual, residual_texel, max(kept, vec4(0.0)));
#if RECORD_VISIBILITY
            visibility_out[e] = 0.0;
#endif
        } else {
            float s = (float(i) + 0.5) / float(ELEMENTS);
            float t = (float(j) + 0.5) / float(ELEMENTS);
            vec3 x = bilinear_point(corner[4 * p].xyz, corner[4 * p + 1].xyz, corner[4 * p + 2].xyz,
                                    corner[4 * p + 3].xyz, s, t);
            vec3 n = normal_area[p].xyz;
            // the sky's visibility is already in each element's sky fraction
            float f = shot_factor(x, n, plane_of[p], shooter_kind == 3 ? sky_fraction[element] : 0.0);
#if RECORD_VISIBILITY
            visibility_out[e] = shooter_kind == 3 ? 1.0 : visibility(x, n, plane_of[p]);
#endif
            if (f > 0.0) {
                vec3 rho = reflectance[p].rgb;
                vec3 delta = rho * shooter_radiosity * f;
                float weight = element_weight[element];
#if INTERREFLECTION
                imageStore(residual, residual_texel, imageLoad(residual, residual_texel) + vec4(weight * delta, 0.0));
#endif
                ivec2 origin = ivec2(p % padded_tiles_per_row, p / padded_tiles_per_row) * (ELEMENTS + 2 * GUTTER)
                             + ivec2(GUTTER);
                vec4 value = imageLoad(light, origin + ivec2(i, j)) + vec4(shooter_radiosity * f, 0.0);
                // the element and the gutter texels that continue it (clamp to edge)
                for (int dy = -GUTTER; dy <= GUTTER; ++dy) {
                    for (int dx = -GUTTER; dx <= GUTTER; ++dx) {
                        ivec2 k = ivec2(i + dx, j + dy);
                        if (clamp(k, ivec2(0), ivec2(ELEMENTS - 1)) == ivec2(i, j)) {
                            imageStore(light, origin + k, value);
                        }
                    }
                }
                float hit = weight * normal_area[p].w / float(per_patch) * f / shooter_area;
                shot = vec4(hit, rho * hit);
            }
        }
    }

    int id = int(gl_LocalInvocationID.x);
    partial[id] = shot;
    barrier();
    for (int stride = 32; stride > 0; stride >>= 1) {
        if (id < stride) {
            partial[id] += partial[id + stride];
        }
        barrier();
    }
    if (id == 0 && partial[0].x > 0.0) {
        uvec4 fixed_point = uvec4(round(partial[0] * SHOT_ENERGY_ONE));
        atomicAdd(energy[0], fixed_point.x);
        atomicAdd(energy[1], fixed_point.y);
        atomicAdd(energy[2], fixed_point.z);
        atomicAdd(energy[3], fixed_point.w);
    }
}
