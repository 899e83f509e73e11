#version 430
// Places each patch's UV bounding box (grown by one texel, computed on the CPU)
// in the lightmap: the fragment stage then decides per texel which patch
// covers it, so every texel the patch touches is reached, however thin it is.

in vec2 in_texel;   // corner of the box, in texels (x right, y up from v = 0)
in int in_patch;    // index into the patch buffers

uniform vec2 size;  // lightmap width, height in texels

flat out int patch_id;

void main() {
    patch_id = in_patch;
    gl_Position = vec4(in_texel / size * 2.0 - 1.0, 0.0, 1.0);
}
