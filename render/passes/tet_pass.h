#pragma once
/// Tetrahedron-clipped quadrics: the front faces of each tetrahedron ray-cast their quadric,
/// the hit clipped against the 4 planes, into the G-buffer (DESIGN §6 tet pass).
#include <span>

#include "core/model.h"
#include "render/passes/frame.h"

namespace quadrix::render {

class TetPass final : public Pass {
public:
  TetPass();  ///< compiles the program. \throws GlError.
  /// \throws InvalidInput past kMaxPrimitiveIndex patches, GlError (out of GPU memory).
  void upload(std::span<const TetPatch> tets);
  std::size_t count() const { return count_; }
  bool needed(const RenderOptions&) const override { return count_ > 0; }
  void run(const Frame& frame) override;

private:
  gl::Program program_;
  gl::Buffer tets_;
  gl::Buffer indices_;     // 12 per tetrahedron: its 4 faces over vertices 4·t + corner
  gl::VertexArray vao_;    // holds indices_ as its element buffer
  gl::Buffer corner_colours_;  // uvec4 per tetrahedron (packed RGB per GPU corner), or 16 bytes
  bool has_corner_colours_ = false;
  std::size_t count_ = 0;
};

}  // namespace quadrix::render
