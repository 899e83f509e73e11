#version 430
// Item buffer of a hemispherical projection: the patch id + 1 (0: nothing or
// the back of a patch) and the distance from the eye of what is seen.
#include "bindings"
#include "opacity"
flat in uint item;
in float distance;
#if OPACITY
in vec2 opacity_uv;
flat in ivec4 opacity_rect;
#endif
layout(location = 0) out uint out_item;
layout(location = 1) out float out_distance;

void main() {
#if OPACITY
    if (transparent_at(opacity_uv, opacity_rect)) {
        discard;
    }
#endif
    out_item = item;
    out_distance = distance;
}
