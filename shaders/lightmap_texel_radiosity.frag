#version 430
// Radiosity of one lightmap texel from the patch whose UV footprint holds it.
//
// Inside test and coverage work on the texel centre and the texel square
// (separating axes), not on GL's rasterization rules, so a texel a patch only
// grazes is still written (at depth 0.5 + distance, the value at its nearest point) while a texel whose centre lies
// in another patch keeps that patch's value (depth 0 wins). The value is the
// bilinear interpolation of the patch's lattice: element centres plus border
// points whose values were averaged with the neighbouring patches (CPU side),
// which makes the map continuous across shared edges.

#include "bindings"

flat in int patch_id;

uniform int elements;  // S: elements per patch side (1 for one value per patch)

layout(std430, binding = STORAGE_LATTICE_CORNERS) readonly buffer PatchCorners { vec4 corners[]; };  // 2 per patch: c0 c1, c2 c3 (texels)
layout(std430, binding = STORAGE_LATTICE_VALUES) readonly buffer Lattice { vec4 lattice[]; };  // (S+2)^2 per patch, rows of t

layout(location = 0) out vec4 out_radiance;  // rgb, 1
layout(location = 1) out int out_patch;      // patch + 1 if the centre is inside, -(patch + 1) if only touched

float cross2(vec2 a, vec2 b) { return a.x * b.y - a.y * b.x; }

// Patch parameters (s, t) of a UV point p on the patch, where
// p = a (1-s)(1-t) + b s (1-t) + c s t + d (1-s) t. Of the two roots of the
// quadratic in t, the one whose (s, t) lies in (or nearest to) the unit square.
float s_at(float t, vec2 e, vec2 f, vec2 g, vec2 h) {
    vec2 along = e + g * t;
    return dot(h - f * t, along) / max(dot(along, along), 1e-20);  // at a triangle's apex any s will do
}

float beyond_unit_square(vec2 st) {
    return max(max(-st.x, st.x - 1.0), max(-st.y, st.y - 1.0));
}

vec2 inverse_bilinear(vec2 p, vec2 a, vec2 b, vec2 c, vec2 d) {
    vec2 e = b - a, f = d - a, g = a - b + c - d, h = p - a;
    float k2 = cross2(g, f);
    float k1 = cross2(e, f) + cross2(h, g);
    float k0 = cross2(h, e);
    vec2 st;
    if (dot(c - d, c - d) <= 1e-12 * dot(e, e)) {
        // A triangle patch (d == c): p - a = s (1-t) e + t f is affine in (s (1-t), t). The
        // quadratic below would carry the spurious root t = 1 (the collapsed edge) here.
        float area = cross2(e, f);
        float t = cross2(e, h) / area;
        st = vec2(cross2(h, f) / area / max(1.0 - t, 1e-6), t);
    } else if (abs(k2) <= 1e-6 * abs(k1)) {
        float t = -k0 / k1;  // a parallelogram: the map is affine
        st = vec2(s_at(t, e, f, g, h), t);
    } else {
        float root = sqrt(max(k1 * k1 - 4.0 * k0 * k2, 0.0));
        float q = -0.5 * (k1 + (k1 >= 0.0 ? root : -root));  // the cancellation-free pair of roots
        float t1 = q / k2;
        float t2 = abs(q) > 0.0 ? k0 / q : t1;
        vec2 st1 = vec2(s_at(t1, e, f, g, h), t1), st2 = vec2(s_at(t2, e, f, g, h), t2);
        st = beyond_unit_square(st1) <= beyond_unit_square(st2) ? st1 : st2;
    }
    return clamp(st, 0.0, 1.0);
}

vec2 nearest_on_segment(vec2 p, vec2 a, vec2 b) {
    vec2 ab = b - a;
    return a + ab * clamp(dot(p - a, ab) / max(dot(ab, ab), 1e-20), 0.0, 1.0);
}

// Parameter -> lattice coordinate: border point 0, element centres 1..S, border point S+1.
float lattice_coordinate(float s) {
    float half_element = 0.5 / float(elements);
    if (s < half_element) return s / half_element;
    if (s > 1.0 - half_element) return float(elements + 1) - (1.0 - s) / half_element;
    return s * float(elements) + 0.5;
}

vec3 lattice_value(int base, int x, int y) {
    return lattice[base + y * (elements + 2) + x].rgb;
}

void main() {
    vec2 p = gl_FragCoord.xy;  // texel centre, in texels
    vec2 c[4] = vec2[4](corners[2 * patch_id].xy, corners[2 * patch_id].zw,
                        corners[2 * patch_id + 1].xy, corners[2 * patch_id + 1].zw);

    float twice_area = 0.0;
    for (int k = 0; k < 4; ++k) twice_area += cross2(c[k], c[(k + 1) % 4]);
    if (abs(twice_area) < 1e-8) discard;  // a face collapsed in UV space owns no texel (and has no inverse)
    float orientation = twice_area >= 0.0 ? 1.0 : -1.0;  // mirrored UVs wind clockwise

    // Largest signed distance of the centre outside an edge, and the separating-axis
    // test of the texel square (half-width 0.5) against the convex footprint.
    float outside = -1e30;
    bool separated = false;
    vec2 low = min(min(c[0], c[1]), min(c[2], c[3]));
    vec2 high = max(max(c[0], c[1]), max(c[2], c[3]));
    separated = any(lessThan(p + 0.5, low)) || any(greaterThan(p - 0.5, high));
    for (int k = 0; k < 4; ++k) {
        vec2 edge = c[(k + 1) % 4] - c[k];
        float len = length(edge);
        if (len < 1e-7) continue;  // the collapsed edge of a triangle patch
        vec2 normal = orientation * vec2(edge.y, -edge.x) / len;
        float distance = dot(p - c[k], normal);
        outside = max(outside, distance);
        separated = separated || distance > 0.5 * (abs(normal.x) + abs(normal.y));
    }
    if (separated) discard;

    bool inside = outside <= 0.0;
    vec2 q = p;  // a grazed texel takes the value of the footprint's nearest point
    if (!inside) {
        float best = 1e30;
        for (int k = 0; k < 4; ++k) {
            vec2 candidate = nearest_on_segment(p, c[k], c[(k + 1) % 4]);
            float d2 = dot(candidate - p, candidate - p);
            if (d2 < best) { best = d2; q = candidate; }
        }
    }
    vec2 st = inverse_bilinear(q, c[0], c[1], c[2], c[3]);
    float x = lattice_coordinate(st.x), y = lattice_coordinate(st.y);
    int x0 = min(int(x), elements), y0 = min(int(y), elements);
    float fx = x - float(x0), fy = y - float(y0);
    int base = patch_id * (elements + 2) * (elements + 2);
    vec3 value = mix(mix(lattice_value(base, x0, y0), lattice_value(base, x0 + 1, y0), fx),
                     mix(lattice_value(base, x0, y0 + 1), lattice_value(base, x0 + 1, y0 + 1), fx), fy);

    // Nearest footprint wins a grazed texel (Euclidean distance: the edge-line distance
    // underestimates it beside a vertex, where a patch touching only by that vertex would win).
    gl_FragDepth = inside ? 0.0 : 0.5 + 0.2 * clamp(distance(p, q), 0.0, 2.0);
    out_radiance = vec4(value, 1.0);
    out_patch = inside ? patch_id + 1 : -(patch_id + 1);
}
