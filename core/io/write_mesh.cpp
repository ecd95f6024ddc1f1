// OFF and OBJ writers: shortest round-trip decimals, written through a temporary file.
#include <fmt/format.h>

#include <ostream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/io/formats.h"

namespace quadrix::io {
namespace {

namespace fs = std::filesystem;

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

void write_text_mesh(const PolygonMesh& mesh, const fs::path& path, bool is_obj) {
  validate_for_writing(mesh, path);

  // fmt's "{}" prints the shortest decimal that reads back to the same double, i.e. lossless
  // like max_digits10 (17 significant digits) but without the noise digits.
  write_file_atomically(path, [&](std::ostream& out) {
    fmt::memory_buffer buf;
    constexpr std::size_t chunk = 1 << 20;
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

}  // namespace

void write_off(const PolygonMesh& mesh, const fs::path& path) { write_text_mesh(mesh, path, false); }
void write_obj(const PolygonMesh& mesh, const fs::path& path) { write_text_mesh(mesh, path, true); }

}  // namespace quadrix::io
