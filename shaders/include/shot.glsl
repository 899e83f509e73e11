// A batch of shots, and the light each sends to a receiving point x with normal n on the plane
// `plane` (a surface side: the patches of one plane cannot hide each other's points). Needs
// "bindings", "constants" and "kernels"; shared by the shooting passes over elements and over
// lightmap texels, which loop over the batch (shooting.shots writes the records).
//
// Kinds: 0 a polygon (a patch, a piece of an emitter or of an area lamp): F = Lambert's exact
// point-to-polygon factor (KERNEL_EXACT 1) or the disk approximation; 1 a point lamp:
// F = cos_recv / (pi r^2) times its spot cone (radiosity: its intensity); 2 a sun: F = cos_recv / pi
// (radiosity: its irradiance); 3 the sky: F = the receiver's sky fraction (given by the caller).
// Visibility: a shot with a hemi-cube slot >= 0 looks the receiver up in its tile of the hemi-cube
// atlas (visibility.HemicubeAtlas); slot -1 in the one visibility map bound (hemispherical, or
// orthographic for a sun: visibility.VisibilityMap). Either way the receiver's patch, or any patch
// of its plane, must show at its direction, or within SEARCH_RADIUS pixels (dissertation
// Algorithm 8). OCCLUSION 0: the scene analysis proved nothing occludes.
//
// Defines: MAX_SHOTS, KERNEL_EXACT, SEARCH_RADIUS, OCCLUDER_MARGIN (the map's guard), OCCLUSION.
//
// SHOT_KINDS (a bit per kind present in the batch) and VISIBILITY_LOOKUP (1: hemi-cubes, 2: the
// map, 3: either) compile a pass for what its batch holds: a software rasterizer (llvmpipe) runs
// both sides of every branch its SIMD lanes may take, so code for absent kinds would cost as
// much as code for present ones. The passes pick the variant per batch (ShotVisibility.prepare).
#ifndef SHOT_KINDS
#define SHOT_KINDS 15
#endif
#ifndef VISIBILITY_LOOKUP
#define VISIBILITY_LOOKUP 3
#endif
#define HAS_KIND(kind) ((SHOT_KINDS & (1 << (kind))) != 0)

// HIDE_BEHIND_OCCLUDERS (both passes set it): a receiver behind the patch its pixel shows is
// hidden, never searched past
#ifndef HIDE_BEHIND_OCCLUDERS
#define HIDE_BEHIND_OCCLUDERS 0
#endif
const float HIDING_MARGIN = 1e-3;  // of the eye-receiver distance: a plane nearer than that hides

struct Shot {
    vec4 eye_area;        // the visibility eye, the polygon's area
    vec4 axis_x_kind;     // the eye's frame: x, and the kind
    vec4 axis_y_patch;    // y, and the patch shot (-1: none), or the cluster shot when extra.w > 0
    vec4 normal_w;        // the pole (a polygon's normal), and its group: 1 + the index of the whole polygon
                          // it is a piece of (group_corner), 0 for none
    vec4 corner[4];       // the polygon, counter-clockwise seen from its front
    vec4 radiosity;       // what it shoots
    vec4 spot;            // the lamp's axis or the sun's travel direction, cos of half the cone (-2: none)
    vec4 extra;           // the cone's soft width, the hemi-cube slot (-1: the map), the sun map's half-width,
                          // the level (1-7) of the cluster of patches shot (all its members), 0: none
};

// after the records, the corners of each group's whole polygon (shots.piece_groups)
layout(std140, binding = UNIFORM_SHOTS) uniform Shots { Shot shots[MAX_SHOTS]; vec4 group_corner[4 * MAX_SHOTS]; };
// per patch: its plane's equation (n, n . x), the id of that plane (a surface side), its corners
// id: plane, shooter clusters at levels 1-3; coarser_id: at levels 4-7 (-1: none)
struct PatchPlane { vec4 equation; ivec4 id; ivec4 coarser_id; vec4 corner[4]; };
layout(std430, binding = STORAGE_PATCH_PLANE) readonly buffer Plane { PatchPlane plane_of[]; };
layout(binding = TEXTURE_HEMICUBES) uniform usampler2D hemicubes;
layout(binding = TEXTURE_ITEM_BUFFER) uniform usampler2D item_buffer;
layout(binding = TEXTURE_DISTANCE_MAP) uniform sampler2D distance_map;  // distance of what each map texel shows (0: nothing)

uniform int shot_count;
uniform int hemicube_resolution;
uniform int hemicube_tiles_per_row;
uniform int item_resolution;

