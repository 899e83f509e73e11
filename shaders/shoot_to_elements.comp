#version 430
// A batch of shots: every receiving element gathers, for each shot k,
//   dH = B_k * F(element point -> shooter k) * V
// into its light (padded tile, gutter texels copied from the element they continue; B = E + rho H),
// and dB = rho_recv * dH into its residual (unpadded tile, weighted by element area so that mip
// means are power per patch area). Each shooter's own residual is cleared before what the batch's
// other shots send it is added (emitters' pieces shoot for no patch: emission is not in the residual).
// F and V come from the "shot" include (its records: shots[0 .. shot_count)).
// Each work group also sums, per shot, the hit fraction and the reflected fractions (per channel)
// of the shooter's power, added in fixed point to energy[4k .. 4k + 3].
//
// Defines: ELEMENT_FORMAT, ELEMENTS, GUTTER, RECORD_VISIBILITY (shot 0's), INTERREFLECTION (0:
// nothing a receiver reflects can reach a reflector, so no residual), and those of "shot".
#include "bindings"
#include "constants"
#include "bilinear"
#include "kernels"
#include "shot"
layout(local_size_x = 64) in;

layout(ELEMENT_FORMAT, binding = IMAGE_LIGHT) uniform image2D light;  // rgba32f, or r32f for a grey scene
layout(ELEMENT_FORMAT, binding = IMAGE_RESIDUAL) uniform image2D residual;

layout(std430, binding = STORAGE_PATCH_CORNERS) readonly buffer Corners { vec4 corner[]; };  // 4 per patch
layout(std430, binding = STORAGE_PATCH_NORMAL_AREA) readonly buffer Patch { vec4 normal_area[]; };  // normal, area
layout(std430, binding = STORAGE_PATCH_REFLECTANCE) readonly buffer Reflectance { vec4 reflectance[]; };
layout(std430, binding = STORAGE_ELEMENT_WEIGHTS) readonly buffer ElementWeight { float element_weight[]; };  // a_e S^2 / A
layout(std430, binding = STORAGE_SHOT_ENERGY) buffer Energy { uint energy[]; };  // 4 per shot
layout(std430, binding = STORAGE_SKY_FRACTION) readonly buffer Sky { float sky_fraction[]; };  // per element (kind 3)
#if RECORD_VISIBILITY
layout(std430, binding = STORAGE_RECORDED_VISIBILITY) writeonly buffer Visibility { float visibility_out[]; };
#endif

uniform int patch_count;
uniform int padded_tiles_per_row;
uniform int residual_tiles_per_row;

shared uint group_energy[4 * MAX_SHOTS];

void main() {
    const int per_patch = ELEMENTS * ELEMENTS;
    int id = int(gl_LocalInvocationID.x);
    for (int k = id; k < 4 * shot_count; k += 64) {
        group_energy[k] = 0u;
    }
    barrier();

    // rows of work groups beyond 65535 (the portable limit per dimension) go to y
    int e = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
    if (e < patch_count * per_patch) {
        int p = e / per_patch;
        int j = (e % per_patch) / ELEMENTS;
        int i = e % ELEMENTS;
        ivec2 residual_texel = ivec2((p % residual_tiles_per_row) * ELEMENTS + i,
                                     (p / residual_tiles_per_row) * ELEMENTS + j);
        float weight = element_weight[e];
        vec4 unshot = imageLoad(residual, residual_texel);
        vec3 gathered = vec3(0.0);  // light H from the whole batch
        float s = (float(i) + 0.5) / float(ELEMENTS);
        float t = (float(j) + 0.5) / float(ELEMENTS);
        vec3 x = bilinear_point(corner[4 * p].xyz, corner[4 * p + 1].xyz, corner[4 * p + 2].xyz,
                                corner[4 * p + 3].xyz, s, t);
        vec3 n = normal_area[p].xyz;
        vec3 rho = reflectance[p].rgb;
        int plane = plane_of[p].id.x;
        float share = weight * normal_area[p].w / float(per_patch);  // the element's area
#if RECORD_VISIBILITY
        visibility_out[e] = 0.0;
#endif
        for (int k = 0; k < shot_count; ++k) {
            int level = int(shots[k].extra.w + 0.5);
            // a cluster shoots all its members
            int shooter = level == 0 ? p : level < 4 ? plane_of[p].id[level] : plane_of[p].coarser_id[level - 4];
            if (int(shots[k].axis_y_patch.w) == shooter) {
                unshot = vec4(0.0);  // the shot leaves the shooter's residual
                continue;
            }
            int kind = int(shots[k].axis_x_kind.w);
            // the sky's visibility is already in each element's sky fraction
            float f = shot_factor(k, x, n, plane, HAS_KIND(3) && kind == 3 ? sky_fraction[e] : 0.0);
#if RECORD_VISIBILITY
            if (k == 0) {
                visibility_out[e] = kind == 3 ? 1.0 : float(shot_sees(0, x, n, plane));
            }
#endif
            if (f > 0.0) {
                gathered += shots[k].radiosity.rgb * f;
                float hit = kind == 0 ? share * f / shots[k].eye_area.w : 0.0;  // of the polygon's power
                if (hit > 0.0) {
                    uvec4 fixed_point = uvec4(round(vec4(hit, rho * hit) * SHOT_ENERGY_ONE));
                    atomicAdd(group_energy[4 * k], fixed_point.x);
                    atomicAdd(group_energy[4 * k + 1], fixed_point.y);
                    atomicAdd(group_energy[4 * k + 2], fixed_point.z);
                    atomicAdd(group_energy[4 * k + 3], fixed_point.w);
                }
            }
        }
#if INTERREFLECTION
        unshot += vec4(weight * rho * gathered, 0.0);
#endif
        imageStore(residual, residual_texel, unshot);
        if (gathered != vec3(0.0)) {
            ivec2 origin = ivec2(p % padded_tiles_per_row, p / padded_tiles_per_row) * (ELEMENTS + 2 * GUTTER)
                         + ivec2(GUTTER);
            vec4 value = imageLoad(light, origin + ivec2(i, j)) + vec4(gathered, 0.0);
            // the element and the gutter texels that continue it (clamp to edge)
            for (int dy = -GUTTER; dy <= GUTTER; ++dy) {
                for (int dx = -GUTTER; dx <= GUTTER; ++dx) {
                    ivec2 k = ivec2(i + dx, j + dy);
                    if (clamp(k, ivec2(0), ivec2(ELEMENTS - 1)) == ivec2(i, j)) {
                        imageStore(light, origin + k, value);
                    }
                }
            }
        }
    }

    barrier();
    for (int k = id; k < 4 * shot_count; k += 64) {
        if (group_energy[k] != 0u) {
            atomicAdd(energy[k], group_energy[k]);
        }
    }
}
