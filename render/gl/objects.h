#pragma once
/// Thin move-only RAII wrappers over OpenGL objects (Magnum-style): one owner per GL name.
#include <glad/gl.h>

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace quadrix::render::gl {

/// Owns one GL name; Delete is called with it on destruction.
template <void (*Delete)(GLuint)>
class Handle {
public:
  Handle() = default;
  explicit Handle(GLuint id) : id_(id) {}
  ~Handle() { reset(); }
  Handle(Handle&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, 0);
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  GLuint id() const { return id_; }
  explicit operator bool() const { return id_ != 0; }
  void reset() {
    if (id_) Delete(id_);
    id_ = 0;
  }

private:
  GLuint id_ = 0;
};

namespace detail {
inline void delete_buffer(GLuint id) { glDeleteBuffers(1, &id); }
inline void delete_vertex_array(GLuint id) { glDeleteVertexArrays(1, &id); }
inline void delete_texture(GLuint id) { glDeleteTextures(1, &id); }
inline void delete_framebuffer(GLuint id) { glDeleteFramebuffers(1, &id); }
inline void delete_query(GLuint id) { glDeleteQueries(1, &id); }
inline void delete_program(GLuint id) { glDeleteProgram(id); }
}  // namespace detail

using Buffer = Handle<detail::delete_buffer>;
using VertexArray = Handle<detail::delete_vertex_array>;
using Texture = Handle<detail::delete_texture>;
using Framebuffer = Handle<detail::delete_framebuffer>;
using Query = Handle<detail::delete_query>;

Buffer make_buffer(GLsizeiptr bytes, const void* data, GLbitfield flags = 0);
VertexArray make_vertex_array();
Texture make_texture_2d(GLenum internal_format, int width, int height);
Query make_query(GLenum target);

/// A linked program with cached uniform locations and typed setters. It refuses to draw (use()
/// throws) while a uniform it declares was never set; samplers are set by their layout binding.
class Program {
public:
  Program() = default;
  /// Compiles and links; the prelude, then `defines` (e.g. "#define MODE 1\n"), are prepended to
  /// every stage. \throws GlError with the compiler log and the stage's file name.
  Program(std::string_view name, std::string_view vertex, std::string_view fragment, std::string_view defines = {});
  GLuint id() const { return handle_.id(); }
  const std::string& name() const { return name_; }
  /// Binds the program for drawing. \throws GlError naming the program and the first active
  /// uniform that was never set.
  void use() const;
  /// Location of an active uniform, −1 for one the program does not declare (setting it is a no-op).
  GLint location(const char* uniform) const;
  void set(const char* u, int v) const { glProgramUniform1i(id(), mark(u), v); }
  void set(const char* u, unsigned v) const { glProgramUniform1ui(id(), mark(u), v); }
  void set(const char* u, float v) const { glProgramUniform1f(id(), mark(u), v); }
  void set(const char* u, double v) const { glProgramUniform1d(id(), mark(u), v); }  ///< a double uniform
  void set(const char* u, const Eigen::Vector2f& v) const { glProgramUniform2fv(id(), mark(u), 1, v.data()); }
  void set(const char* u, const Eigen::Vector3f& v) const { glProgramUniform3fv(id(), mark(u), 1, v.data()); }
  void set(const char* u, const Eigen::Vector3d& v) const { glProgramUniform3dv(id(), mark(u), 1, v.data()); }  ///< dvec3
  void set(const char* u, const Eigen::Vector3i& v) const { glProgramUniform3iv(id(), mark(u), 1, v.data()); }
  void set(const char* u, const Eigen::Vector4f& v) const { glProgramUniform4fv(id(), mark(u), 1, v.data()); }
  void set(const char* u, const Eigen::Matrix3f& m) const {
    glProgramUniformMatrix3fv(id(), mark(u), 1, GL_FALSE, m.data());
  }
  void set(const char* u, const Eigen::Matrix4f& m) const {
    glProgramUniformMatrix4fv(id(), mark(u), 1, GL_FALSE, m.data());
  }

private:
  struct Uniform {
    std::string name;
    GLint location = -1;
    bool is_set = false;
  };
  /// The uniform's location, recorded as set.
  GLint mark(const char* uniform) const;

  Handle<detail::delete_program> handle_;
  std::string name_;
  mutable std::vector<Uniform> uniforms_;  // active non-sampler uniforms, queried after linking
};

/// Throws GlError naming `where` if glGetError reports an error.
void check_error(const char* where);

}  // namespace quadrix::render::gl
