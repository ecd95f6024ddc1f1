// OFF: "[ST][C][N]OFF" (with C, each vertex line's colour after x y z [nx ny nz]: r g b [a],
// scaled by text_colours_rgb8, kept where every vertex has a good one; other extra columns
// ignored), then
// "nv nf [ne]" (on the keyword line or the next), nv vertex lines, nf faces "n i0 … i(n-1)
// [colour]" with 0-based indices; a face may continue on following lines. Nothing may follow.
#include <optional>
#include <vector>

#include <fmt/format.h>

#include "core/error.h"
#include "core/io/file.h"
#include "core/io/formats.h"
#include "core/io/text_colours.h"
#include "core/io/text_reader.h"
#include "core/limits.h"

namespace quadrix::io {

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
  std::vector<std::optional<TextColour>> colours;  // as written
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
    if (has_colours) colours.push_back(read_text_colour(r, 4));
  }
  if (has_colours) s.mesh.colours = text_colours_rgb8(colours, s.mesh.vertices.size(), path);
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