// a visibility map's item for the back of a patch whose back is not simulated (its id + 1 with this
// bit): no receiver is on it, but it hides what lies behind it
const uint BACK_OF = 0x80000000u;

bool on_plane(uint item, int plane) {
    return item != 0u && (item & BACK_OF) == 0u && int(item) - 1 < plane_of.length()
        && plane_of[int(item) - 1].id.x == plane;
}

// Does the patch `item` (seen where the receiver should be) lie between the eye and the receiver
// (eye + d) along that ray? Then the receiver is hidden and no search may look past it: searching
// neighbour pixels would find the floor beside a box's foot and light the floor in its shadow.
bool hides(uint shown, vec3 eye, vec3 d) {
    uint item = shown & ~BACK_OF;
    if (item == 0u || int(item) - 1 >= plane_of.length()) {
        return false;  // the sky, or a patch's back column: a rasterization gap, search
    }
    vec4 equation = plane_of[int(item) - 1].equation;
    float along = dot(equation.xyz, d);
    if (abs(along) < 1e-12 * dot(d, d)) {
        return false;
    }
    float t = (equation.w - dot(equation.xyz, eye)) / along;
    if (!(t > 1e-4 && t < 1.0 - HIDING_MARGIN)) {
        return false;
    }
    // and the exact ray passes through that patch (not just its plane): at a silhouette the pixel
    // may show an occluder the ray itself misses, and then the search decides
    vec3 hit = eye + t * d;
    float slack = -1e-4 * length(t * d);
    for (int i = 0; i < 4; ++i) {
        vec3 a = plane_of[int(item) - 1].corner[i].xyz;
        vec3 b = plane_of[int(item) - 1].corner[(i + 1) % 4].xyz;
        if (distance(a, b) > 0.0 && dot(cross(b - a, hit - a), equation.xyz) < slack * distance(a, b)) {
            return false;
        }
    }
    return true;
}

// Is the receiver's plane seen in direction q (the eye's frame: x, y, pole; q.z > 0) in hemi-cube
// `slot`? The tile is laid out as visibility.hemicube.face_instances lays out the five faces: top
// rows [0, R), then the +x, -x, +y, -y half faces of R/2 rows each. The search stays in one face.
bool hemicube_sees(int slot, vec3 q, int plane, vec3 eye, vec3 d) {
    int r = hemicube_resolution;
    vec3 aq = abs(q);
    float a, b, c, up_min;
    int row0, rows;
    if (q.z >= aq.x && q.z >= aq.y) {
        a = q.x; b = q.y; c = q.z; row0 = 0; rows = r; up_min = -1.0;
    } else {
        rows = r / 2;
        up_min = 0.0;
        b = q.z;
        if (aq.x >= aq.y) {
            a = q.x > 0.0 ? q.y : -q.y;
            c = aq.x;
            row0 = q.x > 0.0 ? r : r + r / 2;
        } else {
            a = q.y > 0.0 ? -q.x : q.x;
            c = aq.y;
            row0 = q.y > 0.0 ? 2 * r : 2 * r + r / 2;
        }
    }
    ivec2 pixel = ivec2(floor(vec2(0.5 * (a / c + 1.0) * float(r), (b / c - up_min) / (1.0 - up_min) * float(rows))));
    ivec2 origin = ivec2(slot % hemicube_tiles_per_row, slot / hemicube_tiles_per_row) * ivec2(r, 3 * r)
                 + ivec2(0, row0);
    pixel = clamp(pixel, ivec2(0), ivec2(r - 1, rows - 1));
    uint seen = texelFetch(hemicubes, origin + pixel, 0).r;
    if (on_plane(seen, plane)) {
        return true;  // most receivers: no search
    }
#if HIDE_BEHIND_OCCLUDERS
    if (hides(seen, eye, d)) {
        return false;  // something in front of it: hidden
    }
#endif
    bool found = false;
    for (int dy = -SEARCH_RADIUS; dy <= SEARCH_RADIUS; ++dy) {
        for (int dx = -SEARCH_RADIUS; dx <= SEARCH_RADIUS; ++dx) {
            ivec2 at = clamp(pixel + ivec2(dx, dy), ivec2(0), ivec2(r - 1, rows - 1));
            found = found || on_plane(texelFetch(hemicubes, origin + at, 0).r, plane);
        }
    }
    return found;
}

