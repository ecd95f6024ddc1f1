// OFF: "[ST][C][N]OFF" (with C, each vertex line's colour after x y z [nx ny nz]: r g b [a],
// integers 0-255 or, where any is written with a point or exponent, 0-1, as Geomview reads them;
// kept where every vertex has one; other extra columns ignored), then
// "nv nf [ne]" (on the keyword line or the next), nv vertex lines, nf faces "n i0 … i(n-1)
// [colour]" with 0-based indices; a face may continue on following lines. Nothing may follow.
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include <fmt/format.h>

#include "core/error.h"
#include "core/io/file.h"
#include "core/io/formats.h"
#include "core/io/text_reader.h"
#include "core/limits.h"

namespace quadrix::io {
namespace {

// A vertex colour "r g b [a]" as written, each within 0..255; fewer than three values (a
// colour-map index) give none. `fractions` is set where one is written with a point or an
// exponent: Geomview reads a file's colours as 0-1 then.
std::optional<std::array<double, 3>> read_colour(TextReader& r, const std::string& what, bool& fractions) {
  std::array<double, 3> c{};
  int n = 0;
  for (; n < 4 && !r.at_line_end(); ++n) {
    const std::string_view tok = r.token();
    double v = 0;
    if (!TextReader::parse(tok, v) || !(v >= 0 && v <= 255)) r.fail("{}: '{}' is not a number in 0..255", what, echo(tok));
    fractions = fractions || tok.find_first_of(".eE") != std::string_view::npos;
    if (n < 3) c[n] = v;
  }
  if (n < 3) return std::nullopt;
  return c;
}

}  // namespace

Surface read_off(std::string_view text, const std::filesystem::path& path) {
  TextReader r(text, path);
  if (!r.next_line()) throw FormatError(fmt::format("{}: empty file, expected an OFF header", path.string()));
  const std::string_view magic = r.token();
  const bool is_off = magic.size() >= 3 && magic.ends_with("OFF") &&
                      magic.substr(0, magic.size() - 3).find_first_not_of("STCN") == std::string_view::npos;
  if (!is_off) r.fail("not an OFF file: header '{}' (4OFF, nOFF and binary OFF are not supported)", echo(magic));
  const bool has_normals = magic.substr(0, magic.size() - 3).find('N') != std::string_view::npos;
  const bool has_colours = magic.substr(0, magic.size() - 3).find('C') != std::string_view::npos;
  if (r.rest_of_line().find("BINARY") != std::string_view::npos) r.fail("binary OFF is not supported");
  if (r.at_line_end() && !r.next_line()) r.fail("truncated OFF file: missing the vertex/face counts line");
  const long long nv = r.integer("vertex count"), nf = r.integer("face count");
  if (nv < 0 || nf < 0) r.fail("negative counts: {} vertices, {} faces", nv, nf);
  if (!r.at_line_end()) r.integer("edge count");
  if (!r.at_line_end()) r.fail("extra value '{}' after the counts", echo(r.token()));

  // Before any reservation: a vertex takes at least 6 bytes ("0 0 0\n"), a face 8 ("3 0 1 2\n").
  const std::size_t left = r.bytes_left();
  const double need = 6.0 * static_cast<double>(nv) + 8.0 * static_cast<double>(nf);
  if (need > static_cast<double>(left) + 2)
    r.fail("truncated file or bad counts: {} vertices and {} faces declared need at least {:.0f} bytes, {} follow",
           nv, nf, need, left);

  Surface s;
  s.mesh.vertices.reserve(static_cast<std::size_t>(nv));
  if (has_normals) s.normals.reserve(static_cast<std::size_t>(nv));
  std::vector<std::array<double, 3>> colours;  // as written
  bool fractions = false;
  for (long long v = 0; v < nv; ++v) {
    if (!r.next_line()) r.fail("truncated OFF file: header declares {} vertices, found {}", nv, v);
    Eigen::Vector3d p, n;
    for (int k = 0; k < 3; ++k) p[k] = r.number(fmt::format("vertex {}", v));
    if (!is_world_point(p)) r.fail("vertex {} ({}, {}, {}) {}", v, p.x(), p.y(), p.z(), world_fault(p));
    s.mesh.vertices.push_back(p);
    if (has_normals) {
      for (int k = 0; k < 3; ++k) n[k] = r.number(fmt::format("vertex {} normal", v));
      if (!n.allFinite() || !(n.norm() > 0)) r.fail("vertex {}: zero or non-finite normal", v);
      s.normals.push_back(n.normalized());
    }
    if (has_colours && !r.at_line_end())
      if (const auto c = read_colour(r, fmt::format("vertex {} colour", v), fractions)) colours.push_back(*c);
  }
  if (colours.size() == s.mesh.vertices.size()) {  // a colour per vertex or none
    s.mesh.colours.reserve(colours.size());
    for (std::size_t v = 0; v < colours.size(); ++v) {
      std::array<std::uint8_t, 3> c{};
      for (int k = 0; k < 3; ++k) {
        if (fractions && colours[v][k] > 1)
          throw FormatError(fmt::format("{}: vertex {}: colour ({}, {}, {}) outside 0..1, where the file writes colours as "
                                        "fractions (with a point)", path.string(), v, colours[v][0], colours[v][1], colours[v][2]));
        c[k] = static_cast<std::uint8_t>(std::lround(fractions ? 255 * colours[v][k] : colours[v][k]));
      }
      s.mesh.colours.push_back(c);
    }
  }
  s.mesh.offsets.reserve(static_cast<std::size_t>(nf) + 1);
  std::vector<int> face;
  for (long long f = 0; f < nf; ++f) {
    if (!r.next_line()) r.fail("truncated OFF file: header declares {} faces, found {}", nf, f);
    const long long n = r.integer(fmt::format("face {} vertex count", f));
    if (n < 3) r.fail("face {} has {} vertices (at least 3 needed)", f, n);
    if (static_cast<double>(n) > static_cast<double>(r.bytes_left()) / 2 + 1)
      r.fail("face {}: {} vertices declared but only {} bytes follow", f, n, r.bytes_left());
    face.clear();
    for (long long k = 0; k < n; ++k) {
      const std::string_view tok = r.token_across_lines();
      long long idx = 0;
      if (tok.empty()) r.fail("truncated OFF file: face {}: expected {} vertex indices, found {}", f, n, k);
      if (!TextReader::parse(tok, idx)) r.fail("face {}: index '{}' is not an integer", f, echo(tok));
      if (idx < 0 || idx >= nv) r.fail("face {}: vertex index {} out of range [0, {})", f, idx, nv);
      face.push_back(static_cast<int>(idx));
    }
    s.mesh.add_face(face);  // trailing colour values on the line, if any, are ignored
  }
  if (r.next_line())
    r.fail("trailing data after the {} vertices and {} faces the header declares: '{}'", nv, nf, echo(r.token()));
  return s;
}

}  // namespace quadrix::io
