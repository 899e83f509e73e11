#version 430
// Item buffer of a hemispherical projection: the vertex stage only passes the
// patch corners on; the geometry stage tessellates and projects them.
in vec3 in_position;
in uint in_patch;  // a front patch
in int in_twin;    // its back patch, -1 when its back is not simulated

out vec3 v_position;
flat out uint v_patch;
flat out int v_twin;

void main() {
    v_position = in_position;
    v_patch = in_patch;
    v_twin = in_twin;
}
