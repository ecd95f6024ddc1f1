// SLIM pass 3: divide the accumulated sums by Σw and write the blended surface into the G-buffer
// (normal, eye depth, colour, depth buffer), so SLIM mixes with the other primitives and the one
// deferred shading pass shades everything.
in vec2 v_uv;
layout(binding = 0) uniform sampler2D acc_normal_weight;
layout(binding = 1) uniform sampler2D acc_depth_colour;
uniform mat4 u_proj;
layout(location = 0) out vec4 out_normal_depth;
layout(location = 1) out vec4 out_albedo;
layout(location = 2) out int out_id;

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 nw = texelFetch(acc_normal_weight, p, 0);
  if (!(nw.w > 0.0)) discard;
  vec4 dc = texelFetch(acc_depth_colour, p, 0);
  float depth = dc.x / nw.w;
  out_normal_depth = vec4(normalize(nw.xyz), depth);
  out_albedo = vec4(dc.yzw / nw.w, 1.0);
  out_id = 1 << 28;  // SLIM (the blend has no single patch)
#ifndef SLIM_RESOLVE_KEEPS_DEPTH
  gl_FragDepth = covered_window_depth(-depth, u_proj);
#endif
}
