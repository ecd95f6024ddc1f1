// Glyphs ([Sigg06] §3): the record every glyph program reads, its frame in eye space, and the
// ray cast in the glyph's parameter space (eq. 6–9). Prepended to the glyph programs' stages.

struct Glyph {
  vec4 centre_hi;  // xyz: int bits, centre − origin in quanta; w: kind (0 sphere, 1 ellipsoid,
                   // 2 cylinder)
  vec4 centre_lo;  // xyz: the rest of centre − origin, w: colour bits
  vec4 inv0;       // rows of M⁻¹ (world → parameter space); inv0.w: primitive id bits
  vec4 inv1;
  vec4 inv2;
  vec4 s0;         // S / s², S = M Mᵀ (world): xx yy zz xy; cylinder: S of one end disc
  vec4 s1;         // yz xz, s (the glyph's size, its longest semi-axis), a (its shortest: spheres, ellipsoids)
  vec4 axis;       // cylinder: half axis a (caps at C ± a)
};
layout(std430, binding = 0) readonly buffer Glyphs { Glyph glyphs[]; };

// The centre in eye space (prelude.glsl from_fixed_origin).
vec3 glyph_centre_eye(Glyph g, mat3 view_rot, float target_distance) {
  return view_rot * from_fixed_origin(g.centre_hi.xyz, g.centre_lo.xyz) + vec3(0.0, 0.0, -target_distance);
}

// M⁻¹ in eye axes: eye-space offsets → parameter space.
mat3 glyph_inverse_eye(Glyph g, mat3 view_rot) {
  return transpose(mat3(g.inv0.xyz, g.inv1.xyz, g.inv2.xyz)) * transpose(view_rot);
}

// The ray through the eye-space direction (k, −1) (k: NDC over the projection's diagonal) in the
// glyph's parameter space, restarted in the plane through the centre (glyph.vert interpolates
// the same ray): u(σ) = o + σ·d, σ = s / scale; inv = M⁻¹ in eye axes.
struct GlyphRay {
  vec3 o, d, dir;
  mat3 inv;
  float centre_z, scale;
  uint kind;
};

GlyphRay glyph_ray(Glyph g, vec2 k, mat3 view_rot, float target_distance) {
  GlyphRay r;
  vec3 C = glyph_centre_eye(g, view_rot, target_distance);
  r.centre_z = C.z;
  r.scale = max(abs(C.z), g.s1.z);
  r.dir = vec3(k, -1.0);
  r.inv = glyph_inverse_eye(g, view_rot);
  r.o = r.inv * vec3(k * -C.z - C.xy, 0.0);
  r.d = r.inv * (r.dir * r.scale);
  r.kind = uint(g.centre_hi.w);
  return r;
}

// The nearest hit along a ray u(σ) = o + σ·d in parameter space, s = σ·scale measured from the
// centre's view plane towards the eye (the eye at s = centre_z), beyond the near plane (eye depth
// ≥ near: a glyph the near plane cuts shows its far side there, as the CPU reference's rays start
// at the near plane). With cull, front faces only (as the CPU reference).
struct GlyphHit {
  bool found;
  float s;
  vec3 grad;  // gradient in parameter space at the hit
};

void glyph_consider(inout GlyphHit h, float sigma, vec3 grad_u, vec3 d, float scale, float centre_z, float near,
                    bool cull) {
  float s = sigma * scale;
  if (s < centre_z + near || (h.found && s >= h.s)) return;  // in front of the near plane, or not nearer
  if (cull && dot(grad_u, d) >= 0.0) return;           // back-facing
  h.found = true;
  h.s = s;
  h.grad = grad_u;
}

GlyphHit cast_glyph(vec3 o, vec3 d, uint kind, float scale, float centre_z, float near, bool cull) {
  GlyphHit h;
  h.found = false;
  h.s = 0.0;
  h.grad = vec3(0.0);
  float s0, s1;
  if (kind != 2u) {
    int n = solve_quadratic(dot(d, d), dot(o, d), dot(o, o) - 1.0, s0, s1);
    if (n > 0) glyph_consider(h, s0, o + s0 * d, d, scale, centre_z, near, cull);
    if (n > 1) glyph_consider(h, s1, o + s1 * d, d, scale, centre_z, near, cull);
  } else {
    float a = dot(d.xy, d.xy);  // 0: the ray runs along the axis and meets only the caps
    int n = a > 0.0 ? solve_quadratic(a, dot(o.xy, d.xy), dot(o.xy, o.xy) - 1.0, s0, s1) : 0;
    vec3 u0 = o + s0 * d, u1 = o + s1 * d;
    if (n > 0 && abs(u0.z) <= 1.0) glyph_consider(h, s0, vec3(u0.xy, 0.0), d, scale, centre_z, near, cull);
    if (n > 1 && abs(u1.z) <= 1.0) glyph_consider(h, s1, vec3(u1.xy, 0.0), d, scale, centre_z, near, cull);
    if (d.z != 0.0) {
      for (int i = 0; i < 2; ++i) {
        float side = i == 0 ? 1.0 : -1.0;
        float s = (side - o.z) / d.z;
        vec2 uxy = o.xy + s * d.xy;
        if (dot(uxy, uxy) <= 1.0) glyph_consider(h, s, vec3(0.0, 0.0, side), d, scale, centre_z, near, cull);
      }
    }
  }
  return h;
}

// [Sigg06] eq. 9: the eye-space normal M⁻ᵀ∇(u), facing the viewer along dir.
vec3 glyph_normal(mat3 inv, vec3 grad, vec3 dir) {
  vec3 n = transpose(inv) * grad;
  n = normalize(n / max(max(abs(n.x), abs(n.y)), abs(n.z)));  // |n|² would leave float for tiny glyphs
  return dot(n, dir) > 0.0 ? -n : n;  // two-sided when culling is off
}
