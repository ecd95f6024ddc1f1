#pragma once
/// Model: the primitive sets every Quadrix module shares (DESIGN §4).
#include <array>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/quadric.h"

namespace quadrix {

/// 8-bit sRGB colour.
using Rgb = std::array<std::uint8_t, 3>;

/// Clip plane in a primitive's local frame: points with nᵀu + d ≥ 0 are kept.
struct ClipPlane {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  double d = 0.0;
  bool keeps(const Eigen::Vector3d& u) const { return n.dot(u) + d >= 0.0; }
  bool operator==(const ClipPlane&) const = default;
};

/// Up to four clip planes of one SLIM patch (a sharp feature's cut, an open edge, the side walls
/// of a mesh face's prism): the patch keeps the points that every plane keeps. Fixed capacity, so
/// a patch stays one flat record (the GPU's too: render/shaders/slim.vert).
struct ClipPlanes {
  static constexpr int kMax = 4;
  std::array<ClipPlane, kMax> planes{};
  int count = 0;

  bool empty() const { return count == 0; }
  int size() const { return count; }
  const ClipPlane* begin() const { return planes.data(); }
  const ClipPlane* end() const { return planes.data() + count; }
  const ClipPlane& operator[](int i) const { return planes[static_cast<std::size_t>(i)]; }
  /// Adds a plane; false (and nothing added) when all kMax are in use.
  bool add(const ClipPlane& p) {
    if (count >= kMax) return false;
    planes[static_cast<std::size_t>(count++)] = p;
    return true;
  }
  void clear() { count = 0; }
  bool keeps(const Eigen::Vector3d& u) const {
    for (int i = 0; i < count; ++i)
      if (!planes[static_cast<std::size_t>(i)].keeps(u)) return false;
    return true;
  }
  bool operator==(const ClipPlanes& o) const {
    if (count != o.count) return false;
    for (int i = 0; i < count; ++i)
      if (!(planes[static_cast<std::size_t>(i)] == o.planes[static_cast<std::size_t>(i)])) return false;
    return true;
  }
  /// One plane.
  static ClipPlanes of(const ClipPlane& p) {
    ClipPlanes c;
    c.add(p);
    return c;
  }
};

/// One SLIM patch (Ohtake et al. 2005): a ball (centre, support radius R) and a quadric g
/// written in local coordinates u = (x − centre) / R, so ‖u‖ ≤ 1 inside the ball.
/// The surface is the per-ray blend of the patches (core/slim.h).
struct SlimPatch {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< world units
  double radius = 1.0;                               ///< support radius R, world units, > 0
  Quadric local;                                     ///< g(u), u = (x − centre)/R
  ClipPlanes clips;  ///< sharp features, open edges, a face's prism: in local u coordinates
  std::optional<Rgb> colour{};
  /// Measured error (fit/patch_error.h): the largest distance from the data points this patch
  /// serves (weight > 0 in their probe's blend) to the blended surface, world units, ≥ 0.
  std::optional<double> measured_error{};
  /// The blend's push bound for this ball, world units (core/slim.h SlimBlendOptions::push): a
  /// coarser level of a hierarchy, fitted at a larger bound, blends with its own; none: the
  /// model's (`slim_max_push`).
  std::optional<double> max_push = std::nullopt;
  /// The patch's quadric in world coordinates.
  Quadric world() const { return local.from_local(centre, radius); }
};

/// A quadric clipped by a tetrahedron ([Stoll06] §5): converted quads, skin and volume cells.
/// The quadric is written relative to the tetrahedron's centroid (y = x − centroid()): world
/// coordinates far from the origin would cost the coefficients their digits (DESIGN §5).
struct TetPatch {
  std::array<Eigen::Vector3d, 4> corners;  ///< world units
  Quadric quadric;                         ///< f(y), y = x − centroid()
  std::optional<Rgb> colour{};
  /// Colour at each corner, interpolated barycentrically inside; takes precedence over colour.
  std::optional<std::array<Rgb, 4>> corner_colours = std::nullopt;

