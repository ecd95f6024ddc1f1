// Ordinary triangle meshes drawn into the same G-buffer ([Toledo04]: ray-cast primitives and
// triangles share one depth buffer, so they mix in any order). Each vertex is its offset from the
// mesh's fixed-point origin (render/passes/frame.h FixedOrigin): whole quanta plus a float rest,
// so near the view target the large parts cancel in integers, however far the target lies from
// the mesh's centre (a float offset from the centre left a tiny part of a large mesh at depth
// p99 1e-3: FarMesh.TinyPartOfALargeMeshAsAtTheOrigin).
layout(location = 0) in ivec3 a_quanta;
layout(location = 1) in vec3 a_rest;
layout(location = 2) in vec3 a_normal;
layout(location = 3) in vec4 a_colour;  // the vertex's colour (the pass's where the mesh has none)
uniform mat4 u_proj;
uniform mat3 u_view_rot;
uniform float u_target_distance;
out vec3 v_normal;
out vec3 v_colour;
out float v_z;
void main() {
  vec3 eye_pos = u_view_rot * from_fixed_origin(a_quanta, a_rest) + vec3(0.0, 0.0, -u_target_distance);
  v_normal = a_normal;
  v_colour = a_colour.rgb;
  v_z = eye_pos.z;
  gl_Position = u_proj * vec4(eye_pos, 1.0);
}