// Is the receiver's plane seen at q in the visibility map (hemispherical: (x, y) / |q|;
// orthographic over the half-width `ortho_extent` > 0)? The ray to the receiver runs from `eye`
// along `d` (a sun's: along its travel, not from its map's origin).
bool map_sees(vec3 q, int plane, float ortho_extent, vec3 eye, vec3 d) {
    float r = length(q);
    vec2 uv = (ortho_extent > 0.0 ? q.xy / ortho_extent : q.xy / r) * 0.5 + 0.5;
    ivec2 texel = clamp(ivec2(floor(uv * float(item_resolution))), ivec2(0), ivec2(item_resolution - 1));
    uint shown = texelFetch(item_buffer, texel, 0).r;
    if (on_plane(shown, plane)) {
        return true;
    }
#if HIDE_BEHIND_OCCLUDERS
    if (hides(shown, eye, d)) {
        return false;  // something in front of it: hidden (the search would peek past an occluder's edge)
    }
#endif
    // Optionally (OCCLUDER_MARGIN >= 0) the search is for rasterization gaps only, not for
    // peeking past occluders: when the own texel shows something clearly nearer, it is hidden.
    float seen = texelFetch(distance_map, texel, 0).r;
    float distance = ortho_extent > 0.0 ? q.z : r;  // the orthographic map's distances run along its axis
    if (OCCLUDER_MARGIN >= 0.0 && seen > 0.0 && seen < distance * (1.0 - OCCLUDER_MARGIN)) {
        return false;
    }
    bool found = false;
    for (int dy = -SEARCH_RADIUS; dy <= SEARCH_RADIUS; ++dy) {
        for (int dx = -SEARCH_RADIUS; dx <= SEARCH_RADIUS; ++dx) {
            ivec2 at = clamp(texel + ivec2(dx, dy), ivec2(0), ivec2(item_resolution - 1));
            found = found || on_plane(texelFetch(item_buffer, at, 0).r, plane);
        }
    }
    return found;
}

// Does shot k see the point x (normal n, on `plane`)? Not for the sky (kind 3).
bool shot_sees(int k, vec3 x, vec3 n, int plane) {
    int kind = int(shots[k].axis_x_kind.w);
    vec3 d = x - shots[k].eye_area.xyz;
    if (kind == 2 ? dot(n, shots[k].spot.xyz) >= 0.0 : dot(n, d) >= 0.0) {
        return false;  // the receiver turns its back to the shooter (the sun lights its other side)
    }
    vec3 q = vec3(dot(d, shots[k].axis_x_kind.xyz), dot(d, shots[k].axis_y_patch.xyz), dot(d, shots[k].normal_w.xyz));
    if (q.z <= 0.0) {
        return false;  // behind the shooter
    }
#if !OCCLUSION
    return true;
#endif
    // a sun's rays run along its travel: the ray to x starts its map's depth before x
    vec3 eye = kind == 2 ? x - q.z * shots[k].normal_w.xyz : shots[k].eye_area.xyz;
    vec3 ray = x - eye;
#if VISIBILITY_LOOKUP == 1
    return hemicube_sees(int(shots[k].extra.y), q, plane, eye, ray);
#elif VISIBILITY_LOOKUP == 2
    return map_sees(q, plane, shots[k].extra.z, eye, ray);
#else
    int slot = int(shots[k].extra.y);
    return slot >= 0 ? hemicube_sees(slot, q, plane, eye, ray) : map_sees(q, plane, shots[k].extra.z, eye, ray);
#endif
}

// F times V of shot k at x; `sky` is the receiver's sky fraction (kind 3: its visibility is in it).
float shot_factor(int k, vec3 x, vec3 n, int plane, float sky) {
    int kind = int(shots[k].axis_x_kind.w);
#if HAS_KIND(3)
    if (kind == 3) {
        return sky;
    }
#endif
    if (!shot_sees(k, x, n, plane)) {
        return 0.0;
    }
#if HAS_KIND(1)
    if (kind == 1) {
        return point_lamp_factor(shots[k].eye_area.xyz, shots[k].spot.xyz, shots[k].spot.w, shots[k].extra.x, x, n);
    }
#endif
#if HAS_KIND(2)
    if (kind == 2) {
        return max(-dot(n, shots[k].spot.xyz), 0.0) / PI;
    }
#endif
#if !HAS_KIND(0)
    return 0.0;
#elif KERNEL_EXACT
    vec3 polygon[4] = vec3[4](shots[k].corner[0].xyz, shots[k].corner[1].xyz, shots[k].corner[2].xyz,
                              shots[k].corner[3].xyz);
    return polygon_form_factor(polygon, x, n);
#else
    return disk_form_factor(shots[k].eye_area.xyz, shots[k].normal_w.xyz, shots[k].eye_area.w, x, n);
#endif
}
