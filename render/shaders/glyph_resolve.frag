// Glyph pass, early-depth path, last step: one ray per pixel into the glyph that glyph.frag
// (GLYPH_NEAREST, both draws) found nearest there, written to the G-buffer with its depth. The ray is the
// one the proxy polygon interpolates (glyph.vert): through the pixel centre, restarted in the
// plane through the glyph's centre.
layout(std430, binding = 2) readonly buffer Nearest { uint nearest[]; };  // per pixel: depth bits, glyph index

uniform mat4 u_proj;
uniform mat3 u_view_rot;
uniform float u_target_distance;
uniform float u_near;  // hits nearer the eye than the near plane are skipped (glyph_lib.glsl)
uniform vec2 u_viewport;
uniform int u_cull;

out float gl_FragDepth;
layout(location = 0) out vec4 out_normal_depth;  // world normal (facing the viewer), eye depth
layout(location = 1) out vec4 out_albedo;
layout(location = 2) out int out_id;

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  uint index = nearest[2 * (p.y * int(u_viewport.x) + p.x) + 1];
  if (index == 0xFFFFFFFFu) discard;  // no glyph here
  Glyph g = glyphs[index];
  vec2 k = (2.0 * gl_FragCoord.xy / u_viewport - 1.0) / vec2(u_proj[0][0], u_proj[1][1]);
  GlyphRay r = glyph_ray(g, k, u_view_rot, u_target_distance);
  GlyphHit h = cast_glyph(r.o, r.d, r.kind, r.scale, r.centre_z, u_near, u_cull != 0);
  if (!h.found) discard;
  float z = r.centre_z - h.s;
  gl_FragDepth = window_depth(z, u_proj);
  out_normal_depth = vec4(transpose(u_view_rot) * glyph_normal(r.inv, h.grad, r.dir), -z);
  out_albedo = vec4(unpack_colour(floatBitsToUint(g.centre_lo.w)), 1.0);
  out_id = floatBitsToInt(g.inv0.w);
}
