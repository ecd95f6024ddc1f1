// One triangle that covers the screen; FULLSCREEN_AT_FAR puts it on the far plane (window
// depth 1), where a GL_GREATER depth test keeps only the pixels some pass drew.
out vec2 v_uv;
void main() {
  vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
  v_uv = p;
#ifdef FULLSCREEN_AT_FAR
  gl_Position = vec4(2.0 * p - 1.0, 1.0, 1.0);
#else
  gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0);
#endif
}
