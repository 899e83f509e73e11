#version 430
// Chooses the next shooter: the patch of largest unshot power. The residual
// texture's mip level log2(S) holds each patch's mean area-weighted residual
// (one texel per tile), so power = area * mean. One work group scans all
// patches and reduces in shared memory; the result is a few numbers:
//   best power, best patch, its mean residual, the total unshot power (RGB),
//   and the energy sums of the previous shot (which it resets).
layout(local_size_x = 256) in;

uniform sampler2D residual;
uniform int level;
uniform int patch_count;
uniform int tiles_per_row;

layout(std430, binding = 1) readonly buffer Patch { vec4 normal_area[]; };
layout(std430, binding = 4) buffer Energy { uint energy[4]; };
layout(std430, binding = 6) writeonly buffer Result {
    vec4 best;          // power score, patch index (as float bits), 0, 0
    vec4 best_residual; // mean residual radiosity of the best patch
    vec4 unshot;        // total unshot power per channel
    vec4 last_shot;     // previous shot: hit fraction, reflected fraction per channel
};

shared float best_score[256];
shared int best_index[256];
shared vec3 total[256];

const float ENERGY_ONE = 1073741824.0;  // 2^30, fixed point of the shot sums

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
        best = vec4(best_score[0], intBitsToFloat(best_index[0]), 0.0, 0.0);
        best_residual = texelFetch(residual, ivec2(p % tiles_per_row, p / tiles_per_row), level);
        unshot = vec4(total[0], 0.0);
        last_shot = vec4(energy[0], energy[1], energy[2], energy[3]) / ENERGY_ONE;
        energy[0] = 0u;
        energy[1] = 0u;
        energy[2] = 0u;
        energy[3] = 0u;
    }
}
