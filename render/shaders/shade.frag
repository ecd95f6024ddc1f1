// Deferred shading of the G-buffer: Phong (head + key light, as the CPU reference's shade),
// an environment line map that shows smoothness, or NPR cel shading with Sobel outlines.
in vec2 v_uv;
layout(binding = 0) uniform sampler2D g_normal_depth;
layout(binding = 1) uniform sampler2D g_albedo;
uniform mat3 u_view_rot;
uniform mat4 u_proj;
uniform vec2 u_viewport;
// SHADING_MODE (0 phong, 1 envmap, 2 npr) is defined when the program is built: one program per
// mode, so a frame runs only the code its mode needs.
uniform vec3 u_background;
out vec4 out_colour;

vec3 view_dir_at(vec2 frag) {
  vec2 ndc = 2.0 * frag / u_viewport - 1.0;
  return normalize(vec3(ndc.x / u_proj[0][0], ndc.y / u_proj[1][1], -1.0));
}

// Outlines [Sigg06]: silhouettes (coverage changes), depth discontinuities (Sobel on eye depth,
// relative to the centre depth) and creases (Sobel on normals).
float edge_strength(ivec2 p) {
  const int kx[9] = int[9](-1, 0, 1, -2, 0, 2, -1, 0, 1);
  const int ky[9] = int[9](-1, -2, -1, 0, 0, 0, 1, 2, 1);
  float centre = texelFetch(g_normal_depth, p, 0).w;
  float gx = 0.0, gy = 0.0;
  vec3 nx = vec3(0.0), ny = vec3(0.0);
  int covered = 0;
  for (int i = 0; i < 9; ++i) {
    ivec2 q = clamp(p + ivec2(i % 3 - 1, i / 3 - 1), ivec2(0), ivec2(u_viewport) - 1);
    vec4 s = texelFetch(g_normal_depth, q, 0);
    covered += s.w > 0.0 ? 1 : 0;
    float d = s.w > 0.0 ? s.w : centre;
    gx += float(kx[i]) * d;
    gy += float(ky[i]) * d;
    nx += float(kx[i]) * s.xyz;
    ny += float(ky[i]) * s.xyz;
  }
  if (covered != 0 && covered != 9) return 1.0;  // silhouette
  if (covered == 0) return 0.0;
  float depth_edge = length(vec2(gx, gy)) / centre;
  float normal_edge = length(nx) + length(ny);
  return max(step(0.05, depth_edge), step(1.2, normal_edge));
}

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 nd = texelFetch(g_normal_depth, p, 0);
  if (nd.w <= 0.0) {
    if (SHADING_MODE == 2 && edge_strength(p) > 0.0) { out_colour = vec4(0.0, 0.0, 0.0, 1.0); return; }
    out_colour = vec4(u_background, 1.0);
    return;
  }
  vec3 albedo = texelFetch(g_albedo, p, 0).rgb;
  vec3 n = normalize(u_view_rot * nd.xyz);
  vec3 to_eye = -view_dir_at(gl_FragCoord.xy);
  vec3 lights[2] = vec3[2](vec3(0.0, 0.0, 1.0), normalize(vec3(-0.5, 0.8, 0.6)));
  float weights[2] = float[2](0.55, 0.45);
  vec3 colour;
  if (SHADING_MODE == 1) {
    // Line map: stripes of the reflected direction; kinks show curvature discontinuities.
    vec3 r = reflect(-to_eye, n);
    float stripes = 0.5 + 0.5 * sin(18.0 * r.y + 6.0 * r.x);
    float d = max(dot(n, lights[0]), 0.0);
    colour = albedo * (0.25 + 0.55 * d) + vec3(0.35) * smoothstep(0.3, 0.7, stripes);
  } else {
    float diffuse = 0.0, spec = 0.0;
    for (int i = 0; i < 2; ++i) {
      float d = max(dot(n, lights[i]), 0.0);
      diffuse += weights[i] * d;
      if (d > 0.0) spec += weights[i] * pow(max(dot(n, normalize(lights[i] + to_eye)), 0.0), 40.0);
    }
    if (SHADING_MODE == 2) {
      diffuse = diffuse > 0.75 ? 0.95 : diffuse > 0.35 ? 0.6 : 0.3;
      spec = spec > 0.5 ? 0.4 : 0.0;
      colour = albedo * (0.15 + diffuse) + spec;
      if (edge_strength(p) > 0.0) colour = vec3(0.0);
    } else {
      colour = albedo * (0.15 + diffuse) + 0.35 * spec;
    }
  }
  out_colour = vec4(clamp(colour, 0.0, 1.0), 1.0);
}
