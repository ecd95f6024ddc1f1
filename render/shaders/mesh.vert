// Ordinary triangle meshes drawn into the same G-buffer ([Toledo04]: ray-cast primitives and
// triangles share one depth buffer, so they mix in any order). Positions are relative to the
// mesh's own origin; the camera-relative offset comes in hi/lo parts.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
uniform mat4 u_proj;
uniform mat3 u_view_rot;
uniform vec3 u_origin_minus_target;  // computed in double on the CPU
uniform float u_target_distance;
out vec3 v_normal;
out float v_z;
void main() {
  vec3 eye_pos = u_view_rot * (u_origin_minus_target + a_position) + vec3(0.0, 0.0, -u_target_distance);
  v_normal = a_normal;
  v_z = eye_pos.z;
  gl_Position = u_proj * vec4(eye_pos, 1.0);
}
