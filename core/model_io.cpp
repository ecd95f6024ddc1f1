#include "core/model_io.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

#include <Eigen/LU>
#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/bounds.h"
#include "core/error.h"
#include "core/implicit/surface.h"
#include "core/io/file.h"
#include "core/io/ply.h"
#include "core/limits.h"
#include "core/log.h"

namespace quadrix {
namespace {

constexpr std::array<const char*, 10> kCoefficientNames = {"k_xx", "k_yy", "k_zz", "k_xy", "k_yz",
                                                           "k_zx", "k_x",  "k_y",  "k_z",  "k_1"};
constexpr std::array<const char*, 4> kSlimNames = {"x", "y", "z", "radius"};
constexpr std::array<const char*, 2> kHierarchyNames = {"parent", "error"};
/// One group per clip plane (ClipPlanes::kMax); the second to fourth are new in revision 4.
constexpr std::array<std::array<const char*, 4>, ClipPlanes::kMax> kClipNames = {{
    {"clip_nx", "clip_ny", "clip_nz", "clip_d"},
    {"clip2_nx", "clip2_ny", "clip2_nz", "clip2_d"},
    {"clip3_nx", "clip3_ny", "clip3_nz", "clip3_d"},
    {"clip4_nx", "clip4_ny", "clip4_nz", "clip4_d"},
}};
constexpr std::array<const char*, 3> kColourNames = {"red", "green", "blue"};
constexpr std::array<const char*, 12> kCornerColourNames = {"red0",   "green0", "blue0", "red1",   "green1", "blue1",
                                                            "red2",   "green2", "blue2", "red3",   "green3", "blue3"};
constexpr const char* kMeasuredErrorName = "measured_error";
constexpr const char* kMaxPushName = "max_push";
constexpr std::array<const char*, 12> kCornerNames = {"x0", "y0", "z0", "x1", "y1", "z1",
                                                      "x2", "y2", "z2", "x3", "y3", "z3"};
constexpr std::array<const char*, 6> kBoundsNames = {"min_x", "min_y", "min_z", "max_x", "max_y", "max_z"};
constexpr std::array<const char*, 9> kAxisNames = {"a0x", "a0y", "a0z", "a1x", "a1y", "a1z", "a2x", "a2y", "a2z"};

std::vector<std::string> names(std::initializer_list<std::span<const char* const>> groups) {
  std::vector<std::string> out;
  for (const auto& g : groups)
    for (const char* n : g) out.emplace_back(n);
  return out;
}

/// Header comments that are part of the format, not metadata.
bool is_reserved_key(std::string_view key) {
  return key == "quadrix-format" || key == "quadrix-encoding" || key == "quadrix-origin";
}

bool has_whitespace(std::string_view s) {
  return std::any_of(s.begin(), s.end(), [](unsigned char c) { return std::isspace(c) != 0; });
}

std::string single_line(std::string v) {
  for (char& c : v)
    if (c == '\n' || c == '\r') c = ' ';
  return v;
}

// ---------------------------------------------------------------- writer

void check_finite(bool ok, std::string_view what, std::size_t i, const std::filesystem::path& path) {
  if (!ok)
    throw InvalidInput(fmt::format("{}: cannot write {} {}: it holds non-finite values or coordinates beyond ±{:g} "
                                   "(the largest world coordinate Quadrix handles)",
                                   path.string(), what, i, kMaxWorldCoordinate));
}

void append_colour(std::string& out, const std::optional<Rgb>& c) {
  const Rgb rgb = c.value_or(Rgb{0, 0, 0});
  for (auto v : rgb) out.push_back(static_cast<char>(v));
}

ply::Element element(std::string name, std::size_t count, const std::vector<std::string>& reals, bool colour,
                     ply::Type real, bool glyph_kind = false) {
  ply::Element e;
  e.name = std::move(name);
  e.count = count;
  if (glyph_kind) e.properties.push_back({"kind", ply::Type::uint8});
  for (const auto& n : reals) e.properties.push_back({n, real});
  if (colour)
    for (const char* n : kColourNames) e.properties.push_back({n, ply::Type::uint8});
  return e;
}

// ---------------------------------------------------------------- compact encoding

/// What a reader rebuilds from the compact encoding (float32 values, positions relative to a
/// float64 origin): the writer stores exactly these values, so it can check them first.
class CompactRounding {
public:
  explicit CompactRounding(const Eigen::Vector3d& origin) : origin_(origin) {}

  static double round(double v) {
    if (std::abs(v) > static_cast<double>(std::numeric_limits<float>::max()))
      return std::copysign(std::numeric_limits<double>::infinity(), v);
    return static_cast<double>(static_cast<float>(v));
  }
  static Eigen::Vector3d round(const Eigen::Vector3d& v) { return {round(v.x()), round(v.y()), round(v.z())}; }
  static QuadricCoefficients round(const QuadricCoefficients& k) {
    QuadricCoefficients r;
    for (std::size_t i = 0; i < k.size(); ++i) r[i] = round(k[i]);
    return r;
  }
  /// The float32 offset stored for a world position.
  Eigen::Vector3d offset(const Eigen::Vector3d& p) const { return round(Eigen::Vector3d(p - origin_)); }
  /// The position a reader rebuilds from it.
  Eigen::Vector3d position(const Eigen::Vector3d& p) const { return origin_ + offset(p); }

  SlimPatch slim(const SlimPatch& s) const {
    SlimPatch r = s;
    r.centre = position(s.centre);
    r.radius = round(s.radius);
    r.local = Quadric::from_coefficients(round(s.local.coefficients()));
    r.clips.clear();
    for (const ClipPlane& p : s.clips) r.clips.add(ClipPlane{round(p.n), round(p.d)});
    return r;
  }
  /// The quadric is relative to the corners' centroid, which moves with the rounded corners:
  /// it is re-expressed about the new centroid (in double) before its own rounding.
  TetPatch tet(const TetPatch& t) const {
    TetPatch r = t;
    for (std::size_t k = 0; k < 4; ++k) r.corners[k] = position(t.corners[k]);
    r.quadric = Quadric::from_coefficients(
        round(t.quadric.translated_to_origin(r.centroid() - t.centroid()).coefficients()));
    return r;
  }
  Glyph glyph(const Glyph& g) const {
    Glyph r = g;
    r.centre = position(g.centre);
    r.radius = round(g.radius);
    for (Eigen::Index k = 0; k < 3; ++k) r.axes.col(k) = round(Eigen::Vector3d(g.axes.col(k)));
    return r;
  }

