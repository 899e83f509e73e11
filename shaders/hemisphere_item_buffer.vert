#version 430
// Item buffer of a hemispherical projection: the vertex stage only passes the
// patch corners on; the geometry stage tessellates and projects them.
in vec3 in_position;
in uint in_patch;  // a front patch
in int in_twin;    // its back patch, -1 when its back is not simulated
#if OPACITY
in vec2 in_opacity_uv;  // texture UVs of an alpha-cut surface (include/opacity.glsl)
in ivec4 in_opacity_rect;
out vec2 v_opacity_uv;
flat out ivec4 v_opacity_rect;
#endif

out vec3 v_position;
flat out uint v_patch;
flat out int v_twin;

void main() {
    v_position = in_position;
    v_patch = in_patch;
    v_twin = in_twin;
#if OPACITY
    v_opacity_uv = in_opacity_uv;
    v_opacity_rect = in_opacity_rect;
#endif
}
