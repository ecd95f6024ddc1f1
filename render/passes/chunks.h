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
  std::size_t occluded_chunks = 0;    ///< skipped as hidden by what the frame had drawn (drawing pass)
  std::size_t occluded_primitives = 0;
};

/// Chunks whose box meets the camera's view frustum, sorted by the distance from the eye to
/// their box (in double, so it holds wherever the model sits). Conservative: a chunk is dropped
/// only when all 8 corners of its box lie outside one frustum plane.
ChunkSelection select_chunks(const Chunks& chunks, const Camera& camera);

/// A rectangle of pixels, GL's rows (row 0 at the bottom); empty when x1 ≤ x0 or y1 ≤ y0.
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  ///< [x0, x1) × [y0, y1)
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  void extend(const PixelRect& o);
};
/// The pixels whose centres the box's projection may cover (one more on each side for
/// rasterisation rules), clamped to the camera's image; the whole image when the box reaches
/// the near plane or behind the eye.
PixelRect box_pixels(const Box3& box, const Camera& camera);

/// The farthest window depth (0 near … 1 far or background) per square tile of a depth image.
struct DepthTiles {
  int width = 0, height = 0;  ///< of the image, pixels
  int tile = 16;              ///< tile side, pixels
  int tiles_x = 0, tiles_y = 0;
  std::vector<float> max_depth;  ///< tiles_x × tiles_y, row 0 at the image's row 0
};
/// Tiles of a width × height depth image (row-major, row 0 first, as glGetTextureImage gives it).
DepthTiles depth_tiles(std::span<const float> depth, int width, int height, int tile = 16);

/// True when the box is surely hidden: it lies wholly beyond the near plane, and every tile its
/// projected bound touches holds only depths nearer than the box's nearest point (window depth
/// computed in double). Image rows as GL numbers them (row 0 at the bottom).
bool box_occluded(const Box3& box, const Camera& camera, const DepthTiles& tiles);

}  // namespace quadrix::render