  /// Why a primitive does not survive the rounding, or empty (see WriteModelOptions).
  static std::string coefficients_problem(const QuadricCoefficients& a, const QuadricCoefficients& b) {
    double top = 0, moved = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      top = std::max(top, std::abs(a[i]));
      moved = std::max(moved, std::abs(b[i] - a[i]));
    }
    if (!(moved <= 1e-6 * top))
      return fmt::format("its quadric's coefficients (largest {:g}) do not fit float32", top);
    return {};
  }
  static std::string moved_problem(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double size) {
    const double moved = (b - a).norm();
    if (!(moved <= 1e-3 * size))
      return fmt::format("float32 moves its position {} by {:g}, more than 1/1000 of its size {:g}",
                         fmt::format("({:g}, {:g}, {:g})", a.x(), a.y(), a.z()), moved, size);
    return {};
  }
  static std::string scalar_problem(double a, double b, std::string_view what) {
    if (!(std::abs(b - a) <= 1e-6 * std::abs(a)) || (a > 0 && !(b > 0)))
      return fmt::format("its {} {:g} does not fit float32", what, a);
    return {};
  }
  std::string slim_problem(const SlimPatch& s) const {
    const SlimPatch r = slim(s);
    std::string why = scalar_problem(s.radius, r.radius, "radius");
    if (why.empty()) why = moved_problem(s.centre, r.centre, s.radius);
    if (why.empty()) why = coefficients_problem(s.local.coefficients(), r.local.coefficients());
    for (int k = 0; why.empty() && k < s.clips.size(); ++k) {
      const ClipPlane& pa = s.clips[k];
      const ClipPlane& pb = r.clips[k];
      const Eigen::Vector4d a(pa.n.x(), pa.n.y(), pa.n.z(), pa.d);
      const Eigen::Vector4d b(pb.n.x(), pb.n.y(), pb.n.z(), pb.d);
      if (!((b - a).cwiseAbs().maxCoeff() <= 1e-6 * a.cwiseAbs().maxCoeff()) || pb.n == Eigen::Vector3d::Zero())
        why = "its clip plane does not fit float32";
    }
    return why;
  }
  std::string tet_problem(const TetPatch& t) const {
    const TetPatch r = tet(t);
    double edge = 0;
    for (std::size_t i = 0; i < 4; ++i)
      for (std::size_t j = i + 1; j < 4; ++j) edge = std::max(edge, (t.corners[i] - t.corners[j]).norm());
    for (std::size_t k = 0; k < 4; ++k)
      if (std::string why = moved_problem(t.corners[k], r.corners[k], edge); !why.empty()) return why;
    const Quadric moved = t.quadric.translated_to_origin(r.centroid() - t.centroid());
    if (std::string why = coefficients_problem(moved.coefficients(), r.quadric.coefficients()); !why.empty()) return why;
    return along_problem(t, r);
  }
  /// A surface that runs along two edges of its tetrahedron from one corner (the bilinear patch
  /// of a quad holds its four sides) touches the face they span there tangentially and stays
  /// within about h·(r/L)² of it at a distance r from that corner (h the thickness, L the size).
  /// Corners moved by δ cut it there out to r ≈ L·√(δ/h): holes at the corners, pinholes to any
  /// ray caster (inspired_mesh_quads at δ/h = 3e-4: 2 % of each quad's size; torus_quad at
  /// δ/h = 0.05: whole quads lost, and stray pieces of the quadric where the moved faces let
  /// them in). Compact only while those holes stay within 1/1000 of the size: δ ≤ 1e-6·h.
  static std::string along_problem(const TetPatch& t, const TetPatch& r) {
    const double thickness = tetrahedron_thickness(t.corners);
    double moved = 0;
    for (std::size_t k = 0; k < 4; ++k) moved = std::max(moved, (r.corners[k] - t.corners[k]).norm());
    if (moved <= 1e-6 * thickness) return {};
    // Edges on the surface: its value at five points along them within 1e-9 of their length.
    const Eigen::Vector3d c = t.centroid();
    const auto on_surface = [&](std::size_t i, std::size_t j) {
      const Eigen::Vector3d a = t.corners[i] - c, b = t.corners[j] - c;
      const double tolerance = 1e-9 * (b - a).norm();
      for (const double s : {0.0, 0.25, 0.5, 0.75, 1.0}) {
        const Eigen::Vector3d y = a + s * (b - a);
        if (!(std::abs(t.quadric.eval(y)) <= tolerance * t.quadric.gradient(y).norm())) return false;
      }
      return true;
    };
    std::array<int, 4> edges_at{};
    for (std::size_t i = 0; i < 4; ++i)
      for (std::size_t j = i + 1; j < 4; ++j)
        if (on_surface(i, j)) ++edges_at[i], ++edges_at[j];
    if (*std::max_element(edges_at.begin(), edges_at.end()) < 2) return {};
    return fmt::format("its surface runs along two of its tetrahedron's edges, where float32 would cut holes {:.2g} "
                       "of its size wide (its corners moved by {:g}, the tetrahedron {:g} thin)",
                       std::sqrt(moved / thickness), moved, thickness);
  }
  /// Whether float32 turns the tetrahedron flat or inside out: a sliver whose height is below
  /// the rounding of its corners.
  bool turns_flat(const TetPatch& t) const {
    const TetPatch r = tet(t);
    const auto volume = [](const std::array<Eigen::Vector3d, 4>& p) {
      return (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]);
    };
    return is_degenerate_tetrahedron(r.corners) || !(volume(t.corners) * volume(r.corners) > 0);
  }
  std::string glyph_problem(const Glyph& g) const {
    const Glyph r = glyph(g);
    double size = g.kind == GlyphKind::ellipsoid ? 0.0 : g.radius;
    for (Eigen::Index k = 0; k < 3; ++k) size = std::max(size, g.axes.col(k).norm());
    if (std::string why = moved_problem(g.centre, r.centre, size); !why.empty()) return why;
    if (g.kind != GlyphKind::ellipsoid)
      if (std::string why = scalar_problem(g.radius, r.radius, "radius"); !why.empty()) return why;
    const double moved = (r.axes - g.axes).cwiseAbs().maxCoeff();
    if (!(moved <= 1e-6 * g.axes.cwiseAbs().maxCoeff()) ||
        (g.kind == GlyphKind::cylinder && r.axes.col(0) == Eigen::Vector3d::Zero()) ||
        (g.kind == GlyphKind::ellipsoid && !(std::abs(r.axes.determinant() - g.axes.determinant()) <=
                                             1e-2 * std::abs(g.axes.determinant()))))
      return "its axes do not fit float32";
    return {};
  }
  /// The first primitive of the model that does not survive the rounding, or empty. Tetrahedra
  /// that turn flat are marked in flat (sized to the tets) instead: they are left out.
  std::string first_problem(const Model& m, std::vector<char>& flat) const {
    const SlimHierarchy& hy = m.slim_hierarchy;
    for (std::size_t i = 0; i < m.slims.size() + hy.others.size(); ++i) {
      std::string why = slim_problem(slim_ball(m, i));
      if (why.empty() && !hy.empty() && !std::isfinite(round(hy.error[i])))
        why = fmt::format("its error {:g} does not fit float32", hy.error[i]);
      if (!why.empty())
        return i < m.slims.size() ? fmt::format("slim patch {}: {}", i, why)
                                  : fmt::format("slim_node {}: {}", i - m.slims.size(), why);
    }
    flat.assign(m.tets.size(), 0);
    for (std::size_t i = 0; i < m.tets.size(); ++i) {
      if (std::string why = tet_problem(m.tets[i]); !why.empty()) return fmt::format("tet patch {}: {}", i, why);
      flat[i] = turns_flat(m.tets[i]);
    }
    const auto dropped = static_cast<std::size_t>(std::count(flat.begin(), flat.end(), 1));
    if (dropped > m.tets.size() / 1000)
      return fmt::format("{} of {} tetrahedra turn flat in float32 (more than 1 in 1000)", dropped, m.tets.size());
    for (std::size_t i = 0; i < m.glyphs.size(); ++i)
      if (std::string why = glyph_problem(m.glyphs[i]); !why.empty()) return fmt::format("glyph {}: {}", i, why);
    return {};
  }

private:
  Eigen::Vector3d origin_;
};

// ---------------------------------------------------------------- reader

