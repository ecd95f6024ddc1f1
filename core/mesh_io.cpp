#include "core/mesh_io.h"

// Design: OFF and OBJ are read by the small strict parsers below, PLY through OpenMesh.
//
// OpenMesh's own readers do not return the file's faces verbatim: ImporterT drops faces with
// out-of-range or repeated vertex indices without an error, and re-adds faces that would make
// the halfedge structure non-manifold on freshly duplicated vertices (so the vertex count
// grows and the face no longer shares vertices with its neighbours). Its OFF reader also reads
// past a truncated file without failing. A PolygonMesh is a face soup and needs none of that,
// and our own parsers can name the file, line and element at fault. For PLY (ASCII and both
// binary flavours, arbitrary extra properties) OpenMesh's reader is worth keeping; there we
// record the faces exactly as the reader hands them over (RecordingImporter) and take only the
// first N vertices, N from the PLY header, so OpenMesh's duplicated vertices never leak out.
//
// Whatever the format, faces that OpenMesh's halfedge mesh would refuse (complex edge/vertex,
// repeated vertex) are counted by building an OpenMesh PolyMesh and reported through
// log::warn; they are kept in the result.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/log.h"

namespace quadrix {
namespace {

namespace fs = std::filesystem;

struct DoubleTraits : OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
};
using OmMesh = OpenMesh::PolyMesh_ArrayKernelT<DoubleTraits>;

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

/// Silences OpenMesh's omerr/omlog (they write to stderr/stdout on their own) for one scope.
/// The streams are process-wide, so concurrent OpenMesh use elsewhere is muted meanwhile.
class OpenMeshQuiet {
public:
  OpenMeshQuiet() : err_(::omerr().is_enabled()), log_(::omlog().is_enabled()) {
    ::omerr().disable();
    ::omlog().disable();
  }
  ~OpenMeshQuiet() {
    if (err_) ::omerr().enable();
    if (log_) ::omlog().enable();
  }
  OpenMeshQuiet(const OpenMeshQuiet&) = delete;
  OpenMeshQuiet& operator=(const OpenMeshQuiet&) = delete;

private:
  bool err_, log_;
};

// ---------------------------------------------------------------------------------------------
// Line-oriented tokenising shared by the OFF and OBJ parsers.

class LineReader {
public:
  LineReader(std::string_view text, const fs::path& path) : text_(text), path_(path) {}

  /// Next line with comments ('#') removed and not blank; false at the end of the text.
  bool next(std::string_view& line) {
    while (pos_ < text_.size()) {
      std::size_t end = text_.find('\n', pos_);
      if (end == std::string_view::npos) end = text_.size();
      std::string_view l = text_.substr(pos_, end - pos_);
      pos_ = end + 1;
      ++line_no_;
      if (const auto hash = l.find('#'); hash != std::string_view::npos) l = l.substr(0, hash);
      if (l.find_first_not_of(" \t\r\f\v") != std::string_view::npos) {
        line = l;
        return true;
      }
    }
    return false;
  }
  std::size_t line_no() const { return line_no_; }

  template <typename... Args>
  [[noreturn]] void fail(fmt::format_string<Args...> f, Args&&... args) const {
    throw FormatError(fmt::format("{}:{}: {}", path_.string(), line_no_, fmt::format(f, std::forward<Args>(args)...)));
  }

private:
  std::string_view text_;
  const fs::path& path_;
  std::size_t pos_ = 0, line_no_ = 0;
};

/// Splits off the next whitespace-separated token; empty at the end of the line.
std::string_view next_token(std::string_view& s) {
  const auto b = s.find_first_not_of(" \t\r\f\v");
  if (b == std::string_view::npos) {
    s = {};
    return {};
  }
  auto e = s.find_first_of(" \t\r\f\v", b);
  if (e == std::string_view::npos) e = s.size();
  const std::string_view tok = s.substr(b, e - b);
  s.remove_prefix(e);
  return tok;
}

bool parse_double(std::string_view tok, double& value) {
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), value);
  return ec == std::errc() && ptr == tok.data() + tok.size() && !tok.empty();
}

