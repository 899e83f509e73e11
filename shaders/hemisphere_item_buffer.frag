#version 430
// Item buffer of a hemispherical projection: the patch id + 1 (0: nothing or
// the back of a patch) and the distance from the eye of what is seen.
flat in uint item;
in float distance;
layout(location = 0) out uint out_item;
layout(location = 1) out float out_distance;

void main() {
    out_item = item;
    out_distance = distance;
}
