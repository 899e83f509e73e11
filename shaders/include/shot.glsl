// One shot's geometry and the light it sends to a receiving point x with normal n on the plane
// `plane` (a surface side: patches of one plane cannot hide each other's points).
// Shared by the shooting pass over elements and the one over lightmap texels.
//
// Defines: KERNEL_EXACT (1: Lambert's exact polygon factor, 0: the disk approximation),
// SEARCH_RADIUS, OCCLUDER_MARGIN, OCCLUSION (0: nothing occludes, V = 1 for facing receivers).
// Kinds (shooter_kind): a polygon (a patch, an emitter piece, an area lamp piece) gives the form
// factor to it; a point lamp F = cos_recv / (pi r^2) times its spot falloff (shooter_radiosity:
// its radiant intensity); a sun F = cos_recv / pi (shooter_radiosity: its irradiance), looked up
// in an orthographic item buffer; the sky F = a receiver's sky fraction (given by the caller).

layout(binding = TEXTURE_ITEM_BUFFER) uniform usampler2D item_buffer;
layout(binding = TEXTURE_DISTANCE_MAP) uniform sampler2D distance_map;  // distance from the eye of what each item texel shows (0: nothing)
layout(std430, binding = STORAGE_PATCH_PLANE) readonly buffer Plane { int plane_of[]; };

uniform int item_resolution;
uniform int shooter_patch;          // its residual is cleared; -1: not a patch
uniform vec3 shooter_position;      // eye of the visibility map
uniform vec3 shooter_axis_x;
uniform vec3 shooter_axis_y;
uniform vec3 shooter_normal;
uniform vec3 shooter_polygon[4];    // corners, counter-clockwise from the front
uniform float shooter_area;
uniform vec3 shooter_radiosity;     // unshot radiosity being shot
uniform int shooter_kind;           // 0: patch polygon, 1: point lamp, 2: directional (sun), 3: sky
uniform vec3 light_direction;       // spot axis, or the sun's travel direction
uniform float spot_cos_half;        // cosine of half the spot cone (-1: all around)
uniform float spot_smooth;          // (1 - spot_cos_half) * blend: width of the soft edge
uniform float ortho_extent;         // > 0: the item buffer is orthographic over this half-width

float visibility(vec3 x, vec3 n, int plane) {
    vec3 d = x - shooter_position;
    if (dot(n, d) >= 0.0) {
        return 0.0;  // the receiver turns its back to the shooter
    }
    vec3 q = vec3(dot(d, shooter_axis_x), dot(d, shooter_axis_y), dot(d, shooter_normal));
    if (q.z <= 0.0) {
        return 0.0;  // behind the shooter
    }
#if !OCCLUSION
    return 1.0;
#endif
    float r = length(q);
    vec2 uv = (ortho_extent > 0.0 ? q.xy / ortho_extent : q.xy / r) * 0.5 + 0.5;
    ivec2 texel = clamp(ivec2(floor(uv * float(item_resolution))), ivec2(0), ivec2(item_resolution - 1));
    // A planar surface cannot hide its own points, so any patch of the receiver's plane
    // seen there counts (patch borders inside a surface are then no obstacle).
    uint centre = texelFetch(item_buffer, texel, 0).r;
    if (centre != 0u && plane_of[int(centre) - 1] == plane) {
        return 1.0;
    }
    // Optionally (OCCLUDER_MARGIN >= 0) the search is for rasterization gaps only, not
    // for peeking past occluders: when the own texel shows something clearly nearer,
    // the receiver is hidden.
    if (ortho_extent > 0.0) {
        r = q.z;  // the orthographic map's distances run along its axis
    }
    float seen = texelFetch(distance_map, texel, 0).r;
    if (OCCLUDER_MARGIN >= 0.0 && seen > 0.0 && seen < r * (1.0 - OCCLUDER_MARGIN)) {
        return 0.0;
    }
    bool found = false;
    for (int dy = -SEARCH_RADIUS; dy <= SEARCH_RADIUS; ++dy) {
        for (int dx = -SEARCH_RADIUS; dx <= SEARCH_RADIUS; ++dx) {
            ivec2 at = clamp(texel + ivec2(dx, dy), ivec2(0), ivec2(item_resolution - 1));
            uint item = texelFetch(item_buffer, at, 0).r;
            found = found || (item != 0u && plane_of[int(item) - 1] == plane);
        }
    }
    return found ? 1.0 : 0.0;
}

// Lambert's contour integral: F = 1/(2 pi) sum_k angle_k (n . unit(r_k x r_k+1)),
// the polygon first clipped to the receiver's front half-space.
float polygon_form_factor(vec3 x, vec3 n) {
    vec3 poly[5];
    int count = 0;
    for (int k = 0; k < 4; ++k) {
        vec3 a = shooter_polygon[k] - x;
        vec3 b = shooter_polygon[(k + 1) % 4] - x;
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

// A point lamp: irradiance I cos / r^2, so the radiance-equivalent factor is cos / (pi r^2).
float point_lamp_factor(vec3 x, vec3 n) {
    vec3 d = x - shooter_position;
    float r2 = dot(d, d);
    vec3 u = d / sqrt(r2);
    float t = spot_smooth > 0.0 ? clamp((dot(u, light_direction) - spot_cos_half) / spot_smooth, 0.0, 1.0)
                                : float(dot(u, light_direction) > spot_cos_half);
    return max(-dot(n, u), 0.0) * t * t * (3.0 - 2.0 * t) / (PI * r2);
}

float disk_form_factor(vec3 x, vec3 n) {
    vec3 d = shooter_position - x;
    float r2 = dot(d, d);
    float r = sqrt(r2);
    float cos_receiver = max(dot(n, d), 0.0) / r;
    float cos_shooter = max(-dot(shooter_normal, d), 0.0) / r;
    return shooter_area * cos_receiver * cos_shooter / (PI * r2 + shooter_area);
}

// F (the kernel) times V (the visibility map) of the shot at x; `sky` is the receiver's sky
// fraction (kind 3, whose visibility is in it already).
float shot_factor(vec3 x, vec3 n, int plane, float sky) {
    if (shooter_kind == 3) {
        return sky;
    }
    if (visibility(x, n, plane) <= 0.0) {
        return 0.0;
    }
    if (shooter_kind == 1) {
        return point_lamp_factor(x, n);
    }
    if (shooter_kind == 2) {
        return max(-dot(n, light_direction), 0.0) / PI;
    }
#if KERNEL_EXACT
    return polygon_form_factor(x, n);
#else
    return disk_form_factor(x, n);
#endif
}
