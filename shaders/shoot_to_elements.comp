#version 430
// One shot: every receiving element gathers the light
//   dH = B_shooter_unshot * F(element point -> shooter) * V
// into its light (padded tile, gutter texels copied from the element they
// continue; B = E + rho H), and dB = rho_recv * dH into its residual (unpadded
// tile, weighted by element area so that mip means are power per patch area).
// The shooter's own residual is cleared.
// V is looked up in the shooter's hemispherical item buffer: the receiver
// looks for its own patch id (or any patch of its own planar surface) at its
// projected position, within SEARCH_RADIUS texels (dissertation Algorithm 8;
// 0 = the texel itself).
// F is the exact unoccluded point-to-polygon form factor (Lambert's contour
// integral over the shooter polygon clipped to the receiver's hemisphere) when
// KERNEL_EXACT is 1, else the disk approximation A cos cos / (pi r^2 + A).
// Each work group also sums the shot's hit fraction and reflected fractions
// (per channel) of the shooter's power, added in fixed point to `energy`.
//
// Lamps shoot too (shooter_kind): a point lamp gives F = cos_recv / (pi r^2) times
// its spot falloff (shooter_radiosity is then its radiant intensity), a sun
// F = cos_recv / pi (shooter_radiosity: its irradiance), looked up in an
// orthographic item buffer; the sky (kind 3) F = each element's unoccluded
// cosine-weighted fraction of its hemisphere (shooter_radiosity: the world colour).
//
// Defines: ELEMENT_FORMAT, ELEMENTS, GUTTER, KERNEL_EXACT, SEARCH_RADIUS, OCCLUDER_MARGIN, RECORD_VISIBILITY,
// OCCLUSION (0: the scene analysis proved nothing occludes, V = 1 for facing receivers),
// INTERREFLECTION (0: nothing a receiver reflects can reach a reflector, so no residual).
#include "bindings"
#include "constants"
#include "bilinear"
layout(local_size_x = 64) in;

layout(ELEMENT_FORMAT, binding = IMAGE_LIGHT) uniform image2D light;  // rgba32f, or r32f for a grey scene
layout(ELEMENT_FORMAT, binding = IMAGE_RESIDUAL) uniform image2D residual;
layout(binding = TEXTURE_ITEM_BUFFER) uniform usampler2D item_buffer;
layout(binding = TEXTURE_DISTANCE_MAP) uniform sampler2D distance_map;  // distance from the eye of what each item texel shows (0: nothing)

layout(std430, binding = STORAGE_PATCH_CORNERS) readonly buffer Corners { vec4 corner[]; };  // 4 per patch
layout(std430, binding = STORAGE_PATCH_NORMAL_AREA) readonly buffer Patch { vec4 normal_area[]; };  // normal, area
layout(std430, binding = STORAGE_PATCH_REFLECTANCE) readonly buffer Reflectance { vec4 reflectance[]; };
layout(std430, binding = STORAGE_ELEMENT_WEIGHTS) readonly buffer ElementWeight { float element_weight[]; };  // a_e S^2 / A
layout(std430, binding = STORAGE_SHOT_ENERGY) buffer Energy { uint energy[4]; };
layout(std430, binding = STORAGE_PATCH_PLANE) readonly buffer Plane { int plane_of[]; };  // patches of one planar surface share it
layout(std430, binding = STORAGE_SKY_FRACTION) readonly buffer Sky { float sky_fraction[]; };  // per element (kind 3)
#if RECORD_VISIBILITY
layout(std430, binding = STORAGE_RECORDED_VISIBILITY) writeonly buffer Visibility { float visibility_out[]; };
#endif

uniform int patch_count;
uniform int padded_tiles_per_row;
uniform int residual_tiles_per_row;
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

shared vec4 partial[64];

