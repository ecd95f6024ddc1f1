// Glyph pass, vertex stage ([Sigg06] §3): spheres, ellipsoids and capped cylinders, each drawn
// as one instance of a convex polygon (u_sides vertices) around its exact projected outline.
//
// A sphere or an ellipsoid is x = C + M u, ‖u‖ ≤ 1; its outline on screen is the ellipse of the
// projected dual quadric P Q* Pᵀ ([Sigg06] eq. 5, where the bounding box is read from the same
// conic). The proxy is the regular octagon circumscribing the unit circle mapped onto that
// ellipse: 5.2 % of its area lies outside ([Toledo04]; a square wastes 21.5 %). A capped
// cylinder is the convex hull of its two end discs (degenerate ellipsoids): the proxy is the
// polygon of u_sides support lines of the two cap ellipses, the first along the projected axis.
// Glyphs reaching the near plane, or around the eye, get the whole viewport; glyphs behind the
// eye get nothing.
//
// With w = 1 the polygon is affine in screen space, so the eye-space ray direction (k, −1) and
// the ray's point in the plane through the centre (perpendicular to the view axis) interpolate
// exactly; the fragment stage restarts each ray there, so nothing large cancels.

// struct Glyph and the Glyphs buffer: glyph_lib.glsl.

uniform mat4 u_proj;
uniform mat3 u_view_rot;
uniform float u_target_distance;
uniform float u_near;
uniform vec2 u_viewport;
uniform int u_sides;  // polygon vertices per glyph (one draw per kind group)
uniform int u_first;  // index of this draw's first glyph

out vec3 v_dir;     // eye-space ray direction through the pixel (z = −1)
out vec3 v_offset;  // ray point in the centre's view plane, relative to the centre (eye axes)
flat out float v_centre_z;  // C.z; the ray's eye-space z is C.z − s, the eye at s = C.z
flat out float v_scale;     // the fragment stage's unit of s: the glyph's distance (or size)
flat out vec3 v_inv0;     // rows of M⁻¹ in eye axes
flat out vec3 v_inv1;
flat out vec3 v_inv2;
flat out uint v_kind;
flat out uint v_colour;
flat out int v_id;
flat out uint v_index;  // in the Glyphs buffer

void project_ellipse(vec3 C, mat3 S, out vec2 c, out mat2 S2) {
  project_ellipse(C, S, vec2(u_proj[0][0], u_proj[1][1]), c, S2);  // NDC
}

void main() {
  Glyph g = glyphs[u_first + gl_InstanceID];
  uint kind = uint(g.centre_hi.w);
  vec3 C = glyph_centre_eye(g, u_view_rot, u_target_distance);
  mat3 Sw = mat3(g.s0.x, g.s0.w, g.s1.y,
                 g.s0.w, g.s0.y, g.s1.x,
                 g.s1.y, g.s1.x, g.s0.z);
  mat3 Sn = u_view_rot * Sw * transpose(u_view_rot);  // S / size²
  float size = g.s1.z;
  vec3 a = u_view_rot * g.axis.xyz;
  // Nearest and farthest eye-space z of the glyph.
  float disc_reach = size * sqrt(max(Sn[2][2], 0.0));
  float reach = kind == 2u ? abs(a.z) + disc_reach : disc_reach;
  float L = max(abs(C.z), size);  // lengths below are in units of L
  mat3 S = Sn * ((size / L) * (size / L));
  float z_near = C.z + reach;
  // Half a hundredth of a pixel of slack (NDC), so rounding never cuts a silhouette pixel.
  vec2 pad = 0.01 / u_viewport;

  int k = strip_vertex(gl_VertexID, u_sides);
  float step = radians(360.0) / float(u_sides);
  vec2 corner;
  float ndc_z = -1.0;
  if (C.z - reach >= 0.0) {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // wholly behind the eye
    return;
  } else if (z_near > -u_near * 1.0001) {
    // Around the eye or reaching the near plane: the whole viewport (each polygon vertex moved to
    // the corner of its quadrant, so the polygon becomes the square).
    float ang = step * (float(k) + 0.5);  // never a multiple of 90° (u_sides is a multiple of 4)
    corner = vec2(cos(ang) > 0.0 ? 1.0 : -1.0, sin(ang) > 0.0 ? 1.0 : -1.0);
  } else {
    float kc = 1.0 / cos(0.5 * step);  // circumradius of the polygon around the unit circle
    if (kind != 2u) {
      vec2 c;
      mat2 S2;
      project_ellipse(C / L, S, c, S2);
      S2 += mat2(pad.x * pad.x, 0.0, 0.0, pad.y * pad.y);
      // L Lᵀ = S2 (Cholesky), so c + L·(unit circle) is the ellipse.
      float l00 = sqrt(max(S2[0][0], 1e-30));
      float l10 = S2[0][1] / l00;
      float l11 = sqrt(max(S2[1][1] - l10 * l10, 0.0));
      float ang = step * (float(k) + 0.5);
      vec2 u = kc * vec2(cos(ang), sin(ang));
      corner = c + vec2(l00 * u.x, l10 * u.x + l11 * u.y);
    } else {
      vec2 c0, c1;
      mat2 S0, S1;
      project_ellipse((C + a) / L, S, c0, S0);
      project_ellipse((C - a) / L, S, c1, S1);
      S0 += mat2(pad.x * pad.x, 0.0, 0.0, pad.y * pad.y);
      S1 += mat2(pad.x * pad.x, 0.0, 0.0, pad.y * pad.y);
      vec2 d = c0 - c1;
      float len = length(d);
      d = len > 1e-12 ? d / len : vec2(1.0, 0.0);
      // Lines nᵢ·x = hᵢ at equal steps from the projected axis; vertex k joins lines k and k + 1.
      float ang0 = step * float(k), ang1 = step * float(k + 1);
      mat2 R0 = mat2(cos(ang0), sin(ang0), -sin(ang0), cos(ang0));
      mat2 R1 = mat2(cos(ang1), sin(ang1), -sin(ang1), cos(ang1));
      vec2 n0 = R0 * d, n1 = R1 * d;
      float h0 = hull_support(c0, S0, c1, S1, n0);
      float h1 = hull_support(c0, S0, c1, S1, n1);
      // Solve [n0; n1] x = (h0, h1).
      float det = n0.x * n1.y - n0.y * n1.x;
      corner = vec2(h0 * n1.y - h1 * n0.y, n0.x * h1 - n1.x * h0) / det;
    }
    ndc_z = (u_proj[2][2] * z_near + u_proj[3][2]) / -z_near;  // nearest point: fragments lie behind
  }
  gl_Position = vec4(corner, ndc_z, 1.0);
  vec2 kk = corner / vec2(u_proj[0][0], u_proj[1][1]);
  v_dir = vec3(kk, -1.0);
  v_offset = vec3(kk * -C.z - C.xy, 0.0);
  v_centre_z = C.z;
  v_scale = L;
  mat3 inv_eye = glyph_inverse_eye(g, u_view_rot);
  v_inv0 = vec3(inv_eye[0][0], inv_eye[1][0], inv_eye[2][0]);
  v_inv1 = vec3(inv_eye[0][1], inv_eye[1][1], inv_eye[2][1]);
  v_inv2 = vec3(inv_eye[0][2], inv_eye[1][2], inv_eye[2][2]);
  v_kind = kind;
  v_colour = floatBitsToUint(g.centre_lo.w);
  v_id = floatBitsToInt(g.inv0.w);
  v_index = uint(u_first + gl_InstanceID);
}
