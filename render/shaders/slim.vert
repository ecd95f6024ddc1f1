// SLIM splats, vertex stage ([Stoll06] §5.1.1, [Sigg06] eq. 5). Per ball one instance of an
// octagonal prism (16 corners, 28 triangles, outward counter-clockwise; back faces culled by GL so
// each pixel is covered once) that bounds the patch's surface piece, not the ball: the slab
// s0 ≤ axisᵀu ≤ s1 of its zero set (core/slim.h slim_patch_slab) cut by the ball, drawn in 3D with
// perspective, so its outline is the convex hull of the projected prism. Also the patch quadric
// rotated into eye axes (flat) and the per-quadric backface test for spheres ([Stoll06] eq. 18).
// Balls without a tight slab get the tight screen rectangle of the ball (the prism's bottom cap
// flattened onto it, w = 1); balls whose prism holds the eye or straddles the near plane get the
// whole viewport: never clipped.
//
// The fragment stage re-starts each ray at an interpolated point of it in local units of R
// (v_local: on the prism face, or in the centre's view plane for the screen rectangle), so nothing
// large cancels even when the eye is far away; v_dir is the ray's eye-space direction.

struct Ball {
  vec4 centre_hi;  // xyz: centre (float part), w: radius R
  vec4 centre_lo;  // xyz: centre − float(centre), w: colour bits
  vec4 q0;         // A00 A11 A22 A01   (g(u), u = (x − c)/R, world axes)
  vec4 q1;         // A12 A02 b0 b1
  vec4 q2;         // b2 c, primitive index bits, slab s1
  vec4 clip;       // n (local, world axes), d; n = 0: no clip plane
  vec4 slab;       // xyz: unit axis (world axes), w: s0; q2.w: s1; s0 > s1: no tight slab
};
layout(std430, binding = 0) readonly buffer Balls { Ball balls[]; };
layout(std430, binding = 1) buffer Stats { uint culled; uint drawn; uint splat_fragments; uint hit_fragments; } stats;

uniform mat4 u_proj;
uniform mat3 u_view_rot;
uniform vec3 u_target_hi;
uniform vec3 u_target_lo;
uniform float u_target_distance;
uniform float u_near;
uniform int u_count_stats;
uniform int u_cull;  // per-quadric culling (per-fragment culling is inherent: SLIM uses front hits)
uniform int u_indexed;  // 1: drawn with the prism's element buffer; 0: gl_VertexID runs over kProxyIndex
uniform int u_tight;    // 1: tight slab prisms; 0: the ball's screen rectangle for every ball

const float kOctagonOut = 1.0823922;  // 1/cos(22.5°): the octagon about a unit circle
// The prism's 28 triangles: bottom cap (0–7, facing −axis), top cap (8–15), 8 side walls.
const int kProxyIndex[84] = int[84](
    0, 2, 1, 0, 3, 2, 0, 4, 3, 0, 5, 4, 0, 6, 5, 0, 7, 6,
    8, 9, 10, 8, 10, 11, 8, 11, 12, 8, 12, 13, 8, 13, 14, 8, 14, 15,
    0, 1, 9, 0, 9, 8, 1, 2, 10, 1, 10, 9, 2, 3, 11, 2, 11, 10, 3, 4, 12, 3, 12, 11,
    4, 5, 13, 4, 13, 12, 5, 6, 14, 5, 14, 13, 6, 7, 15, 6, 15, 14, 7, 0, 8, 7, 8, 15);

out vec3 v_dir;      // eye-space ray direction through the pixel
out vec3 v_offset;   // a point of the ray relative to the centre, units of R, eye axes
flat out vec3 v_centre_eye;
flat out float v_radius;
flat out vec3 v_A0;  // rows of A′ = R A Rᵀ
flat out vec3 v_A1;
flat out vec3 v_A2;
flat out vec4 v_bc;  // b′ = R b, c
flat out vec4 v_clip;
flat out uint v_colour;
flat out int v_id;
#ifdef SLIM_OUTLINE
flat out int v_culled;  // debug overlay ([Stoll06] Fig. 3): culled balls drawn in another colour
#endif

