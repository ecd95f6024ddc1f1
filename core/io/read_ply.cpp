// PLY surfaces through core/io/ply.h (ASCII, binary either endianness): element `vertex`
// (x y z [nx ny nz] [red green blue], other properties ignored) and, when present, element `face` with the list
// `vertex_indices` (or `vertex_index`). Counts, lists and trailing bytes are checked by ply::File.
#include <cmath>

#include <fmt/format.h>

#include "core/error.h"
#include "core/io/formats.h"
#include "core/io/ply.h"
#include "core/limits.h"
#include "core/log.h"

namespace quadrix::io {

Surface read_ply(std::string bytes, const std::filesystem::path& path) {
  const ply::File f = ply::File::from_bytes(std::move(bytes), path);
  const ply::Element* ev = f.header().find("vertex");
  if (!ev) throw FormatError(f.message({}, -1, {}, ply::kNoByte, "no element 'vertex' in the header"));
  std::vector<std::string> props = {"x", "y", "z"};
  const int normal_count = (ev->find("nx") >= 0) + (ev->find("ny") >= 0) + (ev->find("nz") >= 0);
  if (normal_count != 0 && normal_count != 3)
    throw FormatError(
        f.message("vertex", -1, {}, ply::kNoByte, "has some but not all of the normal properties nx ny nz"));
  if (normal_count == 3) props.insert(props.end(), {"nx", "ny", "nz"});
  const std::size_t colour_column = props.size();
  const bool has_colours = ev->find("red") >= 0 && ev->find("green") >= 0 && ev->find("blue") >= 0;
  if (has_colours) props.insert(props.end(), {"red", "green", "blue"});
  std::vector<ply::Request> req = {{"vertex", props, {}}};
  const ply::Element* ef = f.header().find("face");
  if (ef) {
    const char* list = ef->find("vertex_indices") >= 0 ? "vertex_indices" : "vertex_index";
    req.push_back({"face", {}, list});
  }
  const std::vector<ply::Table> tables = f.read(req);
  const ply::Table& t = tables[0];

  Surface s;
  s.mesh.vertices.resize(t.rows);
  if (normal_count == 3) s.normals.resize(t.rows);
  // Normals all zero are placeholders for "none" (as in read_xyz.cpp): read without normals; a
  // zero normal among non-zero ones, or the other way round, is refused at the first row that mixes.
  std::int64_t zero_row = -1, normal_row = -1;
  for (std::size_t i = 0; i < t.rows; ++i) {
    for (std::size_t c = 0; c < props.size(); ++c)
      if (c < 3 ? !is_world_value(t(i, c)) : !std::isfinite(t(i, c)))
        throw FormatError(f.message("vertex", static_cast<std::int64_t>(i), props[c], t.byte_offset(i, c),
                                    fmt::format("value {} {}", t(i, c), world_fault(t(i, c)))));
    s.mesh.vertices[i] = {t(i, 0), t(i, 1), t(i, 2)};
    if (normal_count == 3) {
      const Eigen::Vector3d n(t(i, 3), t(i, 4), t(i, 5));
      const bool zero = !(n.norm() > 0);
      if (zero ? normal_row >= 0 : zero_row >= 0)
        throw FormatError(f.message(
            "vertex", static_cast<std::int64_t>(i), "nx", t.byte_offset(i, 3),
            zero ? fmt::format("zero normal (vertex {}'s is not: either every normal is given, or all are 0 0 0 for none)",
                               normal_row)
                 : fmt::format("normal ({} {} {}) after vertex {}'s zero normal (either every normal is given, or all "
                               "are 0 0 0 for none)",
                               n.x(), n.y(), n.z(), zero_row)));
      std::int64_t& first = zero ? zero_row : normal_row;
      if (first < 0) first = static_cast<std::int64_t>(i);
      if (!zero) s.normals[i] = n.normalized();
    }
    if (has_colours) {
      std::array<std::uint8_t, 3> c{};
      for (int k = 0; k < 3; ++k) {
        const double v = t(i, colour_column + k);
        if (!(v >= 0 && v <= 255))
          throw FormatError(f.message("vertex", static_cast<std::int64_t>(i), props[colour_column + k],
                                      t.byte_offset(i, colour_column + k), fmt::format("colour {} outside 0..255", v)));
        c[k] = static_cast<std::uint8_t>(std::lround(v));
      }
      s.mesh.colours.push_back(c);
    }
  }
  if (zero_row >= 0) {
    s.normals.clear();
    log::warn("{}: every normal is 0 0 0: read as points without normals", path.string());
  }
  if (!ef) return s;
  const ply::Table& ft = tables[1];
  s.mesh.offsets.reserve(ft.rows + 1);
  s.mesh.indices.reserve(ft.list_values.size());
  std::vector<int> face;
  for (std::size_t r = 0; r < ft.rows; ++r) {
    const auto b = ft.list_offsets[r], e = ft.list_offsets[r + 1];
    auto fail = [&](std::string_view what) {
      throw FormatError(f.message("face", static_cast<std::int64_t>(r), ft.list, ft.row_offsets[r], what));
    };
    if (e - b < 3) fail(fmt::format("{} vertices (at least 3 needed)", e - b));
    face.clear();
    for (auto k = b; k < e; ++k) {
      const double v = ft.list_values[k];
      if (v != std::floor(v) || v < 0 || v >= static_cast<double>(t.rows))
        fail(fmt::format("vertex index {} out of range [0, {})", v, t.rows));
      face.push_back(static_cast<int>(v));
    }
    s.mesh.add_face(face);
  }
  return s;
}

}  // namespace quadrix::io
