// Mesh writers, one place for every format: OFF and OBJ (shortest round-trip decimals), binary
// little-endian PLY (double coordinates, uchar colours) and binary STL (float32, faces fanned into
// triangles). Per-vertex colours go to PLY, OFF (COFF) and OBJ ("v x y z r g b", 0..1), per-vertex
// normals to PLY (float nx ny nz), OFF (NOFF, the normal before the colour) and OBJ ("vn", faces
// "f v//v"); STL has neither (each triangle's own normal). Every file is written through a
// temporary file and a rename.
#include <Eigen/Geometry>
#include <fmt/format.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <ostream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/io/formats.h"

namespace quadrix::io {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kChunk = 1 << 20;

void flush(std::ostream& out, fmt::memory_buffer& buf) {
  out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
  buf.clear();
}

// A vertex normal as written: unit, float32 (PLY's float nx ny nz; the text formats print that
// float's shortest round trip).
Eigen::Vector3f written_normal(const Eigen::Vector3d& n) { return n.normalized().cast<float>(); }

void validate_for_writing(const PolygonMesh& mesh, const fs::path& path) {
  if (mesh.offsets.empty() || mesh.offsets.front() != 0 ||
      static_cast<std::size_t>(mesh.offsets.back()) != mesh.indices.size())
    throw InvalidInput(fmt::format("{}: cannot write mesh: inconsistent face offsets", path.string()));
  if (!mesh.colours.empty() && mesh.colours.size() != mesh.vertices.size())
    throw InvalidInput(fmt::format("{}: cannot write mesh: {} colours for {} vertices", path.string(),
                                   mesh.colours.size(), mesh.vertices.size()));
  if (!mesh.normals.empty() && mesh.normals.size() != mesh.vertices.size())
    throw InvalidInput(fmt::format("{}: cannot write mesh: {} normals for {} vertices", path.string(),
                                   mesh.normals.size(), mesh.vertices.size()));
  for (std::size_t v = 0; v < mesh.normals.size(); ++v)
    if (!mesh.normals[v].allFinite() || !(mesh.normals[v].norm() > 0))
      throw InvalidInput(fmt::format("{}: cannot write mesh: vertex {} has a zero or non-finite normal", path.string(), v));
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
    if (!mesh.vertices[v].allFinite())
      throw InvalidInput(fmt::format("{}: cannot write mesh: vertex {} is not finite", path.string(), v));
  for (std::size_t f = 0; f < mesh.face_count(); ++f)
    for (const int v : mesh.face(f))
      if (v < 0 || static_cast<std::size_t>(v) >= mesh.vertices.size())
        throw InvalidInput(fmt::format("{}: cannot write mesh: face {} has vertex index {} out of range [0, {})",
                                       path.string(), f, v, mesh.vertices.size()));
}

void write_text_mesh(const PolygonMesh& mesh, const fs::path& path, bool is_obj) {
  validate_for_writing(mesh, path);
  const bool has_colours = !mesh.colours.empty(), has_normals = !mesh.normals.empty();
  // fmt's "{}" prints the shortest decimal that reads back to the same double, i.e. lossless
  // like max_digits10 (17 significant digits) but without the noise digits.
  write_file_atomically(path, [&](std::ostream& out) {
    fmt::memory_buffer buf;
    if (is_obj)
      fmt::format_to(std::back_inserter(buf), "# quadrix: {} vertices, {} faces\n", mesh.vertices.size(),
                     mesh.face_count());
    else
      fmt::format_to(std::back_inserter(buf), "{}{}OFF\n{} {} 0\n", has_colours ? "C" : "", has_normals ? "N" : "",
                     mesh.vertices.size(), mesh.face_count());
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      const Eigen::Vector3d& p = mesh.vertices[i];
      fmt::format_to(std::back_inserter(buf), "{}{} {} {}", is_obj ? "v " : "", p.x(), p.y(), p.z());
      if (has_normals && !is_obj) {
        const Eigen::Vector3f n = written_normal(mesh.normals[i]);
        fmt::format_to(std::back_inserter(buf), " {} {} {}", n.x(), n.y(), n.z());
      }
      if (has_colours) {
        const auto& c = mesh.colours[i];
        if (is_obj)
          fmt::format_to(std::back_inserter(buf), " {:.4g} {:.4g} {:.4g}", c[0] / 255.0, c[1] / 255.0, c[2] / 255.0);
        else
          fmt::format_to(std::back_inserter(buf), " {} {} {} 255", c[0], c[1], c[2]);
      }
      buf.push_back('\n');
      if (buf.size() > kChunk) flush(out, buf);
    }
    if (has_normals && is_obj)
      for (const Eigen::Vector3d& n : mesh.normals) {
        const Eigen::Vector3f m = written_normal(n);
        fmt::format_to(std::back_inserter(buf), "vn {} {} {}\n", m.x(), m.y(), m.z());
        if (buf.size() > kChunk) flush(out, buf);
      }
    for (std::size_t f = 0; f < mesh.face_count(); ++f) {
      const auto vs = mesh.face(f);
      if (is_obj)
        buf.append(std::string_view("f"));
      else
        fmt::format_to(std::back_inserter(buf), "{}", vs.size());
      for (const int v : vs)
        if (is_obj && has_normals)
          fmt::format_to(std::back_inserter(buf), " {}//{}", v + 1, v + 1);
        else
          fmt::format_to(std::back_inserter(buf), " {}", is_obj ? v + 1 : v);
      buf.push_back('\n');
      if (buf.size() > kChunk) flush(out, buf);
    }
    flush(out, buf);
  });
}