/// Access to one table's columns by name with optional groups and per-value error messages.
class Rows {
public:
  Rows(const ply::File& file, const ply::Table& table) : file_(file), t_(table) {}
  std::size_t size() const { return t_.rows; }
  double get(std::size_t row, std::size_t col) const { return t_(row, col); }
  [[noreturn]] void fail(std::size_t row, std::size_t col, std::string_view what) const {
    throw FormatError(
        file_.message(t_.element, static_cast<std::int64_t>(row), t_.properties[col], t_.byte_offset(row, col), what));
  }
  [[noreturn]] void fail_row(std::size_t row, std::string_view what) const {
    throw FormatError(file_.message(t_.element, static_cast<std::int64_t>(row), {}, t_.byte_offset(row, 0), what));
  }
  /// Reads a finite value.
  double finite(std::size_t row, std::size_t col) const {
    const double v = t_(row, col);
    if (!std::isfinite(v)) fail(row, col, fmt::format("value {} is not finite", v));
    return v;
  }
  /// Reads a world coordinate or length (core/limits.h).
  double world(std::size_t row, std::size_t col) const {
    const double v = finite(row, col);
    if (!is_world_value(v)) fail(row, col, fmt::format("value {:g} {}", v, world_fault(v)));
    return v;
  }
  Eigen::Vector3d vec3(std::size_t row, std::size_t col) const {
    return {world(row, col), world(row, col + 1), world(row, col + 2)};
  }
  /// A position stored relative to origin (the file's quadrix-origin).
  Eigen::Vector3d position(std::size_t row, std::size_t col, const Eigen::Vector3d& origin) const {
    const Eigen::Vector3d p = origin + vec3(row, col);
    if (!p.allFinite()) fail(row, col, "position is not finite after adding the origin");
    return p;
  }
  QuadricCoefficients coefficients(std::size_t row, std::size_t col) const {
    QuadricCoefficients k;
    for (std::size_t i = 0; i < 10; ++i) k[i] = finite(row, col + i);
    return k;
  }
  Rgb colour(std::size_t row, std::size_t col) const {
    Rgb c;
    for (std::size_t i = 0; i < 3; ++i) {
      const double v = finite(row, col + i);
      if (v < 0 || v > 255 || v != std::floor(v))
        fail(row, col + i, fmt::format("colour value {} is not in 0..255", v));
      c[i] = static_cast<std::uint8_t>(v);
    }
    return c;
  }

private:
  const ply::File& file_;
  const ply::Table& t_;
};

/// Whether element e has all of the names (true), none (false); a partial group is an error.
bool optional_group(const ply::File& f, const ply::Element& e, std::span<const char* const> group) {
  std::size_t found = 0;
  for (const char* n : group) found += e.find(n) >= 0;
  if (found == 0) return false;
  if (found == group.size()) return true;
  for (const char* n : group)
    if (e.find(n) < 0)
      throw FormatError(f.message(e.name, -1, n, ply::kNoByte,
                                  "property missing from an optional group (all or none must be present)"));
  return true;
}

std::vector<std::string> required(const ply::File& f, const ply::Element& e, std::vector<std::string> props) {
  for (const auto& p : props)
    if (e.find(p) < 0)
      throw FormatError(f.message(e.name, -1, p, ply::kNoByte, "required property is missing from the header"));
  return props;
}

/// Column layout of a `slim` or `slim_node` request: x y z radius k_* [clip] [colour] [parent error].
struct SlimColumns {
  int clips = 0;  ///< clip plane groups (clip_*, clip2_*, …), each 4 columns
  bool colour = false, hierarchy = false, measured_error = false, max_push = false;
  std::size_t measured_error_col = 0, max_push_col = 0;
  std::size_t parent = 0;  ///< column of `parent` (`error` follows) when hierarchy
};

SlimColumns slim_request(const ply::File& f, const ply::Element& e, bool hierarchy_required,
                         std::vector<ply::Request>& requests) {
  SlimColumns c;
  for (std::size_t k = 0; k < kClipNames.size(); ++k) {
    if (!optional_group(f, e, kClipNames[k])) {
      // The groups come in order: clip3_* without clip2_* names a plane that has no place.
      for (std::size_t j = k + 1; j < kClipNames.size(); ++j)
        if (e.find(kClipNames[j][0]) >= 0)
          throw FormatError(f.message(e.name, -1, kClipNames[j][0], ply::kNoByte,
                                      fmt::format("clip plane {} without clip plane {}", j + 1, k + 1)));
      break;
    }
    c.clips = static_cast<int>(k) + 1;
  }
  c.colour = optional_group(f, e, kColourNames);
  auto props =
      required(f, e, names({std::span<const char* const>(kSlimNames), kCoefficientNames}));
  if (hierarchy_required) required(f, e, names({kHierarchyNames}));
  c.hierarchy = optional_group(f, e, kHierarchyNames);
  for (int k = 0; k < c.clips; ++k) props.insert(props.end(), kClipNames[k].begin(), kClipNames[k].end());
  if (c.colour) props.insert(props.end(), kColourNames.begin(), kColourNames.end());
  c.measured_error = e.find(kMeasuredErrorName) >= 0;
  c.measured_error_col = props.size();
  if (c.measured_error) props.emplace_back(kMeasuredErrorName);
  c.max_push = e.find(kMaxPushName) >= 0;
  c.max_push_col = props.size();
  if (c.max_push) props.emplace_back(kMaxPushName);
  c.parent = props.size();
  if (c.hierarchy) props.insert(props.end(), kHierarchyNames.begin(), kHierarchyNames.end());
  requests.push_back({e.name, std::move(props), {}});
  return c;
}

/// Appends the rows' patches to out and, with a hierarchy, their parent ids (< total) and errors.
void read_slim_rows(const Rows& r, const SlimColumns& cols, const Eigen::Vector3d& origin, std::size_t total,
                    std::vector<SlimPatch>& out, SlimHierarchy& hierarchy) {
  out.reserve(out.size() + r.size());
  for (std::size_t i = 0; i < r.size(); ++i) {
    SlimPatch& s = out.emplace_back();
    s.centre = r.position(i, 0, origin);
    s.radius = r.world(i, 3);
    if (!(s.radius > 0)) r.fail(i, 3, fmt::format("value {} must be > 0", s.radius));
    s.local = Quadric::from_coefficients(r.coefficients(i, 4));
    std::size_t c = 14;
    for (int k = 0; k < cols.clips; ++k, c += 4) {
      ClipPlane p;
      p.n = r.vec3(i, c);
      p.d = r.world(i, c + 3);
      if (p.n != Eigen::Vector3d::Zero()) s.clips.add(p);
    }
    if (cols.colour) s.colour = r.colour(i, c);
    if (cols.measured_error) {
      // −1: not measured (the patch served no point); else a finite distance ≥ 0.
      const double e = r.finite(i, cols.measured_error_col);
      if (e < 0 && e != -1.0) r.fail(i, cols.measured_error_col, fmt::format("measured error {} is negative (−1: none)", e));
      if (e >= 0) s.measured_error = e;
    }
    if (cols.max_push) {
      // −1: the model's push bound; else > 0, world units.
      const double v = r.finite(i, cols.max_push_col);
      if (!(v > 0) && v != -1.0) r.fail(i, cols.max_push_col, fmt::format("max push {} is not > 0 (−1: none)", v));
      if (v > 0) s.max_push = v;
    }
    if (cols.hierarchy) {
      const std::size_t self = hierarchy.parent.size();
      const double p = r.finite(i, cols.parent);
      if (p != std::floor(p) || p < -1 || p >= static_cast<double>(total))
        r.fail(i, cols.parent, fmt::format("parent {} is not an integer in [-1, {})", p, total));
      if (p == static_cast<double>(self)) r.fail(i, cols.parent, fmt::format("parent {} is the ball itself", p));
      const double e = r.finite(i, cols.parent + 1);
      if (e < 0) r.fail(i, cols.parent + 1, fmt::format("error {} is negative", e));
      hierarchy.parent.push_back(static_cast<std::int32_t>(p));
      hierarchy.error.push_back(e);
    }
  }
}