float visibility(vec3 x, vec3 n, int p) {
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
    int plane = plane_of[p];
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

void main() {
    const int per_patch = ELEMENTS * ELEMENTS;
    // rows of work groups beyond 65535 (the portable limit per dimension) go to y
    int e = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
    bool in_range = e < patch_count * per_patch;
    int element = min(e, patch_count * per_patch - 1);
    int p = element / per_patch;
    int j = (element % per_patch) / ELEMENTS;
    int i = element % ELEMENTS;
    vec4 shot = vec4(0.0);  // hit fraction, reflected fraction per channel

    if (in_range) {
        ivec2 residual_texel = ivec2((p % residual_tiles_per_row) * ELEMENTS + i,
                                     (p / residual_tiles_per_row) * ELEMENTS + j);
        if (p == shooter_patch) {
            imageStore(residual, residual_texel, vec4(0.0));
#if RECORD_VISIBILITY
            visibility_out[e] = 0.0;
#endif
        } else {
            float s = (float(i) + 0.5) / float(ELEMENTS);
            float t = (float(j) + 0.5) / float(ELEMENTS);
            vec3 x = bilinear_point(corner[4 * p].xyz, corner[4 * p + 1].xyz, corner[4 * p + 2].xyz,
                                    corner[4 * p + 3].xyz, s, t);
            vec3 n = normal_area[p].xyz;
            // the sky's visibility is already in each element's sky fraction
            float v = shooter_kind == 3 ? 1.0 : visibility(x, n, p);
#if RECORD_VISIBILITY
            visibility_out[e] = v;
#endif
            float f = 0.0;
            if (v > 0.0) {
                if (shooter_kind == 1) {
                    f = point_lamp_factor(x, n);
                } else if (shooter_kind == 2) {
                    f = max(-dot(n, light_direction), 0.0) / PI;
                } else if (shooter_kind == 3) {
                    f = sky_fraction[element];
                } else {
#if KERNEL_EXACT
                    f = polygon_form_factor(x, n);
#else
                    f = disk_form_factor(x, n);
#endif
                }
            }
            if (f > 0.0) {
                vec3 rho = reflectance[p].rgb;
                vec3 delta = rho * shooter_radiosity * f;
                float weight = element_weight[element];
#if INTERREFLECTION
                imageStore(residual, residual_texel, imageLoad(residual, residual_texel) + vec4(weight * delta, 0.0));
#endif
                ivec2 origin = ivec2(p % padded_tiles_per_row, p / padded_tiles_per_row) * (ELEMENTS + 2 * GUTTER)
                             + ivec2(GUTTER);
                vec4 value = imageLoad(light, origin + ivec2(i, j)) + vec4(shooter_radiosity * f, 0.0);
                // the element and the gutter texels that continue it (clamp to edge)
                for (int dy = -GUTTER; dy <= GUTTER; ++dy) {
                    for (int dx = -GUTTER; dx <= GUTTER; ++dx) {
                        ivec2 k = ivec2(i + dx, j + dy);
                        if (clamp(k, ivec2(0), ivec2(ELEMENTS - 1)) == ivec2(i, j)) {
                            imageStore(light, origin + k, value);
                        }
                    }
                }
                float hit = weight * normal_area[p].w / float(per_patch) * f / shooter_area;
                shot = vec4(hit, rho * hit);
            }
        }
    }

    int id = int(gl_LocalInvocationID.x);
    partial[id] = shot;
    barrier();
    for (int stride = 32; stride > 0; stride >>= 1) {
        if (id < stride) {
            partial[id] += partial[id + stride];
        }
        barrier();
    }
    if (id == 0 && partial[0].x > 0.0) {
        uvec4 fixed_point = uvec4(round(partial[0] * SHOT_ENERGY_ONE));
        atomicAdd(energy[0], fixed_point.x);
        atomicAdd(energy[1], fixed_point.y);
        atomicAdd(energy[2], fixed_point.z);
        atomicAdd(energy[3], fixed_point.w);
    }
}
