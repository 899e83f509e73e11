#version 430
// Tessellates one patch (its four corners arrive as a lines_adjacency
// primitive; triangles repeat their last corner) into TESSELLATION x
// TESSELLATION quads written as triangle strips (dissertation Algorithm 7),
// and projects every vertex hemispherically from the eye:
//   (x/|p|, y/|p|, depth linear in |p|), x, y, z in the eye's frame.
// A straight-edged triangle only approximates the curved image of a patch
// edge; tessellating makes the approximation close. TESSELLATION = 1 is the
// plain projection of Coombe et al. Fewer segments are used for patches that
// look small from the eye (SEGMENT_ANGLE radians each at most).
// Rows of the grid are shared among INVOCATIONS geometry shader invocations
// so that the output of each stays within portable limits.
#include "bilinear"
layout(lines_adjacency, invocations = INVOCATIONS) in;
layout(triangle_strip, max_vertices = MAX_VERTICES) out;

in vec3 v_position[];
flat in uint v_patch[];
flat in int v_twin[];
#if OPACITY
in vec2 v_opacity_uv[];
flat in ivec4 v_opacity_rect[];
out vec2 opacity_uv;  // interpolated like the position (include/opacity.glsl)
flat out ivec4 opacity_rect;
#endif

uniform vec3 eye;
uniform vec3 axis_x;
uniform vec3 axis_y;
uniform vec3 axis_z;      // the hemisphere's pole (the shooter's normal)
uniform float near;
uniform float far;
uniform int skip_patch;   // the shooter itself is not drawn (-1: draw all)
uniform float ortho_extent;  // > 0: orthographic along axis_z over this half-width (a sun)

flat out uint item;
out float distance;   // from the eye, for the lookup's occluder test
out float gl_ClipDistance[1];

vec3 corner(float s, float t) {
    return bilinear_point(v_position[0], v_position[1], v_position[2], v_position[3], s, t);
}

#if OPACITY
vec2 opacity_corner(float s, float t) {
    return mix(mix(v_opacity_uv[0], v_opacity_uv[1], s), mix(v_opacity_uv[3], v_opacity_uv[2], s), t);
}
#endif

void emit(vec3 position, uint id) {
    vec3 d = position - eye;
    vec3 q = vec3(dot(d, axis_x), dot(d, axis_y), dot(d, axis_z));
    distance = ortho_extent > 0.0 ? q.z : max(length(q), 1e-20);
    vec2 image = ortho_extent > 0.0 ? q.xy / ortho_extent : q.xy / distance;
    gl_Position = vec4(image, 2.0 * (distance - near) / (far - near) - 1.0, 1.0);
    gl_ClipDistance[0] = q.z;  // the front hemisphere only
    item = id;
    EmitVertex();
}

void main() {
    if (int(v_patch[0]) == skip_patch) {
        return;
    }
    float highest = -1.0;
    for (int k = 0; k < 4; ++k) {
        highest = max(highest, dot(v_position[k] - eye, axis_z));
    }
    if (highest <= 0.0) {
        return;  // wholly behind the eye's hemisphere
    }
    vec3 normal = cross(v_position[2] - v_position[0], v_position[3] - v_position[1]);
    // A back seen is its twin patch; a single-sided back occludes but receives nothing: its id with
    // the BACK_OF bit (include/shot.glsl), so a lookup knows what hides a receiver behind it.
    // An orthographic view (a sun) looks along its pole from everywhere: the eye point is not where
    // the rays come from (a wall the sun grazes would face away from it).
    vec3 toward_eye = ortho_extent > 0.0 ? -axis_z : eye - v_position[0];
    bool front = dot(toward_eye, normal) > 0.0;
    uint id = front ? v_patch[0] + 1u : (v_twin[0] >= 0 ? uint(v_twin[0]) + 1u : (v_patch[0] + 1u) | 0x80000000u);
    // Adaptive: as many segments per side as the patch's angular size needs
    // (a chord of SEGMENT_ANGLE radians strays ~angle^2/8 from the curved image).
    float extent = 0.0;
    for (int k = 0; k < 4; ++k) {
        vec3 a = normalize(v_position[k] - eye);
        for (int m = k + 1; m < 4; ++m) {
            extent = max(extent, acos(clamp(dot(a, normalize(v_position[m] - eye)), -1.0, 1.0)));
        }
    }
    int n = clamp(int(ceil(extent / SEGMENT_ANGLE)), 1, TESSELLATION);
    for (int j = gl_InvocationID; j < n; j += INVOCATIONS) {
        float t0 = float(j) / float(n);
        float t1 = float(j + 1) / float(n);
        for (int i = 0; i <= n; ++i) {
            float s = float(i) / float(n);
#if OPACITY
            opacity_rect = v_opacity_rect[0];
            opacity_uv = opacity_corner(s, t0);
#endif
            emit(corner(s, t0), id);
#if OPACITY
            opacity_rect = v_opacity_rect[0];
            opacity_uv = opacity_corner(s, t1);
#endif
            emit(corner(s, t1), id);
        }
        EndPrimitive();
    }
}