/// Implicit surfaces from the `implicit` table: the expression as a list of ASCII bytes, the
/// parameter values in the expression's order of first appearance, the bounds, a colour.
void read_implicit_rows(const ply::File& f, const ply::Table& t, bool colour, std::vector<ImplicitSurface>& out) {
  const Rows r(f, t);
  const ply::Table::List& params = t.more_lists.at(0);
  const auto fail_list = [&](std::size_t row, std::string_view list, std::string_view what) {
    throw FormatError(f.message(t.element, static_cast<std::int64_t>(row), list, t.row_offsets[row], what));
  };
  out.reserve(out.size() + r.size());
  for (std::size_t i = 0; i < r.size(); ++i) {
    ImplicitSurface& s = out.emplace_back();
    for (std::uint64_t k = t.list_offsets[i]; k < t.list_offsets[i + 1]; ++k) {
      const double c = t.list_values[k];
      if (c != std::floor(c) || c < 32 || c > 126)
        fail_list(i, "expression",
                  fmt::format("character {} of the expression is {}, not printable ASCII (32..126)",
                              k - t.list_offsets[i] + 1, c));
      s.expression.push_back(static_cast<char>(c));
    }
    if (s.expression.empty()) fail_list(i, "expression", "the expression is empty");
    implicit::Expression e;
    try {
      e = implicit::Expression::parse(s.expression);
    } catch (const InvalidInput& x) {
      fail_list(i, "expression", x.what());
    }
    const std::size_t n = params.offsets[i + 1] - params.offsets[i];
    if (n != e.parameters().size())
      fail_list(i, "parameters",
                fmt::format("{} values for the {} parameters of '{}'{}", n, e.parameters().size(), io::echo(s.expression),
                            e.parameters().empty() ? "" : fmt::format(" ({})", fmt::join(e.parameters(), ", "))));
    for (std::size_t k = 0; k < n; ++k) {
      const double v = params.values[params.offsets[i] + k];
      if (!std::isfinite(v))
        fail_list(i, "parameters", fmt::format("value {} of parameter '{}' is not finite", v, e.parameters()[k]));
      s.parameters[e.parameters()[k]] = v;
    }
    s.bounds.min = r.vec3(i, 0);
    s.bounds.max = r.vec3(i, 3);
    for (std::size_t k = 0; k < 3; ++k)
      if (!(s.bounds.min[static_cast<Eigen::Index>(k)] < s.bounds.max[static_cast<Eigen::Index>(k)]))
        r.fail(i, 3 + k, fmt::format("bounds {} {} >= {} {}: the box is empty", kBoundsNames[k],
                                     s.bounds.min[static_cast<Eigen::Index>(k)], kBoundsNames[3 + k],
                                     s.bounds.max[static_cast<Eigen::Index>(k)]));
    if (colour) s.colour = r.colour(i, 6);
  }
}

/// "X Y Z": three finite numbers.
Eigen::Vector3d parse_origin(const ply::File& f, const std::string& text) {
  Eigen::Vector3d o;
  const char* p = text.data();
  const char* end = text.data() + text.size();
  for (int a = 0; a < 3; ++a) {
    while (p < end && (*p == ' ' || *p == '\t')) ++p;
    const auto [next, ec] = std::from_chars(p, end, o[a]);
    if (ec != std::errc() || !std::isfinite(o[a]) || (next < end && *next != ' ' && *next != '\t')) p = nullptr;
    if (!p) break;
    p = next;
  }
  while (p && p < end && (*p == ' ' || *p == '\t')) ++p;
  if (!p || p != end)
    throw FormatError(f.message({}, -1, {}, ply::kNoByte,
                                fmt::format("bad 'comment quadrix-origin {}' line (three finite numbers)",
                                            text.substr(0, 80))));
  return o;
}

