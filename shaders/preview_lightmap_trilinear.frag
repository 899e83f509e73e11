#version 430
// Preview shading: the object's lightmap sampled trilinearly (LINEAR_MIPMAP_LINEAR on the
// coverage-aware mip chain) is the outgoing radiance B ("combined"), or the light H arriving
// ("light"), shown as B = E + rho H with the surface's emission and reflectance.

#include "bindings"

in vec2 uv;
flat in int surface;

layout(binding = TEXTURE_LIGHTMAP) uniform sampler2D lightmap;
layout(std430, binding = STORAGE_SURFACE_REFLECTANCE) readonly buffer Reflectance { vec4 reflectance[]; };
layout(std430, binding = STORAGE_SURFACE_EMISSION) readonly buffer Emission { vec4 emission[]; };
uniform int shows_light;  // 1: the lightmap holds H

layout(location = 0) out vec4 out_radiance;  // linear radiance, alpha 1 where drawn
layout(location = 1) out int out_surface;    // surface index + 1, 0 for the background

void main() {
    vec3 value = texture(lightmap, uv).rgb;
    if (shows_light != 0) {
        value = emission[surface].rgb + reflectance[surface].rgb * value;
    }
    out_radiance = vec4(value, 1.0);
    out_surface = surface + 1;
}
