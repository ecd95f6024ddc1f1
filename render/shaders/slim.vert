// SLIM splats, vertex stage ([Stoll06] §5.1.1, [Sigg06] eq. 5): one instanced polygon per ball
// that bounds the patch's surface piece, not the ball. The piece lies in the slab
// s0 ≤ axisᵀu ≤ s1 of its zero set cut by the ball (core/slim.h slim_patch_slab, computed at
// load); the proxy is the convex polygon of u_sides support lines (the first along the
// projected axis, then at equal steps) of the projected frustum about that slab that holds the
// piece (the hull of its two cap discs' exact projected ellipses, [Sigg06] eq. 5): thin where the piece is seen edge-on,
// and with 8 sides it cuts the corners a rectangle leaves around a disc seen face-on (21.5 % of
// a rectangle around a circle lies outside it, 5.2 % of an octagon). Balls without a tight slab
// get the ball's axis-aligned tight screen rectangle; balls whose proxy holds the eye or
// straddles the near plane get the whole viewport: never clipped. Rectangles are drawn as the
// same u_sides-gon with repeated corners. Also the patch quadric rotated into eye axes (flat) and
// the per-quadric backface test for spheres ([Stoll06] eq. 18).
//
// The polygon lies at one depth, in front of every point of the surface piece: the nearer of the
// ball's front and the frustum's nearest point, so a depth test before the fragment stage (pass 2
// of the early-depth path, render/passes/slim_pass.h) rejects only fragments whose hits would
// fail it.
//
// With w = 1 the polygon is affine in screen space, so the eye-space ray direction (x/P00, y/P11, −1)
// and the ray's point in the plane through the centre (perpendicular to the view axis) are
// interpolated exactly; the fragment stage re-starts each ray there (local units of R), so
// nothing large cancels even when the eye is far away.

struct Ball {
  vec4 centre_hi;  // xyz: int bits, centre − origin in quanta (u_quantum), w: radius R
  vec4 centre_lo;  // xyz: the rest of centre − origin, w: colour bits
  vec4 q0;         // A00 A11 A22 A01   (g(u), u = (x − c)/R, world axes)
  vec4 q1;         // A12 A02 b0 b1
  vec4 q2;         // b2 c, primitive index bits, slab s1
  vec4 slab;       // xyz: unit axis (world axes), w: s0; q2.w: s1; s0 > s1: no tight slab
  vec4 clip[4];    // n (local, world axes), d; the patch keeps nᵀu + d ≥ 0; n = 0: unused
  vec4 extra;      // x: the ball's own blend push bound (world units), ≤ 0: the model's; y, z: the
                   // slab's frustum radii r0, r1 at s0, s1 (units of R); w unused
};
layout(std430, binding = 0) readonly buffer Balls { Ball balls[]; };
layout(std430, binding = 1) buffer Stats {  // as in slim.frag
  uint culled;
  uint drawn;
  uint splat_fragments;
  uint hit_fragments;
  uint glyph_proxy_fragments;
  uint glyph_hit_fragments;
  uint accumulate_fragments;
  uint cast_fragments;
} stats;

uniform mat4 u_proj;
uniform mat3 u_view_rot;
uniform float u_target_distance;
uniform float u_near;
uniform int u_count_stats;
uniform int u_cull;  // per-quadric culling (per-fragment culling is inherent: SLIM uses front hits)
uniform int u_tight;  // 1: polygons about the slab of the surface piece; 0: the ball's screen rectangle
uniform int u_base;   // the first ball of this draw
uniform int u_sides;  // vertices of the proxy polygon (a multiple of 4; 4: rectangles)

out vec3 v_dir;      // eye-space ray direction through the pixel (z = −1)
out vec3 v_offset;   // ray point in the centre's view plane, relative to the centre, units of R
flat out vec3 v_centre_eye;
flat out float v_radius;
flat out float v_max_push;
flat out vec3 v_A0;  // rows of A′ = R A Rᵀ
flat out vec3 v_A1;
flat out vec3 v_A2;
flat out vec4 v_bc;  // b′ = R b, c
flat out vec4 v_clip[4];
flat out uint v_colour;
flat out int v_id;
#ifdef SLIM_OUTLINE
flat out int v_culled;  // debug overlay ([Stoll06] Fig. 3): culled balls drawn in another colour
#endif

