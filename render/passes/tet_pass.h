#pragma once
/// Tetrahedron-clipped quadrics: the front faces of each tetrahedron ray-cast their quadric,
/// the hit clipped against the 4 planes, into the G-buffer (DESIGN §6 tet pass). Tetrahedra are
/// grouped into spatial chunks at upload; a frame skips the chunks outside the view frustum and
/// draws the rest nearest first, so that the early depth test rejects hidden tetrahedra
/// (RenderOptions::tet_early_depth).
#include <array>
#include <optional>
#include <span>

#include "core/model.h"
#include "render/passes/chunks.h"
#include "render/passes/frame.h"

namespace quadrix::render {

class TetPass final : public Pass {
public:
  TetPass();  ///< compiles the program. \throws GlError.
  /// \throws InvalidInput past kMaxPrimitiveIndex patches, GlError (out of GPU memory).
  /// `tessellation`: no two tetrahedra overlap beyond a face (RenderOptions::tet_early_depth).
  void upload(std::span<const TetPatch> tets, bool tessellation = false);
  std::size_t count() const { return count_; }
  bool needed(const RenderOptions&) const override { return count_ > 0; }
  void run(const Frame& frame) override;
  /// The chunks the last frame skipped (outside the view frustum) and the patches in them.
  std::size_t culled_chunks() const { return selection_.culled_chunks; }
  std::size_t culled_in_chunks() const { return selection_.culled_primitives; }
  std::size_t chunk_count() const { return chunks_.size(); }
  /// The chunks the last frame skipped as hidden behind those it had drawn, and their patches.
  std::size_t occluded_chunks() const { return selection_.occluded_chunks; }
  std::size_t occluded_in_chunks() const { return selection_.occluded_primitives; }

private:
  /// Writes the depth buffer from the G-buffer's eye depth (after an early-depth frame).
  void depth_from_gbuffer(const Frame& frame);
  void draw_chunks(const Frame& frame, const gl::Program& program, std::span<const std::uint32_t> chunks);
  /// The depth buffer read back (a pipeline stall) as tiles of its farthest depth.
  DepthTiles read_depth_tiles(const FrameTargets& targets);
  /// Below this many visible chunks the occlusion round trip is not worth its stall.
  static constexpr std::size_t kMinChunksForOcclusion = 64;
  static constexpr std::size_t kChunkSize = 1024;

  /// The program of each depth mode and corner colouring, built on first use: models without
  /// corner colours pass 8 fewer values to every triangle (llvmpipe sets each up per triangle:
  /// the 503k-cell Marschner–Lobb volume at 128², 226–231 ms a frame instead of 240).
  const gl::Program& program(bool entry_face_depth, bool corner_colours);
  std::array<std::optional<gl::Program>, 4> programs_;  // [2 · entry-face depth + corner colours]
  gl::Program depth_program_;
  Chunks chunks_;
  ChunkSelection selection_;
  std::vector<GLsizei> draw_counts_;
  std::vector<const void*> draw_offsets_;
  gl::Framebuffer depth_fbo_;       // the G-buffer's depth texture alone
  unsigned depth_generation_ = 0;   // the FrameTargets generation depth_fbo_ was made for
  std::vector<std::uint8_t> drawn_last_;  // per chunk: drawn and not found hidden last frame
  bool has_history_ = false;
  bool tessellation_ = false;
  std::vector<float> depth_pixels_;
  FixedOrigin origin_;              // the stored centres are relative to it (quanta and a rest)
  gl::Buffer tets_;
  gl::Buffer indices_;     // 12 per tetrahedron: its 4 faces over vertices 4·t + corner
  gl::VertexArray vao_;    // holds indices_ as its element buffer
  gl::Buffer corner_colours_;  // uvec4 per tetrahedron (packed RGB per GPU corner), or 16 bytes
  bool has_corner_colours_ = false;
  std::size_t count_ = 0;
};

}  // namespace quadrix::render
