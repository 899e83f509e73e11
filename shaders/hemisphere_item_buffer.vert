#version 430
// Item buffer of a hemispherical projection: the vertex stage only passes the
// patch corners on; the geometry stage tessellates and projects them.
in vec3 in_position;
in uint in_patch;

out vec3 v_position;
flat out uint v_patch;

void main() {
    v_position = in_position;
    v_patch = in_patch;
}
