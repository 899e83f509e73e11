#version 430
// Chooses the next shooter: the patch of largest unshot power. The residual
// texture's mip level log2(S) holds each patch's mean area-weighted residual
// (one texel per tile), so power = area * mean. One work group scans all
// patches and reduces in shared memory; the result is a few numbers:
//   best power, best patch, its mean residual, the total unshot power (RGB),
//   the bilinear parameters (s, t) of its unshot power's centroid (where its
//   visibility map is rendered from: a patch half hidden under a box then
//   shoots from its lit part), and the energy sums of the previous shot
//   (which it resets).
#include "bindings"
layout(local_size_x = 256) in;

layout(binding = TEXTURE_RESIDUAL) uniform sampler2D residual;
uniform int level;
uniform int patch_count;
uniform int tiles_per_row;
uniform int elements;  // S

layout(std430, binding = STORAGE_PATCH_NORMAL_AREA) readonly buffer Patch { vec4 normal_area[]; };
layout(std430, binding = STORAGE_SHOT_ENERGY) buffer Energy { uint energy[4]; };
layout(std430, binding = STORAGE_SELECTION) writeonly buffer Result {  // read back as selection.SELECTION_DTYPE
    vec4 best;          // power score, patch index (as float bits), power centroid s, t
    vec4 best_residual; // mean residual radiosity of the best patch
    vec4 unshot;        // total unshot power per channel
    vec4 last_shot;     // previous shot: hit fraction, reflected fraction per channel
};

shared float best_score[256];
shared int best_index[256];
shared vec3 total[256];

void main() {
    int id = int(gl_LocalInvocationID.x);
    float score = -1.0;
    int index = -1;
    vec3 sum = vec3(0.0);
    for (int p = id; p < patch_count; p += 256) {
        vec3 mean = texelFetch(residual, ivec2(p % tiles_per_row, p / tiles_per_row), level).rgb;
        vec3 power = normal_area[p].w * mean;
        float s = power.r + power.g + power.b;
        if (s > score) {
            score = s;
            index = p;
        }
        sum += power;
    }
    best_score[id] = score;
    best_index[id] = index;
    total[id] = sum;
    barrier();
    for (int stride = 128; stride > 0; stride >>= 1) {
        if (id < stride) {
            float other = best_score[id + stride];
            int other_index = best_index[id + stride];
            if (other > best_score[id] || (other == best_score[id] && other_index >= 0 && other_index < best_index[id])) {
                best_score[id] = other;
                best_index[id] = other_index;
            }
            total[id] += total[id + stride];
        }
        barrier();
    }
    if (id == 0) {
        int p = max(best_index[0], 0);
        ivec2 origin = ivec2(p % tiles_per_row, p / tiles_per_row) * elements;
        vec3 power_centre = vec3(0.0);  // weighted s, t and weight
        for (int j = 0; j < elements; ++j) {
            for (int i = 0; i < elements; ++i) {
                vec3 r = texelFetch(residual, origin + ivec2(i, j), 0).rgb;
                float w = r.r + r.g + r.b;
                power_centre += w * vec3((float(i) + 0.5) / float(elements), (float(j) + 0.5) / float(elements), 1.0);
            }
        }
        vec2 st = power_centre.z > 0.0 ? power_centre.xy / power_centre.z : vec2(0.5);
        best = vec4(best_score[0], intBitsToFloat(best_index[0]), st);
        best_residual = texelFetch(residual, ivec2(p % tiles_per_row, p / tiles_per_row), level);
        unshot = vec4(total[0], 0.0);
        last_shot = vec4(energy[0], energy[1], energy[2], energy[3]) / SHOT_ENERGY_ONE;
        energy[0] = 0u;
        energy[1] = 0u;
        energy[2] = 0u;
        energy[3] = 0u;
    }
}