  Eigen::Vector3d centroid() const { return 0.25 * ((corners[0] + corners[1]) + (corners[2] + corners[3])); }
  /// The quadric in world coordinates (loses precision far from the origin; for tests and tools).
  Quadric world() const { return quadric.translated_to_origin(-centroid()); }
  /// A patch from a quadric given in world coordinates.
  static TetPatch from_world(const std::array<Eigen::Vector3d, 4>& corners, const Quadric& world_quadric,
                             std::optional<Rgb> colour = std::nullopt) {
    TetPatch t{corners, {}, colour};
    t.quadric = world_quadric.translated_to_origin(t.centroid());
    return t;
  }
};

enum class GlyphKind : std::uint8_t { sphere = 0, ellipsoid = 1, cylinder = 2 };

/// [Sigg06] glyphs. sphere: centre, radius. ellipsoid: centre and three semi-axis vectors
/// (the columns of axes). cylinder: centre, radius, axes.col(0) = half the axis (end caps at
/// centre ± axes.col(0)), closed by flat discs.
struct Glyph {
  GlyphKind kind = GlyphKind::sphere;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 1.0;
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  std::optional<Rgb> colour{};
};

/// Axis-aligned box; empty when min > max.
struct Box3 {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d max = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  bool empty() const { return (min.array() > max.array()).any(); }
  void extend(const Eigen::Vector3d& p) { min = min.cwiseMin(p); max = max.cwiseMax(p); }
  void extend(const Box3& o) { min = min.cwiseMin(o.min); max = max.cwiseMax(o.max); }
  Eigen::Vector3d centre() const { return 0.5 * (min + max); }
  double diagonal() const { return empty() ? 0.0 : (max - min).norm(); }
};

/// An implicit surface S(x, y, z) = 0 in world coordinates, drawn where it lies inside its
/// bounds ([Singh10]). The expression grammar is core/implicit/expression.h; every parameter
/// it names needs a value here.
struct ImplicitSurface {
  std::string expression;
  std::map<std::string, double> parameters;
  Box3 bounds;  ///< world units, not empty
  std::optional<Rgb> colour{};
};

/// A SLIM hierarchy beside the drawn patches (Ohtake et al. 2005 §4, Kanai's .slim2t): a forest
/// of balls, each merged ball a fit over the balls below it, with its fitting error.
/// Ball ids: id < Model::slims.size() is Model::slims[id], the rest are others[id − slims.size()];
/// every ball appears once. By default the drawn patches are the leaves and `others` the
/// interior (merged) balls.
struct SlimHierarchy {
  std::vector<SlimPatch> others;      ///< balls not in Model::slims (interior balls by default)
  std::vector<std::int32_t> parent;   ///< per ball id: the parent's id, −1 for a root; a forest
  std::vector<double> error;          ///< per ball id: fitting error, finite, ≥ 0 (producer's unit)
  std::size_t size() const { return parent.size(); }
  bool empty() const { return parent.empty(); }
};

/// Everything a .qxm file holds.
struct Model {
  std::vector<SlimPatch> slims;  ///< the SLIM patches drawn (the hierarchy's leaves by default)
  SlimHierarchy slim_hierarchy;  ///< empty, or parent links and errors for slims + others
  std::vector<TetPatch> tets;
  std::vector<Glyph> glyphs;
  std::vector<ImplicitSurface> implicits;
  /// Header metadata (`comment key value` lines): producer, units, max_error, …
  std::map<std::string, std::string> metadata;

  std::size_t size() const { return slims.size() + tets.size() + glyphs.size() + implicits.size(); }
  bool empty() const { return size() == 0; }
};

/// Whether the model says (metadata `tetrahedra tessellation`, as `convert volume` writes) that its
/// tetrahedra are the cells of one tessellation: no two overlap, and neighbours share whole faces
/// (a grid's Kuhn cells, a tetrahedral mesh's cells). A skin's mixed cells, triangulated
/// differently on each side of a shared face, and a quad mesh's tetrahedra are not marked.
inline bool tetrahedra_tessellate(const Model& model) {
  const auto it = model.metadata.find("tetrahedra");
  return it != model.metadata.end() && it->second == "tessellation";
}

/// A metadata value read as a number (strtod: the whole leading number, any value it parses,
/// infinities included; callers check the range they accept); nullopt when absent or not a number.
std::optional<double> metadata_number(const Model& model, const std::string& key);

/// The hierarchy's ball by id (see SlimHierarchy).
inline const SlimPatch& slim_ball(const Model& m, std::size_t id) {
  return id < m.slims.size() ? m.slims[id] : m.slim_hierarchy.others[id - m.slims.size()];
}

/// Shape of a SLIM hierarchy: levels = balls on the longest root-to-leaf path.
struct SlimHierarchyStats {
  std::size_t levels = 0, leaves = 0, interior = 0, roots = 0;
  double min_error = 0, max_error = 0;  ///< over all balls
};
/// \throws InvalidInput when the hierarchy is not a forest over slims + others (see check below).
SlimHierarchyStats slim_hierarchy_stats(const Model& m);

/// Checks sizes, parent ids in {−1} ∪ [0, n), no self-parent, no cycle, errors finite and ≥ 0.
/// Returns an empty string when valid, else what is wrong ("ball 12: parent 12 is itself").
std::string validate_slim_hierarchy(const Model& m);

/// A cut of the hierarchy by error, as ball ids in increasing order: walking down from each
/// root, a ball is taken when its error ≤ max_error or it is a leaf, else its children are
/// visited. Where errors grow towards the roots (as a fitter writes them) this is the set of
/// balls with error ≤ max_error whose parent's error > max_error, plus the leaves above no such
/// ball; every leaf lies under exactly one chosen ball. max_error < 0 gives the leaves.
/// An empty hierarchy gives the ids of all Model::slims.
/// \throws InvalidInput when the hierarchy is not valid (validate_slim_hierarchy).
std::vector<std::int32_t> select_slim_cut(const Model& m, double max_error);

/// Bounds of one primitive's bounding volume (ball, tetrahedron, glyph extent).
Box3 bounds(const SlimPatch& s);
Box3 bounds(const TetPatch& t);
Box3 bounds(const Glyph& g);
/// Bounds of the whole model (empty box for an empty model).
Box3 bounds(const Model& m);

}  // namespace quadrix
