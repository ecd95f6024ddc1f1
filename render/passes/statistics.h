#pragma once
/// Frame statistics: occlusion and fragment-invocation queries around the G-buffer passes, and
/// the counters their shaders add to (culled primitives, SLIM splat, hit, pass-2 and ray-cast
/// fragments, glyph proxy and hit fragments).
#include "render/gl/objects.h"
#include "render/renderer.h"

namespace quadrix::render {

class FrameStatistics {
public:
  FrameStatistics();
  /// SSBO the passes bind at binding 1 (written only when u_count_stats is 1).
  GLuint buffer() const { return counters_.id(); }
  /// Zeroes the counters and starts the queries.
  void begin();
  void end();
  /// Waits for the queries and copies the figures into `stats`.
  void read(FrameStats& stats) const;

private:
  gl::Buffer counters_;
  gl::Query samples_, invocations_;
  bool has_invocations_ = false;
};

}  // namespace quadrix::render
