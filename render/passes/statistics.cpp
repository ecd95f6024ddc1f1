#include "render/passes/statistics.h"

#include <cstring>

#ifndef GL_FRAGMENT_SHADER_INVOCATIONS_ARB
#define GL_FRAGMENT_SHADER_INVOCATIONS_ARB 0x82F4
#endif

namespace quadrix::render {
namespace {
// culled, drawn, SLIM splat and hit fragments, glyph proxy and hit fragments, SLIM pass-2
// fragments and ray casts.
constexpr int kCounters = 8;
}  // namespace

bool has_pipeline_statistics() {
  GLint n = 0;
  glGetIntegerv(GL_NUM_EXTENSIONS, &n);
  for (GLint i = 0; i < n; ++i) {
    const auto* e = reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, i));
    if (e && std::strcmp(e, "GL_ARB_pipeline_statistics_query") == 0) return true;
  }
  return false;
}

FrameStatistics::FrameStatistics()
    : counters_(gl::make_buffer(kCounters * sizeof(GLuint), nullptr, GL_DYNAMIC_STORAGE_BIT | GL_MAP_READ_BIT)),
      samples_(gl::make_query(GL_SAMPLES_PASSED)),
      has_invocations_(has_pipeline_statistics()) {
  if (has_invocations_) invocations_ = gl::make_query(GL_FRAGMENT_SHADER_INVOCATIONS_ARB);
}

void FrameStatistics::begin() {
  glBeginQuery(GL_SAMPLES_PASSED, samples_.id());
  if (has_invocations_) glBeginQuery(GL_FRAGMENT_SHADER_INVOCATIONS_ARB, invocations_.id());
  const GLuint z[kCounters] = {};
  glNamedBufferSubData(counters_.id(), 0, sizeof(z), z);
}

void FrameStatistics::end() {
  glEndQuery(GL_SAMPLES_PASSED);
  if (has_invocations_) glEndQuery(GL_FRAGMENT_SHADER_INVOCATIONS_ARB);
}

void FrameStatistics::read(FrameStats& st) const {
  GLuint64 v = 0;
  glGetQueryObjectui64v(samples_.id(), GL_QUERY_RESULT, &v);
  st.fragments_hit = v;
  if (has_invocations_) {
    glGetQueryObjectui64v(invocations_.id(), GL_QUERY_RESULT, &v);
    st.fragments = v;
  } else {
    st.fragments = static_cast<std::uint64_t>(-1);
  }
  GLuint counts[kCounters] = {};
  glGetNamedBufferSubData(counters_.id(), 0, sizeof(counts), counts);
  st.culled = counts[0];
  st.slim_splat_fragments = counts[2];
  st.slim_hit_fragments = counts[3];
  st.glyph_proxy_fragments = counts[4];
  st.glyph_hit_fragments = counts[5];
  st.slim_accumulate_fragments = counts[6];
  st.slim_cast_fragments = counts[7];
}

}  // namespace quadrix::render
