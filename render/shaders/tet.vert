// Tetrahedron pass, vertex stage ([Stoll06] §5): one instance per tetrahedron, 12 vertices
// (its 4 faces). Work linear in the view vector is done here and interpolated (incremental ray
// casting): the entry point o, the view vector v, A·o + b, A·v and the four clip planes at o and
// along v. All local coordinates are relative to the centroid and scaled by the tetrahedron's
// size s, so float keeps its precision (DESIGN §5).

struct Tet {
  vec4 centre_hi;   // xyz: int bits, centroid − the model's origin in quanta (u_quantum), w: scale s
  vec4 centre_lo;   // xyz: the rest of that difference, w: colour bits
  vec4 corner[4];   // local corners (p − c)/s; w: primitive index bits
  vec4 q0;          // A00 A11 A22 A01
  vec4 q1;          // A12 A02 b0 b1
  vec4 q2;          // b2 c — —
};
layout(std430, binding = 0) readonly buffer Tets { Tet tets[]; };
layout(std430, binding = 2) readonly buffer TetCornerColours { uvec4 corner_colours[]; };
layout(std430, binding = 1) buffer Stats { uint culled; uint drawn; uint splat_fragments; uint hit_fragments; } stats;

uniform mat4 u_proj;
uniform mat3 u_view_rot;
uniform vec3 u_target_minus_eye;   // (target − eye), from double
uniform float u_target_distance;   // ‖target − eye‖: the target is at (0, 0, −distance) in eye space
uniform int u_cull;        // per-quadric and per-fragment backface culling
uniform int u_count_stats;
uniform int u_indexed;
uniform int u_base;         // instanced: the first tetrahedron of this draw

out vec3 v_o;
out vec3 v_dir;
out vec3 v_Aob;
out vec3 v_Av;
out vec4 v_plane_o;
out vec4 v_plane_v;
out float v_z_entry;
flat out vec4 v_bc;
flat out uint v_colour;
#if TET_CORNER_COLOURS  // colours per corner (binding 2), blended barycentrically
flat out uvec4 v_corner_colours;
flat out vec4 v_heights;       // each corner's distance from its opposite face (local units)
#endif
flat out int v_id;

// Faces with outward counter-clockwise order for a positively oriented tetrahedron.
const int kFace[12] = int[12](1, 2, 3, 0, 3, 2, 0, 1, 3, 0, 2, 1);

void main() {
  // Indexed: 4 vertices per tetrahedron (gl_VertexID = 4·tet + corner) shared by its 4 faces
  // through the element buffer, so each corner is shaded once, not three times. Instanced (the
  // statistics frame): 12 vertices per instance, each counted exactly once.
  int tet = u_indexed != 0 ? gl_VertexID >> 2 : u_base + gl_InstanceID;
  int k = u_indexed != 0 ? gl_VertexID & 3 : kFace[gl_VertexID];
  Tet t = tets[tet];
  mat3 A = mat3(t.q0.x, t.q0.w, t.q1.y,
                t.q0.w, t.q0.y, t.q1.x,
                t.q1.y, t.q1.x, t.q0.z);
  vec3 b = vec3(t.q1.z, t.q1.w, t.q2.x);
  float c = t.q2.y;
  float s = t.centre_hi.w;
  // Positions relative to the view target, then to the eye: a far eye puts only the view-axis
  // component far away, so screen positions keep float precision (DESIGN §5). No large float
  // coordinate appears: the origin's offset from the target was taken in double, and its whole
  // quanta meet the centre's in integers (prelude.glsl from_fixed_origin).
  vec3 centre_from_target = from_fixed_origin(t.centre_hi.xyz, t.centre_lo.xyz);
  vec3 rel_centre = centre_from_target + u_target_minus_eye;

  // Per-quadric backface culling, [Stoll06] eq. 19 rewritten about each corner so no large
  // terms cancel: c′ + p′ᵢᵀb′ = f(pᵢ) − yᵢᵀ(A pᵢ + b), with yᵢ the eye-relative corner.
  bool culled = false;
  if (u_cull != 0) {
    culled = true;
    for (int i = 0; i < 4; ++i) {
      vec3 p = t.corner[i].xyz;
      vec3 y = rel_centre / s + p;
      vec3 g = A * p + b;
      float f = dot(p, g) + dot(b, p) + c;
      if (f - dot(y, g) >= 0.0) { culled = false; break; }
    }
  }
  if (u_count_stats != 0 && u_indexed == 0 && gl_VertexID == 0) {
    if (culled) atomicAdd(stats.culled, 1u); else atomicAdd(stats.drawn, 1u);
  }
  if (culled) {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // outside the clip volume: the face is dropped
    return;
  }

  vec3 o = t.corner[k].xyz;
  vec3 rel = rel_centre + s * o;           // eye-relative world position of this corner
  vec3 eye_pos = u_view_rot * (centre_from_target + s * o) + vec3(0.0, 0.0, -u_target_distance);
  gl_Position = u_proj * vec4(eye_pos, 1.0);
  v_o = o;
  v_dir = rel / s;                         // x(λ) = o + λ·v; λ = −1 is the eye
  v_Aob = A * o + b;
  v_Av = A * v_dir;
  v_z_entry = eye_pos.z;
  // Inward planes nᵢ·x + dᵢ ≥ 0 of the faces opposite each corner (unit nᵢ, local units).
  for (int i = 0; i < 4; ++i) {
    vec3 p0 = t.corner[(i + 1) & 3].xyz, p1 = t.corner[(i + 2) & 3].xyz, p2 = t.corner[(i + 3) & 3].xyz;
    vec3 n = normalize(cross(p1 - p0, p2 - p0));
    if (dot(n, t.corner[i].xyz - p0) < 0.0) n = -n;
    float d = -dot(n, p0);
    v_plane_o[i] = dot(n, o) + d;
    v_plane_v[i] = dot(n, v_dir);
#if TET_CORNER_COLOURS
    v_heights[i] = dot(n, t.corner[i].xyz) + d;
#endif
  }
#if TET_CORNER_COLOURS
  v_corner_colours = corner_colours[tet];
#endif
  v_bc = vec4(b, c);
  v_colour = floatBitsToUint(t.centre_lo.w);
  v_id = floatBitsToInt(t.corner[0].w);
}
