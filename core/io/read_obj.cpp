// OBJ: "v x y z [w | r g b]" (the colour, 0-1, kept where every vertex has one), "vn x y z" and
// "f v[/vt][/vn] …" with 1-based or negative (relative) indices; every other statement (vt, g, o,
// s, usemtl, l, …) is ignored.
#include <algorithm>
#include <cctype>
#include <cmath>

#include <fmt/format.h>

#include "core/error.h"
#include "core/io/file.h"
#include "core/io/formats.h"
#include "core/io/text_reader.h"
#include "core/limits.h"

namespace quadrix::io {

Surface read_obj(std::string_view text, const std::filesystem::path& path) {
  TextReader r(text, path);
  Surface s;
  PolygonMesh& mesh = s.mesh;
  std::vector<Eigen::Vector3d> normals;
  std::vector<std::array<std::uint8_t, 3>> colours;  // while every vertex so far has one
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
        // x y z r g b: a colour (MeshLab's and Quadrix's own OBJ); x y z w: a weight, ignored.
        if (!r.at_line_end()) {
          const std::string_view first = r.token();
          double c0 = 0;
          if (!TextReader::parse(first, c0)) r.fail("vertex {}: '{}' is not a number", i, echo(first));
          if (!r.at_line_end()) {
            Eigen::Vector3d c(c0, 0, 0);
            c[1] = r.number(fmt::format("vertex {} green", i));  // in order: a constructor's arguments are not
            c[2] = r.number(fmt::format("vertex {} blue", i));
            if (!c.allFinite() || (c.array() < 0).any() || (c.array() > 1).any())
              r.fail("vertex {}: colour ({}, {}, {}) outside [0, 1]", i, c.x(), c.y(), c.z());
            if (colours.size() + 1 == mesh.vertices.size())
              colours.push_back({static_cast<std::uint8_t>(std::lround(255 * c.x())), static_cast<std::uint8_t>(std::lround(255 * c.y())),
                                 static_cast<std::uint8_t>(std::lround(255 * c.z()))});
          }
        }
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
  if (colours.size() == mesh.vertices.size()) mesh.colours = std::move(colours);
  return s;
}

}  // namespace quadrix::io
