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
// Samplers and images: their units come from layout(binding = …) in the shaders.
bool is_opaque(GLenum type) {
  switch (type) {
    case GL_SAMPLER_1D: case GL_SAMPLER_2D: case GL_SAMPLER_3D: case GL_SAMPLER_CUBE:
    case GL_SAMPLER_2D_SHADOW: case GL_SAMPLER_2D_ARRAY: case GL_SAMPLER_BUFFER:
    case GL_INT_SAMPLER_2D: case GL_UNSIGNED_INT_SAMPLER_2D: case GL_SAMPLER_2D_MULTISAMPLE:
    case GL_IMAGE_2D: case GL_INT_IMAGE_2D: case GL_UNSIGNED_INT_IMAGE_2D: case GL_IMAGE_3D:
    case GL_UNSIGNED_INT_ATOMIC_COUNTER:
      return true;
    default:
      return false;
  }
}

GLuint compile(GLenum stage, std::string_view name, std::string_view source, std::string_view defines) {
  // The defines go right after the prelude's #version line: #extension directives must come
  // before any code.
  const std::string_view prelude = shader_source("prelude.glsl");
  const std::size_t body = prelude.find('\n') + 1;
  const std::string full = std::string(prelude.substr(0, body)) + std::string(defines) + "\n" +
                           std::string(prelude.substr(body)) + "\n#line 1\n" + std::string(source);
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
  name_ = name;
  GLint count = 0, max_length = 0;
  glGetProgramiv(p, GL_ACTIVE_UNIFORMS, &count);
  glGetProgramiv(p, GL_ACTIVE_UNIFORM_MAX_LENGTH, &max_length);
  std::string buffer(static_cast<std::size_t>(std::max(max_length, 1)), '\0');
  for (GLint i = 0; i < count; ++i) {
    GLsizei length = 0;
    GLint size = 0;
    GLenum type = 0;
    glGetActiveUniform(p, static_cast<GLuint>(i), max_length, &length, &size, &type, buffer.data());
    std::string uniform(buffer.data(), static_cast<std::size_t>(length));
    if (is_opaque(type)) continue;  // bound through layout(binding = …)
    if (uniform.ends_with("[0]")) uniform.resize(uniform.size() - 3);
    const GLint loc = glGetUniformLocation(p, uniform.c_str());
    if (loc < 0) continue;  // in a uniform block: set through its buffer
    uniforms_.push_back({std::move(uniform), loc, false});
  }
}

GLint Program::location(const char* uniform) const {
  for (const auto& u : uniforms_)
    if (u.name == uniform) return u.location;
  return -1;
}

GLint Program::mark(const char* uniform) const {
  for (auto& u : uniforms_)
    if (u.name == uniform) {
      u.is_set = true;
      return u.location;
    }
  return -1;
}

void Program::use() const {
  for (const auto& u : uniforms_)
    if (!u.is_set) throw GlError(fmt::format("program '{}' draws with uniform '{}' never set", name_, u.name));
  glUseProgram(handle_.id());
}

void check_error(const char* where) {
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR) throw GlError(fmt::format("{}: GL error 0x{:x}", where, e));
}

}  // namespace quadrix::render::gl
