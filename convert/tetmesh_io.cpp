// Tetrahedral meshes (Medit .mesh, TetGen .node/.ele) and per-vertex value files.
#include "convert/tetmesh_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <string_view>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/bounds.h"
#include "core/error.h"
#include "core/io/file.h"
#include "core/io/text_reader.h"
#include "core/limits.h"

namespace quadrix {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;

std::string lower(std::string_view s) {
  std::string out(s);
  for (auto& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// A token's place in its file, for messages about it once reading has moved on.
struct Place {
  std::size_t line = 0, col = 0;
};

Place here(const io::TextReader& in) { return {in.line_number(), in.column()}; }

// The first inconsistency of a mesh: tetrahedron t (or vertex v when is_vertex) and what is wrong.
struct Problem {
  bool is_vertex = false;
  std::size_t index = 0;
  std::string what;
};

// Indices in range (shown in the file's base), finite coordinates, no degenerate tetrahedron.
std::optional<Problem> find_problem(const TetMesh& m, int base) {
  for (std::size_t v = 0; v < m.vertices.size(); ++v)
    if (!is_world_point(m.vertices[v]))
      return Problem{true, v,
                     fmt::format("vertex {} ({}, {}, {}) {}", v + base, m.vertices[v].x(), m.vertices[v].y(),
                                 m.vertices[v].z(), world_fault(m.vertices[v]))};
  const long long n = static_cast<long long>(m.vertices.size());
  for (std::size_t t = 0; t < m.tets.size(); ++t) {
    const auto& c = m.tets[t];
    for (int k = 0; k < 4; ++k)
      if (c[k] < 0 || c[k] >= n)
        return Problem{false, t,
                       fmt::format("tetrahedron {}: vertex index {} is outside {}..{}", t + base,
                                   static_cast<long long>(c[k]) + base, base, n - 1 + base)};
    const Vector3d a = m.vertices[c[0]], e1 = m.vertices[c[1]] - a, e2 = m.vertices[c[2]] - a,
                   e3 = m.vertices[c[3]] - a;
    const double L = std::max({e1.norm(), e2.norm(), e3.norm(), (e2 - e1).norm(), (e3 - e1).norm(), (e3 - e2).norm()});
    const double six_v = e1.cross(e2).dot(e3);
    if (is_degenerate_tetrahedron({a, m.vertices[c[1]], m.vertices[c[2]], m.vertices[c[3]]}))
      return Problem{false, t,
                     fmt::format("tetrahedron {} ({} {} {} {}) is degenerate: volume {:.3g} for longest edge {:.3g}",
                                 t + base, c[0] + base, c[1] + base, c[2] + base, c[3] + base, six_v / 6, L)};
  }
  return std::nullopt;
}

// Entries per element of the Medit sections we skip (Dimension 3).
std::optional<int> medit_skip_width(const std::string& kw) {
  static const std::pair<const char*, int> table[] = {
      {"edges", 3},          {"triangles", 4},         {"quadrilaterals", 5},     {"hexahedra", 9},
      {"prisms", 7},         {"pyramids", 6},          {"corners", 1},            {"ridges", 1},
      {"requiredvertices", 1}, {"requirededges", 1},   {"requiredtriangles", 1},  {"requiredquadrilaterals", 1},
      {"normals", 3},        {"normalatvertices", 2},  {"tangents", 3},           {"tangentatvertices", 2},
      {"edgesp2", 4},        {"trianglesp2", 7},       {"tetrahedrap2", 11},      {"crack", 2},
      {"equivalentvertices", 2}, {"requiredtetrahedra", 1}, {"boundingbox", 6}};
  for (const auto& [name, w] : table)
    if (kw == name) return w;
  return std::nullopt;
}

}  // namespace

TetMesh read_medit_mesh(const fs::path& path) {
  const std::string text = io::read_file(path);
  io::TextReader in(text, path);
  TetMesh m;
  m.source = path.string();
  std::vector<Place> tet_places;
  bool has_vertices = false, has_tets = false, has_dimension = false;

  // A keyword's place and name, for messages about its section.
  struct Keyword {
    std::string name;
    Place at;
  };
  const auto section_count = [&](const Keyword& kw) {
    const std::string_view t = in.token_across_lines();
    if (t.empty()) in.fail("the file ends after '{}' (no count)", kw.name);
    long long n = 0;
    if (!io::TextReader::parse(t, n) || n < 0 || n > 0x7fffffff)
      in.fail("'{}' count '{}' is not a non-negative integer", kw.name, io::echo(t));
    return n;
  };
  const auto next_in = [&](const Keyword& kw, long long entry, long long count) {
    const std::string_view t = in.token_across_lines();
    if (t.empty())
      in.fail("the file ends inside '{}' (line {}) after {} of its {} entries (truncated?)", kw.name, kw.at.line,
              entry, count);
    return t;
  };
  const auto not_number = [&](std::string_view t, const Keyword& kw, long long entry, long long count) {
    in.fail("'{}' is not a number (entry {} of {} in '{}' at line {}; a count that disagrees with the file?)",
            io::echo(t), entry + 1, count, kw.name, kw.at.line);
  };

  for (;;) {
    const std::string_view word = in.token_across_lines();
    if (word.empty()) in.fail("no 'End' keyword (the file is truncated?)");
    const Keyword kw{std::string(io::echo(word)), here(in)};
    const std::string k = lower(word);
    if (k == "end") break;
    if (k == "meshversionformatted") {
      const std::string_view t = in.token_across_lines();
      long long v = 0;
      if (!io::TextReader::parse(t, v) || v < 1 || v > 4)
        in.fail("MeshVersionFormatted must be 1..4, not '{}'", io::echo(t));
    } else if (k == "dimension") {
      const std::string_view t = in.token_across_lines();
      long long v = 0;
      if (!io::TextReader::parse(t, v) || v != 3)
        in.fail("Dimension {} (only 3-D meshes are supported)", t.empty() ? "missing" : io::echo(t));
      has_dimension = true;
    } else if (k == "vertices") {
      if (has_vertices) in.fail("a second 'Vertices' section");
      has_vertices = true;
      const long long n = section_count(kw);
      // A vertex takes at least 8 bytes ("0 0 0 0\n"): never reserve past what the file can hold.
      m.vertices.reserve(static_cast<std::size_t>(std::min<long long>(n, in.bytes_left() / 8 + 1)));
      for (long long i = 0; i < n; ++i) {
        Vector3d x;
        for (int a = 0; a < 4; ++a) {  // x y z ref
          const std::string_view t = next_in(kw, i, n);
          double v = 0;
          if (!io::TextReader::parse(t, v)) not_number(t, kw, i, n);
          if (a < 3) {
            if (!std::isfinite(v)) in.fail("vertex {} has a non-finite coordinate '{}'", i + 1, io::echo(t));
            if (!is_world_value(v)) in.fail("vertex {} coordinate {:g} {}", i + 1, v, world_fault(v));
            x[a] = v;
          }
        }
        m.vertices.push_back(x);
      }
    } else if (k == "tetrahedra") {
      if (has_tets) in.fail("a second 'Tetrahedra' section");
      has_tets = true;
      const long long n = section_count(kw);
      m.tets.reserve(static_cast<std::size_t>(std::min<long long>(n, in.bytes_left() / 10 + 1)));
      tet_places.reserve(m.tets.capacity());
      for (long long i = 0; i < n; ++i) {
        std::array<int, 4> c{};
        Place at;
        for (int a = 0; a < 5; ++a) {
          const std::string_view t = next_in(kw, i, n);
          if (a == 0) at = here(in);
          long long v = 0;
          if (!io::TextReader::parse(t, v)) not_number(t, kw, i, n);
          if (a < 4) {
            if (v < 1 || v > 0x7fffffff) in.fail("tetrahedron {}: vertex index {} is not a 1-based index", i + 1, v);
            c[a] = static_cast<int>(v - 1);
          }
        }
        m.tets.push_back(c);
        tet_places.push_back(at);
      }
    } else if (const auto w = medit_skip_width(k)) {
      const long long n = section_count(kw);
      for (long long i = 0; i < n; ++i)
        for (int a = 0; a < *w; ++a) {
          const std::string_view t = next_in(kw, i, n);
          double v = 0;
          if (!io::TextReader::parse(t, v)) not_number(t, kw, i, n);
        }
    } else {
      in.fail("unknown keyword '{}'", kw.name);
    }
  }
  if (const std::string_view t = in.token_across_lines(); !t.empty())
    in.fail("'{}' after 'End' (trailing data)", io::echo(t));
  if (!has_dimension) in.fail("no 'Dimension 3' line");
  if (m.vertices.empty()) in.fail("no vertices");
  if (m.tets.empty()) in.fail("no tetrahedra");
  if (const auto p = find_problem(m, 1)) {
    const Place at = p->is_vertex ? Place{} : tet_places[p->index];
    throw FormatError(io::text_message(path, at.line, at.col, p->what));
  }
  return m;
}

namespace {

// The tokens of the reader's current line (at most `max` of them; one more means "too many").
std::vector<std::string_view> line_tokens(io::TextReader& in, std::size_t max) {
  std::vector<std::string_view> out;
  for (std::string_view t = in.token(); !t.empty() && out.size() <= max; t = in.token()) out.push_back(t);
  return out;
}

// A TetGen header or row field: a non-negative int.
long long tetgen_integer(const io::TextReader& in, const std::vector<std::string_view>& tokens, std::size_t k,
                         const char* what) {
  long long v = 0;
  if (k >= tokens.size() || !io::TextReader::parse(tokens[k], v) || v < 0 || v > 0x7fffffff)
    throw FormatError(io::text_message(in.path(), in.line_number(), 1,
                                       fmt::format("{} '{}' is not a non-negative integer", what,
                                                   k < tokens.size() ? io::echo(tokens[k]) : "missing")));
  return v;
}

// After the declared rows: anything but comments and blank lines is trailing data.
void expect_end(io::TextReader& in, long long rows, const char* what) {
  if (in.next_line()) in.fail("'{}' after the {} {} the header declares (trailing data)", io::echo(in.token()), rows, what);
}

}  // namespace

TetMesh read_tetgen_mesh(const fs::path& path) {
  fs::path node = path, ele = path;
  node.replace_extension(".node");
  ele.replace_extension(".ele");
  TetMesh m;
  m.source = node.string();

  const std::string node_text = io::read_file(node);
  io::TextReader nodes(node_text, node);
  if (!nodes.next_line()) throw FormatError(io::text_message(node, 1, 1, "empty file"));
  const auto head = line_tokens(nodes, 4);
  const std::size_t head_line = nodes.line_number();
  const long long np = tetgen_integer(nodes, head, 0, "point count");
  const long long dim = head.size() > 1 ? tetgen_integer(nodes, head, 1, "dimension") : 3;
  const long long nattr = head.size() > 2 ? tetgen_integer(nodes, head, 2, "attribute count") : 0;
  const long long nmark = head.size() > 3 ? tetgen_integer(nodes, head, 3, "boundary marker flag") : 0;
  if (dim != 3) nodes.fail("dimension {} (only 3 is supported)", dim);
  if (np == 0) nodes.fail("no points");
  const std::size_t node_width = static_cast<std::size_t>(4 + nattr + (nmark > 0 ? 1 : 0));
  long long base = 0;
  // A point row takes at least 2 bytes per number: never reserve past what the file can hold.
  m.vertices.reserve(static_cast<std::size_t>(std::min<long long>(np, nodes.bytes_left() / (2 * node_width) + 1)));
  for (long long i = 0; i < np; ++i) {
    if (!nodes.next_line())
      throw FormatError(io::text_message(node, head_line, 1,
                                         fmt::format("the header says {} points, the file holds {} (truncated?)", np, i)));
    const auto l = line_tokens(nodes, node_width);
    if (l.size() != node_width) nodes.fail("{} numbers, a point has {} here", l.size(), node_width);
    const long long id = tetgen_integer(nodes, l, 0, "point number");
    if (i == 0) {
      if (id > 1) nodes.fail("the first point is number {} (0 or 1)", id);
      base = id;
    } else if (id != base + i) {
      nodes.fail("point number {}, expected {}", id, base + i);
    }
    Vector3d x;
    for (int a = 0; a < 3; ++a) {
      double v = 0;
      if (!io::TextReader::parse(l[1 + a], v)) nodes.fail("'{}' is not a number", io::echo(l[1 + a]));
      if (!std::isfinite(v)) nodes.fail("point {} has a non-finite coordinate '{}'", id, io::echo(l[1 + a]));
      if (!is_world_value(v)) nodes.fail("point {} coordinate {:g} {}", id, v, world_fault(v));
      x[a] = v;
    }
    m.vertices.push_back(x);
  }
  expect_end(nodes, np, "points");

  const std::string ele_text = io::read_file(ele);
  io::TextReader eles(ele_text, ele);
  if (!eles.next_line()) throw FormatError(io::text_message(ele, 1, 1, "empty file"));
  const auto ehead = line_tokens(eles, 3);
  const std::size_t ehead_line = eles.line_number();
  const long long nt = tetgen_integer(eles, ehead, 0, "tetrahedron count");
  const long long per = ehead.size() > 1 ? tetgen_integer(eles, ehead, 1, "nodes per tetrahedron") : 4;
  const long long eattr = ehead.size() > 2 ? tetgen_integer(eles, ehead, 2, "attribute count") : 0;
  if (per != 4 && per != 10) eles.fail("{} nodes per tetrahedron (4 or 10)", per);
  if (nt == 0) eles.fail("no tetrahedra");
  const std::size_t ele_width = static_cast<std::size_t>(1 + per + eattr);
  std::vector<Place> tet_places;
  m.tets.reserve(static_cast<std::size_t>(std::min<long long>(nt, eles.bytes_left() / (2 * ele_width) + 1)));
  for (long long i = 0; i < nt; ++i) {
    if (!eles.next_line())
      throw FormatError(io::text_message(
          ele, ehead_line, 1, fmt::format("the header says {} tetrahedra, the file holds {} (truncated?)", nt, i)));
    const auto l = line_tokens(eles, ele_width);
    if (l.size() != ele_width) eles.fail("{} numbers, a tetrahedron has {} here", l.size(), ele_width);
    std::array<int, 4> c{};
    for (int a = 0; a < 4; ++a) {
      const long long v = tetgen_integer(eles, l, 1 + a, "vertex index");
      if (v < base || v >= base + np)
        eles.fail("tetrahedron {}: vertex index {} is outside {}..{}", i + base, v, base, base + np - 1);
      c[a] = static_cast<int>(v - base);
    }
    m.tets.push_back(c);
    tet_places.push_back({eles.line_number(), 1});
  }
  expect_end(eles, nt, "tetrahedra");
  if (const auto p = find_problem(m, static_cast<int>(base))) {
    const Place at = p->is_vertex ? Place{} : tet_places[p->index];
    throw FormatError(io::text_message(p->is_vertex ? node : ele, at.line, at.col, p->what));
  }
  return m;
}

TetMesh read_tet_mesh(const fs::path& path) {
  const std::string ext = lower(path.extension().string());
  if (ext == ".mesh") return read_medit_mesh(path);
  if (ext == ".node" || ext == ".ele") return read_tetgen_mesh(path);
  throw InvalidInput(fmt::format("'{}': unknown tetrahedral mesh format (.mesh, .node/.ele)", path.string()));
}

void write_medit_mesh(const TetMesh& mesh, const fs::path& path) {
  write_file_atomically(path, [&](std::ostream& out) {
    out << "MeshVersionFormatted 2\nDimension 3\n\nVertices\n" << mesh.vertices.size() << "\n";
    for (const auto& v : mesh.vertices) out << fmt::format("{:.17g} {:.17g} {:.17g} 0\n", v.x(), v.y(), v.z());
    out << "\nTetrahedra\n" << mesh.tets.size() << "\n";
    for (const auto& t : mesh.tets) out << fmt::format("{} {} {} {} 0\n", t[0] + 1, t[1] + 1, t[2] + 1, t[3] + 1);
    out << "\nEnd\n";
  });
}

std::vector<double> read_vertex_values(const fs::path& path, std::size_t vertex_count) {
  const std::string text = io::read_file(path);
  io::TextReader in(text, path);
  std::vector<double> values;
  values.reserve(std::min(vertex_count, text.size() / 2 + 1));
  for (std::string_view t = in.token_across_lines(); !t.empty(); t = in.token_across_lines()) {
    double v = 0;
    if (!io::TextReader::parse(t, v)) in.fail("'{}' is not a number (value {})", io::echo(t), values.size() + 1);
    if (!std::isfinite(v)) in.fail("value {} ('{}', vertex {}) is not finite", values.size() + 1, io::echo(t), values.size() + 1);
    if (values.size() == vertex_count) in.fail("more values than the mesh's {} vertices", vertex_count);
    values.push_back(v);
  }
  if (values.size() != vertex_count)
    in.fail("{} values for {} vertices (the file ends here)", values.size(), vertex_count);
  return values;
}

void validate_tet_mesh(const TetMesh& mesh) {
  if (mesh.tets.empty()) throw InvalidInput(fmt::format("{}: no tetrahedra", mesh.source));
  if (const auto p = find_problem(mesh, 0)) throw InvalidInput(fmt::format("{}: {}", mesh.source, p->what));
}

}  // namespace quadrix