bool parse_long(std::string_view tok, long long& value) {
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), value);
  return ec == std::errc() && ptr == tok.data() + tok.size() && !tok.empty();
}

Eigen::Vector3d parse_point(std::string_view& rest, const LineReader& lines, std::size_t vertex) {
  Eigen::Vector3d p;
  for (int k = 0; k < 3; ++k) {
    const std::string_view tok = next_token(rest);
    if (tok.empty()) lines.fail("vertex {}: expected 3 coordinates, found {}", vertex, k);
    if (!parse_double(tok, p[k])) lines.fail("vertex {}: '{}' is not a number", vertex, tok);
  }
  if (!p.allFinite()) lines.fail("vertex {} has a non-finite coordinate ({}, {}, {})", vertex, p.x(), p.y(), p.z());
  return p;
}

// ---------------------------------------------------------------------------------------------
// OFF: "OFF" (optionally with the ST/C/N prefixes, whose extra per-vertex columns are ignored),
// then "nv nf ne", nv vertex lines, nf face lines "n i0 … i(n-1) [colour]". Indices are 0-based.

PolygonMesh parse_off(std::string_view text, const fs::path& path) {
  LineReader lines(text, path);
  std::string_view line;
  if (!lines.next(line)) throw FormatError(fmt::format("{}: empty file, expected an OFF header", path.string()));
  std::string_view rest = line;
  const std::string_view magic = next_token(rest);
  const bool is_off = magic.size() >= 3 && magic.substr(magic.size() - 3) == "OFF" &&
                      magic.find_first_not_of("STCN") == magic.size() - 3;
  if (!is_off) lines.fail("not an OFF file: header '{}' (4OFF, nOFF and binary OFF are not supported)", magic);
  if (next_token(rest) == "BINARY") lines.fail("binary OFF is not supported");

  // The counts may follow the magic on the same line.
  std::string_view counts = rest;
  if (counts.find_first_not_of(" \t\r\f\v") == std::string_view::npos) {
    if (!lines.next(line)) lines.fail("truncated OFF file: missing the vertex/face counts line");
    counts = line;
  }
  long long nv = 0, nf = 0;
  const std::string_view nv_tok = next_token(counts), nf_tok = next_token(counts);
  if (!parse_long(nv_tok, nv) || !parse_long(nf_tok, nf) || nv < 0 || nf < 0)
    lines.fail("expected 'vertex_count face_count edge_count', found '{} {}'", nv_tok, nf_tok);
  constexpr long long max_count = 1LL << 30;
  if (nv > max_count || nf > max_count) lines.fail("implausible counts: {} vertices, {} faces", nv, nf);

  PolygonMesh mesh;
  mesh.vertices.reserve(static_cast<std::size_t>(nv));
  for (long long v = 0; v < nv; ++v) {
    if (!lines.next(line))
      lines.fail("truncated OFF file: header declares {} vertices, found {}", nv, v);
    mesh.vertices.push_back(parse_point(line, lines, static_cast<std::size_t>(v)));
  }
  mesh.offsets.reserve(static_cast<std::size_t>(nf) + 1);
  mesh.indices.reserve(static_cast<std::size_t>(nf) * 4);
  std::vector<int> face;
  for (long long f = 0; f < nf; ++f) {
    if (!lines.next(line)) lines.fail("truncated OFF file: header declares {} faces, found {}", nf, f);
    long long n = 0;
    const std::string_view n_tok = next_token(line);
    if (!parse_long(n_tok, n)) lines.fail("face {}: vertex count '{}' is not an integer", f, n_tok);
    if (n < 3) lines.fail("face {} has {} vertices (at least 3 needed)", f, n);
    face.clear();
    for (long long k = 0; k < n; ++k) {
      std::string_view tok = next_token(line);
      // OFF is whitespace-separated: a face record may continue on the next line.
      while (tok.empty() && lines.next(line)) tok = next_token(line);
      long long idx = 0;
      if (tok.empty()) lines.fail("face {}: expected {} vertex indices, found {}", f, n, k);
      if (!parse_long(tok, idx)) lines.fail("face {}: index '{}' is not an integer", f, tok);
      if (idx < 0 || idx >= nv) lines.fail("face {}: vertex index {} out of range [0, {})", f, idx, nv);
      face.push_back(static_cast<int>(idx));
    }
    mesh.add_face(face);  // trailing colour values, if any, are ignored
  }
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// OBJ: "v x y z [w | r g b]" and "f v[/vt][/vn] …" with 1-based or negative (relative) indices;
// every other statement (vt, vn, g, o, s, usemtl, l, …) is ignored.

PolygonMesh parse_obj(std::string_view text, const fs::path& path) {
  LineReader lines(text, path);
  PolygonMesh mesh;
  std::string_view line;
  std::vector<int> face;
  struct Pending {  // positive indices are checked once all vertices are known
    std::size_t face, line;
    long long index;
  };
  std::vector<Pending> forward;
  bool has_statement = false;
  while (lines.next(line)) {
    std::string_view rest = line;
    const std::string_view key = next_token(rest);
    if (key == "v") {
      has_statement = true;
      mesh.vertices.push_back(parse_point(rest, lines, mesh.vertices.size()));
    } else if (key == "f") {
      has_statement = true;
      const std::size_t f = mesh.face_count();
      face.clear();
      for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
        const std::string_view v_tok = tok.substr(0, tok.find('/'));
        long long idx = 0;
        if (!parse_long(v_tok, idx)) lines.fail("face {}: '{}' is not a vertex reference", f, tok);
        const auto nv = static_cast<long long>(mesh.vertices.size());
        if (idx == 0) lines.fail("face {}: vertex index 0 (OBJ indices start at 1)", f);
        if (idx < 0) {
          if (-idx > nv) lines.fail("face {}: relative vertex index {} reaches before the first vertex", f, idx);
          idx += nv;
        } else {
          if (idx > (1LL << 31) - 1) lines.fail("face {}: vertex index {} out of range", f, idx);
          if (idx > nv) forward.push_back({f, lines.line_no(), idx});
          idx -= 1;
        }
        face.push_back(static_cast<int>(idx));
      }
      if (face.size() < 3) lines.fail("face {} has {} vertices (at least 3 needed)", f, face.size());
      mesh.add_face(face);
    } else if (!key.empty() && std::all_of(key.begin(), key.end(), [](unsigned char c) { return std::isprint(c); })) {
      has_statement = true;  // vt, vn, g, o, s, usemtl, mtllib, l, p, …: not needed here
    } else {
      lines.fail("not an OBJ file: unexpected bytes");
    }
  }
  if (!has_statement) throw FormatError(fmt::format("{}: empty OBJ file", path.string()));
  for (const Pending& p : forward)
    if (p.index > static_cast<long long>(mesh.vertices.size()))
      throw FormatError(fmt::format("{}:{}: face {}: vertex index {} out of range [1, {}]", path.string(), p.line,
                                    p.face, p.index, mesh.vertices.size()));
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// PLY through OpenMesh.

/// Records every face exactly as OpenMesh's reader passes it, before ImporterT filters it.
class RecordingImporter final : public OpenMesh::IO::ImporterT<OmMesh> {
public:
  RecordingImporter(OmMesh& mesh, PolygonMesh& soup) : ImporterT<OmMesh>(mesh), soup_(soup) {}
  using ImporterT<OmMesh>::add_face;
  OpenMesh::FaceHandle add_face(const VHandles& vhs) override {
    soup_.offsets.push_back(static_cast<int>(soup_.indices.size() + vhs.size()));
    for (const auto& vh : vhs) soup_.indices.push_back(vh.idx());
    return ImporterT<OmMesh>::add_face(vhs);
  }

private:
  PolygonMesh& soup_;
};

struct PlyCounts {
  long long vertices = -1, faces = -1;
};

PlyCounts ply_header_counts(std::string_view text, const fs::path& path) {
  if (text.substr(0, 4) != "ply\n" && text.substr(0, 5) != "ply\r\n")
    throw FormatError(fmt::format("{}: not a PLY file (missing 'ply' magic line)", path.string()));
  const auto end = text.find("end_header");
  if (end == std::string_view::npos) throw FormatError(fmt::format("{}: PLY header has no end_header", path.string()));
  PlyCounts counts;
  std::string_view header = text.substr(0, end);
  while (!header.empty()) {
    auto eol = header.find('\n');
    std::string_view line = header.substr(0, eol);
    header.remove_prefix(eol == std::string_view::npos ? header.size() : eol + 1);
    if (next_token(line) != "element") continue;
    const std::string_view name = next_token(line), count = next_token(line);
    long long n = 0;
    if (!parse_long(count, n) || n < 0)
      throw FormatError(fmt::format("{}: PLY element '{}' has an invalid count '{}'", path.string(), name, count));
    if (name == "vertex") counts.vertices = n;
    if (name == "face") counts.faces = n;
  }
  if (counts.vertices < 0) throw FormatError(fmt::format("{}: PLY header declares no vertex element", path.string()));
  if (counts.faces < 0) throw FormatError(fmt::format("{}: PLY header declares no face element", path.string()));
  // Every vertex and face takes at least one byte: refuse absurd counts before OpenMesh reserves.
  if (counts.vertices + counts.faces > static_cast<long long>(text.size() - end))
    throw FormatError(fmt::format("{}: PLY header declares {} vertices and {} faces, but only {} bytes follow it",
                                  path.string(), counts.vertices, counts.faces, text.size() - end));
  return counts;
}

PolygonMesh read_ply(std::string_view text, const fs::path& path) {
  const PlyCounts counts = ply_header_counts(text, path);
  PolygonMesh mesh;
  OmMesh om;
  RecordingImporter importer(om, mesh);
  OpenMesh::IO::Options options;
  bool ok = false;
  {
    OpenMeshQuiet quiet;
    ok = OpenMesh::IO::IOManager().read(path.string(), importer, options);
  }
  if (!ok) throw FormatError(fmt::format("{}: OpenMesh could not parse the PLY file", path.string()));
  if (static_cast<long long>(om.n_vertices()) < counts.vertices)
    throw FormatError(fmt::format("{}: truncated PLY: header declares {} vertices, read {}", path.string(),
                                  counts.vertices, om.n_vertices()));
  if (static_cast<long long>(mesh.face_count()) != counts.faces)
    throw FormatError(fmt::format("{}: truncated PLY: header declares {} faces, read {}", path.string(), counts.faces,
                                  mesh.face_count()));
  // Vertices past the declared count are OpenMesh's copies for non-manifold faces: dropped.
  mesh.vertices.resize(static_cast<std::size_t>(counts.vertices));
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    const auto& p = om.point(OmMesh::VertexHandle(static_cast<int>(v)));
    mesh.vertices[v] = {p[0], p[1], p[2]};
    if (!mesh.vertices[v].allFinite())
      throw FormatError(fmt::format("{}: vertex {} has a non-finite coordinate ({}, {}, {})", path.string(), v, p[0],
                                    p[1], p[2]));
  }
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto vs = mesh.face(f);
    if (vs.size() < 3)
      throw FormatError(fmt::format("{}: face {} has {} vertices (at least 3 needed)", path.string(), f, vs.size()));
    for (const int v : vs)
      if (v < 0 || v >= counts.vertices)
        throw FormatError(fmt::format("{}: face {}: vertex index {} out of range [0, {})", path.string(), f, v,
                                      counts.vertices));
  }
  return mesh;
}

