#version 430
flat in uint item;
in float view_depth;
uniform float near;
uniform float far;
out uint out_item;

void main() {
    out_item = item;
    gl_FragDepth = clamp(log(view_depth / near) / log(far / near), 0.0, 1.0);
}
