#pragma once
/// Spatial chunks of primitives: grouped once at upload (Morton order of their centres, a fixed
/// number per chunk, a box each), and per frame the chunks that may show in the view frustum,
/// nearest first — so whole chunks are skipped before the vertex stage and the rest are drawn
/// front to back for the early depth test.
#include <cstdint>
#include <span>
#include <vector>

#include "core/camera.h"
#include "core/model.h"

namespace quadrix::render {

struct ChunkOptions {
  std::size_t chunk_size = 1024;  ///< primitives per chunk (the last one may hold fewer)
};

/// Primitives regrouped into chunks. GPU slot s holds primitive order[s]; chunk c is the slots
/// [first[c], first[c] + count[c]).
struct Chunks {
  std::vector<std::uint32_t> order;
  std::vector<std::uint32_t> first, count;
  std::vector<Box3> boxes;  ///< per chunk, world units: the union of its primitives' boxes
  std::size_t size() const { return boxes.size(); }
};

/// Chunks of primitives given their bounding boxes (world units, none empty).
Chunks make_chunks(std::span<const Box3> primitive_boxes, const ChunkOptions& options = {});

/// The chunks a frame draws.
struct ChunkSelection {
  std::vector<std::uint32_t> chunks;  ///< chunk indices, nearest box first
  std::size_t culled_chunks = 0;      ///< wholly outside the view frustum (near and far planes included)
  std::size_t culled_primitives = 0;  ///< primitives in those chunks
};

/// Chunks whose box meets the camera's view frustum, sorted by the distance from the eye to
/// their box (in double, so it holds wherever the model sits). Conservative: a chunk is dropped
/// only when all 8 corners of its box lie outside one frustum plane.
ChunkSelection select_chunks(const Chunks& chunks, const Camera& camera);

}  // namespace quadrix::render
