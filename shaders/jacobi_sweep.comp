#version 430
// One Jacobi sweep of (I - diag(rho) F) B = E for all three channels:
//   B_new[i] = E[i] + rho[i] * sum_j F[i][j] B_old[j]
// Branch-free as in the dissertation's Algorithm 5 (rows past the end are
// clamped and their writes land in a padding slot). Each invocation also folds
// its largest change and largest value into two atomics (float bits of
// non-negative numbers order like unsigned integers), read back every k sweeps.
#include "bindings"
layout(local_size_x = 64) in;

layout(std430, binding = STORAGE_FORM_FACTORS) readonly buffer FormFactors { float form_factor[]; };
layout(std430, binding = STORAGE_JACOBI_EMISSION) readonly buffer Emission { vec4 emission[]; };
layout(std430, binding = STORAGE_JACOBI_REFLECTANCE) readonly buffer Reflectance { vec4 reflectance[]; };
layout(std430, binding = STORAGE_RADIOSITY_OLD) readonly buffer Old { vec4 radiosity_old[]; };
layout(std430, binding = STORAGE_RADIOSITY_NEW) writeonly buffer New { vec4 radiosity_new[]; };
layout(std430, binding = STORAGE_CONVERGENCE) buffer Convergence { uint max_change_bits; uint max_value_bits; };

uniform int patch_count;

void main() {
    int i = int(gl_GlobalInvocationID.x);
    int row = min(i, patch_count - 1);
    // Two partial sums (even and odd columns) halve the rounding error's growth.
    vec4 sum_even = vec4(0.0);
    vec4 sum_odd = vec4(0.0);
    int base = row * patch_count;
    int j = 0;
    for (; j + 1 < patch_count; j += 2) {
        sum_even += form_factor[base + j] * radiosity_old[j];
        sum_odd += form_factor[base + j + 1] * radiosity_old[j + 1];
    }
    for (; j < patch_count; ++j) {
        sum_even += form_factor[base + j] * radiosity_old[j];
    }
    vec4 value = emission[row] + reflectance[row] * (sum_even + sum_odd);
    vec4 change = abs(value - radiosity_old[row]);
    // invocations past the end write to the padding slot at patch_count and fold zeros
    float in_range = float(i < patch_count);
    radiosity_new[min(i, patch_count)] = value;
    atomicMax(max_change_bits, floatBitsToUint(in_range * max(max(change.r, change.g), change.b)));
    atomicMax(max_value_bits, floatBitsToUint(in_range * max(max(value.r, value.g), value.b)));
}
