#version 430
// Preview shading: the object's lightmap is the outgoing radiance, sampled
// trilinearly (LINEAR_MIPMAP_LINEAR on the coverage-aware mip chain).

#include "bindings"

in vec2 uv;
flat in int surface;

layout(binding = TEXTURE_LIGHTMAP) uniform sampler2D lightmap;

layout(location = 0) out vec4 out_radiance;  // linear radiance, alpha 1 where drawn
layout(location = 1) out int out_surface;    // surface index + 1, 0 for the background

void main() {
    out_radiance = vec4(texture(lightmap, uv).rgb, 1.0);
    out_surface = surface + 1;
}
