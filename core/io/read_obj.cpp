// OBJ: "v x y z [w | r g b]" (the colour scaled by text_colours_rgb8, kept where every vertex
// has a good one), "vn x y z" and
// "f v[/vt][/vn] …" with 1-based or negative (relative) indices; every other statement (vt, g, o,
// s, usemtl, l, …) is ignored.
#include <algorithm>
#include <cctype>
#include <optional>

#include <fmt/format.h>

#include "core/error.h"
#include "core/io/file.h"
#include "core/io/formats.h"
#include "core/io/text_colours.h"
#include "core/io/text_reader.h"
#include "core/limits.h"

namespace quadrix::io {

Surface read_obj(std::string_view text, const std::filesystem::path& path) {
  TextReader r(text, path);
  Surface s;
  PolygonMesh& mesh = s.mesh;
  std::vector<Eigen::Vector3d> normals;
  std::vector<std::optional<TextColour>> colours;  // as written, per vertex
  std::vector<int> face;
  struct Pending {  // positive indices are checked once all vertices are known
    std::size_t face, line, col;
    long long index;
  };
  std::vector<Pending> forward;
  bool has_statement = false;
  while (r.next_line()) {
    const std::string_view key = r.token();
    has_statement = true;
    if (key == "v" || key == "vn") {
      const bool is_v = key == "v";
      const std::size_t i = is_v ? mesh.vertices.size() : normals.size();
      Eigen::Vector3d p;
      for (int k = 0; k < 3; ++k) p[k] = r.number(fmt::format("{} {}", is_v ? "vertex" : "normal", i));
      if (is_v ? !is_world_point(p) : !p.allFinite())
        r.fail("{} {} ({}, {}, {}) {}", is_v ? "vertex" : "normal", i, p.x(), p.y(), p.z(), world_fault(p));
      if (is_v) {
        mesh.vertices.push_back(p);
        // x y z r g b: a colour (MeshLab's and Quadrix's own OBJ); x y z w: a weight, no colour.
        colours.push_back(read_text_colour(r, 3));
      } else {
        if (!(p.norm() > 0)) r.fail("normal {}: zero normal", i);
        normals.push_back(p.normalized());
      }
    } else if (key == "f") {
      const std::size_t f = mesh.face_count();
      face.clear();
      for (std::string_view tok = r.token(); !tok.empty(); tok = r.token()) {
        long long idx = 0;
        if (!TextReader::parse(tok.substr(0, tok.find('/')), idx))
          r.fail("face {}: '{}' is not a vertex reference", f, echo(tok));
        const auto nv = static_cast<long long>(mesh.vertices.size());
        if (idx == 0) r.fail("face {}: vertex index 0 (OBJ indices start at 1)", f);
        if (idx < 0) {
          if (idx < -nv) r.fail("face {}: relative vertex index {} reaches before the first vertex", f, idx);
          idx += nv;
        } else {
          if (idx > (1LL << 31) - 1) r.fail("face {}: vertex index {} out of range", f, idx);
          if (idx > nv) forward.push_back({f, r.line_number(), r.column(), idx});
          idx -= 1;
        }
        face.push_back(static_cast<int>(idx));
      }
      if (face.size() < 3) r.fail("face {} has {} vertices (at least 3 needed)", f, face.size());
      mesh.add_face(face);
    } else if (!std::all_of(key.begin(), key.end(), [](unsigned char c) { return std::isprint(c); })) {
      r.fail("not an OBJ file: unexpected bytes '{}'", echo(key));
    }  // vt, g, o, s, usemtl, mtllib, l, p, …: not needed here
  }
  if (!has_statement) throw FormatError(fmt::format("{}: empty OBJ file", path.string()));
  if (mesh.vertices.empty()) throw FormatError(fmt::format("{}: no points (no 'v' lines)", path.string()));
  for (const Pending& p : forward)
    if (p.index > static_cast<long long>(mesh.vertices.size()))
      throw FormatError(text_message(path, p.line, p.col,
                                     fmt::format("face {}: vertex index {} out of range [1, {}]", p.face, p.index,
                                                 mesh.vertices.size())));
  if (normals.size() == mesh.vertices.size()) s.normals = std::move(normals);
  mesh.colours = text_colours_rgb8(colours, mesh.vertices.size(), path);
  return s;
}

}  // namespace quadrix::io