/// Number of faces OpenMesh's halfedge mesh refuses (complex edge or vertex, repeated vertex),
/// adding the faces in file order. Indices must be valid.
std::size_t count_non_manifold_faces(const PolygonMesh& mesh) {
  OpenMesh::PolyMesh_ArrayKernelT<> om;
  om.reserve(mesh.vertices.size(), mesh.indices.size() / 2 + 3, mesh.face_count());
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) om.add_vertex({0.0f, 0.0f, 0.0f});
  OpenMeshQuiet quiet;
  std::size_t refused = 0;
  std::vector<OpenMesh::VertexHandle> vhs;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    vhs.clear();
    for (const int v : mesh.face(f)) vhs.emplace_back(v);
    bool repeated = false;
    for (std::size_t a = 0; a < vhs.size() && !repeated; ++a)
      for (std::size_t b = a + 1; b < vhs.size(); ++b) repeated = repeated || vhs[a] == vhs[b];
    if (repeated || !om.add_face(vhs).is_valid()) ++refused;
  }
  return refused;
}

void flush(std::ostream& out, fmt::memory_buffer& buf) {
  out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
  buf.clear();
}

void validate_for_writing(const PolygonMesh& mesh, const fs::path& path) {
  if (mesh.offsets.empty() || mesh.offsets.front() != 0 ||
      static_cast<std::size_t>(mesh.offsets.back()) != mesh.indices.size())
    throw InvalidInput(fmt::format("{}: cannot write mesh: inconsistent face offsets", path.string()));
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
    if (!mesh.vertices[v].allFinite())
      throw InvalidInput(fmt::format("{}: cannot write mesh: vertex {} is not finite", path.string(), v));
  for (std::size_t f = 0; f < mesh.face_count(); ++f)
    for (const int v : mesh.face(f))
      if (v < 0 || static_cast<std::size_t>(v) >= mesh.vertices.size())
        throw InvalidInput(fmt::format("{}: cannot write mesh: face {} has vertex index {} out of range [0, {})",
                                       path.string(), f, v, mesh.vertices.size()));
}

}  // namespace

