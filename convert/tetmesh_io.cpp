// Tetrahedral meshes (Medit .mesh, TetGen .node/.ele) and per-vertex value files.
#include "convert/tetmesh_io.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <string_view>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/error.h"

namespace quadrix {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;

std::string lower(std::string_view s) {
  std::string out(s);
  for (auto& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

struct Token {
  std::string_view text;
  int line = 0;
};

// Whitespace-separated tokens with their line numbers; `#` comments run to the end of the line.
class Tokens {
public:
  explicit Tokens(std::string_view text) : s_(text) {}
  std::optional<Token> next() {
    for (;;) {
      while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) {
        if (s_[pos_] == '\n') ++line_;
        ++pos_;
      }
      if (pos_ >= s_.size()) return std::nullopt;
      if (s_[pos_] != '#') break;
      while (pos_ < s_.size() && s_[pos_] != '\n') ++pos_;
    }
    const std::size_t b = pos_;
    while (pos_ < s_.size() && !std::isspace(static_cast<unsigned char>(s_[pos_])) && s_[pos_] != '#') ++pos_;
    return Token{s_.substr(b, pos_ - b), line_};
  }
  int line() const { return line_; }
  std::size_t remaining_bytes() const { return s_.size() - pos_; }

private:
  std::string_view s_;
  std::size_t pos_ = 0;
  int line_ = 1;
};

std::optional<double> to_double(std::string_view t) {
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  double v = 0;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  if (r.ec != std::errc() || r.ptr != t.data() + t.size()) return std::nullopt;
  return v;
}

std::optional<long long> to_integer(std::string_view t) {
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  long long v = 0;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  if (r.ec != std::errc() || r.ptr != t.data() + t.size()) return std::nullopt;
  return v;
}

// The first inconsistency of a mesh: tetrahedron t (or vertex v when is_vertex) and what is wrong.
struct Problem {
  bool is_vertex = false;
  std::size_t index = 0;
  std::string what;
};

// Indices in range (shown in the file's base), finite coordinates, no degenerate tetrahedron.
std::optional<Problem> find_problem(const TetMesh& m, int base) {
  for (std::size_t v = 0; v < m.vertices.size(); ++v)
    if (!m.vertices[v].allFinite())
      return Problem{true, v,
                     fmt::format("vertex {} has a non-finite coordinate ({}, {}, {})", v + base, m.vertices[v].x(),
                                 m.vertices[v].y(), m.vertices[v].z())};
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
    double L = std::max({e1.norm(), e2.norm(), e3.norm(), (e2 - e1).norm(), (e3 - e1).norm(), (e3 - e2).norm()});
    const double six_v = e1.cross(e2).dot(e3);
    if (!(std::abs(six_v) > kDegenerateTet * L * L * L))
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
  const std::string file = path.string();
  const std::string text = read_file(path);
  Tokens tok(text);
  TetMesh m;
  m.source = file;
  std::vector<int> tet_lines;
  bool has_vertices = false, has_tets = false, has_dimension = false;

  // A section's count, then `count` entries of `width` numbers each, read through `take`.
  const auto section_count = [&](const Token& kw) {
    const auto t = tok.next();
    if (!t) throw FormatError(fmt::format("{} line {}: the file ends after '{}' (no count)", file, kw.line, kw.text));
    const auto n = to_integer(t->text);
    if (!n || *n < 0 || *n > 0x7fffffff)
      throw FormatError(fmt::format("{} line {}: '{}' count '{}' is not a non-negative integer", file, t->line,
                                    kw.text, t->text));
    return *n;
  };
  const auto next_in = [&](const Token& kw, long long entry, long long count) {
    const auto t = tok.next();
    if (!t)
      throw FormatError(fmt::format("{}: the file ends inside '{}' (line {}) after {} of its {} entries (truncated?)",
                                    file, kw.text, kw.line, entry, count));
    return *t;
  };
  const auto not_number = [&](const Token& t, const Token& kw, long long entry, long long count) {
    return FormatError(fmt::format("{} line {}: '{}' is not a number (entry {} of {} in '{}' at line {}; "
                                   "a count that disagrees with the file?)",
                                   file, t.line, t.text, entry + 1, count, kw.text, kw.line));
  };

  for (;;) {
    const auto kw = tok.next();
    if (!kw) throw FormatError(fmt::format("{}: no 'End' keyword (the file is truncated?)", file));
    const std::string k = lower(kw->text);
    if (k == "end") break;
    if (k == "meshversionformatted") {
      const auto t = tok.next();
      const auto v = t ? to_integer(t->text) : std::nullopt;
      if (!v || *v < 1 || *v > 4)
        throw FormatError(fmt::format("{} line {}: MeshVersionFormatted must be 1..4", file, kw->line));
    } else if (k == "dimension") {
      const auto t = tok.next();
      const auto v = t ? to_integer(t->text) : std::nullopt;
      if (!v || *v != 3)
        throw FormatError(fmt::format("{} line {}: Dimension {} (only 3-D meshes are supported)", file, kw->line,
                                      t ? std::string(t->text) : "missing"));
      has_dimension = true;
    } else if (k == "vertices") {
      if (has_vertices) throw FormatError(fmt::format("{} line {}: a second 'Vertices' section", file, kw->line));
      has_vertices = true;
      const long long n = section_count(*kw);
      m.vertices.reserve(static_cast<std::size_t>(std::min<long long>(n, tok.remaining_bytes() / 8 + 1)));
      for (long long i = 0; i < n; ++i) {
        Vector3d x;
        for (int a = 0; a < 4; ++a) {  // x y z ref
          const Token t = next_in(*kw, i, n);
          const auto v = to_double(t.text);
          if (!v) throw not_number(t, *kw, i, n);
          if (a < 3) {
            if (!std::isfinite(*v))
              throw FormatError(fmt::format("{} line {}: vertex {} has a non-finite coordinate '{}'", file, t.line,
                                            i + 1, t.text));
            x[a] = *v;
          }
        }
        m.vertices.push_back(x);
      }
    } else if (k == "tetrahedra") {
      if (has_tets) throw FormatError(fmt::format("{} line {}: a second 'Tetrahedra' section", file, kw->line));
      has_tets = true;
      const long long n = section_count(*kw);
      m.tets.reserve(static_cast<std::size_t>(std::min<long long>(n, tok.remaining_bytes() / 10 + 1)));
      tet_lines.reserve(m.tets.capacity());
      for (long long i = 0; i < n; ++i) {
        std::array<int, 4> c{};
        int line = 0;
        for (int a = 0; a < 5; ++a) {
          const Token t = next_in(*kw, i, n);
          if (a == 0) line = t.line;
          const auto v = to_integer(t.text);
          if (!v) throw not_number(t, *kw, i, n);
          if (a < 4) {
            if (*v < 1 || *v > 0x7fffffff)
              throw FormatError(fmt::format("{} line {}: tetrahedron {}: vertex index {} is not a 1-based index",
                                            file, t.line, i + 1, *v));
            c[a] = static_cast<int>(*v - 1);
          }
        }
        m.tets.push_back(c);
        tet_lines.push_back(line);
      }
    } else if (const auto w = medit_skip_width(k)) {
      const long long n = section_count(*kw);
      for (long long i = 0; i < n; ++i)
        for (int a = 0; a < *w; ++a) {
          const Token t = next_in(*kw, i, n);
          if (!to_double(t.text)) throw not_number(t, *kw, i, n);
        }
    } else {
      throw FormatError(fmt::format("{} line {}: unknown keyword '{}'", file, kw->line, kw->text));
    }
  }
  if (!has_dimension) throw FormatError(fmt::format("{}: no 'Dimension 3' line", file));
  if (m.vertices.empty()) throw FormatError(fmt::format("{}: no vertices", file));
  if (m.tets.empty()) throw FormatError(fmt::format("{}: no tetrahedra", file));
  if (const auto p = find_problem(m, 1))
    throw FormatError(fmt::format("{} line {}: {}", file, tet_lines[p->index], p->what));
  return m;
}

TetMesh read_tetgen_mesh(const fs::path& path) {
  fs::path node = path, ele = path;
  node.replace_extension(".node");
  ele.replace_extension(".ele");
  TetMesh m;
  m.source = node.string();

  // Non-blank lines split into tokens, with their line numbers.
  struct Line {
    int number = 0;
    std::vector<std::string_view> tokens;
  };
  const auto lines_of = [](const std::string& text) {
    std::vector<Line> out;
    std::size_t b = 0;
    int number = 0;
    while (b < text.size()) {
      std::size_t e = text.find('\n', b);
      if (e == std::string::npos) e = text.size();
      ++number;
      std::string_view s(text.data() + b, e - b);
      if (const auto h = s.find('#'); h != std::string_view::npos) s = s.substr(0, h);
      Line l{number, {}};
      Tokens t(s);
      while (const auto x = t.next()) l.tokens.push_back(x->text);
      if (!l.tokens.empty()) out.push_back(std::move(l));
      b = e + 1;
    }
    return out;
  };
  const auto integer = [](const std::string& file, const Line& l, std::size_t k, const char* what) {
    const auto v = k < l.tokens.size() ? to_integer(l.tokens[k]) : std::nullopt;
    if (!v || *v < 0 || *v > 0x7fffffff)
      throw FormatError(fmt::format("{} line {}: {} '{}' is not a non-negative integer", file, l.number, what,
                                    k < l.tokens.size() ? l.tokens[k] : "missing"));
    return *v;
  };

  const std::string node_text = read_file(node), node_file = node.string();
  const auto nodes = lines_of(node_text);
  if (nodes.empty()) throw FormatError(fmt::format("{}: empty file", node_file));
  const long long np = integer(node_file, nodes[0], 0, "point count");
  const long long dim = nodes[0].tokens.size() > 1 ? integer(node_file, nodes[0], 1, "dimension") : 3;
  const long long nattr = nodes[0].tokens.size() > 2 ? integer(node_file, nodes[0], 2, "attribute count") : 0;
  const long long nmark = nodes[0].tokens.size() > 3 ? integer(node_file, nodes[0], 3, "boundary marker flag") : 0;
  if (dim != 3)
    throw FormatError(
        fmt::format("{} line {}: dimension {} (only 3 is supported)", node_file, nodes[0].number, dim));
  if (np == 0) throw FormatError(fmt::format("{} line {}: no points", node_file, nodes[0].number));
  if (static_cast<long long>(nodes.size()) - 1 < np)
    throw FormatError(fmt::format("{}: header (line {}) says {} points, the file holds {} (truncated?)", node_file,
                                  nodes[0].number, np, nodes.size() - 1));
  const std::size_t node_width = static_cast<std::size_t>(4 + nattr + (nmark > 0 ? 1 : 0));
  long long base = 0;
  m.vertices.reserve(static_cast<std::size_t>(np));
  for (long long i = 0; i < np; ++i) {
    const Line& l = nodes[static_cast<std::size_t>(i + 1)];
    if (l.tokens.size() != node_width)
      throw FormatError(fmt::format("{} line {}: {} numbers, a point has {} here", node_file, l.number,
                                    l.tokens.size(), node_width));
    const long long id = integer(node_file, l, 0, "point number");
    if (i == 0) {
      if (id > 1)
        throw FormatError(
            fmt::format("{} line {}: the first point is number {} (0 or 1)", node_file, l.number, id));
      base = id;
    } else if (id != base + i) {
      throw FormatError(fmt::format("{} line {}: point number {}, expected {}", node_file, l.number, id, base + i));
    }
    Vector3d x;
    for (int a = 0; a < 3; ++a) {
      const auto v = to_double(l.tokens[1 + a]);
      if (!v) throw FormatError(fmt::format("{} line {}: '{}' is not a number", node_file, l.number, l.tokens[1 + a]));
      if (!std::isfinite(*v))
        throw FormatError(fmt::format("{} line {}: point {} has a non-finite coordinate '{}'", node_file, l.number,
                                      id, l.tokens[1 + a]));
      x[a] = *v;
    }
    m.vertices.push_back(x);
  }

  const std::string ele_text = read_file(ele), ele_file = ele.string();
  const auto eles = lines_of(ele_text);
  if (eles.empty()) throw FormatError(fmt::format("{}: empty file", ele_file));
  const long long nt = integer(ele_file, eles[0], 0, "tetrahedron count");
  const long long per = eles[0].tokens.size() > 1 ? integer(ele_file, eles[0], 1, "nodes per tetrahedron") : 4;
  const long long eattr = eles[0].tokens.size() > 2 ? integer(ele_file, eles[0], 2, "attribute count") : 0;
  if (per != 4 && per != 10)
    throw FormatError(fmt::format("{} line {}: {} nodes per tetrahedron (4 or 10)", ele_file, eles[0].number, per));
  if (nt == 0) throw FormatError(fmt::format("{} line {}: no tetrahedra", ele_file, eles[0].number));
  if (static_cast<long long>(eles.size()) - 1 < nt)
    throw FormatError(fmt::format("{}: header (line {}) says {} tetrahedra, the file holds {} (truncated?)", ele_file,
                                  eles[0].number, nt, eles.size() - 1));
  const std::size_t ele_width = static_cast<std::size_t>(1 + per + eattr);
  std::vector<int> tet_lines;
  m.tets.reserve(static_cast<std::size_t>(nt));
  for (long long i = 0; i < nt; ++i) {
    const Line& l = eles[static_cast<std::size_t>(i + 1)];
    if (l.tokens.size() != ele_width)
      throw FormatError(fmt::format("{} line {}: {} numbers, a tetrahedron has {} here", ele_file, l.number,
                                    l.tokens.size(), ele_width));
    std::array<int, 4> c{};
    for (int a = 0; a < 4; ++a) {
      const long long v = integer(ele_file, l, 1 + a, "vertex index");
      if (v < base || v >= base + np)
        throw FormatError(fmt::format("{} line {}: tetrahedron {}: vertex index {} is outside {}..{}", ele_file,
                                      l.number, i + base, v, base, base + np - 1));
      c[a] = static_cast<int>(v - base);
    }
    m.tets.push_back(c);
    tet_lines.push_back(l.number);
  }
  if (const auto p = find_problem(m, static_cast<int>(base)))
    throw FormatError(fmt::format("{} line {}: {}", ele_file, tet_lines[p->index], p->what));
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
  const std::string file = path.string();
  const std::string text = read_file(path);
  Tokens tok(text);
  std::vector<double> values;
  values.reserve(vertex_count);
  while (const auto t = tok.next()) {
    const auto v = to_double(t->text);
    if (!v) throw FormatError(fmt::format("{} line {}: '{}' is not a number (value {})", file, t->line, t->text,
                                          values.size() + 1));
    if (!std::isfinite(*v))
      throw FormatError(fmt::format("{} line {}: value {} ('{}', vertex {}) is not finite", file, t->line,
                                    values.size() + 1, t->text, values.size() + 1));
    if (values.size() == vertex_count)
      throw FormatError(fmt::format("{} line {}: more values than the mesh's {} vertices", file, t->line,
                                    vertex_count));
    values.push_back(*v);
  }
  if (values.size() != vertex_count)
    throw FormatError(fmt::format("{}: {} values for {} vertices (the file ends at line {})", file, values.size(),
                                  vertex_count, tok.line()));
  return values;
}

void validate_tet_mesh(const TetMesh& mesh) {
  if (mesh.tets.empty()) throw InvalidInput(fmt::format("{}: no tetrahedra", mesh.source));
  if (const auto p = find_problem(mesh, 0)) throw InvalidInput(fmt::format("{}: {}", mesh.source, p->what));
}

}  // namespace quadrix
