// A point of a patch: the bilinear map of its four corners, counter-clockwise from the front
// (a triangle repeats its last corner), at parameters s, t in [0, 1].
vec3 bilinear_point(vec3 c0, vec3 c1, vec3 c2, vec3 c3, float s, float t) {
    return c0 * (1.0 - s) * (1.0 - t) + c1 * s * (1.0 - t) + c2 * s * t + c3 * (1.0 - s) * t;
}
