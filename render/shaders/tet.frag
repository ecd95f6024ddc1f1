// Tetrahedron pass, fragment stage ([Stoll06] §5): solve along x(λ) = o + λ·v from the entry
// point on the front face, visit roots nearest first (eq. 15), clip against the four planes,
// write the G-buffer and a depth. TET_EXACT_DEPTH: the hit's depth (never nearer than the face:
// depth_greater keeps early-Z conservative where the driver honours it). Otherwise the face's own
// depth is tested and written, which needs no gl_FragDepth write, so every driver tests it before
// the shader runs: exact for the tetrahedra of one tessellation, whose order along a ray is that
// of their entry faces; a later pass turns the G-buffer's eye depth into the depth buffer.
in vec3 v_o;
in vec3 v_dir;
in vec3 v_Aob;
in vec3 v_Av;
in vec4 v_plane_o;
in vec4 v_plane_v;
in float v_z_entry;
flat in vec4 v_bc;
flat in uint v_colour;
#if TET_CORNER_COLOURS  // tet.vert
flat in uvec4 v_corner_colours;
flat in vec4 v_heights;
#endif
flat in int v_id;

uniform mat4 u_proj;
uniform int u_cull;
uniform float u_clip_eps;  // tolerance of the plane tests, in local units

#ifdef TET_EXACT_DEPTH
layout(depth_greater) out float gl_FragDepth;
#endif
layout(location = 0) out vec4 out_normal_depth;  // world normal (facing the viewer), eye depth
layout(location = 1) out vec4 out_albedo;
layout(location = 2) out int out_id;

// The ray is x(μ) = o + μ·d from the entry point o with the unit direction d = v/‖v‖: o carries
// the position, so even when the eye is 10⁶ sizes away (v huge, rays nearly parallel, their
// directions equal to float precision) the hit stays exact to float precision in local units.
vec4 plane_d;

bool inside(float t) {
  vec4 d = v_plane_o + t * plane_d;
  return all(greaterThanEqual(d, vec4(-u_clip_eps)));
}

void main() {
  float inv_len = inversesqrt(dot(v_dir, v_dir));
  vec3 d = v_dir * inv_len;
  vec3 Ad = v_Av * inv_len;
  plane_d = v_plane_v * inv_len;
  float a = dot(d, Ad);
  float b = dot(d, v_Aob);
  float c = dot(v_o, v_Aob) + dot(v_bc.xyz, v_o) + v_bc.w;
  float t;
  bool hit = false;
  const float t_min = -1e-4;  // a hit a hair in front of the entry face still belongs here
  if (u_cull != 0) {
    hit = front_root(a, b, c, t) && t >= t_min && inside(t);
  } else {
    float t0, t1;
    int n = solve_quadratic(a, b, c, t0, t1);
    if (n > 0 && t0 >= t_min && inside(t0)) { t = t0; hit = true; }
    else if (n > 1 && t1 >= t_min && inside(t1)) { t = t1; hit = true; }
  }
  if (!hit) discard;
  t = max(t, 0.0);
  vec3 grad = v_Aob + t * Ad;  // ½∇f at the hit (linear in t)
  vec3 n = normalize(grad);
  if (dot(n, d) > 0.0) n = -n;  // two-sided when culling is off
  // Eye-space z: the entry point's z plus t local units along d (z_entry/‖v‖ per local unit).
  float z = v_z_entry + t * (v_z_entry * inv_len);
#ifdef TET_EXACT_DEPTH
  gl_FragDepth = window_depth(z, u_proj);
#endif
  out_normal_depth = vec4(n, -z);
  vec3 albedo = unpack_colour(v_colour);
#if TET_CORNER_COLOURS
  {
    // Barycentric coordinates: each plane's distance over its corner's height.
    vec4 w = max((v_plane_o + t * plane_d) / v_heights, vec4(0.0));
    w /= max(w.x + w.y + w.z + w.w, 1e-30);
    albedo = w.x * unpack_colour(v_corner_colours.x) + w.y * unpack_colour(v_corner_colours.y) +
             w.z * unpack_colour(v_corner_colours.z) + w.w * unpack_colour(v_corner_colours.w);
  }
#endif
  out_albedo = vec4(albedo, 1.0);
  out_id = v_id;
}
