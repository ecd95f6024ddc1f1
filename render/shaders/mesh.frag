in vec3 v_normal;
in vec3 v_colour;
in float v_z;
uniform int u_id_base;
layout(location = 0) out vec4 out_normal_depth;
layout(location = 1) out vec4 out_albedo;
layout(location = 2) out int out_id;
void main() {
  vec3 n = normalize(v_normal);
  out_normal_depth = vec4(gl_FrontFacing ? n : -n, -v_z);
  out_albedo = vec4(v_colour, 1.0);
  out_id = u_id_base + gl_PrimitiveID;
}
