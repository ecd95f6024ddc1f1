#include "render/passes/mesh_pass.h"

#include <vector>

#include "core/bounds.h"
#include "core/primitive.h"
#include "render/shaders.h"

namespace quadrix::render {

MeshPass::MeshPass() : program_("mesh", shader_source("mesh.vert"), shader_source("mesh.frag")) {}

void MeshPass::upload(const PolygonMesh& mesh, Rgb colour) {
  Box3 box;
  for (const auto& v : mesh.vertices) box.extend(v);
  origin_ = box.empty() ? Eigen::Vector3d::Zero() : box.centre();
  colour_ = colour;
  std::vector<float> data;  // position, normal per vertex; flat face normals
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto face = mesh.face(f);
    for (std::size_t k = 1; k + 1 < face.size(); ++k) {
      const Eigen::Vector3d a = mesh.vertices[face[0]], b = mesh.vertices[face[k]], c = mesh.vertices[face[k + 1]];
      Eigen::Vector3d n = (b - a).cross(c - a);
      if (!(n.norm() > 0)) continue;
      n.normalize();
      for (const auto* p : {&a, &b, &c}) {
        const Eigen::Vector3f q = (*p - origin_).cast<float>();
        data.insert(data.end(), {q.x(), q.y(), q.z(), float(n.x()), float(n.y()), float(n.z())});
      }
    }
  }
  vertices_ = static_cast<GLsizei>(data.size() / 6);
  vbo_ = gl::make_buffer(static_cast<GLsizeiptr>(data.size() * sizeof(float)), data.data());
  vao_ = gl::make_vertex_array();
  glVertexArrayVertexBuffer(vao_.id(), 0, vbo_.id(), 0, 6 * sizeof(float));
  for (GLuint a = 0; a < 2; ++a) {
    glEnableVertexArrayAttrib(vao_.id(), a);
    glVertexArrayAttribFormat(vao_.id(), a, 3, GL_FLOAT, GL_FALSE, a * 3 * sizeof(float));
    glVertexArrayAttribBinding(vao_.id(), a, 0);
  }
  has_mesh_ = true;
}

void MeshPass::run(const Frame& f) {
  begin_gbuffer_draw(f);
  set_camera_uniforms(program_, f.camera);
  program_.set("u_origin_minus_target", Eigen::Vector3f((origin_ - f.camera.target_world).cast<float>()));
  program_.set("u_colour", Eigen::Vector3f(colour_[0] / 255.f, colour_[1] / 255.f, colour_[2] / 255.f));
  program_.set("u_id_base", primitive_id(PrimitiveKind::mesh, 0));  // + the triangle's gl_PrimitiveID
  program_.use();
  glBindVertexArray(vao_.id());
  glDrawArrays(GL_TRIANGLES, 0, vertices_);
}

}  // namespace quadrix::render
