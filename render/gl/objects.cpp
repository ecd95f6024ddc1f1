#include "render/gl/objects.h"

#include <fmt/format.h>

#include "core/error.h"
#include "render/shaders.h"

namespace quadrix::render::gl {

Buffer make_buffer(GLsizeiptr bytes, const void* data, GLbitfield flags) {
  GLuint id = 0;
  glCreateBuffers(1, &id);
  glNamedBufferStorage(id, std::max<GLsizeiptr>(bytes, 16), data && bytes > 0 ? data : nullptr, flags);
  Buffer b(id);
  check_error("glNamedBufferStorage (out of GPU memory?)");
  return b;
}

VertexArray make_vertex_array() {
  GLuint id = 0;
  glCreateVertexArrays(1, &id);
  return VertexArray(id);
}

Texture make_texture_2d(GLenum internal_format, int width, int height) {
  GLuint id = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &id);
  glTextureStorage2D(id, 1, internal_format, width, height);
  glTextureParameteri(id, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(id, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTextureParameteri(id, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(id, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return Texture(id);
}

Query make_query(GLenum) {
  // glGenQueries: the target is bound at glBeginQuery (glCreateQueries rejects extension targets
  // such as GL_FRAGMENT_SHADER_INVOCATIONS_ARB on some drivers).
  GLuint id = 0;
  glGenQueries(1, &id);
  return Query(id);
}

namespace {
GLuint compile(GLenum stage, std::string_view name, std::string_view source, std::string_view defines) {
  const std::string full = std::string(shader_source("prelude.glsl")) + "\n" + std::string(defines) + "\n#line 1\n" +
                           std::string(source);
  const GLuint s = glCreateShader(stage);
  const char* text = full.c_str();
  glShaderSource(s, 1, &text, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
    std::string log(std::max(len, 1), '\0');
    glGetShaderInfoLog(s, len, nullptr, log.data());
    glDeleteShader(s);
    throw GlError(fmt::format("shader {} ({}) failed to compile:\n{}", name,
                              stage == GL_VERTEX_SHADER ? "vertex" : "fragment", log));
  }
  return s;
}
}  // namespace

Program::Program(std::string_view name, std::string_view vertex, std::string_view fragment, std::string_view defines) {
  const GLuint vs = compile(GL_VERTEX_SHADER, name, vertex, defines);
  GLuint fs = 0;
  try {
    fs = compile(GL_FRAGMENT_SHADER, name, fragment, defines);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  const GLuint p = glCreateProgram();
  glAttachShader(p, vs);
  glAttachShader(p, fs);
  glLinkProgram(p);
  glDeleteShader(vs);
  glDeleteShader(fs);
  handle_ = Handle<detail::delete_program>(p);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetProgramiv(p, GL_INFO_LOG_LENGTH, &len);
    std::string log(std::max(len, 1), '\0');
    glGetProgramInfoLog(p, len, nullptr, log.data());
    throw GlError(fmt::format("program {} failed to link:\n{}", name, log));
  }
}

GLint Program::location(const char* uniform) const {
  auto it = locations_.find(uniform);
  if (it != locations_.end()) return it->second;
  const GLint loc = glGetUniformLocation(id(), uniform);
  locations_.emplace(uniform, loc);
  return loc;
}

void check_error(const char* where) {
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR) throw GlError(fmt::format("{}: GL error 0x{:x}", where, e));
}

}  // namespace quadrix::render::gl