void main() {
  Ball ball = balls[gl_InstanceID];
  float R = ball.centre_hi.w;
  vec3 C = u_view_rot * camera_relative(ball.centre_hi.xyz, ball.centre_lo.xyz, u_target_hi, u_target_lo) +
           vec3(0.0, 0.0, -u_target_distance);
  mat3 A = mat3(ball.q0.x, ball.q0.w, ball.q1.y,
                ball.q0.w, ball.q0.y, ball.q1.x,
                ball.q1.y, ball.q1.x, ball.q0.z);
  mat3 Ae = u_view_rot * A * transpose(u_view_rot);
  vec3 be = u_view_rot * vec3(ball.q1.z, ball.q1.w, ball.q2.x);
  float c = ball.q2.y;

  // [Stoll06] eq. 18 about the centre: c′ − e′ᵀb′ = c + e′ᵀb with e′ the eye in local units; the
  // patch faces away everywhere in its ball when c − yᵀb < −‖b − A y‖, y = C/R.
  vec3 y = C / R;
  bool culled = u_cull != 0 && c - dot(y, be) < -length(be - Ae * y);
  if (u_count_stats != 0 && gl_VertexID == 0) {
    if (culled) atomicAdd(stats.culled, 1u); else atomicAdd(stats.drawn, 1u);
  }
#ifdef SLIM_OUTLINE
  v_culled = culled ? 1 : 0;
  const int kLoop[5] = int[5](0, 1, 3, 2, 0);
  int vid = kLoop[gl_VertexID];
#else
  if (culled) {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    return;
  }
  int vid = u_indexed != 0 ? gl_VertexID : kProxyIndex[gl_VertexID];  // prism corner 0..15
#endif

  // The prism: octagon of inradius ρ (the slab's disc) about the axis, caps at s0 (corners 0–7)
  // and s1 (8–15); corner k at angle (k + ½)·45° in the frame (t1, t2, axis), right-handed.
  bool tight = ball.slab.w <= ball.q2.w && u_tight != 0;
  float s0 = ball.slab.w, s1 = ball.q2.w;
  float rho = (s0 <= 0.0 && s1 >= 0.0) ? 1.0 : sqrt(max(0.0, 1.0 - min(s0 * s0, s1 * s1)));
  float reach = tight ? sqrt(rho * rho * kOctagonOut * kOctagonOut + max(s0 * s0, s1 * s1)) : 1.0;
  float Rp = R * reach;  // a sphere about the centre that holds the proxy
  bool inside_or_near = dot(C, C) <= Rp * Rp * 1.0001 || C.z + Rp > -u_near;
  vec2 scale = vec2(u_proj[0][0], u_proj[1][1]);
  if (tight && !inside_or_near) {
    vec3 axis = u_view_rot * ball.slab.xyz;
    vec3 t1 = normalize(abs(axis.x) < 0.9 ? cross(axis, vec3(1.0, 0.0, 0.0)) : cross(axis, vec3(0.0, 1.0, 0.0)));
    vec3 t2 = cross(axis, t1);
    int k = vid & 7;
    float angle = (float(k) + 0.5) * 0.78539816;
    vec3 u = rho * kOctagonOut * (cos(angle) * t1 + sin(angle) * t2) + (vid < 8 ? s0 : s1) * axis;
    vec3 p = C + R * u;
    gl_Position = u_proj * vec4(p, 1.0);
    v_dir = p;
    v_offset = u;
  } else {
    // The ball's tight screen rectangle ([Sigg06] eq. 5 for a sphere: tangent lines from the eye
    // in the xz and yz planes give the silhouette slopes k = x/(−z), ndc = P·k), or the viewport;
    // corners 0–7 trace it with decreasing angle (the bottom cap's front winding), 8–15 repeat
    // them (the top cap then faces away, the side walls have no area).
    vec2 lo = vec2(-1.0), hi = vec2(1.0);
    float ndc_z = -1.0;
    if (!inside_or_near) {
      float zz = C.z * C.z - R * R;
      vec2 k_lo, k_hi;
      for (int a = 0; a < 2; ++a) {
        float ca = C[a];
        float root = R * sqrt(max(ca * ca + zz, 0.0));
        float k0 = (-ca * C.z - root) / zz, k1 = (-ca * C.z + root) / zz;
        k_lo[a] = min(k0, k1);
        k_hi[a] = max(k0, k1);
      }
      lo = clamp(k_lo * scale, -1.0, 1.0);
      hi = clamp(k_hi * scale, -1.0, 1.0);
      float zn = C.z + R;  // nearest depth of the ball: fragments only move away from it
      ndc_z = (u_proj[2][2] * zn + u_proj[3][2]) / -zn;
    }
#ifdef SLIM_OUTLINE
    vec2 corner = vec2((vid & 1) != 0 ? hi.x : lo.x, (vid & 2) != 0 ? hi.y : lo.y);
#else
    int q = (vid & 7) >> 1;  // 0: (hi, lo), 1: (lo, lo), 2: (lo, hi), 3: (hi, hi)
    vec2 corner = vec2(q == 0 || q == 3 ? hi.x : lo.x, q >= 2 ? hi.y : lo.y);
#endif
    gl_Position = vec4(corner, ndc_z, 1.0);
    vec2 k = corner / scale;
    v_dir = vec3(k, -1.0);
    // The ray meets the plane z = C.z at −C.z·(k, −1); relative to the centre, in units of R.
    v_offset = vec3(k * -C.z - C.xy, 0.0) / R;
  }
  v_centre_eye = C;
  v_radius = R;
  v_A0 = Ae[0];  // columns of a symmetric matrix are its rows
  v_A1 = Ae[1];
  v_A2 = Ae[2];
  v_bc = vec4(be, c);
  v_clip = vec4(u_view_rot * ball.clip.xyz, ball.clip.w);
  v_colour = floatBitsToUint(ball.centre_lo.w);
  v_id = floatBitsToInt(ball.q2.z);
}