Model read_qxm(const ply::File& f) {
  const ply::Header& h = f.header();
  Model model;
  // Format version, encoding, origin and metadata from the comments.
  bool has_version = false, has_origin = false;
  int format_version = 0;
  std::string encoding;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (const auto& c : h.comments) {
    const std::size_t sp = std::min(c.find_first_of(" \t"), c.size());
    const std::string key = c.substr(0, sp);
    std::string value = c.substr(std::min(c.find_first_not_of(" \t", sp), c.size()));
    if (key.empty()) continue;
    if (key == "quadrix-format") {
      int version = 0;
      const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), version);
      if (ec != std::errc() || end != value.data() + value.size())
        throw FormatError(
            f.message({}, -1, {}, ply::kNoByte, fmt::format("bad 'comment quadrix-format {}' line", value)));
      if (version < 1 || version > kQxmFormatVersion)
        throw FormatError(f.message(
            {}, -1, {}, ply::kNoByte,
            fmt::format("unsupported quadrix-format {} (this build reads 1..{})", version, kQxmFormatVersion)));
      has_version = true;
      format_version = version;
      continue;
    }
    if (key == "quadrix-encoding") {
      if (value != "compact" && value != "double")
        throw FormatError(f.message({}, -1, {}, ply::kNoByte,
                                    fmt::format("bad 'comment quadrix-encoding {}' line (compact or double)", value)));
      encoding = value;
      continue;
    }
    if (key == "quadrix-origin") {
      if (has_origin) throw FormatError(f.message({}, -1, {}, ply::kNoByte, "two 'comment quadrix-origin' lines"));
      origin = parse_origin(f, value);
      has_origin = true;
      continue;
    }
    model.metadata[key] = std::move(value);
  }
  if (!has_version)
    throw FormatError(f.message({}, -1, {}, ply::kNoByte, "not a .qxm file (no 'comment quadrix-format' line)"));
  if (format_version < 3 && (has_origin || !encoding.empty()))
    throw FormatError(f.message({}, -1, {}, ply::kNoByte,
                                fmt::format("'comment quadrix-{}' needs quadrix-format 3 or later, the file says {}",
                                            has_origin ? "origin" : "encoding", format_version)));
  if (encoding == "compact" && !has_origin)
    throw FormatError(f.message({}, -1, {}, ply::kNoByte,
                                "the compact encoding needs a 'comment quadrix-origin X Y Z' line"));

  // Which elements and optional groups are present.
  const ply::Element* es = h.find("slim");
  const ply::Element* en = h.find("slim_node");
  const ply::Element* et = h.find("tet");
  const ply::Element* eg = h.find("glyph");
  const ply::Element* ei = h.find("implicit");
  if (!es && !et && !eg && !ei)
    throw FormatError(f.message({}, -1, {}, ply::kNoByte, "no element 'slim', 'tet', 'glyph' or 'implicit'"));

  std::vector<ply::Request> requests;
  SlimColumns slim_columns, node_columns;
  bool tet_colour = false, tet_corner_colours = false, glyph_colour = false, implicit_colour = false;
  int is = -1, in = -1, it = -1, ig = -1, ii = -1;
  if (es) {
    slim_columns = slim_request(f, *es, false, requests);
    is = static_cast<int>(requests.size()) - 1;
  }
  if (en) {
    if (!es || !slim_columns.hierarchy)
      throw FormatError(f.message("slim_node", -1, {}, ply::kNoByte,
                                  "element 'slim_node' needs element 'slim' with properties 'parent' and 'error'"));
    node_columns = slim_request(f, *en, true, requests);
    in = static_cast<int>(requests.size()) - 1;
  }
  if (et) {
    tet_colour = optional_group(f, *et, kColourNames);
    auto props = required(f, *et, names({kCornerNames, kCoefficientNames}));
    if (tet_colour) props.insert(props.end(), kColourNames.begin(), kColourNames.end());
    tet_corner_colours = optional_group(f, *et, kCornerColourNames);
    if (tet_corner_colours) props.insert(props.end(), kCornerColourNames.begin(), kCornerColourNames.end());
    it = static_cast<int>(requests.size());
    requests.push_back({"tet", std::move(props), {}});
  }
  if (eg) {
    glyph_colour = optional_group(f, *eg, kColourNames);
    auto props = required(
        f, *eg,
        names({std::span<const char* const>(std::array<const char*, 5>{"kind", "x", "y", "z", "radius"}), kAxisNames}));
    if (glyph_colour) props.insert(props.end(), kColourNames.begin(), kColourNames.end());
    ig = static_cast<int>(requests.size());
    requests.push_back({"glyph", std::move(props), {}});
  }

  if (ei) {
    implicit_colour = optional_group(f, *ei, kColourNames);
    auto props = required(f, *ei, names({kBoundsNames}));
    if (implicit_colour) props.insert(props.end(), kColourNames.begin(), kColourNames.end());
    ii = static_cast<int>(requests.size());
    requests.push_back({"implicit", std::move(props), "expression", {"parameters"}});
  }

  const std::vector<ply::Table> tables = f.read(requests);

  if (is >= 0) {
    const Rows r(f, tables[is]);
    const std::size_t total = r.size() + (in >= 0 ? tables[in].rows : 0);
    read_slim_rows(r, slim_columns, origin, total, model.slims, model.slim_hierarchy);
    if (in >= 0) read_slim_rows(Rows(f, tables[in]), node_columns, origin, total, model.slim_hierarchy.others,
                                model.slim_hierarchy);
    if (slim_columns.hierarchy) {
      // A forest: following parents from any ball reaches a root.
      const SlimHierarchy& hy = model.slim_hierarchy;
      std::vector<char> state(total, 0);  // 0 unseen, 1 on the current walk, 2 reaches a root
      for (std::size_t i = 0; i < total; ++i) {
        std::size_t j = i;
        while (state[j] == 0) {
          state[j] = 1;
          if (hy.parent[j] < 0) break;
          j = static_cast<std::size_t>(hy.parent[j]);
        }
        if (state[j] == 1 && hy.parent[j] >= 0) {
          const bool drawn = j < r.size();
          const Rows rj(f, tables[drawn ? is : in]);
          const std::size_t row = drawn ? j : j - r.size();
          rj.fail(row, (drawn ? slim_columns : node_columns).parent, "parent links form a cycle through this ball");
        }
        for (std::size_t k = i; state[k] == 1; k = static_cast<std::size_t>(hy.parent[k])) {
          state[k] = 2;
          if (hy.parent[k] < 0) break;
        }
      }
    }
  }
  if (it >= 0) {
    const Rows r(f, tables[it]);
    model.tets.resize(r.size());
    for (std::size_t i = 0; i < r.size(); ++i) {
      TetPatch& t = model.tets[i];
      for (std::size_t k = 0; k < 4; ++k) t.corners[k] = r.position(i, 3 * k, origin);
      t.quadric = Quadric::from_coefficients(r.coefficients(i, 12));
      if (is_degenerate_tetrahedron(t.corners)) r.fail_row(i, "degenerate tetrahedron (zero volume)");
      if (tet_colour) t.colour = r.colour(i, 22);
      if (tet_corner_colours) {
        std::array<Rgb, 4> c;
        for (std::size_t k = 0; k < 4; ++k) c[k] = r.colour(i, (tet_colour ? 25 : 22) + 3 * k);
        t.corner_colours = c;
      }
    }
  }
  if (ig >= 0) {
    const Rows r(f, tables[ig]);
    model.glyphs.resize(r.size());
    for (std::size_t i = 0; i < r.size(); ++i) {
      Glyph& g = model.glyphs[i];
      const double kind = r.get(i, 0);
      if (kind != 0 && kind != 1 && kind != 2)
        r.fail(i, 0, fmt::format("glyph kind {} is not 0 (sphere), 1 (ellipsoid) or 2 (cylinder)", kind));
      g.kind = static_cast<GlyphKind>(static_cast<int>(kind));
      g.centre = r.position(i, 1, origin);
      g.radius = r.world(i, 4);
      for (std::size_t k = 0; k < 3; ++k) g.axes.col(static_cast<Eigen::Index>(k)) = r.vec3(i, 5 + 3 * k);
      if (g.kind != GlyphKind::ellipsoid && !(g.radius > 0))
        r.fail(i, 4, fmt::format("value {} must be > 0", g.radius));
      if (g.kind == GlyphKind::ellipsoid && !(std::abs(g.axes.determinant()) > 0))
        r.fail(i, 5, "degenerate ellipsoid axes (determinant 0)");
      if (g.kind == GlyphKind::cylinder && g.axes.col(0) == Eigen::Vector3d::Zero())
        r.fail(i, 5, "cylinder axis is zero");
      if (glyph_colour) g.colour = r.colour(i, 14);
    }
  }
  if (ii >= 0) read_implicit_rows(f, tables[ii], implicit_colour, model.implicits);
  return model;
}

bool has_extension(const std::filesystem::path& p, std::string_view ext) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e == ext;
}

template <class T>
T load_le(const std::string& b, std::size_t at) {
  T v;
  std::memcpy(&v, b.data() + at, sizeof(T));
  return v;
}

bool looks_like_slim2t(const std::string& b) {
  if (b.size() < 12) return false;
  const std::int32_t d = load_le<std::int32_t>(b, 0);
  return d == 1 || d == 2 || d == -1 || d == -2;
}

/// Gradient direction of a ball's quadric at a world point (unscaled: only its sign is used).
Eigen::Vector3d direction_at(const SlimPatch& s, const Eigen::Vector3d& x) {
  return s.local.gradient((x - s.centre) / s.radius);
}