template <typename T>
void put(fmt::memory_buffer& buf, T value) {
  static_assert(std::endian::native == std::endian::little, "binary writers assume a little-endian host");
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  buf.append(bytes, bytes + sizeof(T));
}

}  // namespace

void write_off(const PolygonMesh& mesh, const fs::path& path) { write_text_mesh(mesh, path, false); }
void write_obj(const PolygonMesh& mesh, const fs::path& path) { write_text_mesh(mesh, path, true); }

void write_ply(const PolygonMesh& mesh, const fs::path& path) {
  validate_for_writing(mesh, path);
  const bool has_colours = !mesh.colours.empty(), has_normals = !mesh.normals.empty();
  write_file_atomically(path, [&](std::ostream& out) {
    fmt::memory_buffer buf;
    fmt::format_to(std::back_inserter(buf),
                   "ply\nformat binary_little_endian 1.0\ncomment written by quadrix\nelement vertex {}\n"
                   "property double x\nproperty double y\nproperty double z\n",
                   mesh.vertices.size());
    if (has_normals) buf.append(std::string_view("property float nx\nproperty float ny\nproperty float nz\n"));
    if (has_colours) buf.append(std::string_view("property uchar red\nproperty uchar green\nproperty uchar blue\n"));
    fmt::format_to(std::back_inserter(buf), "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
                   mesh.face_count());
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      for (int k = 0; k < 3; ++k) put(buf, mesh.vertices[i][k]);
      if (has_normals) {
        const Eigen::Vector3f n = written_normal(mesh.normals[i]);
        for (int k = 0; k < 3; ++k) put(buf, n[k]);
      }
      if (has_colours)
        for (int k = 0; k < 3; ++k) put(buf, mesh.colours[i][k]);
      if (buf.size() > kChunk) flush(out, buf);
    }
    for (std::size_t f = 0; f < mesh.face_count(); ++f) {
      const auto vs = mesh.face(f);
      if (vs.size() > 255)
        throw InvalidInput(fmt::format("{}: cannot write PLY: face {} has {} vertices (at most 255)", path.string(), f,
                                       vs.size()));
      put(buf, static_cast<std::uint8_t>(vs.size()));
      for (const int v : vs) put(buf, static_cast<std::int32_t>(v));
      if (buf.size() > kChunk) flush(out, buf);
    }
    flush(out, buf);
  });
}

void write_stl(const PolygonMesh& mesh, const fs::path& path) {
  validate_for_writing(mesh, path);
  std::size_t triangles = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f)
    if (mesh.face(f).size() >= 3) triangles += mesh.face(f).size() - 2;
  if (triangles > 0xffffffffu)
    throw InvalidInput(fmt::format("{}: cannot write STL: {} triangles (at most 2^32 - 1)", path.string(), triangles));
  write_file_atomically(path, [&](std::ostream& out) {
    fmt::memory_buffer buf;
    char header[80] = {};
    std::snprintf(header, sizeof header, "binary STL written by quadrix");
    buf.append(header, header + 80);
    put(buf, static_cast<std::uint32_t>(triangles));
    for (std::size_t f = 0; f < mesh.face_count(); ++f) {
      const auto vs = mesh.face(f);
      for (std::size_t k = 1; k + 1 < vs.size(); ++k) {
        const Eigen::Vector3d& a = mesh.vertices[vs[0]];
        const Eigen::Vector3d& b = mesh.vertices[vs[k]];
        const Eigen::Vector3d& c = mesh.vertices[vs[k + 1]];
        Eigen::Vector3d n = (b - a).cross(c - a);
        if (n.norm() > 0) n.normalize();
        for (int i = 0; i < 3; ++i) put(buf, static_cast<float>(n[i]));
        for (const Eigen::Vector3d* p : {&a, &b, &c})
          for (int i = 0; i < 3; ++i) put(buf, static_cast<float>((*p)[i]));
        put(buf, std::uint16_t{0});
        if (buf.size() > kChunk) flush(out, buf);
      }
    }
    flush(out, buf);
  });
}

}  // namespace quadrix::io
