#version 430
// Preview camera: world-space surface triangles to clip space, carrying the
// lightmap UVs and the surface index through to the fragment stage.

in vec3 in_position;
in vec2 in_uv;
in int in_surface;

uniform mat4 view_projection;

out vec2 uv;
flat out int surface;

void main() {
    uv = in_uv;
    surface = in_surface;
    gl_Position = view_projection * vec4(in_position, 1.0);
}
