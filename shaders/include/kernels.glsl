// Form-factor kernels from a receiving point x with normal n, shared by the shooting passes.

// Lambert's contour integral: F = 1/(2 pi) sum_k angle_k (n . unit(r_k x r_k+1)),
// the polygon (corners counter-clockwise seen from its front) first clipped to the receiver's
// front half-space.
float polygon_form_factor(vec3 polygon[4], vec3 x, vec3 n) {
    // a quad clipped by a plane keeps at most 5 corners, but for x on (or very near) the polygon's
    // own plane rounding can alternate the corners' signs (+ - + -): 2 corners and 4 crossings
    vec3 poly[6];
    int count = 0;
    for (int k = 0; k < 4; ++k) {
        vec3 a = polygon[k] - x;
        vec3 b = polygon[(k + 1) % 4] - x;
        float da = dot(a, n);
        float db = dot(b, n);
        if (da >= 0.0) {
            poly[count++] = a;
        }
        if ((da >= 0.0) != (db >= 0.0)) {
            poly[count++] = a + (b - a) * (da / (da - db));
        }
    }
    float sum = 0.0;
    for (int k = 0; k < count; ++k) {
        vec3 a = poly[k];
        vec3 b = poly[(k + 1) % count];
        float la = length(a);
        float lb = length(b);
        if (la < 1e-20 || lb < 1e-20) {
            continue;
        }
        vec3 c = cross(a / la, b / lb);
        float lc = length(c);
        if (lc > 1e-12) {
            sum += atan(lc, dot(a, b) / (la * lb)) * dot(n, c) / lc;
        }
    }
    // the shooter's corners run counter-clockwise seen from its front, i.e.
    // clockwise seen from a receiver in front of it: the sum is negative
    return max(-sum, 0.0) / (2.0 * PI);
}

// A point lamp: irradiance I cos / r^2, so the radiance-equivalent factor is cos / (pi r^2), times
// Cycles' spot cone (smoothstep over the blend band inside the cone's edge).
float point_lamp_factor(vec3 lamp, vec3 axis, float cos_half, float smooth_width, vec3 x, vec3 n) {
    vec3 d = x - lamp;
    float r2 = dot(d, d);
    vec3 u = d / sqrt(r2);
    float t = smooth_width > 0.0 ? clamp((dot(u, axis) - cos_half) / smooth_width, 0.0, 1.0)
                                 : float(dot(u, axis) > cos_half);
    return max(-dot(n, u), 0.0) * t * t * (3.0 - 2.0 * t) / (PI * r2);
}

// The disk approximation A cos cos / (pi r^2 + A) of a polygon of area A at `centre`.
float disk_form_factor(vec3 centre, vec3 normal, float area, vec3 x, vec3 n) {
    vec3 d = centre - x;
    float r2 = dot(d, d);
    float r = sqrt(r2);
    float cos_receiver = max(dot(n, d), 0.0) / r;
    float cos_shooter = max(-dot(normal, d), 0.0) / r;
    return area * cos_receiver * cos_shooter / (PI * r2 + area);
}
