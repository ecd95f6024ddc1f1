// STL, ASCII ("solid … facet normal … outer loop vertex ×3 endloop endfacet … endsolid") and
// binary (80-byte header, uint32 count, 50 bytes per triangle, little-endian). Facet normals
// are ignored (the winding gives the orientation); vertices with identical coordinates are
// merged so that the mesh is connected.
#include <cstdint>
#include <cstring>
#include <map>

#include <fmt/format.h>

#include "core/error.h"
#include "core/io/file.h"
#include "core/io/formats.h"
#include "core/io/text_reader.h"
#include "core/limits.h"

namespace quadrix::io {
namespace {

class VertexMerger {
public:
  explicit VertexMerger(PolygonMesh& mesh) : mesh_(mesh) {}
  int add(const Eigen::Vector3d& p) {
    const auto [it, is_new] = index_.try_emplace({p.x(), p.y(), p.z()}, static_cast<int>(mesh_.vertices.size()));
    if (is_new) mesh_.vertices.push_back(p);
    return it->second;
  }

private:
  PolygonMesh& mesh_;
  std::map<std::array<double, 3>, int> index_;
};

std::uint32_t load_u32(std::string_view b, std::size_t at) {
  std::uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

Surface read_binary(std::string_view b, const std::filesystem::path& path) {
  Surface s;
  VertexMerger merge(s.mesh);
  const std::size_t n = load_u32(b, 80);
  s.mesh.offsets.reserve(n + 1);
  s.mesh.indices.reserve(3 * n);
  for (std::size_t t = 0; t < n; ++t) {
    const std::size_t at = 84 + 50 * t;
    std::array<int, 3> face{};
    for (std::size_t k = 0; k < 3; ++k) {
      Eigen::Vector3f p;
      std::memcpy(p.data(), b.data() + at + 12 + 12 * k, 12);
      if (!is_world_point(p.cast<double>()))
        throw FormatError(byte_message(path, at + 12 + 12 * k,
                                       fmt::format("triangle {} corner ({}, {}, {}) {}", t, p.x(), p.y(), p.z(),
                                                   world_fault(p.cast<double>()))));
      face[k] = merge.add(p.cast<double>());
    }
    s.mesh.add_face(face);
  }
  return s;
}

Surface read_ascii(std::string_view text, const std::filesystem::path& path) {
  TextReader r(text, path, '\0');
  Surface s;
  VertexMerger merge(s.mesh);
  auto expect = [&](std::string_view word) {
    const std::string_view tok = r.token_across_lines();
    if (tok != word) r.fail("expected '{}', found '{}'", word, tok.empty() ? "the end of the file" : echo(tok));
  };
  r.next_line();
  expect("solid");
  r.next_line();  // the solid's name is free text
  std::vector<int> face;
  for (;;) {
    const std::string_view kw = r.token_across_lines();
    if (kw == "endsolid") break;
    if (kw != "facet") r.fail("expected 'facet' or 'endsolid', found '{}'", kw.empty() ? "the end of the file" : echo(kw));
    const std::size_t t = s.mesh.face_count();
    expect("normal");
    for (int k = 0; k < 3; ++k) r.number(fmt::format("facet {} normal", t));
    expect("outer");
    expect("loop");
    face.clear();
    for (std::string_view tok = r.token_across_lines(); tok != "endloop"; tok = r.token_across_lines()) {
      if (tok != "vertex") r.fail("facet {}: expected 'vertex' or 'endloop', found '{}'", t, tok.empty() ? "the end of the file" : echo(tok));
      Eigen::Vector3d p;
      for (int k = 0; k < 3; ++k) p[k] = r.number(fmt::format("facet {} vertex {}", t, face.size()));
      if (!is_world_point(p)) r.fail("facet {} vertex {} ({}, {}, {}) {}", t, face.size(), p.x(), p.y(), p.z(), world_fault(p));
      face.push_back(merge.add(p));
    }
    if (face.size() < 3) r.fail("facet {} has {} vertices (at least 3 needed)", t, face.size());
    expect("endfacet");
    s.mesh.add_face(face);
  }
  r.token();  // the optional name after endsolid
  if (r.next_line()) r.fail("trailing data after 'endsolid': '{}'", echo(r.token()));
  return s;
}

}  // namespace

bool is_binary_stl(std::string_view b) {
  return b.size() >= 84 && b.size() - 84 == 50 * static_cast<std::uint64_t>(load_u32(b, 80));
}

Surface read_stl(std::string_view bytes, const std::filesystem::path& path) {
  if (is_binary_stl(bytes)) return read_binary(bytes, path);
  if (bytes.starts_with("solid")) return read_ascii(bytes, path);
  if (bytes.size() < 84)
    throw FormatError(byte_message(path, bytes.size(), "truncated binary STL: 84 header bytes needed"));
  throw FormatError(byte_message(path, 80,
                                 fmt::format("binary STL declares {} triangles ({} bytes) but the file holds {} bytes",
                                             load_u32(bytes, 80), 84 + 50 * std::uint64_t{load_u32(bytes, 80)},
                                             bytes.size())));
}

}  // namespace quadrix::io
