#pragma once
/// Ordinary triangles (polygons fanned, flat face normals) drawn into the same G-buffer as the
/// quadrics, depth-correct against them.
#include "core/mesh_io.h"
#include "render/passes/frame.h"

namespace quadrix::render {

class MeshPass final : public Pass {
public:
  MeshPass();  ///< compiles the program. \throws GlError.
  /// The mesh's triangles, each vertex in its own colour where the mesh has colours, else `colour`.
  void upload(const PolygonMesh& mesh, Rgb colour);
  bool needed(const RenderOptions&) const override { return has_mesh_; }
  void run(const Frame& frame) override;

private:
  gl::Program program_;
  gl::VertexArray vao_;
  gl::Buffer vbo_;
  GLsizei vertices_ = 0;
  FixedOrigin origin_;  // vertices are whole quanta plus a float rest from it
  bool has_mesh_ = false;
};

}  // namespace quadrix::render