/// Orients an unoriented (.slim2t degree < 0) hierarchy; returns a one-line account.
/// Leaves are the data: they keep their relative signs. (1) Outward: when most leaves' gradients
/// point towards the centroid of the leaf centres rather than away, every ball is flipped.
/// (2) Every interior ball is made to agree with the majority of the leaves below it that lie in
/// its support (its gradient at each leaf's centre against the leaf's gradient there); gradients
/// at a merged ball's own centre say little, since a coarse ball's centre can lie far from its
/// zero set. Leaves that disagree with their parent at their centre are counted, not flipped.
std::string orient_slim2t(std::vector<SlimPatch>& balls, const std::vector<std::int32_t>& parent,
                          const std::vector<char>& has_child) {
  const std::size_t n = balls.size();
  auto flip = [](SlimPatch& s) { s.local = s.local * -1.0; };
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  std::size_t leaves = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (!has_child[i]) centroid += balls[i].centre, ++leaves;
  if (leaves == 0) return "no leaves";
  centroid /= static_cast<double>(leaves);
  std::size_t away = 0, towards = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (has_child[i]) continue;
    const double d = direction_at(balls[i], balls[i].centre).dot(balls[i].centre - centroid);
    away += d > 0;
    towards += d < 0;
  }
  const bool flip_all = towards > away;
  if (flip_all)
    for (SlimPatch& s : balls) flip(s);
  // Votes of the leaves below each interior ball, within its support.
  std::vector<std::int64_t> votes(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (has_child[i]) continue;
    const Eigen::Vector3d x = balls[i].centre;
    const Eigen::Vector3d g = direction_at(balls[i], x);
    for (std::int32_t a = parent[i]; a >= 0; a = parent[static_cast<std::size_t>(a)]) {
      const SlimPatch& b = balls[static_cast<std::size_t>(a)];
      if ((x - b.centre).norm() > b.radius) continue;
      const double d = direction_at(b, x).dot(g);
      votes[static_cast<std::size_t>(a)] += (d > 0) - (d < 0);
    }
  }
  std::size_t flipped = 0, undecided = 0, leaf_disagree = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!has_child[i]) continue;
    if (votes[i] < 0) flip(balls[i]), ++flipped;
    undecided += votes[i] == 0;
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (has_child[i] || parent[i] < 0) continue;
    const Eigen::Vector3d x = balls[i].centre;
    leaf_disagree += direction_at(balls[static_cast<std::size_t>(parent[i])], x).dot(direction_at(balls[i], x)) < 0;
  }
  return fmt::format(
      "unoriented file: {} of {} leaf gradients pointed towards the leaves' centroid, {} away{}; "
      "{} of {} interior balls flipped to agree with the leaves below them ({} without a vote); "
      "{} leaves disagree with their parent at their centre (kept)",
      towards, leaves, away, flip_all ? ", so every ball was flipped" : "", flipped, n - leaves, undecided,
      leaf_disagree);
}

Model parse_slim2t(const std::string& b, const std::filesystem::path& path) {
  const std::string file = path.string();
  auto fail = [&](std::int64_t ball, std::size_t byte, std::string_view what) -> void {
    if (ball >= 0) throw FormatError(fmt::format("{}: ball {} at byte {}: {}", file, ball, byte, what));
    throw FormatError(fmt::format("{}: at byte {}: {}", file, byte, what));
  };
  if (b.size() < 12) fail(-1, 0, fmt::format("truncated .slim2t header ({} bytes, 12 expected)", b.size()));
  const std::int32_t degree = load_le<std::int32_t>(b, 0);
  const std::int32_t nballs = load_le<std::int32_t>(b, 4);
  const std::int32_t nuser = load_le<std::int32_t>(b, 8);
  if (degree != 1 && degree != 2 && degree != -1 && degree != -2)
    fail(-1, 0, fmt::format("degree {} is not ±1 or ±2 (not a .slim2t file?)", degree));
  if (nballs < 0) fail(-1, 4, fmt::format("ball count {} is negative", nballs));
  if (nuser < 0 || nuser >= 1024) fail(-1, 8, fmt::format("user value count {} is not in 0..1023", nuser));
  const std::size_t stride = (15 + static_cast<std::size_t>(nuser)) * 4;
  const std::size_t fits = (b.size() - 12) / stride;
  const std::size_t n = static_cast<std::size_t>(nballs);
  if (n > fits)
    fail(static_cast<std::int64_t>(fits), 12 + fits * stride,
         fmt::format("truncated: {} balls of {} bytes declared but only {} bytes follow the header", nballs, stride,
                     b.size() - 12));
  if (b.size() != 12 + n * stride)
    fail(-1, 12 + n * stride,
         fmt::format("{} bytes follow the {} declared balls of {} bytes", b.size() - 12 - n * stride, nballs, stride));

  std::vector<SlimPatch> balls(n);
  std::vector<std::int32_t> parent(n, -1);
  std::vector<double> error(n, 0.0);
  std::vector<char> has_child(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t at = 12 + i * stride;
    auto value = [&](std::size_t j, std::string_view what) {
      const double v = load_le<float>(b, at + 4 * j);
      if (!std::isfinite(v))
        fail(static_cast<std::int64_t>(i), at + 4 * j, fmt::format("{} value {} is not finite", what, v));
      return v;
    };
    SlimPatch& s = balls[i];
    for (std::size_t j = 0; j < 3; ++j) {
      s.centre[static_cast<Eigen::Index>(j)] = value(j, "centre");
      if (!is_world_value(s.centre[static_cast<Eigen::Index>(j)]))
        fail(static_cast<std::int64_t>(i), at + 4 * j,
             fmt::format("centre value {:g} {}", s.centre[static_cast<Eigen::Index>(j)], world_fault(s.centre[static_cast<Eigen::Index>(j)])));
    }
    QuadricCoefficients k;
    for (std::size_t j = 0; j < 10; ++j) k[j] = value(3 + j, "coefficient");
    s.radius = value(13, "radius");
    if (!(s.radius > 0)) fail(static_cast<std::int64_t>(i), at + 52, fmt::format("radius {} must be > 0", s.radius));
    if (!is_world_value(s.radius))
      fail(static_cast<std::int64_t>(i), at + 52, fmt::format("radius {:g} {}", s.radius, world_fault(s.radius)));
    // Coefficients are in y = x − centre, unscaled; the patch wants u = y / R.
    s.local = Quadric::from_coefficients(k).to_local(Eigen::Vector3d::Zero(), s.radius);
    // The parent id is a float32 holding an integer: 1-based, −1 for a root.
    const double p = value(14, "parent id");
    if (p != std::floor(p) || !(p == -1 || (p >= 1 && p <= nballs)))
      fail(static_cast<std::int64_t>(i), at + 56,
           fmt::format("parent id {} is not an integer in {{-1}} or [1, {}]", p, nballs));
    if (p == static_cast<double>(i) + 1)
      fail(static_cast<std::int64_t>(i), at + 56, fmt::format("parent id {} is the ball itself", p));
    if (p > 0) {
      parent[i] = static_cast<std::int32_t>(p) - 1;
      has_child[static_cast<std::size_t>(parent[i])] = 1;
    }
    if (nuser > 0) {
      error[i] = value(15, "error (first user value)");
      if (error[i] < 0)
        fail(static_cast<std::int64_t>(i), at + 60, fmt::format("error (first user value) {} is negative", error[i]));
    }
  }
  // A forest: following parents from any ball reaches a root within n steps.
  {
    std::vector<char> state(n, 0);  // 0 unseen, 1 on the current walk, 2 reaches a root
    for (std::size_t i = 0; i < n; ++i) {
      std::size_t j = i;
      while (state[j] == 0) {
        state[j] = 1;
        if (parent[j] < 0) break;
        j = static_cast<std::size_t>(parent[j]);
      }
      if (state[j] == 1 && parent[j] >= 0)
        fail(static_cast<std::int64_t>(j), 12 + j * stride + 56, "parent links form a cycle through this ball");
      for (std::size_t k = i; state[k] == 1; k = static_cast<std::size_t>(parent[k])) {
        state[k] = 2;
        if (parent[k] < 0) break;
      }
    }
  }

  Model model;
  model.metadata["source_format"] = "slim2t";
  model.metadata["slim2t_degree"] = std::to_string(degree);
  if (nuser == 0) model.metadata["slim2t_error"] = "none recorded (errors read as 0)";
  if (degree < 0) model.metadata["slim2t_orientation"] = orient_slim2t(balls, parent, has_child);
  // Leaves first (the drawn patches), then the interior balls; ids renumbered to that order.
  std::vector<std::int32_t> id(n);
  std::size_t leaves = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (!has_child[i]) id[i] = static_cast<std::int32_t>(leaves++);
  std::size_t next = leaves;
  for (std::size_t i = 0; i < n; ++i)
    if (has_child[i]) id[i] = static_cast<std::int32_t>(next++);
  model.slims.reserve(leaves);
  SlimHierarchy& h = model.slim_hierarchy;
  h.others.reserve(n - leaves);
  h.parent.resize(n);
  h.error.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto j = static_cast<std::size_t>(id[i]);
    h.parent[j] = parent[i] < 0 ? -1 : id[static_cast<std::size_t>(parent[i])];
    h.error[j] = error[i];
  }
  for (std::size_t i = 0; i < n; ++i) (has_child[i] ? h.others : model.slims).push_back(std::move(balls[i]));
  return model;
}

}  // namespace