PolygonMesh read_mesh(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  if (ext != ".off" && ext != ".obj" && ext != ".ply")
    throw FormatError(fmt::format("{}: unsupported mesh format '{}' (expected .off, .obj or .ply)", path.string(), ext));
  const std::string text = read_file(path);
  if (text.empty()) throw FormatError(fmt::format("{}: empty file", path.string()));

  PolygonMesh mesh = ext == ".off" ? parse_off(text, path) : ext == ".obj" ? parse_obj(text, path) : read_ply(text, path);
  if (mesh.face_count() == 0) throw FormatError(fmt::format("{}: the mesh has no faces", path.string()));

  if (const std::size_t refused = count_non_manifold_faces(mesh); refused > 0)
    log::warn("{}: {} of {} faces are non-manifold or degenerate (complex edge or vertex, repeated vertex); they "
              "are kept, but OpenMesh's halfedge mesh would drop them",
              path.string(), refused, mesh.face_count());
  log::debug("{}: {} vertices, {} faces", path.string(), mesh.vertices.size(), mesh.face_count());
  return mesh;
}

void write_mesh(const PolygonMesh& mesh, const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  if (ext != ".off" && ext != ".obj")
    throw InvalidInput(fmt::format("{}: cannot write mesh format '{}' (expected .off or .obj)", path.string(), ext));
  validate_for_writing(mesh, path);

  // fmt's "{}" prints the shortest decimal that reads back to the same double, i.e. lossless
  // like max_digits10 (17 significant digits) but without the noise digits.
  write_file_atomically(path, [&](std::ostream& out) {
    fmt::memory_buffer buf;
    constexpr std::size_t chunk = 1 << 20;
    const bool is_obj = ext == ".obj";
    if (is_obj)
      fmt::format_to(std::back_inserter(buf), "# quadrix: {} vertices, {} faces\n", mesh.vertices.size(),
                     mesh.face_count());
    else
      fmt::format_to(std::back_inserter(buf), "OFF\n{} {} 0\n", mesh.vertices.size(), mesh.face_count());
    for (const Eigen::Vector3d& p : mesh.vertices) {
      fmt::format_to(std::back_inserter(buf), "{}{} {} {}\n", is_obj ? "v " : "", p.x(), p.y(), p.z());
      if (buf.size() > chunk) flush(out, buf);
    }
    for (std::size_t f = 0; f < mesh.face_count(); ++f) {
      const auto vs = mesh.face(f);
      if (is_obj)
        buf.append(std::string_view("f"));
      else
        fmt::format_to(std::back_inserter(buf), "{}", vs.size());
      for (const int v : vs) fmt::format_to(std::back_inserter(buf), " {}", is_obj ? v + 1 : v);
      buf.push_back('\n');
      if (buf.size() > chunk) flush(out, buf);
    }
    flush(out, buf);
  });
}

}  // namespace quadrix
