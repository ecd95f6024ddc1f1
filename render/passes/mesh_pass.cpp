#include "render/passes/mesh_pass.h"

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/bounds.h"
#include "core/primitive.h"
#include "render/shaders.h"

namespace quadrix::render {

MeshPass::MeshPass() : program_("mesh", shader_source("mesh.vert"), shader_source("mesh.frag")) {}

namespace {

// One vertex as the vertex stage reads it: its offset from the mesh's fixed-point origin, its
// normal: the mesh's own per-vertex normal where it has them (`quadrix mesh` writes the drawn
// surface's), turned to its face's side, else its face's; and its colour: the mesh's own per-
// vertex colour where it has them (a molecule's atoms, a coloured scan's fit), else the pass's.
struct GpuVertex {
  std::int32_t q[3];
  float rest[3];
  float normal[3];
  std::uint8_t colour[4];
};
static_assert(sizeof(GpuVertex) == 40);

}  // namespace

void MeshPass::upload(const PolygonMesh& mesh, Rgb colour) {
  Box3 box;
  for (const auto& v : mesh.vertices) box.extend(v);
  origin_ = box.empty() ? FixedOrigin{} : FixedOrigin::of(box);
  const bool smooth = mesh.normals.size() == mesh.vertices.size();
  const bool coloured = mesh.colours.size() == mesh.vertices.size();
  std::vector<GpuVertex> data;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto face = mesh.face(f);
    for (std::size_t k = 1; k + 1 < face.size(); ++k) {
      const int corner[3] = {face[0], face[k], face[k + 1]};
      const Eigen::Vector3d a = mesh.vertices[corner[0]], b = mesh.vertices[corner[1]], c = mesh.vertices[corner[2]];
      Eigen::Vector3d n = (b - a).cross(c - a);
      if (!(n.norm() > 0)) continue;
      n.normalize();
      for (const int v : corner) {
        Eigen::Vector3d m = n;
        if (smooth && mesh.normals[v].allFinite() && mesh.normals[v].norm() > 0)
          m = mesh.normals[v].dot(n) < 0 ? Eigen::Vector3d(-mesh.normals[v].normalized()) : mesh.normals[v].normalized();
        const FixedOrigin::Offset o = origin_.offset(mesh.vertices[v] - origin_.origin);
        const Rgb& c = coloured ? mesh.colours[v] : colour;
        data.push_back({{o.q.x(), o.q.y(), o.q.z()}, {o.rest.x(), o.rest.y(), o.rest.z()},
                        {float(m.x()), float(m.y()), float(m.z())}, {c[0], c[1], c[2], 255}});
      }
    }
  }
  vertices_ = static_cast<GLsizei>(data.size());
  vbo_ = gl::make_buffer(static_cast<GLsizeiptr>(data.size() * sizeof(GpuVertex)), data.data());
  vao_ = gl::make_vertex_array();
  glVertexArrayVertexBuffer(vao_.id(), 0, vbo_.id(), 0, sizeof(GpuVertex));
  for (GLuint a = 0; a < 4; ++a) {
    glEnableVertexArrayAttrib(vao_.id(), a);
    if (a == 0)
      glVertexArrayAttribIFormat(vao_.id(), a, 3, GL_INT, offsetof(GpuVertex, q));
    else if (a == 3)
      glVertexArrayAttribFormat(vao_.id(), a, 4, GL_UNSIGNED_BYTE, GL_TRUE, offsetof(GpuVertex, colour));
    else
      glVertexArrayAttribFormat(vao_.id(), a, 3, GL_FLOAT, GL_FALSE, a == 1 ? offsetof(GpuVertex, rest) : offsetof(GpuVertex, normal));
    glVertexArrayAttribBinding(vao_.id(), a, 0);
  }
  has_mesh_ = true;
}

void MeshPass::run(const Frame& f) {
  begin_gbuffer_draw(f);
  set_camera_uniforms(program_, f.camera);
  set_origin_uniforms(program_, origin_, f.camera);
  program_.set("u_id_base", primitive_id(PrimitiveKind::mesh, 0));  // + the triangle's gl_PrimitiveID
  program_.use();
  glBindVertexArray(vao_.id());
  glDrawArrays(GL_TRIANGLES, 0, vertices_);
}

}  // namespace quadrix::render