Model read_model(const std::filesystem::path& path) {
  if (has_extension(path, ".slim2t")) return read_slim2t(path);
  std::string bytes = io::read_file(path);
  if (!bytes.starts_with("ply") && looks_like_slim2t(bytes)) return parse_slim2t(bytes, path);
  return read_qxm(ply::File::from_bytes(std::move(bytes), path));
}

Model read_slim2t(const std::filesystem::path& path) { return parse_slim2t(io::read_file(path), path); }

std::string_view encoding_name(ModelEncoding encoding) {
  return encoding == ModelEncoding::compact ? "compact" : "double";
}

WriteModelResult write_model(const Model& model, const std::filesystem::path& path, const WriteModelOptions& options) {
  const SlimHierarchy& hy = model.slim_hierarchy;
  if (const std::string why = validate_slim_hierarchy(model); !why.empty())
    throw InvalidInput(fmt::format("{}: cannot write the SLIM hierarchy: {}", path.string(), why));
  const bool hierarchy = !hy.empty();
  for (std::size_t i = 0; i < model.slims.size() + hy.others.size(); ++i) {
    const SlimPatch& s = slim_ball(model, i);
    check_finite(is_world_point(s.centre) && is_world_value(s.radius) && s.local.is_finite() &&
                     std::all_of(s.clips.begin(), s.clips.end(),
                                 [](const ClipPlane& p) { return is_world_point(p.n) && is_world_value(p.d); }),
                 i < model.slims.size() ? "slim patch" : "slim_node", i, path);
  }
  for (std::size_t i = 0; i < model.tets.size(); ++i) {
    const TetPatch& t = model.tets[i];
    bool ok = t.quadric.is_finite();
    for (const auto& p : t.corners) ok = ok && is_world_point(p);
    check_finite(ok, "tet patch", i, path);
  }
  for (std::size_t i = 0; i < model.glyphs.size(); ++i) {
    const Glyph& g = model.glyphs[i];
    check_finite(is_world_point(g.centre) && is_world_value(g.radius) &&
                     g.axes.allFinite() && g.axes.cwiseAbs().maxCoeff() <= kMaxWorldCoordinate,
                 "glyph", i, path);
  }

  // Implicit surfaces: parameter values in the order the expression names them.
  std::vector<std::vector<double>> implicit_parameters;
  for (std::size_t i = 0; i < model.implicits.size(); ++i) {
    const ImplicitSurface& s = model.implicits[i];
    try {
      implicit_parameters.push_back(implicit::compile(s).parameters);
    } catch (const InvalidInput& e) {
      throw InvalidInput(fmt::format("{}: cannot write implicit surface {}: {}", path.string(), i, e.what()));
    }
    if (std::any_of(s.expression.begin(), s.expression.end(), [](char c) { return c < 32 || c > 126; }))
      throw InvalidInput(fmt::format("{}: cannot write implicit surface {}: the expression is not printable ASCII",
                                     path.string(), i));
    if (implicit_parameters.back().size() > 255)
      throw InvalidInput(fmt::format("{}: cannot write implicit surface {}: more than 255 parameters", path.string(), i));
  }

  // The compact encoding when every primitive survives float32 about the bounding-box centre.
  WriteModelResult result;
  result.encoding = options.encoding;
  const Box3 box = bounds(model);
  const Eigen::Vector3d origin = box.empty() || !box.centre().allFinite() ? Eigen::Vector3d::Zero() : box.centre();
  const CompactRounding rounding(origin);
  std::vector<char> flat;  // compact: tetrahedra left out (float32 turns them flat)
  if (options.encoding == ModelEncoding::compact) {
    if (std::string why = rounding.first_problem(model, flat); !why.empty()) {
      if (!options.fallback_to_full)
        throw InvalidInput(fmt::format("{}: cannot write the compact encoding: {} (the double encoding can)",
                                       path.string(), why));
      log::warn("{}: written in the double encoding: {}", path.string(), why);
      result.encoding = ModelEncoding::full;
      result.fallback = std::move(why);
      flat.clear();
    }
  }
  flat.resize(model.tets.size(), 0);
  result.dropped_tets = static_cast<std::size_t>(std::count(flat.begin(), flat.end(), 1));
  if (result.dropped_tets > 0)
    log::warn("{}: left out {} of {} tetrahedra that float32 turns flat (slivers thinner than the rounding of "
              "their corners)",
              path.string(), result.dropped_tets, model.tets.size());
  const bool compact = result.encoding == ModelEncoding::compact;
  const ply::Type real = compact ? ply::Type::float32 : ply::Type::float64;
  const auto append_reals = [&](std::string& out, std::initializer_list<double> vs) {
    for (double v : vs) ply::append_le(out, real, v);
  };
  const auto append_position = [&](std::string& out, const Eigen::Vector3d& p) {
    const Eigen::Vector3d v = compact ? rounding.offset(p) : p;
    append_reals(out, {v.x(), v.y(), v.z()});
  };

  // Clip plane groups written: as many as the patch with the most has (drawn, hierarchy's others).
  const auto clip_groups = [](std::span<const SlimPatch> ps) {
    int n = 0;
    for (const SlimPatch& s : ps) n = std::max(n, s.clips.size());
    return n;
  };
  const auto has_colour = [](const SlimPatch& s) { return s.colour.has_value(); };
  const int slim_clip = clip_groups(model.slims);
  const bool slim_colour = std::any_of(model.slims.begin(), model.slims.end(), has_colour);
  const auto has_error = [](const SlimPatch& s) { return s.measured_error.has_value(); };
  const bool slim_error = std::any_of(model.slims.begin(), model.slims.end(), has_error);
  const bool node_error = std::any_of(hy.others.begin(), hy.others.end(), has_error);
  const auto has_push = [](const SlimPatch& s) { return s.max_push.has_value(); };
  const bool slim_push = std::any_of(model.slims.begin(), model.slims.end(), has_push);
  const bool node_push = std::any_of(hy.others.begin(), hy.others.end(), has_push);
  for (std::size_t i = 0; i < model.slims.size() + hy.others.size(); ++i)
    if (const auto& v = slim_ball(model, i).max_push; v && !(std::isfinite(*v) && *v > 0))
      throw InvalidInput(fmt::format("{}: cannot write slim patch {}: max push {} is not finite and > 0",
                                     path.string(), i, *v));
  for (std::size_t i = 0; i < model.slims.size() + hy.others.size(); ++i)
    if (const auto& e = slim_ball(model, i).measured_error; e && !(std::isfinite(*e) && *e >= 0))
      throw InvalidInput(fmt::format("{}: cannot write slim patch {}: measured error {} is not finite and >= 0",
                                     path.string(), i, *e));
  const int node_clip = clip_groups(hy.others);
  const bool node_colour = std::any_of(hy.others.begin(), hy.others.end(), has_colour);
  const bool tet_colour =
      std::any_of(model.tets.begin(), model.tets.end(), [](const TetPatch& t) { return t.colour.has_value(); });
  const bool tet_corner_colours = std::any_of(model.tets.begin(), model.tets.end(),
                                              [](const TetPatch& t) { return t.corner_colours.has_value(); });
  const bool glyph_colour =
      std::any_of(model.glyphs.begin(), model.glyphs.end(), [](const Glyph& g) { return g.colour.has_value(); });

  ply::Header h;
  h.encoding = ply::Encoding::binary_little_endian;
  h.comments.push_back(fmt::format("quadrix-format {}", kQxmFormatVersion));
  h.comments.push_back(fmt::format("quadrix-encoding {}", encoding_name(result.encoding)));
  if (compact) h.comments.push_back(fmt::format("quadrix-origin {:.17g} {:.17g} {:.17g}", origin.x(), origin.y(), origin.z()));
  for (const auto& [key, value] : model.metadata) {
    if (key.empty() || has_whitespace(key) || key == "bbox" || is_reserved_key(key)) continue;
    h.comments.push_back(value.empty() ? key : key + " " + single_line(value));
  }
  if (!box.empty())
    h.comments.push_back(fmt::format("bbox {} {} {} {} {} {}", box.min.x(), box.min.y(), box.min.z(), box.max.x(),
                                     box.max.y(), box.max.z()));
  const bool all = model.empty();  // an empty model still declares the whole profile
  const auto slim_element = [&](std::string name, std::size_t count, int clips, bool colour, bool error, bool push) {
    auto props = names({std::span<const char* const>(kSlimNames), kCoefficientNames});
    for (int k = 0; k < clips; ++k) props.insert(props.end(), kClipNames[k].begin(), kClipNames[k].end());
    ply::Element e = element(std::move(name), count, props, colour, real);
    if (error) e.properties.push_back({kMeasuredErrorName, ply::Type::float64});
    if (push) e.properties.push_back({kMaxPushName, ply::Type::float64});
    if (hierarchy) {
      e.properties.push_back({"parent", ply::Type::int32});
      e.properties.push_back({"error", real});
    }
    return e;
  };
  if (all || hierarchy || !model.slims.empty())
    h.elements.push_back(slim_element("slim", model.slims.size(), slim_clip, slim_colour, slim_error, slim_push));
  if (hierarchy && !hy.others.empty())
    h.elements.push_back(slim_element("slim_node", hy.others.size(), node_clip, node_colour, node_error, node_push));
  if (all || !model.tets.empty()) {
    h.elements.push_back(element("tet", model.tets.size() - result.dropped_tets,
                                 names({kCornerNames, kCoefficientNames}), tet_colour, real));
    if (tet_corner_colours)
      for (const char* n : kCornerColourNames) h.elements.back().properties.push_back({n, ply::Type::uint8});
  }
  if (all || !model.glyphs.empty()) {
    auto props = names({std::span<const char* const>(std::array<const char*, 4>{"x", "y", "z", "radius"}), kAxisNames});
    h.elements.push_back(element("glyph", model.glyphs.size(), props, glyph_colour, real, true));
  }

  const bool implicit_colour = std::any_of(model.implicits.begin(), model.implicits.end(),
                                           [](const ImplicitSurface& s) { return s.colour.has_value(); });
  if (!model.implicits.empty()) {
    ply::Element e = element("implicit", model.implicits.size(), names({kBoundsNames}), implicit_colour,
                                 ply::Type::float64);  // world coordinates in either encoding
    e.properties.insert(e.properties.begin(), {{"expression", ply::Type::uint8, true, ply::Type::uint32},
                                               {"parameters", ply::Type::float64, true, ply::Type::uint8}});
    h.elements.push_back(std::move(e));
  }

  std::string out = ply::header_text(h);
  const std::size_t r = ply::type_size(real);
  out.reserve(out.size() + (model.slims.size() + hy.others.size()) * (20 * r + 7) +
              model.tets.size() * (22 * r + 3) + model.glyphs.size() * (13 * r + 4));
  for (std::size_t i = 0; i < model.slims.size() + hy.others.size(); ++i) {
    const SlimPatch& s = compact ? rounding.slim(slim_ball(model, i)) : slim_ball(model, i);
    const bool drawn = i < model.slims.size();
    append_position(out, slim_ball(model, i).centre);
    append_reals(out, {s.radius});
    for (double v : s.local.coefficients()) ply::append_le(out, real, v);
    // A patch with fewer planes than the element's groups fills the rest with all-zero rows.
    for (int k = 0; k < (drawn ? slim_clip : node_clip); ++k) {
      const ClipPlane p = k < s.clips.size() ? s.clips[k] : ClipPlane{};
      append_reals(out, {p.n.x(), p.n.y(), p.n.z(), p.d});
    }
    if (drawn ? slim_colour : node_colour) append_colour(out, s.colour);
    if (drawn ? slim_error : node_error) ply::append_le(out, ply::Type::float64, s.measured_error.value_or(-1.0));
    if (drawn ? slim_push : node_push) ply::append_le(out, ply::Type::float64, s.max_push.value_or(-1.0));
    if (hierarchy) {
      ply::append_le(out, ply::Type::int32, hy.parent[i]);
      ply::append_le(out, real, hy.error[i]);
    }
  }
  for (std::size_t i = 0; i < model.tets.size(); ++i) {
    if (flat[i]) continue;
    const TetPatch& exact = model.tets[i];
    const TetPatch& t = compact ? rounding.tet(exact) : exact;
    for (const auto& p : exact.corners) append_position(out, p);
    for (double v : t.quadric.coefficients()) ply::append_le(out, real, v);
    if (tet_colour) append_colour(out, t.colour);
    if (tet_corner_colours) {
      // A patch without its own corner colours repeats its colour at every corner.
      const Rgb c = t.colour.value_or(Rgb{200, 200, 200});
      const std::array<Rgb, 4> cs = t.corner_colours.value_or(std::array<Rgb, 4>{c, c, c, c});
      for (const Rgb& rgb : cs) append_colour(out, rgb);
    }
  }
  for (const Glyph& g : model.glyphs) {
    out.push_back(static_cast<char>(static_cast<std::uint8_t>(g.kind)));
    append_position(out, g.centre);
    append_reals(out, {g.radius});
    for (int k = 0; k < 3; ++k) append_reals(out, {g.axes(0, k), g.axes(1, k), g.axes(2, k)});
    if (glyph_colour) append_colour(out, g.colour);
  }
  for (std::size_t i = 0; i < model.implicits.size(); ++i) {
    const ImplicitSurface& s = model.implicits[i];
    ply::append_le(out, ply::Type::uint32, static_cast<double>(s.expression.size()));
    out += s.expression;
    ply::append_le(out, ply::Type::uint8, static_cast<double>(implicit_parameters[i].size()));
    for (double v : implicit_parameters[i]) ply::append_le(out, ply::Type::float64, v);
    for (double v : {s.bounds.min.x(), s.bounds.min.y(), s.bounds.min.z(), s.bounds.max.x(), s.bounds.max.y(),
                     s.bounds.max.z()})
      ply::append_le(out, ply::Type::float64, v);
    if (implicit_colour) append_colour(out, s.colour);
  }
  write_file_atomically(path,
                        [&](std::ostream& os) { os.write(out.data(), static_cast<std::streamsize>(out.size())); });
  result.bytes = out.size();
  return result;
}

}  // namespace quadrix
