// Opacity textures (visibility/opacity.py): an alpha-cut surface lets light through where its
// texture's alpha is under ALPHA_CUTOFF, so an item buffer drops its fragments there. A polygon
// carries its texture UVs and the texture's rectangle in the atlas (x, y, width, height in texels;
// width 0: opaque); UVs repeat, as an image texture's do. Needs "bindings".
#if OPACITY
layout(binding = TEXTURE_OPACITY) uniform sampler2D opacity_atlas;

bool transparent_at(vec2 uv, ivec4 rect) {
    if (rect.z <= 0) {
        return false;
    }
    ivec2 texel = rect.xy + clamp(ivec2(floor(fract(uv) * vec2(rect.zw))), ivec2(0), rect.zw - ivec2(1));
    return texelFetch(opacity_atlas, texel, 0).r < ALPHA_CUTOFF;
}
#endif
