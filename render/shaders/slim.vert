// SLIM splats, vertex stage ([Stoll06] §5.1.1, [Sigg06] eq. 5): one instanced quad per ball with
// the tight screen bound of the ball, the patch quadric rotated into eye axes (flat), and the
// per-quadric backface test for spheres ([Stoll06] eq. 18). Balls the camera is in, or that
// straddle the near plane, get the whole viewport: never clipped.
//
// With w = 1 the quad is affine in screen space, so the eye-space ray direction (x/P00, y/P11, −1)
// and the ray's point in the plane through the centre (perpendicular to the view axis) are
// interpolated exactly; the fragment stage re-starts each ray there (local units of R), so
// nothing large cancels even when the eye is far away.

struct Ball {
  vec4 centre_hi;  // xyz: centre (float part), w: radius R
  vec4 centre_lo;  // xyz: centre − float(centre), w: colour bits
  vec4 q0;         // A00 A11 A22 A01   (g(u), u = (x − c)/R, world axes)
  vec4 q1;         // A12 A02 b0 b1
  vec4 q2;         // b2 c, primitive index bits, —
  vec4 clip;       // n (local, world axes), d; n = 0: no clip plane
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

out vec3 v_dir;      // eye-space ray direction through the pixel (z = −1)
out vec3 v_offset;   // ray point in the centre's view plane, relative to the centre, units of R
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
  int vid = gl_VertexID;
#endif

  // Tight bound ([Sigg06] eq. 5 for a sphere): the tangent lines from the eye in the xz and yz
  // planes give the slopes k = x/(−z) of the silhouette, ndc = P·k.
  vec2 lo = vec2(-1.0), hi = vec2(1.0);
  float ndc_z = -1.0;
  bool inside_or_near = dot(C, C) <= R * R * 1.0001 || C.z + R > -u_near;
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
    vec2 scale = vec2(u_proj[0][0], u_proj[1][1]);
    lo = clamp(k_lo * scale, -1.0, 1.0);
    hi = clamp(k_hi * scale, -1.0, 1.0);
    float zn = C.z + R;  // nearest depth of the ball: fragments only move away from it
    ndc_z = (u_proj[2][2] * zn + u_proj[3][2]) / -zn;
  }
  vec2 corner = vec2((vid & 1) != 0 ? hi.x : lo.x, (vid & 2) != 0 ? hi.y : lo.y);
  gl_Position = vec4(corner, ndc_z, 1.0);
  vec2 k = corner / vec2(u_proj[0][0], u_proj[1][1]);
  v_dir = vec3(k, -1.0);
  // The ray meets the plane z = C.z at −C.z·(k, −1); relative to the centre, in units of R.
  v_offset = vec3(k * -C.z - C.xy, 0.0) / R;
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