void main() {
  Ball ball = balls[u_base + gl_InstanceID];
  float R = ball.centre_hi.w;
  vec3 C = u_view_rot * from_fixed_origin(ball.centre_hi.xyz, ball.centre_lo.xyz) +
           vec3(0.0, 0.0, -u_target_distance);
  mat3 A = mat3(ball.q0.x, ball.q0.w, ball.q1.y,
                ball.q0.w, ball.q0.y, ball.q1.x,
                ball.q1.y, ball.q1.x, ball.q0.z);
  mat3 Ae = u_view_rot * A * transpose(u_view_rot);
  vec3 be = u_view_rot * vec3(ball.q1.z, ball.q1.w, ball.q2.x);
  float c = ball.q2.y;

  // [Stoll06] eq. 18 about the centre: a point u of the zero set (local units) faces the eye
  // −y (y = C/R) when c − yᵀb + (b − A y)ᵀu > 0, so the patch faces away wherever its zero set
  // can be when c − yᵀb + max wᵀu ≤ 0, w = b − A y, the max over the region that holds the zero
  // set: the ball (‖w‖), or with a tight slab the ball cut by the slab s0 ≤ aᵀu ≤ s1, where
  // max over ‖u‖ ≤ 1 at aᵀu = s is w_a·s + ‖w⊥‖·√(1 − s²), concave in s, greatest at
  // s = w_a/‖w‖ clamped to [s0, s1]. The slab culls a curved patch seen past its silhouette that
  // the whole ball keeps (its A y term reaches across the ball); a margin of float rounding.
  vec3 y = C / R;
  vec3 w = be - Ae * y;
  float w_len = length(w);
  float w_max = w_len;
  bool has_slab = ball.slab.w <= ball.q2.w;
  if (has_slab) {
    vec3 a_eye = u_view_rot * ball.slab.xyz;
    float w_a = dot(w, a_eye);
    float w_perp = length(w - w_a * a_eye);  // not √(‖w‖² − w_a²): w lies near a for flat patches
    float s = w_len > 0.0 ? clamp(w_a / w_len, ball.slab.w, ball.q2.w) : 0.0;
    w_max = min(w_len, w_a * s + w_perp * sqrt(max(0.0, 1.0 - s * s)));
  }
  float y_b = dot(y, be);
  bool culled = u_cull != 0 && c - y_b + w_max < -1e-5 * (abs(c) + abs(y_b) + w_len);
#if SLIM_PASS == 1
  bool count_balls = u_count_stats != 0 && gl_VertexID == 0;  // once per ball and frame
#else
  bool count_balls = false;
#endif
  if (count_balls) {
    if (culled) atomicAdd(stats.culled, 1u); else atomicAdd(stats.drawn, 1u);
  }
  // k: this vertex's place around the polygon (counter-clockwise from the first quadrant).
#ifdef SLIM_OUTLINE
  v_culled = culled ? 1 : 0;
  int k_poly = gl_VertexID % u_sides;  // a line strip of u_sides + 1 vertices
#else
  if (culled) {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    return;
  }
  int k_poly = strip_vertex(gl_VertexID, u_sides);
#endif
  // The rectangles' corner for vertex k: vertex k of the polygon lies near the angle
  // (k + ½)·360°/u_sides, so its quadrant picks the corner.
  int quadrant = (4 * k_poly + 2) / u_sides;
  bvec2 hi_corner = bvec2(quadrant == 0 || quadrant == 3, quadrant < 2);

  // The frustum about the slab that holds the piece: caps at s0 and s1, of radii r0 and r1.
  bool tight = has_slab && u_tight != 0;
  float s0 = ball.slab.w, s1 = ball.q2.w;
  float r0 = ball.extra.y, r1 = ball.extra.z;
  float reach = tight ? sqrt(max(r0 * r0 + s0 * s0, r1 * r1 + s1 * s1)) : 1.0;
  float Rp = R * reach;  // a sphere about the centre that holds the proxy
  bool inside_or_near = dot(C, C) <= Rp * Rp * 1.0001 || C.z + Rp > -u_near;
  vec2 scale = vec2(u_proj[0][0], u_proj[1][1]);
  vec2 corner;
  float ndc_z = -1.0;
  float zn = C.z + R;  // nearest depth of the ball: fragments only move away from it
  if (inside_or_near) {
    corner = vec2(hi_corner.x ? 1.0 : -1.0, hi_corner.y ? 1.0 : -1.0);
  } else {
    if (tight) {
      // Extents in screen slopes k = xy/(−z) along the projected axis a and a⊥.
      vec3 axis = u_view_rot * ball.slab.xyz;
      vec2 kc = C.xy / -C.z;
      vec3 ahead = C + R * axis;
      vec2 a = ahead.xy / -ahead.z - kc;
      a = dot(a, a) > 1e-20 * dot(kc, kc) + 1e-30 ? normalize(a) : vec2(1.0, 0.0);
      vec2 ap = vec2(-a.y, a.x);
      // The frustum (its two cap discs of radii r0 and r1, at s0 and s1) projects onto the hull
      // of the caps' projected ellipses ([Sigg06] eq. 5, prelude.glsl project_ellipse): its
      // extents along a and a⊥ are their supports, in slopes, lengths in units of L.
      float L = max(-C.z, R);
      mat3 disc = mat3(1.0) - outerProduct(axis, axis);
      vec2 c0, c1;
      mat2 S0, S1;
      project_ellipse((C + R * s0 * axis) / L, (R * r0 / L) * (R * r0 / L) * disc, vec2(1.0), c0, S0);
      project_ellipse((C + R * s1 * axis) / L, (R * r1 / L) * (R * r1 / L) * disc, vec2(1.0), c1, S1);
      // Vertex k joins support lines k and k + 1, nᵢ = cos θᵢ a + sin θᵢ a⊥ at θᵢ = i·360°/u_sides,
      // each nᵢ·(k − kc) = hᵢ, the hull's support measured from the centre's slope.
      float step = radians(360.0) / float(u_sides);
      float t0 = step * float(k_poly), t1 = step * float(k_poly + 1);
      vec2 n0 = cos(t0) * a + sin(t0) * ap, n1 = cos(t1) * a + sin(t1) * ap;
      float h0 = hull_support(c0, S0, c1, S1, n0) - dot(kc, n0);
      float h1 = hull_support(c0, S0, c1, S1, n1) - dot(kc, n1);
      // Widen by a few float ulps of the slopes so rounding never trims a covered pixel: the
      // extents along a and a⊥ (the proxy's width and height) bound every support's scale.
      float width = hull_support(c0, S0, c1, S1, a) + hull_support(c0, S0, c1, S1, -a);
      float height = hull_support(c0, S0, c1, S1, ap) + hull_support(c0, S0, c1, S1, -ap);
      float pad = 1e-5 * (length(kc) + width + height);
      h0 += pad;
      h1 += pad;
      // The nearest point of the frustum: a cap centre's z plus its rim's reach in z.
      float rim_z = sqrt(max(0.0, 1.0 - axis.z * axis.z));
      float z_frustum = C.z + R * max(s0 * axis.z + r0 * rim_z, s1 * axis.z + r1 * rim_z);
      zn = min(zn, z_frustum);
      float det = n0.x * n1.y - n0.y * n1.x;  // sin(step) · (±1 from a's handedness)
      corner = (kc + vec2(h0 * n1.y - h1 * n0.y, n0.x * h1 - n1.x * h0) / det) * scale;
    } else {
      // The ball's tight screen rectangle ([Sigg06] eq. 5 for a sphere): the tangent lines from
      // the eye in the xz and yz planes give the slopes k = x/(−z) of the silhouette, ndc = P·k.
      float zz = C.z * C.z - R * R;
      vec2 k_lo, k_hi;
      for (int i = 0; i < 2; ++i) {
        float ci = C[i];
        float root = R * sqrt(max(ci * ci + zz, 0.0));
        float k0 = (-ci * C.z - root) / zz, k1 = (-ci * C.z + root) / zz;
        k_lo[i] = min(k0, k1);
        k_hi[i] = max(k0, k1);
      }
      vec2 lo = clamp(k_lo * scale, -1.0, 1.0), hi = clamp(k_hi * scale, -1.0, 1.0);
      corner = vec2(hi_corner.x ? hi.x : lo.x, hi_corner.y ? hi.y : lo.y);
    }
  }
  if (!inside_or_near) {
    // A margin of 16 float steps of window depth, so rounding never puts the polygon behind a hit.
    ndc_z = max((u_proj[2][2] * zn + u_proj[3][2]) / -zn - 4e-6, -1.0);
  }
  gl_Position = vec4(corner, ndc_z, 1.0);
  vec2 k = corner / scale;
  v_dir = vec3(k, -1.0);
  // The ray meets the plane z = C.z at −C.z·(k, −1); relative to the centre, in units of R.
  v_offset = vec3(k * -C.z - C.xy, 0.0) / R;
  v_centre_eye = C;
  v_radius = R;
  v_max_push = ball.extra.x;
  v_A0 = Ae[0];  // columns of a symmetric matrix are its rows
  v_A1 = Ae[1];
  v_A2 = Ae[2];
  v_bc = vec4(be, c);
  for (int k = 0; k < 4; ++k) v_clip[k] = vec4(u_view_rot * ball.clip[k].xyz, ball.clip[k].w);
  v_colour = floatBitsToUint(ball.centre_lo.w);
  v_id = floatBitsToInt(ball.q2.z);
}
