// Deferred shading of the G-buffer: Phong (head + key light, as the CPU reference's shade),
// an environment line map that shows smoothness, or NPR cel shading (its outlines: outline.frag);
// the key light shadowed from a shadow map (SHADOWS 1). Drawn on the far plane with the depth
// test GL_GREATER, so only pixels some pass drew run it (render/passes/shade_pass.h); the rest
// keep the background the pass cleared them to.
in vec2 v_uv;
layout(binding = 0) uniform sampler2D g_normal_depth;
layout(binding = 1) uniform sampler2D g_albedo;
uniform mat3 u_view_rot;
uniform mat4 u_proj;
uniform vec2 u_viewport;
// SHADING_MODE (0 phong, 1 envmap, 2 npr) and SHADOWS (0, 1) are defined when the program is
// built: one program per mode and shadowing, so a frame runs only the code it needs (on llvmpipe
// the shadow lookup behind a uniform's ?: cost 10 ms of a 1024² frame with shadows off).
uniform vec3 u_background;
out vec4 out_colour;

vec3 view_dir_at(vec2 frag) {
  vec2 ndc = 2.0 * frag / u_viewport - 1.0;
  return normalize(vec3(ndc.x / u_proj[0][0], ndc.y / u_proj[1][1], -1.0));
}

#if SHADOWS
// Key-light visibility from the shadow map (core/lighting.h), adaptive PCF [Sigg06] §5: 8 taps on
// a ring of u_shadow_softness texels; only where they disagree (the penumbra) 64 taps on a grid.
layout(binding = 2) uniform sampler2D g_shadow_depth;
uniform mat4 u_eye_to_light;
uniform vec2 u_light_proj;        // the light's P[2][2], P[3][2]
uniform float u_shadow_texel;     // a map texel at the scene, world units
uniform float u_shadow_softness;  // PCF radius, texels
uniform float u_shadow_size;      // texels per side

float light_depth_at(vec2 uv) {
  float ndc = 2.0 * texelFetch(g_shadow_depth, ivec2(uv * u_shadow_size), 0).r - 1.0;
  return u_light_proj.y / (ndc + u_light_proj.x);
}

float lit_tap(vec2 uv, float depth, float bias) {
  if (any(lessThan(uv, vec2(0.0))) || any(greaterThanEqual(uv, vec2(1.0)))) return 1.0;
  return depth <= light_depth_at(uv) + bias ? 1.0 : 0.0;
}

float key_light_visibility(vec3 p_eye, vec3 n_eye) {
  // Normal offset of 1.5 texels against acne; a texel of slack on the comparison.
  vec4 c = u_eye_to_light * vec4(p_eye + 1.5 * u_shadow_texel * n_eye, 1.0);
  if (c.w <= 0.0) return 1.0;
  vec2 uv = 0.5 * c.xy / c.w + 0.5;
  float depth = c.w, bias = u_shadow_texel;
  float r = u_shadow_softness / u_shadow_size;
  float lit = 0.0;
  for (int i = 0; i < 8; ++i) {
    float a = 0.7853982 * float(i) + 0.3926991;
    lit += lit_tap(uv + r * vec2(cos(a), sin(a)), depth, bias);
  }
  if (lit == 0.0 || lit == 8.0) return lit / 8.0;
  lit = 0.0;
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i)
      lit += lit_tap(uv + r * (vec2(float(i), float(j)) - 3.5) / 3.5, depth, bias);
  return lit / 64.0;
}
#endif

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 nd = texelFetch(g_normal_depth, p, 0);
  if (nd.w <= 0.0) {
    out_colour = vec4(u_background, 1.0);
    return;
  }
  vec3 albedo = texelFetch(g_albedo, p, 0).rgb;
  vec3 n = normalize(u_view_rot * nd.xyz);
  vec3 dir = view_dir_at(gl_FragCoord.xy);
  vec3 to_eye = -dir;
#if SHADOWS
  float key = key_light_visibility(dir * (nd.w / -dir.z), n);
#else
  float key = 1.0;
#endif
  vec3 lights[2] = vec3[2](vec3(0.0, 0.0, 1.0), normalize(vec3(-0.5, 0.8, 0.6)));
  float weights[2] = float[2](0.55, 0.45 * key);
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
    } else {
      colour = albedo * (0.15 + diffuse) + 0.35 * spec;
    }
  }
  out_colour = vec4(clamp(colour, 0.0, 1.0), 1.0);
}
