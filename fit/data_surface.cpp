#include "fit/data_surface.h"

#include <algorithm>
#include <atomic>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <tuple>
#include <unordered_map>

#include <Eigen/Eigenvalues>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_invoke.h>

#include "core/bvh.h"
#include "core/error.h"
#include "core/io/io.h"
#include "core/morton.h"
#include "core/ray.h"
#include "core/slim.h"
#include "fit/point_index.h"

namespace quadrix {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// DataSurfaceOptions::hole_rims: the widest angle between a point's consecutive neighbours about
// it that flags it as on an open boundary (from_points); the extent, in its points' spacings, of
// the shortest run of boundary points kept where only the hole_rims rules made them boundary
// points, and the distance, in spacings, within which two such points belong to one run
// (confirm_boundaries).
constexpr double kHoleRimGap = 100.0 * std::numbers::pi / 180.0;
constexpr double kRimRunExtent = 6.0, kRimRunStep = 2.0;
// ... and the most two points' spacings may differ for one to be the far rim of a hole at the other
// (confirm_boundaries).
constexpr double kFarRimSpacings = 2.0;
// How from_points flagged a boundary point, for confirm_boundaries (hole_rims): by the widest gap;
// by the centroid test, with another sheet's point in its empty direction (a crease's side).
constexpr std::uint8_t kByGap = 1, kCreaseSide = 2;

// Squared distance from x to triangle (a, b, c) by the Voronoi region of its closest point
// (vertex, edge or face regions tested with dot products, as in Ericson's Real-Time Collision
// Detection §5.1.5); degenerate triangles fall through to their edges.
double point_triangle_distance2(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ax = x - a;
  const double d1 = ab.dot(ax), d2 = ac.dot(ax);
  if (d1 <= 0 && d2 <= 0) return ax.squaredNorm();
  const Eigen::Vector3d bx = x - b;
  const double d3 = ab.dot(bx), d4 = ac.dot(bx);
  if (d3 >= 0 && d4 <= d3) return bx.squaredNorm();
  const Eigen::Vector3d cx = x - c;
  const double d5 = ab.dot(cx), d6 = ac.dot(cx);
  if (d6 >= 0 && d5 <= d6) return cx.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double l = d1 - d3;
    return l > 0 ? (ax - (d1 / l) * ab).squaredNorm() : ax.squaredNorm();
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double l = d2 - d6;
    return l > 0 ? (ax - (d2 / l) * ac).squaredNorm() : ax.squaredNorm();
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double l = (d4 - d3) + (d5 - d6);
    return l > 0 ? (bx - ((d4 - d3) / l) * (c - b)).squaredNorm() : bx.squaredNorm();
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) {  // degenerate: the nearest of the three edges
    const auto seg = [](const Eigen::Vector3d& p, const Eigen::Vector3d& e) {
      const double l2 = e.squaredNorm();
      const double t = l2 > 0 ? std::clamp(p.dot(e) / l2, 0.0, 1.0) : 0.0;
      return (p - t * e).squaredNorm();
    };
    return std::min({seg(ax, ab), seg(bx, c - b), seg(ax, ac)});
  }
  const double v = vb / sum, w = vc / sum;
  return (ax - v * ab - w * ac).squaredNorm();
}

// The primitives (triangles or points) nearest a thread's last few distance queries on one
// surface: queries come in runs along one patch, so they are asked first.
struct Hints {
  std::uint64_t owner = 0;  // the surface's serial
  std::array<std::uint32_t, 4> ids{};
  unsigned next = 0;
  void use_for(std::uint64_t serial) {
    if (owner != serial) owner = serial, ids.fill(0), next = 0;
  }
  void remember(std::uint32_t id) {
    if (std::find(ids.begin(), ids.end(), id) == ids.end()) ids[next++ % ids.size()] = id;
  }
};

// Which of six 60° sectors of the tangent plane (basis u, w = n × u, u = n.unitOrthogonal())
// the tangential offset v points into.
int tangent_sector(const Eigen::Vector3d& v, const Eigen::Vector3d& u, const Eigen::Vector3d& w) {
  const double a = std::atan2(v.dot(w), v.dot(u));
  return std::clamp(int(std::floor((a + std::numbers::pi) / (std::numbers::pi / 3.0))), 0, 5);
}
// The unit direction (along u, w) at angle −π + (k + f)·π/3: f = 0 and 1 the edges of sector k.
Eigen::Vector2d sector_direction(int k, double f) {
  const double a = -std::numbers::pi + (k + f) * std::numbers::pi / 3.0;
  return {std::cos(a), std::sin(a)};
}

}  // namespace

double point_triangle_distance(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                               const Eigen::Vector3d& c) {
  return std::sqrt(point_triangle_distance2(x, a, b, c));
}

struct DataSurface::Impl {
  // Tells this surface's per-thread query caches (distance) from another's that a later
  // allocation may put at the same address.
  const std::uint64_t serial = [] {
    static std::atomic<std::uint64_t> next{1};
    return next++;
  }();
  // Points: positions, normals, disc radii, kd-tree. Mesh: triangle corners and their BVH.
  std::vector<Eigen::Vector3d> points, normals;
  std::vector<double> disc;
  std::vector<double> spacing;  // points: the sample spacing (DataSurface::spacing)
  std::vector<Eigen::Vector3d> inward;  // boundary points: unit tangent towards the data; else 0
  // Points: the farthest neighbour asked in each 60° sector of the tangent plane (tangent_sector);
  // a boundary point's disc reaches no farther than that plus boundary_reach of it there.
  std::vector<std::array<float, 6>> sector_far;
  // Points: the lines that cut a disc short at a crease (DataSurfaceOptions::crease_cuts), in its
  // tangent frame (u, w of tangent_sector): point i's disc keeps the p with a·p ≤ c for each
  // (a_u, a_w, c) of cuts[cut_begin[i] … cut_begin[i + 1]) (c ≥ 0: its own point stays). Empty
  // cut_begin: no disc is cut.
  std::vector<std::uint32_t> cut_begin;
  std::vector<Eigen::Vector3d> cuts;
  // Points: crease points whose normal is their face's (split_at_creases), and the second discs
  // appended after the given points for those on an edge (indices from `given` on).
  std::size_t given = 0, crease_points = 0, crease_copies = 0;
  // 1 where split_at_creases gave the point its face's plane, or made it (a second disc): planar
  // by construction (the crease cuts' gate; its neighbours within a disc may be another face's
  // rounded ones, as a plate's edge rows are).
  std::vector<std::uint8_t> faced;
  // Points: planar for the crease cuts (from_points: faced, or their own sheet's neighbours
  // within crease_planarity of the spacing of their plane); empty without crease_cuts.
  std::vector<std::uint8_t> planar;
  // Points: the disc's second-order term, the height ½(a x² + 2b xy + c y²) over the tangent plane
  // (x, y along normal.unitOrthogonal() and normal × it), fitted to the same-sheet neighbours'
  // heights: a tangent disc is flat, so where E is below the sampling's sag (a sphere of 400
  // points at 1e-3) the true surface itself read as off the data (400 patches for a sphere).
  // As a world-frame tensor K (tangential: Kn = 0; height ½ tᵀKt at the tangential offset t),
  // empty where the disc is flat; bend_reach: its largest |height| on the disc, ½·max|λ|·radius².
  std::vector<Eigen::Matrix3f> bend;
  std::vector<float> bend_reach;
  double lipschitz = 1.0;  // DataSurface::lipschitz: above 1 once a disc is bent
  std::vector<std::array<Eigen::Vector3d, 3>> triangles;
  bool wound_inward = false;  // the triangles enclose a negative volume: their winding faces inwards
  std::unique_ptr<PointIndex> index;
  Bvh bvh;
  // Boundary samples and their index over their positions (index_them() after the last push).
  struct Samples {
    std::vector<DataSurface::BoundarySample> samples;
    // A cloud's boundary points (DataSurface::past_boundary): their normals and end_reach, one
    // per sample, and 1 for those at an open rim (cut_at_rims' usable ones: no other sheet
    // ahead); empty for a mesh's open edges.
    std::vector<Eigen::Vector3d> normals;
    std::vector<double> reach;
    std::vector<std::uint8_t> rim;
    double widest_reach = 0;  // the largest of reach
    std::vector<Eigen::Vector3d> points;  // the index's span
    std::unique_ptr<PointIndex> index;
    void index_them() {
      points.clear();
      for (const auto& b : samples) points.push_back(b.point);
      if (!points.empty()) index = std::make_unique<PointIndex>(std::span<const Eigen::Vector3d>(points));
    }
    // Appends the samples within r of c (nb: scratch).
    void near(const Eigen::Vector3d& c, double r, std::vector<DataSurface::BoundarySample>& out, std::vector<Neighbour>& nb) const {
      if (!index) return;
      index->radius(c, r, nb);
      for (const auto& [i, d2] : nb) out.push_back(samples[i]);
    }
  };
  Samples boundary;  // open-boundary samples
  // Points: those the centroid test took for a boundary's whose discs the crease cuts close
  // instead (from_points), as boundary samples (boundary_near with crease_sides).
  Samples crease_sides;
  // Points: 1 for a crease side (above), whose disc keeps the boundary's star of sectors (limited
  // to the farthest neighbour there plus boundary_reach) but reaches its whole radius, as far as
  // the cuts let it, in the sectors without a neighbour (sector_far set to the radius there).
  std::vector<std::uint8_t> star_only;
  // Mesh: the open edges, boundary[k] being open_edges[k]'s midpoint; half the longest one.
  std::vector<std::array<Eigen::Vector3d, 2>> open_edges;
  double open_edge_half = 0;
  // Points: a BVH over the tangent discs' boxes, built on first use (distance and ray casts).
  mutable std::once_flag disc_bvh_once;
  mutable Bvh disc_bvh;

  // How far x's tangential offset from point i lies outside its disc (0: over the disc), and its
  // height above the disc (its plane, or the bent disc at the offset clamped to its radius). A
  // boundary point's disc (always flat), past its farthest neighbour in the offset's sector,
  // reaches on only boundary_reach of its radius: along an open sheet's edge
  // towards a corner the edge points' discs ran a spacing past the corner (blobs at a square's
  // corners, ~9E at 1e-3); and beyond the boundary (away from `inward`) only boundary_reach of
  // it. The one disc shape for distances and ray casts. The excess is the Euclidean distance to
  // the disc, or for a boundary point's the larger of the distances to its two parts (the star
  // of sectors, the disc cut short beyond the boundary): 0 on the shape and 1-Lipschitz, like the
  // distance itself. (Measured in the sector of the offset alone, and past the boundary in a
  // stretched frame, it jumped by up to 4× near a scan's edge: a raw scan's fit at 1e-2 read 5.3E
  // from the data 0.34E from a point at 1.4E.)
  //
  // A disc cut at a crease (cut_begin) is the disc less what lies past its cut lines; its height
  // is taken over the nearest point of that shape, and a boundary point's excess is the larger of
  // the two shapes' (as above).
  double disc_excess(std::uint32_t i, const Eigen::Vector3d& x, double& h) const {
    const Eigen::Vector3d v = x - points[i];
    h = normals[i].dot(v);
    const Eigen::Vector3d t = v - h * normals[i];
    const bool cut = !cut_begin.empty() && cut_begin[i + 1] > cut_begin[i];
    const bool star = inward[i].squaredNorm() > 0 || (i < star_only.size() && star_only[i]);
    if (!cut) {
      h -= bend_height(i, t);
      if (!star) return std::max(0.0, t.norm() - disc[i]);
    }
    const Eigen::Vector3d u = normals[i].unitOrthogonal(), w = normals[i].cross(u);
    const Eigen::Vector2d p(t.dot(u), t.dot(w));
    double out = 0;
    if (cut) {
      Eigen::Vector2d nearest;
      out = cut_excess(i, p, nearest);
      h -= bend_height(i, nearest.x() * u + nearest.y() * w);
      if (!star) return out;
    }
    return std::max({out, star_excess(i, p, tangent_sector(t, u, w)),
                     cut_disc_excess(p, Eigen::Vector2d(inward[i].dot(u), inward[i].dot(w)), disc[i], end_reach(i))});
  }
  // Distance from p (tangent-plane coordinates) to point i's disc less what lies past its crease
  // cuts (a convex shape holding the origin), and its nearest point of that shape. The nearest
  // point lies on the arc (p's radial projection, where the cuts keep it) or on a cut line's
  // segment inside the disc and the other cuts (p's projection clamped to it).
  double cut_excess(std::uint32_t i, const Eigen::Vector2d& p, Eigen::Vector2d& nearest) const {
    const double r = disc[i];
    const std::uint32_t b = cut_begin[i], e = cut_begin[i + 1];
    const double slack = 1e-12 * r;
    const auto kept = [&](const Eigen::Vector2d& q, std::uint32_t skip) {
      for (std::uint32_t k = b; k < e; ++k)
        if (k != skip && cuts[k].head<2>().dot(q) > cuts[k].z() + slack) return false;
      return true;
    };
    const double len = p.norm();
    if (len <= r && kept(p, e)) {
      nearest = p;
      return 0.0;
    }
    double best = kInf;
    nearest = Eigen::Vector2d::Zero();
    const auto consider = [&](const Eigen::Vector2d& q) {
      if (const double d = (p - q).norm(); d < best) best = d, nearest = q;
    };
    if (len > 0) {
      const Eigen::Vector2d q = p * (r / len);
      if (kept(q, e)) consider(q);
    }
    for (std::uint32_t k = b; k < e; ++k) {
      const Eigen::Vector2d a = cuts[k].head<2>(), along(-a.y(), a.x());
      const double c = cuts[k].z();
      if (c >= r) continue;
      const Eigen::Vector2d foot = c * a;
      double lo = -std::sqrt(r * r - c * c), hi = -lo;
      for (std::uint32_t j = b; j < e && lo <= hi; ++j) {
        if (j == k) continue;
        // a_j·(foot + s·along) ≤ c_j
        const double slope = cuts[j].head<2>().dot(along), room = cuts[j].z() - cuts[j].head<2>().dot(foot);
        if (std::abs(slope) <= 1e-12) {
          if (room < -slack) lo = 1, hi = 0;
        } else if (slope > 0) {
          hi = std::min(hi, room / slope);
        } else {
          lo = std::max(lo, room / slope);
        }
      }
      if (lo <= hi) consider(foot + std::clamp(p.dot(along), lo, hi) * along);
    }
    return best;
  }
  // The bent disc's height at the tangential offset t (world frame), t clamped to the disc's
  // radius; 0 for a flat disc.
  double bend_height(std::uint32_t i, const Eigen::Vector3d& t) const {
    if (bend_reach.empty() || bend_reach[i] == 0.0f) return 0.0;
    const double len = t.norm();
    const Eigen::Vector3d q = len > disc[i] ? Eigen::Vector3d(t * (disc[i] / len)) : t;
    return 0.5 * q.dot(bend[i].cast<double>() * q);
  }
  double reach_of_bend(std::uint32_t i) const { return bend_reach.empty() ? 0.0 : double(bend_reach[i]); }
  // The first t in (tmin, tmax) where the ray meets point i's disc (flat or bent, within its
  // shape: disc_excess 0), else +inf. Bent: z − ½q(x, y) along the ray is a quadratic in t.
  double disc_hit(std::uint32_t i, const Ray& ray, double tmin, double tmax) const {
    const Eigen::Vector3d& n = normals[i];
    const Eigen::Vector3d v = ray.origin - points[i];
    const auto within = [&](double t) {
      double h = 0;
      return t > tmin && t < tmax && disc_excess(i, ray.at(t), h) <= 0.0;
    };
    if (reach_of_bend(i) == 0.0) {
      const double along = n.dot(ray.dir);
      if (along == 0.0) return kInf;
      const double t = -n.dot(v) / along;
      return within(t) ? t : kInf;
    }
    // n·(v + td) − ½(v + td)ᵀK(v + td) = 0 (K is tangential, so v and d need no projecting):
    // αt² + 2βt + γ = 0, solved by core's solver (core/ray.h).
    const Eigen::Matrix3d K = bend[i].cast<double>();
    const Eigen::Vector3d Kv = K * v, Kd = K * ray.dir;
    const RayQuadratic e{-0.5 * ray.dir.dot(Kd), 0.5 * (n.dot(ray.dir) - v.dot(Kd)), n.dot(v) - 0.5 * v.dot(Kv)};
    const Roots roots = solve_ray_quadratic(e);
    for (int r = 0; r < roots.count; ++r)
      if (within(roots.t[r])) return roots.t[r];
    return kInf;
  }
  // The unit normal of point i's disc at x (on it): n for a flat disc, the bent one's gradient.
  Eigen::Vector3d disc_normal(std::uint32_t i, const Eigen::Vector3d& x) const {
    if (reach_of_bend(i) == 0.0) return normals[i];
    return (normals[i] - bend[i].cast<double>() * (x - points[i])).normalized();
  }

  // Distance from p (tangent-plane coordinates along u, w of tangent_sector, in sector `own`) to
  // the union of the six 60° sectors of radius min(disc, farthest neighbour there + boundary_reach·disc).
  double star_excess(std::uint32_t i, const Eigen::Vector2d& p, int own) const {
    // Unit directions of the sectors' edges: sector k spans angles −π + kπ/3 … −π + (k+1)π/3.
    static const std::array<Eigen::Vector2d, 7> kEdge = [] {
      std::array<Eigen::Vector2d, 7> e;
      for (int k = 0; k <= 6; ++k) e[k] = sector_direction(k, 0.0);
      return e;
    }();
    const double len = p.norm();
    double best = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 6; ++k) {
      const double r = std::min(disc[i], double(sector_far[i][k]) + options.boundary_reach * disc[i]);
      if (k == own) {
        best = std::min(best, std::max(0.0, len - r));
        continue;
      }
      for (const auto& e : {kEdge[k], kEdge[k + 1]}) {  // the sector's edges, segments 0 … r·e
        const double s = std::clamp(p.dot(e), 0.0, r);
        best = std::min(best, (p - s * e).norm());
      }
    }
    return best;
  }
  // Distance from p to the disc of radius r cut by the line where −p·in = c (in: towards the
  // data, in the same plane; c: end_reach).
  double cut_disc_excess(const Eigen::Vector2d& p, Eigen::Vector2d in, double r, double c) const {
    const double in_len = in.norm();
    const double len = p.norm();
    if (!(in_len > 0)) return std::max(0.0, len - r);
    in /= in_len;
    const double o = -p.dot(in);  // beyond the boundary by
    if (len <= r && o <= c) return 0.0;
    // Outside: the nearer of the kept arc (where p's radial projection lies on it) and the chord.
    double best = std::numeric_limits<double>::infinity();
    if (len > r && o * r <= c * len) best = len - r;
    const Eigen::Vector2d along(-in.y(), in.x());
    const double half = std::sqrt(std::max(0.0, r * r - c * c));
    const double s = std::clamp(p.dot(along), -half, half);
    return std::min(best, (p - (-c * in + s * along)).norm());
  }
  // How far a boundary point's disc reaches past it, away from `inward` (cut_disc_excess; the
  // end lines of cut_at_rims).
  double end_reach(std::size_t i) const { return options.boundary_reach * disc[i]; }
  double disc_distance(std::uint32_t i, const Eigen::Vector3d& x) const {
    double h = 0;
    const double out = disc_excess(i, x, h);
    return std::sqrt(h * h + out * out);
  }
  const Bvh& discs() const {
    std::call_once(disc_bvh_once, [&] {
      std::vector<Box3> boxes(points.size());
      for (std::size_t i = 0; i < points.size(); ++i) {
        // A disc of radius r about p with unit normal n spans r·√(1 − nₐ²) = r·‖(n_b, n_c)‖ along
        // axis a (the norm of the other two: no cancellation for a normal near the axis).
        const Eigen::Vector3d& n = normals[i];
        // A bent disc's height reaches up to bend_reach along its normal.
        const Eigen::Vector3d half =
            disc[i] * Eigen::Vector3d(std::hypot(n.y(), n.z()), std::hypot(n.x(), n.z()), std::hypot(n.x(), n.y())) +
            reach_of_bend(std::uint32_t(i)) * n.cwiseAbs();
        boxes[i].extend(points[i] - half);
        boxes[i].extend(points[i] + half);
      }
      disc_bvh = Bvh(boxes);
    });
    return disc_bvh;
  }

  DataSurfaceOptions options;

  // Cut lines per disc ((point, (a_u, a_w, c)) pairs, gathered per thread), appended after each
  // disc's lines already there (cut_begin, cuts): the crease cuts', then the rim cuts'.
  using Lines = std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>;
  void add_cuts(tbb::enumerable_thread_specific<Lines>& found) {
    Lines all;
    for (auto& f : found) all.insert(all.end(), f.begin(), f.end());
    if (all.empty()) return;
    std::stable_sort(all.begin(), all.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    const std::size_t n = points.size();
    std::vector<Eigen::Vector3d> merged;
    merged.reserve(cuts.size() + all.size());
    std::vector<std::uint32_t> begin(n + 1, 0);
    std::size_t next = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!cut_begin.empty()) merged.insert(merged.end(), cuts.begin() + cut_begin[i], cuts.begin() + cut_begin[i + 1]);
      for (; next < all.size() && all[next].first == i; ++next) merged.push_back(all[next].second);
      begin[i + 1] = std::uint32_t(merged.size());
    }
    cuts = std::move(merged);
    cut_begin = std::move(begin);
  }
  // Whether a line in direction a lies within 20° of one kept for the same disc (out[first …]):
  // the next line in much the same direction cuts little more.
  static bool near_kept(const Lines& out, std::size_t first, const Eigen::Vector2d& a) {
    return std::any_of(out.begin() + std::ptrdiff_t(first), out.end(), [&](const auto& o) { return o.second.template head<2>().dot(a) > 0.94; });
  }
};

DataSurface::DataSurface() : impl_(std::make_unique<Impl>()) {}
DataSurface::DataSurface(DataSurface&&) noexcept = default;
DataSurface& DataSurface::operator=(DataSurface&&) noexcept = default;
DataSurface::~DataSurface() = default;

DataSurface DataSurface::from_points(std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals,
                                     const DataSurfaceOptions& options) {
  if (points.empty()) throw InvalidInput("DataSurface: no points");
  if (normals.size() != points.size()) throw InvalidInput("DataSurface: one normal per point is needed");
  DataSurface s;
  auto& m = *s.impl_;
  m.options = options;
  m.points.assign(points.begin(), points.end());
  m.normals.assign(normals.begin(), normals.end());
  m.given = m.points.size();
  m.index = std::make_unique<PointIndex>(std::span<const Eigen::Vector3d>(m.points));
  if (options.crease_cuts && options.crease_points) split_at_creases(m);
  m.disc.assign(m.points.size(), 0.0);
  m.spacing.assign(m.points.size(), 0.0);
  m.sector_far.assign(m.points.size(), std::array<float, 6>{});
  m.inward.assign(m.points.size(), Eigen::Vector3d::Zero());
  std::vector<double> fitted_disc;  // bent discs: the radius when the bend was fitted (0: flat)
  if (options.bent_discs) {
    m.bend.assign(m.points.size(), Eigen::Matrix3f::Zero());
    m.bend_reach.assign(m.points.size(), 0.0f);
    fitted_disc.assign(m.points.size(), 0.0);
  }
  // Visited in Morton order (neighbouring queries share the tree's cache lines: a 1M-point cloud
  // in random order spent 39 s here). Neighbours on the same sheet only (normals within 60°):
  // across a thin part or a gap the other sheet's points are no evidence of this sheet's spacing
  // or boundary. The nearest `needed` are asked first, twice as many when some were filtered.
  const std::vector<std::uint32_t> order = morton_order(m.points);
  const std::size_t needed = std::max(options.spacing_neighbour, options.boundary_neighbours) + 1;
  std::vector<double> reach(m.points.size(), 0.0);  // the farthest same-sheet neighbour asked
  std::vector<std::uint8_t> rim_kind(m.points.size(), 0);  // hole_rims: kByGap, kCreaseSide or 0
  std::vector<std::uint8_t> planar(m.points.size(), 0);  // crease cuts: cut_at_creases
  // A point and its second disc on an edge (split_at_creases), or two such, at one place: not
  // each other's neighbours (within 60° of each other, one would read a spacing of 0). With
  // hole_rims, nor two input points at one place.
  const auto twins = [&](std::size_t i, std::uint32_t j, double d2) { return d2 == 0 && (m.options.hole_rims || i >= m.given || j >= m.given); };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m.points.size(), 1024), [&](const auto& r) {
    std::vector<Neighbour> nb;
    std::vector<Eigen::Vector3d> same;  // tangential offsets of same-sheet neighbours
    std::vector<double> dist;
    for (std::size_t o = r.begin(); o != r.end(); ++o) {
      const std::size_t i = order[o];
      const Eigen::Vector3d& n = m.normals[i];
      // (hole_rims) Each place once: a cloud with every point twice (merged scans, a mesh's
      // unwelded vertices) read half as many neighbours, so twice the chance gaps about a point,
      // and a spacing of the copies'; asked again with 8 times as many where copies left too few.
      const std::array<std::size_t, 3> asked{needed, 2 * needed - 1, 8 * needed};
      std::size_t copies = 0;
      for (std::size_t a = 0; a < 3 && (a < 2 || copies > 0); ++a) {
        const std::size_t k = asked[a];
        m.index->nearest(m.points[i], k, nb);
        same.clear();
        dist.clear();
        copies = 0;
        for (std::size_t j = 0; j < nb.size(); ++j) {
          if (nb[j].first == i || m.normals[nb[j].first].dot(n) < 0.5) continue;
          if (twins(i, nb[j].first, nb[j].second)) {
            copies += i < m.given && nb[j].first < m.given;  // (hole_rims) an input point twice
            continue;
          }
          if (options.hole_rims && j > 0 && nb[j].first < m.given && nb[j - 1].first < m.given && nb[j].second == nb[j - 1].second &&
              m.points[nb[j].first] == m.points[nb[j - 1].first]) {
            ++copies;
            continue;
          }
          const Eigen::Vector3d v = m.points[nb[j].first] - m.points[i];
          same.push_back(v - n.dot(v) * n);
          dist.push_back(std::sqrt(nb[j].second));
          if (a == 2 && same.size() + 1 >= needed) break;  // as many places as without the copies
        }
        if (same.size() + 1 >= needed || nb.size() < k) break;
      }
      if (same.empty()) continue;
      reach[i] = dist.back();
      m.spacing[i] = dist[std::min(options.spacing_neighbour, dist.size()) - 1];
      m.disc[i] = options.disc_factor * m.spacing[i];
      // Sampled more sparsely one way (a scanner's lines farther apart than their points): the
      // disc reaches 3/4 of the way to the nearest point in each 60° sector of the tangent plane
      // that holds one (a line-scanned wave's discs, sized along its lines, left the strips
      // between them off the data: 4,293 patches at 1e-3 where a grid of as many points needs 63).
      // Where the nearest points fill fewer than four sectors (all along the point's own line),
      // four times as many are asked. With hole_rims, only as far as the nearer of two opposite
      // sectors' nearest points (a scan's lines lie on both sides of the point): beside a hole, a
      // slot or a bay the nearest point across it lies on one side only, and the disc of a point
      // at its rim, widened 3/4 of the way across, covered the hole up to 3.4 spacings in. Not
      // where another sheet's point is among the nearest: beside a stair's concave edge the
      // nearer sector was the edge's, the tread's discs stopped short of the riser, and the fit
      // left holes along the edge (2.6e-4 of the true stairs' pixels against 8.9e-5).
      {
        const Eigen::Vector3d u = n.unitOrthogonal(), w = n.cross(u);
        std::array<double, 6> nearest;
        auto& farthest = m.sector_far[i];
        const auto fill = [&](const std::vector<Neighbour>& from) {
          nearest.fill(kInf);
          farthest.fill(0.0f);
          int filled = 0;
          for (const auto& [j, d2] : from) {
            if (j == i || !(d2 > 0) || m.normals[j].dot(n) < 0.5) continue;
            const int sector = tangent_sector(m.points[j] - m.points[i], u, w);
            filled += nearest[sector] == kInf;
            nearest[sector] = std::min(nearest[sector], std::sqrt(d2));
            farthest[sector] = std::max(farthest[sector], float(std::sqrt(d2)));
          }
          return filled;
        };
        if (fill(nb) < 4 && nb.size() >= needed) {
          std::vector<Neighbour> wide;
          m.index->nearest(m.points[i], 4 * needed, wide);
          fill(wide);
        }
        double widest = 0;
        const bool paired = options.hole_rims && std::none_of(nb.begin(), nb.end(), [&](const Neighbour& q) {
          return q.first != i && m.normals[q.first].dot(n) < 0.5;
        });
        for (int k = 0; k < 6; ++k) {
          const double d = paired ? std::min(nearest[k], nearest[(k + 3) % 6]) : nearest[k];
          if (d < kInf) widest = std::max(widest, d);
        }
        m.disc[i] = std::max(m.disc[i], options.sector_reach * widest);
      }
      // Planar (DataSurfaceOptions::crease_planarity), from the neighbours asked above.
      if (options.crease_cuts) {
        double sum = 0;
        int count = 0;
        for (std::size_t j = 0; j < nb.size(); ++j) {
          if (nb[j].first == i || twins(i, nb[j].first, nb[j].second) || nb[j].second > m.disc[i] * m.disc[i] ||
              m.normals[nb[j].first].dot(n) < options.crease_cos)
            continue;
          const double h = n.dot(m.points[nb[j].first] - m.points[i]);
          sum += h * h, ++count;
        }
        planar[i] = (i < m.faced.size() && m.faced[i]) || (count >= 2 && std::sqrt(sum / count) <= options.crease_planarity * m.spacing[i]);
      }
      if (options.bent_discs && same.size() >= 5) {
        // Least squares of h = ½(a x² + 2b xy + c y²) over the same-sheet neighbours; the bend
        // capped so the disc's slope at its rim stays below max_disc_slope.
        const Eigen::Vector3d u = n.unitOrthogonal(), w = n.cross(u);
        Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
        Eigen::Vector3d Atb = Eigen::Vector3d::Zero();
        double flat = 0;  // Σh²: the flat disc's residual
        for (std::size_t j = 0; j < nb.size(); ++j) {
          if (nb[j].first == i || twins(i, nb[j].first, nb[j].second) || m.normals[nb[j].first].dot(n) < 0.5) continue;
          const Eigen::Vector3d v = m.points[nb[j].first] - m.points[i];
          const double x = v.dot(u), y = v.dot(w), hh = v.dot(n);
          const Eigen::Vector3d row(0.5 * x * x, x * y, 0.5 * y * y);
          AtA += row * row.transpose();
          Atb += row * hh;
          flat += hh * hh;
        }
        // Only where the neighbours spread over the plane (all on the point's own scan line,
        // the cross terms rest on tiny offsets) and the bend explains the heights (residual
        // Σ(h − q)² = Σh² − kᵀAᵀb at the least-squares solution): where noise or a crease
        // dominates them, the disc stays flat. Capped in the pass after confirm_boundaries,
        // which may widen the disc.
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> spread(AtA, Eigen::EigenvaluesOnly);
        const Eigen::Vector3d k = AtA.ldlt().solve(Atb);
        const double residual = flat - k.dot(Atb);
        if (spread.eigenvalues()(0) >= 1e-3 * spread.eigenvalues()(2) && k.allFinite() &&
            residual <= options.bend_residual * flat) {
          m.bend[i] = (k[0] * u * u.transpose() + k[1] * (u * w.transpose() + w * u.transpose()) + k[2] * w * w.transpose())
                          .cast<float>();
          fitted_disc[i] = m.disc[i];
        }
      }
      const std::size_t kb = std::min(options.boundary_neighbours, same.size());
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      double mean = 0;
      for (std::size_t j = 0; j < kb; ++j) centroid += same[j], mean += dist[j];
      centroid /= double(kb);
      mean /= double(kb);
      if (centroid.norm() > options.boundary_offset * mean) {
        m.inward[i] = centroid.normalized();
        // (hole_rims) Another sheet's point in the empty direction: a crease's side, which no run
        // of boundary points passes through (confirm_boundaries).
        if (options.hole_rims)
          for (const auto& [j, d2] : nb)
            if (j != i && m.normals[j].dot(n) < 0.5 && (m.points[j] - m.points[i]).dot(m.inward[i]) < 0) {
              rim_kind[i] = kCreaseSide;
              break;
            }
      } else if (options.hole_rims && kb >= 8) {
        // At a hole's rim (a concave boundary) the neighbours wrap around the hole, and their
        // centroid lies less than boundary_offset of their distance away: in a square with a round
        // hole ten spacings across, the discs of such points reached up to 3 spacings into it.
        // The widest angle between consecutive neighbours about the point (about 130° on such a
        // rim, 100° or more inside a random sampling for 1.3 % of its points, whose short runs
        // confirm_boundaries clears) flags them too, away from that gap. Not where a second gap
        // is half as wide (a scan line's points have two of 180°), nor where another sheet's point
        // lies in the gap (the other face beside a crease: an open box's wall beside its edges).
        const Eigen::Vector3d u = n.unitOrthogonal(), w = n.cross(u);
        std::array<double, 64> angle;
        std::size_t na = 0;
        for (std::size_t j = 0; j < kb && na < angle.size(); ++j)
          if (same[j].squaredNorm() > 0) angle[na++] = std::atan2(same[j].dot(w), same[j].dot(u));
        std::sort(angle.begin(), angle.begin() + std::ptrdiff_t(na));
        double widest_gap = 0, second = 0, middle = 0;
        for (std::size_t j = 0; j < na; ++j) {
          const double g = j + 1 < na ? angle[j + 1] - angle[j] : angle[0] + 2 * std::numbers::pi - angle[j];
          if (g > widest_gap) second = widest_gap, widest_gap = g, middle = angle[j] + 0.5 * g;
          else second = std::max(second, g);
        }
        const auto other_sheet_in_gap = [&] {
          for (const auto& [j, d2] : nb) {
            if (j == i || m.normals[j].dot(n) >= 0.5) continue;
            const Eigen::Vector3d v = m.points[j] - m.points[i];
            const Eigen::Vector3d t = v - n.dot(v) * n;
            if (!(t.squaredNorm() > 0)) continue;
            if (std::abs(std::remainder(std::atan2(t.dot(w), t.dot(u)) - middle, 2 * std::numbers::pi)) < 0.5 * widest_gap)
              return true;
          }
          return false;
        };
        if (na >= 8 && widest_gap >= kHoleRimGap && second < 0.5 * widest_gap && !other_sheet_in_gap()) {
          m.inward[i] = -(std::cos(middle) * u + std::sin(middle) * w);
          rim_kind[i] = kByGap;
        }
      }
    }
  });
  confirm_boundaries(m, reach, rim_kind);
  if (options.crease_cuts) {
    cut_at_creases(m, planar);
    m.planar = planar;
  }
  // A point beside a crease has no neighbour on its own sheet past the crease, so the centroid
  // test above takes it for an open boundary, and its disc stopped a quarter of its radius past
  // it there (the star of sectors) well before the crease: beside a box's corners no disc reached
  // the corner's tip (a 20,000-point box without normals: its discs left 3.7e-4 of the true box's
  // pixels open, 49 of 67 sampled ones within 15E of a corner, and the fit, true to its data,
  // 5.4e-4; now 3.8e-5 and 3.3e-5). A point is on an open boundary only where a 60° sector of its
  // tangent plane without a neighbour (sector_far) is not closed by its crease cuts: every ray
  // across the sector (its middle, and 15° and 29° to either side) leaves the disc through a cut
  // line within the radius, the cut's normal within 60° of the ray. At an edge or corner of a
  // closed part the cuts close them; at the rim of an open box's wall the sector past the rim stays
  // open, beside a vertical edge too. (Closed by the sector's middle alone, or by a cut nearly
  // parallel to its rays, a rim point beside the edge lost its boundary and its disc ran up along
  // the edge past the rim: 3.2 spacings, 35E at 1e-3, where 2.45 elsewhere on the rim, and the fit
  // followed, 0.13 % → 0.22 % of the true open box's pixels beyond 2E, max 9.7E → 31E; a
  // reviewer's case.) Such a point keeps its star in the sectors with neighbours and reaches its
  // whole radius (as far as the cuts let it) in those without (star_only), and is kept apart
  // (crease_sides): a ball over such points may still stop short of the crease as at a boundary
  // (BallFitter::try_boundary); without that, fandisk sampled by 20,000 points without normals
  // fitted at 3e-3 with 555 patches instead of 460 and 1.4e-4 of its pixels open instead of
  // 3.9e-5.
  if (!m.cut_begin.empty()) {
    for (std::size_t i = 0; i < m.points.size(); ++i) {
      if (m.inward[i].squaredNorm() == 0 || m.cut_begin[i + 1] == m.cut_begin[i]) continue;
      const auto ray_cut = [&](const Eigen::Vector2d& d) {
        for (std::uint32_t k = m.cut_begin[i]; k < m.cut_begin[i + 1]; ++k) {
          const double along = m.cuts[k].head<2>().dot(d);
          if (along >= 0.5 && m.cuts[k].z() <= along * m.disc[i]) return true;
        }
        return false;
      };
      // The rays across a sector, as fractions of its 60°: its middle, 15° and 29° to either side.
      static constexpr std::array<double, 5> kAcross{0.5 - 29.0 / 60.0, 0.25, 0.5, 0.75, 0.5 + 29.0 / 60.0};
      std::array<bool, 6> shut{};
      bool closed = true;
      for (int s = 0; s < 6 && closed; ++s) {
        if (m.sector_far[i][s] > 0) continue;
        shut[s] = std::all_of(kAcross.begin(), kAcross.end(), [&](double f) { return ray_cut(sector_direction(s, f)); });
        closed = shut[s];
      }
      if (!closed) {
        // An open boundary beside a crease: the centroid test's direction leans away from the
        // crease (the other face's points are no neighbours), by up to 50° at an open box's rim
        // beside its vertical edges, where the rim's discs then stopped on a slant, reaching
        // 1.6 spacings past the rim beside the edge. The lean is taken out along each cut's
        // normal (with rim_cuts, whose lines it sets).
        if (options.rim_cuts) {
          const Eigen::Vector3d u = m.normals[i].unitOrthogonal(), w = m.normals[i].cross(u);
          Eigen::Vector3d in = m.inward[i];
          for (std::uint32_t k = m.cut_begin[i]; k < m.cut_begin[i + 1]; ++k) {
            const Eigen::Vector3d a = m.cuts[k].x() * u + m.cuts[k].y() * w;
            in -= std::min(0.0, in.dot(a)) * a;
          }
          if (in.norm() > 0.5) m.inward[i] = in.normalized();
        }
        continue;
      }
      m.crease_sides.samples.push_back({m.points[i], m.inward[i]});
      m.inward[i] = Eigen::Vector3d::Zero();
      if (m.star_only.empty()) m.star_only.assign(m.points.size(), 0);
      m.star_only[i] = 1;
      for (int s = 0; s < 6; ++s)
        if (shut[s]) m.sector_far[i][s] = float(m.disc[i]);
    }
  }
  // A boundary point's disc stays flat (a crease side's too): its shape (a star of sectors, cut
  // short past the boundary) measures the tangential excess to its nearest shape point, and the
  // height there is that of the tangent plane (the bent height at the clamped offset would not
  // belong to a point of the disc).
  // So does a disc confirm_boundaries widened past the neighbours its bend was fitted to (a step
  // in the sampling density): extrapolated there, the bend would make the data permissive. The
  // others are capped at max_disc_slope on their final radius.
  double slope = 0;  // the steepest bent disc's rim slope (2·reach/radius)
  for (std::size_t i = 0; i < m.bend.size(); ++i) {
    const bool star = m.inward[i].squaredNorm() > 0 || (!m.star_only.empty() && m.star_only[i]);
    if (fitted_disc[i] == 0.0 || star || m.disc[i] > fitted_disc[i]) {
      m.bend[i].setZero();
      continue;
    }
    const Eigen::Matrix3d K = m.bend[i].cast<double>();
    const double kmax = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(K, Eigen::EigenvaluesOnly).eigenvalues().cwiseAbs().maxCoeff();
    const double scale = kmax * m.disc[i] > options.max_disc_slope ? options.max_disc_slope / (kmax * m.disc[i]) : 1.0;
    m.bend[i] = (scale * K).cast<float>();
    // Rounded up past the float copy's rounding, so the boxes and prunes stay conservative.
    m.bend_reach[i] = float(0.5 * scale * kmax * m.disc[i] * m.disc[i] * (1.0 + 1e-5));
    slope = std::max(slope, 2.0 * double(m.bend_reach[i]) / m.disc[i]);
  }
  m.lipschitz = std::hypot(1.0, slope);
  for (std::size_t i = 0; i < m.points.size(); ++i)
    if (m.inward[i].squaredNorm() > 0) {
      m.boundary.samples.push_back({m.points[i], m.inward[i]});
      m.boundary.normals.push_back(m.normals[i]);
      m.boundary.reach.push_back(m.end_reach(i));
      m.boundary.widest_reach = std::max(m.boundary.widest_reach, m.end_reach(i));
      m.boundary.rim.push_back(0);
    }
  m.boundary.index_them();
  m.crease_sides.index_them();
  cut_at_rims(m);
  return s;
}

// Rim cuts. A point near an open boundary whose own neighbours surround it is no boundary point
// by the centroid test (its 24 nearest reach well past the rim on the data's side), so its whole
// disc, up to two spacings wide, reached past the rim where the boundary points' own discs stop
// (end_reach past them): an open box sampled by 20,000 points had its data reach 1.85-2.2
// spacings above the rim (20-24E at 1e-3), and the fit, within 2E of its data, stood up to 12E
// past the true rim (0.08-0.16 % of its pixels beyond 2E, nearly all there; p99.9 1.4-2.8E).
//
// The boundary points that stand for an open rim: none with another sheet's point within two
// disc radii ahead of it over its tangent plane (within 60° of its outward tangent: the other
// face of a crease, below). Near each disc (any point's, the boundary's own too), those of its
// sheet (normals within acos(crease_cos)) within its radius and the farthest end are grouped by
// their outward tangents (within 45° of the nearest's; up to kGroups groups: a sheet's corner
// has two rims), a group of at least kGroup. For directions every 7.5° within 45° of a group's
// mean outward tangent (each boundary point's smoothed over those within its disc: the centroid
// test's directions tilt by 10-20° along a straight rim sampled at random, and a line 6° off the
// rim's normal already rose past its points a few spacings along it), the support line of the
// group's ends, x·e ≤ max(b·e + end_reach(b)), is a line where the data ends if every point of
// the disc's own sheet within its radius and kBeyond spacings more lies on its kept side (up to
// kSlack of the spacing, which that point's disc covers): a hole's rim, a bay, scattered
// boundary points of a sparse spot (5 groups of 1-2 on 20,000 points drawn from the bunny cut
// its data open) fail it. The nearest such lines to the disc's point, at least 20° apart,
// kLinesPerRim per group, cut the disc as crease cuts do (cut_excess: one disc shape), its own
// point kept; not in a direction within 45° of one of its crease cuts, which ends it there
// already.
void DataSurface::cut_at_rims(Impl& m) {
  constexpr std::size_t kGroups = 2, kGroup = 3, kLinesPerRim = 3;
  constexpr int kSteps = 6;  // directions kStep apart to either side of a group's mean
  constexpr double kStep = std::numbers::pi / 24;
  constexpr double kAhead = 0.5;  // cosine of the cone ahead of a boundary point
  constexpr double kOffPlane = 0.34;  // sine of the angle off its plane that makes a point another sheet's
  constexpr double kFacing = 0.9;     // normals within 25° of opposite: a thin part's other side, not a crease
  constexpr double kBeyond = 2.0, kSlack = 0.1;  // of the disc's spacing
  if (!m.options.rim_cuts || m.boundary.samples.empty()) return;
  const std::size_t n = m.points.size();
  const auto& o = m.options;
  // The boundary points by sample (from_points pushes them in point order).
  std::vector<std::uint32_t> at;
  at.reserve(m.boundary.samples.size());
  for (std::size_t i = 0; i < n; ++i)
    if (m.inward[i].squaredNorm() > 0) at.push_back(std::uint32_t(i));
  const double widest = m.boundary.widest_reach;  // the farthest any boundary's end lies past its point
  // Smoothed outward tangents; zero where another sheet lies ahead.
  std::vector<Eigen::Vector3d> outward(at.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, at.size(), 256), [&](const auto& r) {
    std::vector<Neighbour> nb;
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      const std::uint32_t b = at[k];
      const Eigen::Vector3d& nrm = m.normals[b];
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      m.boundary.index->radius(m.points[b], m.disc[b], nb);
      for (const auto& [j, d2] : nb)
        if (m.normals[at[j]].dot(nrm) >= o.crease_cos && m.inward[at[j]].dot(m.inward[b]) >= 0.5) sum -= m.inward[at[j]];
      sum -= sum.dot(nrm) * nrm;
      outward[k] = sum.norm() > 0 ? Eigen::Vector3d(sum.normalized()) : Eigen::Vector3d(-m.inward[b]);
      // Another sheet's point (turned from its normal, or off its plane by 20°) over its tangent
      // plane ahead of it, within 60° of its outward tangent: the other face of a crease (whose
      // cuts did not close its sectors, or of rounded normals without cuts: a sparse box's), a
      // concave crease's rising face. No open rim. (In space a convex edge's other face lies at
      // 90° to the outward tangent; ahead of an open box's rim beside a vertical edge the other
      // wall lies level with it, beside. The other side of a thin part facing it is no crease:
      // an open pouch's rim kept its data 13.5E past it.)
      m.index->radius(m.points[b], 2.0 * m.disc[b], nb);
      for (const auto& [j, d2] : nb) {
        if (!(d2 > 0)) continue;
        const Eigen::Vector3d v = m.points[j] - m.points[b];
        if (m.normals[j].dot(nrm) >= o.crease_cos && std::abs(v.dot(nrm)) <= kOffPlane * std::sqrt(d2)) continue;  // its own sheet
        if (m.normals[j].dot(nrm) <= -kFacing) continue;  // the other side of a thin part
        const Eigen::Vector3d t = v - v.dot(nrm) * nrm;  // where it lies over the tangent plane
        const double len = t.norm();
        if (-t.dot(m.inward[b]) > kAhead * len || t.dot(outward[k]) > kAhead * len) {
          outward[k].setZero();
          break;
        }
      }
    }
  });
  // The usable ones, indexed apart (most clouds have none, or a few scattered).
  std::vector<std::uint32_t> usable;
  std::vector<Eigen::Vector3d> usable_at;
  for (std::size_t k = 0; k < at.size(); ++k)
    if (outward[k].squaredNorm() > 0) {
      usable.push_back(std::uint32_t(k)), usable_at.push_back(m.points[at[k]]);
      m.boundary.rim[k] = 1;
    }
  if (usable.size() < kGroup) return;
  const PointIndex rims{std::span<const Eigen::Vector3d>(usable_at)};
  // The lines, (point, (a_u, a_w, c)) pairs, each thread's; rare (rims).
  tbb::enumerable_thread_specific<Impl::Lines> found;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
    auto& out = found.local();
    std::vector<Neighbour> nb, own;
    std::vector<std::uint32_t> near, group;  // boundary samples (indices into `at`)
    std::vector<Eigen::Vector3d> candidates;  // (a_u, a_w, c)
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      if (!(m.disc[i] > 0)) continue;
      const Eigen::Vector3d &p = m.points[i], &nrm = m.normals[i];
      // (A boundary point whose end reaches past a radius of this disc is asked within three
      // radii only: with the widest end of the whole cloud, a few sparse points' discs made
      // every point of a dense square ask hundreds, 10× the time of from_points.)
      rims.radius(p, m.disc[i] + std::min(widest, 2.0 * m.disc[i]), nb, true);
      near.clear();
      for (const auto& [j, d2] : nb)
        if (const std::uint32_t k = usable[j]; at[k] != i && m.normals[at[k]].dot(nrm) >= o.crease_cos) near.push_back(k);
      if (near.size() < kGroup) continue;
      m.index->radius(p, m.disc[i] + kBeyond * m.spacing[i], own);
      const Eigen::Vector3d u = nrm.unitOrthogonal(), w = nrm.cross(u);
      const double slack = kSlack * m.spacing[i];
      const auto crease_cut = [&](const Eigen::Vector2d& a) {
        if (m.cut_begin.empty()) return false;
        for (std::uint32_t k = m.cut_begin[i]; k < m.cut_begin[i + 1]; ++k)
          if (m.cuts[k].head<2>().dot(a) >= std::numbers::sqrt2 / 2) return true;
        return false;
      };
      const std::size_t first = out.size();
      for (std::size_t g = 0; g < kGroups && !near.empty(); ++g) {
        const Eigen::Vector3d seed = outward[near.front()];
        group.clear();
        std::erase_if(near, [&](std::uint32_t k) {
          if (outward[k].dot(seed) < std::numbers::sqrt2 / 2) return false;
          group.push_back(k);
          return true;
        });
        if (group.size() < kGroup) continue;
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (const std::uint32_t k : group) mean += outward[k];
        const Eigen::Vector2d d(mean.dot(u), mean.dot(w));  // in the disc's plane
        if (d.norm() < 0.5 * double(group.size())) continue;  // across the disc's plane
        const Eigen::Vector2d d0 = d.normalized();
        candidates.clear();
        for (int step = -kSteps; step <= kSteps; ++step) {
          const double turn = step * kStep;
          const Eigen::Vector2d a(std::cos(turn) * d0.x() - std::sin(turn) * d0.y(), std::sin(turn) * d0.x() + std::cos(turn) * d0.y());
          const Eigen::Vector3d e = a.x() * u + a.y() * w;
          double end = -kInf;
          for (const std::uint32_t k : group) end = std::max(end, m.points[at[k]].dot(e) + m.end_reach(at[k]));
          const double c = end - p.dot(e);
          if (c < 0 || c >= m.disc[i] || crease_cut(a)) continue;
          if (std::any_of(own.begin(), own.end(), [&](const Neighbour& q) {
                return m.normals[q.first].dot(nrm) >= 0.5 && m.points[q.first].dot(e) > end + slack;
              }))
            continue;
          candidates.emplace_back(a.x(), a.y(), c);
        }
        std::sort(candidates.begin(), candidates.end(), [](const auto& x, const auto& y) { return x.z() < y.z(); });
        std::size_t kept = 0;
        for (const Eigen::Vector3d& l : candidates) {
          if (kept == kLinesPerRim) break;
          if (Impl::near_kept(out, first, l.head<2>())) continue;
          out.emplace_back(std::uint32_t(i), l);
          ++kept;
        }
      }
    }
  });
  m.add_cuts(found);  // after each disc's crease cuts
}

// A point whose nearest neighbours lie to one side is on an open boundary only if the other
// side holds no data either. Where the sampling density changes (a scan's overlap, a part
// scanned closer), a sparse point's nearest neighbours are all on the dense side: it would be
// taken for a boundary (its disc short towards its sparse neighbours) and its disc sized by the
// dense side's spacing, leaving the surface between the sparse points outside the data's
// surface. So the other side is searched, beyond the neighbourhood the centroid test has judged
// and out to 8 times its reach, for a point on the same sheet (normal within 60°, within 30° of
// the tangent plane, within 30° of the empty direction: a jagged rim's own points lie along it)
// whose own spacing reaches back (at most gap_spacings of it away: the far rim of a hole in a
// scan is sampled at its own, finer spacing, so a hole stays open where its rim's points are
// taken for a boundary at all; holes up to about 6 spacings across are not, as before); where
// one is found the point is not on a boundary, and its disc reaches 3/4 of the way there.
// With hole_rims (DataSurfaceOptions), the far point must lie within 2.5 of its spacings, and
// not be a boundary point itself facing away from this one (the far rim of the same hole, slot or
// bay): a rim point's spacing is larger than inside (its neighbours lie on one side), and in a
// square sampled at random with a hole eight spacings across, points on the far rim reached back
// across it, the rim point's disc was widened 3/4 of the way there and covered the hole 2.6
// spacings in; the bunny's base, sampled by 20,000 points, has slits two spacings wide that its
// data bridged. (A 10× density step's sparse side, 3.2 spacings of the dense side apart, is still
// found: DataSurface.AStepInTheSamplingDensityIsNeitherABoundaryNorAHole.) Those rules, and the
// widest-gap flag (from_points), also keep the rims of a random sampling's chance voids, which
// are as wide as such slits: ln N + ln ln N points' worth of area, about two spacings across for
// 20,000 points. A slit is long and a void round, so a point these rules alone made a boundary
// point stays one only in a run of boundary points (each within 2 spacings of the next, normals
// within 60°, not through a crease's side) at least 6 spacings long; elsewhere it is cleared as
// before them, its disc widened as the 3-spacing rule would have widened it (the closed sphere
// of DataSurface.AStepInTheSamplingDensityIsNeitherABoundaryNorAHole: 39 false boundary samples
// without the runs, none with; a 20,000-point open box's largest void, 5.1 spacings).
void DataSurface::confirm_boundaries(Impl& m, const std::vector<double>& reach, const std::vector<std::uint8_t>& rim_kind) {
  constexpr double kReach = 8.0, kOldGap = 3.0;
  const bool hole_rims = m.options.hole_rims;
  const double gap_spacings = hole_rims ? 2.5 : kOldGap;
  // The spacings and boundary directions before any is changed below (read by every thread
  // while flagged points' change).
  const std::vector<double> spacing0 = m.spacing;
  const std::vector<Eigen::Vector3d> inward0 = hole_rims ? m.inward : std::vector<Eigen::Vector3d>{};
  // No point farther than kOldGap × the widest spacing can reach back.
  const double widest = spacing0.empty() ? 0.0 : *std::max_element(spacing0.begin(), spacing0.end());
  std::vector<std::uint32_t> flagged;
  for (std::size_t i = 0; i < m.points.size(); ++i)
    if (m.inward[i].squaredNorm() > 0) flagged.push_back(std::uint32_t(i));
  // hole_rims: the distance to the point that would have cleared i without the hole_rims rules
  // (0: none would have).
  std::vector<double> old_clear(hole_rims ? m.points.size() : 0, 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, flagged.size(), 64), [&](const auto& r) {
    std::vector<Neighbour> nb;
    for (std::size_t f = r.begin(); f != r.end(); ++f) {
      const std::uint32_t i = flagged[f];
      const Eigen::Vector3d &p = m.points[i], &n = m.normals[i], &dir = m.inward[i];
      const double inner2 = reach[i] * reach[i];
      m.index->radius(p, std::min(kReach * reach[i], kOldGap * widest), nb, true);
      for (const auto& [j, d2] : nb) {
        if (d2 <= inner2 || m.normals[j].dot(n) < 0.5) continue;
        const Eigen::Vector3d v = m.points[j] - p;
        const double h = n.dot(v);
        const Eigen::Vector3d t = v - h * n;
        const double tn = t.norm();
        if (!(tn > 0) || std::abs(h) > 0.58 * tn || t.dot(dir) > -0.866 * tn || tn > kOldGap * spacing0[j]) continue;
        if (hole_rims) {
          if (old_clear[i] == 0) old_clear[i] = tn;
          // A far rim facing back, in a sampling like this point's: a density change's sparse point
          // may face away from its dense side too (radar.xyz, a scan of very uneven density, opened
          // holes as wide as a third of the model in a view, where its fit had covered them).
          const bool alike = std::max(spacing0[i], spacing0[j]) <= kFarRimSpacings * std::min(spacing0[i], spacing0[j]);
          if (tn > gap_spacings * spacing0[j] || (alike && inward0[j].dot(t) > 0)) continue;
        }
        m.inward[i] = Eigen::Vector3d::Zero();
        m.disc[i] = std::max(m.disc[i], 0.75 * tn);
        m.spacing[i] = std::max(m.spacing[i], 0.5 * tn);
        break;
      }
    }
  });
  if (!hole_rims) return;
  // The runs: boundary points joined within kRimRunStep spacings (union-find over those still flagged).
  std::erase_if(flagged, [&](std::uint32_t i) { return m.inward[i].squaredNorm() == 0; });
  std::unordered_map<std::uint32_t, std::uint32_t> parent;
  for (const std::uint32_t i : flagged) parent[i] = i;
  const auto root = [&](std::uint32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  std::vector<Neighbour> nb;
  for (const std::uint32_t i : flagged) {
    if (rim_kind[i] == kCreaseSide) continue;
    m.index->radius(m.points[i], kRimRunStep * spacing0[i], nb, false);  // the pair's larger spacing: from either end
    for (const auto& [j, d2] : nb) {
      if (j == i || rim_kind[j] == kCreaseSide || m.inward[j].squaredNorm() == 0 || m.normals[j].dot(m.normals[i]) < 0.5) continue;
      const double step = kRimRunStep * std::max(spacing0[i], spacing0[j]);
      if (d2 > step * step) continue;
      const std::uint32_t a = root(i), b = root(j);
      if (a != b) parent[a] = b;
    }
  }
  std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> runs;
  for (const std::uint32_t i : flagged) runs[root(i)].push_back(i);
  std::vector<double> spacings;
  for (const auto& [r, run] : runs) {
    // The run's extent: the farthest of its points from the farthest from its first (within a
    // factor of 2 of its diameter), in the median of its points' spacings.
    const auto farthest = [&](std::uint32_t a) {
      std::uint32_t far = a;
      double d = 0;
      for (const std::uint32_t k : run)
        if (const double e = (m.points[k] - m.points[a]).squaredNorm(); e > d) d = e, far = k;
      return std::pair{far, d};
    };
    const double extent2 = farthest(farthest(run.front()).first).second;
    spacings.clear();
    for (const std::uint32_t k : run) spacings.push_back(spacing0[k]);
    std::nth_element(spacings.begin(), spacings.begin() + std::ptrdiff_t(spacings.size() / 2), spacings.end());
    const double sp = spacings[spacings.size() / 2];
    if (sp > 0 && extent2 >= kRimRunExtent * kRimRunExtent * sp * sp) continue;
    for (const std::uint32_t k : run) {
      if (rim_kind[k] != kByGap && old_clear[k] == 0) continue;  // a boundary point before the hole_rims rules
      m.inward[k] = Eigen::Vector3d::Zero();
      if (old_clear[k] > 0 && rim_kind[k] != kByGap) {  // a point the gap flagged was no boundary point to widen
        m.disc[k] = std::max(m.disc[k], 0.75 * old_clear[k]);
        m.spacing[k] = std::max(m.spacing[k], 0.5 * old_clear[k]);
      }
    }
  }
}

// Crease cuts (DataSurfaceOptions::crease_cuts): each point within a disc's radius and a spacing
// whose normal m turns between acos(crease_cos) and the reverse of acos(knife_cos) from the disc's
// n cuts the disc at its tangent plane, keeping the disc's own side: at a convex crease (the other
// face's point q lies below the disc's plane and the disc's point below q's: (q − p)·(n − m) < 0)
// the side below q's plane, at a concave one the side above; a q whose plane has the disc's own
// point on the other side cuts nothing. A pair too close to the crease to tell which it is
// (|(q − p)·(n − m)| under a tenth of their distance: both on the edge, apart along it) is left to
// the others. Of the lines, the nearest to the point first, at most kMaxCuts, none within 20° of a
// nearer one (the next line in much the same direction cuts little more). A dihedral sharper than
// acos(knife_cos) (normals more than 166° apart) is not cut: its fins stay.
void DataSurface::cut_at_creases(Impl& m, const std::vector<std::uint8_t>& planar) {
  constexpr std::size_t kMaxCuts = 4;
  const double cos_max = m.options.crease_cos, knife_cos = m.options.knife_cos;
  const std::size_t n = m.points.size();
  const double slack = m.crease_copies > 0 ? 1e-9 : 0.0;
  // Planar points only (DataSurfaceOptions::crease_planarity; `planar`, judged from_points from
  // the neighbours within each disc that it asks anyway: a pass of its own took 1.4 s of
  // from_points' 4.3 s on 1M points drawn from the armadillo). On a smooth surface sampled
  // sparsely the normals turn as much between neighbours, and a neighbour's plane cuts the surface
  // itself: cut wherever normals turned 41°, 5,000 points drawn from the bunny left 2.5 % of the
  // mesh farther than 2E from their discs, against 0.13 % uncut, and the kitten at 1e-3 went from
  // 630 patches to 877 with a hole share of 1.1e-2 (exit 7).
  // Cut lines are rare (creases): each thread keeps (point, line) pairs, gathered below.
  tbb::enumerable_thread_specific<Impl::Lines> found;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
    auto& out = found.local();
    std::vector<Neighbour> nb;
    std::vector<Eigen::Vector3d> lines;
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      if (!(m.disc[i] > 0) || !planar[i]) continue;
      const Eigen::Vector3d &p = m.points[i], &nrm = m.normals[i];
      const Eigen::Vector3d u = nrm.unitOrthogonal(), w = nrm.cross(u);
      m.index->radius(p, m.disc[i] + m.spacing[i], nb);
      lines.clear();
      for (const auto& [j, d2] : nb) {
        const Eigen::Vector3d& mj = m.normals[j];
        const double cosine = mj.dot(nrm);
        if (j == i || cosine >= cos_max || cosine <= -knife_cos || !planar[j]) continue;
        const Eigen::Vector3d d = m.points[j] - p;
        const double side = d.dot(nrm - mj);
        // (d2 = 0: a point's second disc on an edge, split_at_creases, which tells neither.)
        if (!(d2 > 0) || std::abs(side) < 0.1 * std::sqrt(d2)) continue;
        const double sigma = side < 0 ? 1.0 : -1.0;  // convex: keep below q's plane
        const Eigen::Vector3d mt = mj - cosine * nrm;
        const double mt_len = mt.norm();
        // p lies on the far side of q's plane from what the crease says (q on another arm of a
        // face, the far side of a rib or slot): q's plane is no edge of p's face (clamped to a line
        // through p, it kept the wrong half: beside a slot 0.03 wide, 350 of 5,000 face points
        // read up to 0.42 spacings farther from the cut discs than from the whole ones).
        // (A point of the other face's plane through an edge point's disc, split_at_creases, lies
        // on it up to rounding: its line passes through the point.)
        if (sigma * d.dot(mj) < -slack * std::sqrt(d2)) continue;
        const double c = std::max(0.0, sigma * d.dot(mj)) / mt_len;
        const Eigen::Vector3d a = sigma * mt / mt_len;
        lines.emplace_back(a.dot(u), a.dot(w), c);
      }
      std::erase_if(lines, [&](const Eigen::Vector3d& l) { return l.z() >= m.disc[i]; });
      std::sort(lines.begin(), lines.end(), [](const auto& x, const auto& y) { return x.z() < y.z(); });
      std::size_t kept = 0;
      const std::size_t first = out.size();
      for (const Eigen::Vector3d& l : lines) {
        if (kept == kMaxCuts) break;
        const Eigen::Vector2d a = l.head<2>().normalized();
        if (Impl::near_kept(out, first, a)) continue;
        out.emplace_back(std::uint32_t(i), Eigen::Vector3d(a.x(), a.y(), l.z()));
        ++kept;
      }
    }
  });
  m.add_cuts(found);
}

// Crease points (DataSurfaceOptions::crease_points). Where point i's crease_neighbours nearest
// (not those facing away: the far side of a thin part) hold a normal turned more than half the
// crease angle from its own, they are explained, all but two, within tol (twice crease_planarity
// of the 6th nearest's distance) by planes, RANSAC-like:
// - the first through the point: of the planes through it and two of its ten nearest, holding
//   at least four, the first of the three that hold most (a degree apart) that the refit keeps;
// - then up to two more, each through one or two of the rest and the point or any neighbour
//   (an edge's points lie on both faces), holding most of the rest, at least three.
// Each plane is refitted by least squares (through the point for the first) to the points it
// holds whose normals lie within 30° of it (where three or more do: another face's points near
// their common edge, within tol of it, tilted the fit 2° beside a box's inner corner). A plane is
// refused where its points spread along a line alone (an edge's points hold any plane through
// it), or where fewer than half of their normals lie within 60° of it (a plane across a corner's
// three faces). The planes must turn more than acos(crease_cos), and less than its reverse, from
// each other: a smooth surface sampled exactly (a sphere's cap) is explained only by near-parallel
// planes, noise by none.
// The first plane's normal, oriented along the point's own, becomes its disc's; each other plane
// that holds the point gives a second disc there, oriented along its points' normals. A point is
// left as it is where its own normal's plane holds, spread across it, as many of them as the best
// plane through it less the two it was made from, or where one of its planes through it lies
// within 1° of its normal: a face's exact normal beside an edge (the crease cuts stop its disc; refitted here,
// a hexagonal prism's exact normals drew fins of 10E at 1e-3 where they had 2E).
// Then the faces' planes spread to the points beside them (see below). Every point given its
// face's plane is planar for the crease cuts (Impl::faced); one whose normal lies within 1° of
// that plane keeps its own.
void DataSurface::split_at_creases(Impl& m) {
  const auto& o = m.options;
  const std::size_t n = m.points.size(), k = o.crease_neighbours + 1;
  constexpr std::size_t kStray = 2;  // neighbours left unexplained (a curved face's, a fourth face's)
  const auto cos_deg = [](double deg) { return std::cos(deg * std::numbers::pi / 180.0); };
  const double kTurned = std::cos(0.5 * std::acos(o.crease_cos));  // half the crease angle
  const double kSameNormal = cos_deg(1.0), kClose = cos_deg(30.0), kAgree = cos_deg(60.0);
  struct Plane {
    Eigen::Vector3d c;
    double d;
    std::size_t held;
  };
  // Neighbours facing away (the far side of a thin part) are left out: normals turned more than
  // 101.5°, or with knife edges (knife_cos) more than acos(−knife_cos), 166°, so an acute edge's
  // other face counts (a 30° wedge's turns 150°: left out, the points beside the knife edge had
  // fewer than 8 neighbours and kept PCA's rounded normals; the data stood 32E past the edge).
  const double facing_away = o.knife_cos > o.crease_cos ? -o.knife_cos : -0.2;
  std::vector<Eigen::Vector3d> face(n, Eigen::Vector3d::Zero());  // zero: unchanged
  // tol per point: twice crease_planarity of its 6th nearest's distance, of those not facing away
  // (0 where fewer lie near); the spread below asks it again.
  std::vector<double> tol_of(n, 0.0);
  tbb::enumerable_thread_specific<Impl::Lines> found;
  const std::span<const std::uint32_t> order = m.index->order();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 512), [&](const auto& r) {
    auto& out = found.local();
    std::vector<Neighbour> nb;
    std::vector<Eigen::Vector3d> v;  // offsets from the point
    std::vector<std::uint32_t> id;
    std::vector<std::uint8_t> left;  // not yet explained by a plane
    std::vector<std::size_t> rest;   // their indices
    std::vector<Plane> tried;        // candidates for the first plane
    for (std::size_t oi = r.begin(); oi != r.end(); ++oi) {
      const std::uint32_t i = order[oi];
      const Eigen::Vector3d &p = m.points[i], &nrm = m.normals[i];
      m.index->nearest(p, k, nb);
      v.clear(), id.clear();
      for (const auto& [j, d2] : nb)
        if (j != i && m.normals[j].dot(nrm) >= facing_away) v.push_back(m.points[j] - p), id.push_back(j);
      if (v.size() >= 6) tol_of[i] = 2.0 * o.crease_planarity * v[5].norm();
      if (v.size() < 8) continue;
      // Only where the normals turn: a crease's neighbourhood holds normals of both faces or
      // between them, a smooth surface's turn slowly (its scan lines, planes through the point
      // and each line, are no faces: without this, 257 points of a raw range scan changed).
      if (std::none_of(id.begin(), id.end(), [&](std::uint32_t j) { return m.normals[j].dot(nrm) < kTurned; })) continue;
      const double tol = tol_of[i];
      if (!(tol > 0)) continue;  // copies of the point among its nearest
      // Points that spread across a plane (not only along a line: an edge's points hold any plane
      // through it), by the moments' eigenvalues λ₁ ≤ λ₂ of count of them: across a fifth of
      // their length, or an RMS width of 10 tol (rows of a face sampled 3× finer one way).
      const auto spread = [&](const Eigen::Vector3d& lambda, std::size_t count) {
        return lambda(2) > 0 && (lambda(1) >= 0.04 * lambda(2) || lambda(1) >= double(count) * 100.0 * tol * tol);
      };
      // How many its own normal's plane holds, spread across it (0 where only along a line).
      // And whether its normal is its face's exact one: shared (within 1°) by points on its plane
      // that spread across it with the point (an edge's averaged normals are shared along the
      // edge's line alone). Such a point is left as it is: beside an edge, a plane through it
      // across the edge took exact normals 75° off.
      std::size_t own_held = 0;
      {
        Eigen::Matrix3d T = Eigen::Matrix3d::Zero(), X = Eigen::Matrix3d::Zero();
        std::size_t shared = 0;
        for (std::size_t a = 0; a < v.size(); ++a)
          if (std::abs(v[a].dot(nrm)) <= tol) {
            T += v[a] * v[a].transpose(), ++own_held;
            if (m.normals[id[a]].dot(nrm) >= kSameNormal) X += v[a] * v[a].transpose(), ++shared;
          }
        if (own_held == v.size()) continue;
        if (shared >= 2 && spread(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(X, Eigen::EigenvaluesOnly).eigenvalues(), shared)) continue;
        if (own_held >= 3) {
          const Eigen::Vector3d e = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(T, Eigen::EigenvaluesOnly).eigenvalues();
          if (!spread(e, own_held)) own_held = 0;
        } else {
          own_held = 0;
        }
      }
      // The best plane c·x = d among candidates, over the offsets still left; its count.
      left.assign(v.size(), 1);
      const auto count = [&](const Eigen::Vector3d& c, double d) {
        std::size_t held = 0;
        for (std::size_t a = 0; a < v.size(); ++a) held += left[a] && std::abs(c.dot(v[a]) - d) <= tol;
        return held;
      };
      const auto plane = [](const Eigen::Vector3d& x, const Eigen::Vector3d& y, const Eigen::Vector3d& z, Eigen::Vector3d& c) {
        const Eigen::Vector3d e = y - x, f = z - x;
        c = e.cross(f);
        const double len = c.norm();
        if (!(len > 0.25 * e.norm() * f.norm())) return false;  // within about 15° of a line
        c /= len;
        return true;
      };
      // A candidate refitted to its points, or refused (held 0); held: those left that it holds.
      const auto refine = [&](const Plane& c, bool through) {
        // Its points: all it holds, those another plane explained too (an edge's, on both faces;
        // a face beside an edge, its own points alone, may be a row along it), and the point.
        const auto holds = [&](std::size_t a) { return std::abs(c.c.dot(v[a]) - c.d) <= tol; };
        const bool holds_point = through || std::abs(c.d) <= tol;
        // (A plane across a corner's three faces holds points whose normals all lie 55° off it; a
        // face's rounded or averaged ones lean only near its edges.)
        std::size_t held = 0, agree = 0, close = 0;
        for (std::size_t a = 0; a < v.size(); ++a)
          if (holds(a)) {
            const double along = std::abs(c.c.dot(m.normals[id[a]]));
            ++held, agree += along >= kAgree, close += along >= kClose;
          }
        if (2 * agree < held) return Plane{c.c, c.d, 0};
        // The least-squares plane of its points whose normals lie within acos(within) of it,
        // unless they lie along a line (at a box's corners such planes turned normals 60-90° off
        // every face). Through the point: the moments about it.
        const auto fit_to = [&](double within, Eigen::Vector3d& f, double& d) {
          const auto used = [&](std::size_t a) { return holds(a) && std::abs(c.c.dot(m.normals[id[a]])) >= within; };
          Eigen::Vector3d mean = Eigen::Vector3d::Zero();
          std::size_t count_used = holds_point ? 1 : 0;
          for (std::size_t a = 0; a < v.size(); ++a)
            if (used(a)) mean += v[a], ++count_used;
          if (count_used < 3) return false;
          mean /= double(count_used);
          Eigen::Matrix3d S = holds_point ? Eigen::Matrix3d(mean * mean.transpose()) : Eigen::Matrix3d::Zero(), T = Eigen::Matrix3d::Zero();
          for (std::size_t a = 0; a < v.size(); ++a)
            if (used(a)) {
              S += (v[a] - mean) * (v[a] - mean).transpose();
              T += v[a] * v[a].transpose();
            }
          const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> fit(through ? T : S);
          if (!spread(fit.eigenvalues(), count_used)) return false;
          if (through && count_used >= 4) {
            // The point must lie on its points' own plane: a side face's point 1.5 tol below a
            // prism's top took the top's points, a plane through it tilted 0.8° to reach them.
            const std::size_t own = count_used - 1;
            const Eigen::Vector3d centre = mean * (double(count_used) / double(own));
            Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
            for (std::size_t a = 0; a < v.size(); ++a)
              if (used(a)) C += (v[a] - centre) * (v[a] - centre).transpose();
            const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> apart(C);
            // (Its points along a line, the point beside it: a plane through the point and a row
            // of another face's points, turned 17° off it beside a plate's edge.)
            if (!spread(apart.eigenvalues(), own) || std::abs(apart.eigenvectors().col(0).dot(centre)) > tol) return false;
          }
          f = fit.eigenvectors().col(0);
          if (f.dot(c.c) < 0) f = -f;
          d = through ? 0.0 : f.dot(mean);
          return true;
        };
        // Those within 30° first where three or more are (another face's points near their common
        // edge, within tol of it, tilted the fit 2° beside a box's inner corner); those within 60°
        // where they lie along a line (a row of a face's points beside an edge, with the edge's
        // averaged or rounded normals; not the other face's).
        Eigen::Vector3d f;
        double d = 0;
        if (!(close >= 3 && fit_to(kClose, f, d)) && !fit_to(kAgree, f, d)) return Plane{c.c, c.d, 0};
        const Plane r{f, d, count(c.c, c.d)};
        // The candidate itself where the fit holds fewer of those left (the candidate's are within
        // tol, the fit's may not be).
        return count(r.c, r.d) >= r.held ? r : Plane{c.c, c.d, r.held};
      };
      std::array<Plane, 3> planes{};
      std::size_t found_planes = 0;
      {
        // Candidates by how many they hold; the first that refine keeps, of the first
        // kFirstTries apart by a degree (a plane through the point and a row of another face's
        // points can hold as many as its own face's beside a plate's edge).
        constexpr std::size_t kFirstTries = 3;
        const std::size_t near = std::min<std::size_t>(10, v.size());
        tried.clear();
        Eigen::Vector3d c;
        for (std::size_t a = 0; a < near; ++a)
          for (std::size_t b = a + 1; b < near; ++b)
            if (plane(Eigen::Vector3d::Zero(), v[a], v[b], c))
              if (const std::size_t held = count(c, 0.0); held >= 4) tried.push_back({c, 0.0, held});
        std::stable_sort(tried.begin(), tried.end(), [](const Plane& x, const Plane& y) { return x.held > y.held; });
        // (A candidate holds the two it was made from whatever it is.)
        if (tried.empty() || own_held + 2 >= tried.front().held) continue;
        std::size_t tries = 0, kept = 0;
        for (std::size_t t = 0; t < tried.size() && tries < kFirstTries; ++t) {
          if (std::any_of(tried.begin(), tried.begin() + std::ptrdiff_t(t), [&](const Plane& q) { return std::abs(q.c.dot(tried[t].c)) >= kSameNormal; }))
            continue;
          ++tries;
          planes[0] = refine(tried[t], true);
          kept = t;
          if (planes[0].held > 0) break;
        }
        // (The plane kept, not only the best, must hold more than the point's own normal's.)
        if (planes[0].held == 0 || own_held + 2 >= tried[kept].held) continue;
        found_planes = 1;
      }
      bool explained = false;
      while (true) {
        const Plane& last = planes[found_planes - 1];
        for (std::size_t a = 0; a < v.size(); ++a)
          if (left[a] && std::abs(last.c.dot(v[a]) - last.d) <= tol) left[a] = 0;
        rest.clear();
        for (std::size_t a = 0; a < v.size(); ++a)
          if (left[a]) rest.push_back(a);
        if (rest.size() <= kStray) {
          explained = true;
          break;
        }
        if (found_planes == planes.size()) break;
        Plane best{Eigen::Vector3d::Zero(), 0.0, 0};
        const std::size_t first = std::min<std::size_t>(6, rest.size());
        Eigen::Vector3d c;
        for (std::size_t a = 0; a < first; ++a)
          for (std::size_t b = a + 1; b <= first && b <= rest.size(); ++b) {
            // the second of the rest, or the point itself (b == first)
            const Eigen::Vector3d y = b < first ? v[rest[b]] : Eigen::Vector3d::Zero();
            for (std::size_t z = 0; z <= v.size(); ++z) {
              const Eigen::Vector3d x3 = z < v.size() ? v[z] : Eigen::Vector3d::Zero();
              if (!plane(v[rest[a]], y, x3, c)) continue;
              const double d = c.dot(v[rest[a]]);
              if (const std::size_t held = count(c, d); held > best.held) best = {c, d, held};
            }
          }
        if (best.held < 3) break;
        planes[found_planes] = refine(best, false);
        if (planes[found_planes++].held == 0) break;
      }
      // One plane with strays beside it: the strays' face is no plane here (a curved face's
      // rim), so no crease cut would stop this point's disc at it; left as it is (fandisk's
      // vertices at 3e-3: 2.6 % of the pixels beyond 2E where 0.15 % were).
      if (!explained || (found_planes == 1 && !rest.empty())) continue;
      if (std::any_of(planes.begin(), planes.begin() + std::ptrdiff_t(found_planes),
                      [&](const Plane& q) { return std::abs(q.d) <= tol && std::abs(q.c.dot(nrm)) >= kSameNormal; }))
        continue;
      // Orientation: each along the normals of the points it holds alone (not an edge's), the
      // first along the point's own too. (By the point's own alone, at a tetrahedron's 70°
      // edges, where a PCA normal can lean more than 90° off its face, 22 points' discs faced
      // inwards and drew fins there: 0.07 % of the pixels beyond 2E at 3e-3 became 0.7 %.)
      std::array<double, 3> sign{};
      sign[0] = planes[0].c.dot(nrm);
      for (std::size_t a = 0; a < v.size(); ++a) {
        std::size_t on = 0, which = 0;
        for (std::size_t q = 0; q < found_planes; ++q)
          if (std::abs(planes[q].c.dot(v[a]) - planes[q].d) <= tol) ++on, which = q;
        if (on == 1) sign[which] += planes[which].c.dot(m.normals[id[a]]);
      }
      if (std::any_of(sign.begin(), sign.begin() + std::ptrdiff_t(found_planes), [](double x) { return std::abs(x) < 0.1; }))
        continue;
      // Oriented, the faces turn from each other by more than acos(crease_cos) and less than the
      // reverse of acos(knife_cos): a knife edge's faces (a 30° wedge's turn 150°) are faces too.
      // (Unoriented, as before knife_cos, they had to turn less than 139°: the wedge's edge kept
      // PCA's rounded normals, its discs uncut, and its data stood 32E past the edge at 1e-3.)
      // A plane turned past that, off the point, is a thin part's far side (its rounded or noisy
      // normals within 166° of the point's, so among the neighbours since knife_cos): no reason
      // to leave the point as it is (a plate 1 × 1 × 0.02 without normals: 14,377 faced points
      // became 6,916 and its discs 6.5 % → 14.6 % beyond 2E of the plate; a reviewer's case).
      bool apart = true;
      for (std::size_t a = 0; a < found_planes; ++a)
        for (std::size_t b = a + 1; b < found_planes; ++b) {
          const double turn = (sign[a] > 0 ? 1.0 : -1.0) * (sign[b] > 0 ? 1.0 : -1.0) * planes[a].c.dot(planes[b].c);
          if (o.knife_cos > o.crease_cos && turn <= -o.knife_cos && std::abs(planes[b].d) > tol) continue;
          apart = apart && turn < o.crease_cos && turn > -o.knife_cos;
        }
      if (!apart) continue;
      face[i] = sign[0] > 0 ? planes[0].c : Eigen::Vector3d(-planes[0].c);
      for (std::size_t q = 1; q < found_planes; ++q)
        if (std::abs(planes[q].d) <= tol) out.emplace_back(i, sign[q] > 0 ? planes[q].c : Eigen::Vector3d(-planes[q].c));
    }
  });
  // Then the faces' planes spread to the points beside the edges that the above left: PCA's
  // normals lean there a degree or two (a plate 1 x 1 x 0.05 without normals kept 740 points
  // beside its edges rounded, their discs uncut past the edges: the crease cuts take planar points
  // only). In each of kSpread rounds, a point not yet faced takes the plane of the nearest faced
  // point whose plane it lies on (within tol), facing its own side (a point a spacing from an
  // edge can lean 75° towards the other face: a box 1 x 0.6 x 0.3 of 20,000 points kept 45
  // such points rounded more than 2° where only normals within 30° took the plane, now 14).
  // (A rule for a point whose own face's plane alone was found, taken where the other face's
  // points took theirs, changed 1 point of the box and none of a thin plate with this one.)
  // The plane must hold three quarters of the point's nearest whose normals (their faces' where
  // they have one) lie within 30° of it, spread across it (across a fifth of their length): a
  // cylinder's tangent plane holds a band along its axis, and without this the planes spread
  // along such bands to a third of a cylinder's points (radius 40 spacings), 3° off at most.
  const auto holds_around = [&](const std::vector<Neighbour>& nb, const Eigen::Vector3d& x, const Eigen::Vector3d& f,
                                double tol) {
    std::size_t close = 0, held = 0;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
    for (const auto& [j, d2] : nb)
      if ((face[j].squaredNorm() > 0 ? face[j] : m.normals[j]).dot(f) >= kClose) {
        ++close;
        const Eigen::Vector3d v = m.points[j] - x;  // (offsets: a model far from the origin)
        if (std::abs(f.dot(v)) <= tol) ++held, mean += v, S += v * v.transpose();
      }
    if (held < 4 || 4 * held < 3 * close) return false;
    mean /= double(held);
    const Eigen::Vector3d lambda =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(S / double(held) - mean * mean.transpose(), Eigen::EigenvaluesOnly).eigenvalues();
    return lambda(2) > 0 && lambda(1) >= 0.04 * lambda(2);
  };
  // Only the points near those faced in the round before are asked (twice as many nearest as
  // they ask: neighbourhoods are not symmetric).
  constexpr int kSpread = 3;
  std::vector<std::uint32_t> fresh, asked;
  for (std::size_t i = 0; i < n; ++i)
    if (face[i].squaredNorm() > 0) fresh.push_back(std::uint32_t(i));
  std::vector<std::uint8_t> is_asked(n, 0);
  for (int round = 0; round < kSpread && !fresh.empty(); ++round) {
    asked.clear();
    {
      std::vector<Neighbour> nb;
      for (const std::uint32_t j : fresh) {
        m.index->nearest(m.points[j], 2 * k, nb);
        for (const auto& [i, d2] : nb)
          if (face[i].squaredNorm() == 0 && !is_asked[i]) is_asked[i] = 1, asked.push_back(std::uint32_t(i));
      }
      for (const std::uint32_t i : asked) is_asked[i] = 0;
    }
    std::vector<Eigen::Vector3d> taken(asked.size(), Eigen::Vector3d::Zero());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, asked.size(), 256), [&](const auto& r) {
      std::vector<Neighbour> nb;
      for (std::size_t a = r.begin(); a != r.end(); ++a) {
        const std::uint32_t i = asked[a];
        const Eigen::Vector3d &p = m.points[i], &nrm = m.normals[i];
        const double tol = tol_of[i];
        if (!(tol > 0)) continue;
        m.index->nearest(p, k, nb);
        for (const auto& [j, d2] : nb) {
          const Eigen::Vector3d& f = face[j];
          if (j == i || f.squaredNorm() == 0 || m.normals[j].dot(nrm) < -0.2) continue;
          if (f.dot(nrm) > 0 && std::abs(f.dot(m.points[j] - p)) <= tol && holds_around(nb, m.points[j], f, tol)) {
            taken[a] = f;
            break;
          }
        }
      }
    });
    fresh.clear();
    for (std::size_t a = 0; a < asked.size(); ++a)
      if (taken[a].squaredNorm() > 0) face[asked[a]] = taken[a], fresh.push_back(asked[a]);
  }
  m.faced.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    if (face[i].squaredNorm() > 0) {
      m.faced[i] = 1;
      // A normal within 1° of its face's is kept (a face's exact or given normal, spread to).
      if (face[i].dot(m.normals[i]) >= kSameNormal) continue;
      m.normals[i] = face[i];
      ++m.crease_points;
    }
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> copies;
  for (auto& f : found) copies.insert(copies.end(), f.begin(), f.end());
  if (copies.empty()) return;
  std::sort(copies.begin(), copies.end(), [](const auto& x, const auto& y) {  // the threads' order aside
    return std::tie(x.first, x.second.x(), x.second.y(), x.second.z()) < std::tie(y.first, y.second.x(), y.second.y(), y.second.z());
  });
  m.index.reset();  // its span is the points, about to grow
  for (const auto& [i, c] : copies) m.points.push_back(m.points[i]), m.normals.push_back(c), m.faced.push_back(1);
  m.crease_copies = copies.size();
  m.index = std::make_unique<PointIndex>(std::span<const Eigen::Vector3d>(m.points));
}

DataSurface DataSurface::from_mesh(const PolygonMesh& mesh) {
  DataSurface s;
  auto& m = *s.impl_;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto vs = mesh.face(f);
    for (std::size_t k = 1; k + 1 < vs.size(); ++k) {
      const Eigen::Vector3d &a = mesh.vertices[vs[0]], &b = mesh.vertices[vs[k]], &c = mesh.vertices[vs[k + 1]];
      // A degenerate triangle (a pole's sliver of a lat-long grid) carries no surface, but a ray
      // along an edge of it "hits" it with no defined side: the probe heights then start inside.
      const double L2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
      if (is_sliver((b - a).cross(c - a).norm(), L2)) continue;
      m.triangles.push_back({a, b, c});
    }
  }
  if (m.triangles.empty()) throw InvalidInput("DataSurface: the mesh has no faces (of non-zero area)");
  // The triangles' BVH is built while the open boundary is found.
  std::vector<Box3> boxes;
  tbb::parallel_invoke(
      [&] {
        boxes.reserve(m.triangles.size());
        for (const auto& t : m.triangles) {
          Box3 b;
          for (const auto& v : t) b.extend(v);
          boxes.push_back(b);
        }
        m.bvh = Bvh(boxes);
      },
      [&] { from_mesh_boundary(mesh, m); });
  return s;
}

void DataSurface::from_mesh_boundary(const PolygonMesh& mesh, Impl& m) {
  // Open edges (used by one face): their vertices and midpoints, with the tangent into the face.
  // Edge uses by sorting (with a std::map here from_mesh was 6.7 % of a bunny fit profile).
  const EdgeUses uses(mesh);
  std::map<int, Eigen::Vector3d> vertex_inward;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto vs = mesh.face(f);
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const int v : vs) centroid += mesh.vertices[v];
    centroid /= double(vs.size());
    for (std::size_t k = 0; k < vs.size(); ++k) {
      const int a = vs[k], b = vs[(k + 1) % vs.size()];
      if (!uses.open(a, b)) continue;
      const Eigen::Vector3d e = (mesh.vertices[b] - mesh.vertices[a]).normalized();
      const Eigen::Vector3d mid = 0.5 * (mesh.vertices[a] + mesh.vertices[b]);
      Eigen::Vector3d in = centroid - mid;
      in -= in.dot(e) * e;
      if (!(in.norm() > 0) || !e.allFinite()) continue;
      in.normalize();
      m.boundary.samples.push_back({mid, in});
      m.open_edges.push_back({mesh.vertices[a], mesh.vertices[b]});
      m.open_edge_half = std::max(m.open_edge_half, 0.5 * (mesh.vertices[b] - mesh.vertices[a]).norm());
      for (const int v : {a, b}) {
        auto [it, fresh] = vertex_inward.try_emplace(v, Eigen::Vector3d::Zero());
        it->second += in;
      }
    }
  }
  for (const auto& [v, in] : vertex_inward)
    if (in.norm() > 0) m.boundary.samples.push_back({mesh.vertices[v], in.normalized()});
  m.boundary.index_them();
  m.wound_inward = uses.wound_inward(mesh);
}

bool DataSurface::has_faces() const { return !impl_->triangles.empty(); }
double DataSurface::disc_radius(std::size_t i) const { return impl_->disc.at(i); }
const Eigen::Vector3d& DataSurface::normal(std::size_t i) const { return impl_->normals.at(i); }
std::size_t DataSurface::crease_points() const { return impl_->crease_points; }
std::size_t DataSurface::crease_copies() const { return impl_->crease_copies; }
bool DataSurface::faced(std::size_t i) const { return i < impl_->faced.size() && impl_->faced[i] != 0; }
bool DataSurface::planar(std::size_t i) const { return i < impl_->planar.size() && impl_->planar[i] != 0; }
double DataSurface::spacing(std::size_t i) const { return impl_->spacing.at(i); }
void DataSurface::boundary_near(const Eigen::Vector3d& c, double r, std::vector<BoundarySample>& out, bool crease_sides) const {
  out.clear();
  thread_local std::vector<Neighbour> nb;
  impl_->boundary.near(c, r, out, nb);
  if (crease_sides) impl_->crease_sides.near(c, r, out, nb);
}

void DataSurface::past_boundary(const Eigen::Vector3d& c, double r, std::span<const double> offsets, std::vector<Ray>& out) const {
  out.clear();
  const auto& b = impl_->boundary;
  if (!b.index || b.normals.empty()) return;
  thread_local std::vector<Neighbour> nb;
  // A rim point outside the ball may still have its lines cross it.
  const double farthest = offsets.empty() ? 0.0 : *std::max_element(offsets.begin(), offsets.end());
  b.index->radius(c, r + b.widest_reach + farthest, nb);
  for (const auto& [k, d2] : nb)
    if (b.rim[k])
      for (const double off : offsets) {
        const Ray line{b.samples[k].point - (b.reach[k] + off) * b.samples[k].inward, b.normals[k]};
        const Eigen::Vector3d v = c - line.origin;
        if ((v - v.dot(line.dir) * line.dir).squaredNorm() < r * r) out.push_back(line);
      }
}

double DataSurface::lipschitz() const { return impl_->lipschitz; }

Eigen::Matrix3d DataSurface::bend_tensor(std::size_t i) const {
  const auto& m = *impl_;
  return m.bend.empty() ? Eigen::Matrix3d::Zero() : Eigen::Matrix3d(m.bend[i].cast<double>());
}

double DataSurface::bend_height(std::size_t i, const Eigen::Vector3d& t) const {
  return impl_->bend_height(std::uint32_t(i), t);
}

bool DataSurface::near_open_boundary(const Eigen::Vector3d& x, double r) const {
  const auto& m = *impl_;
  if (!m.boundary.index) return false;
  thread_local std::vector<Neighbour> nb;
  // An edge's points lie within half its length of its midpoint.
  m.boundary.index->radius(x, r + m.open_edge_half, nb);
  for (const auto& [i, d2] : nb) {
    if (i >= m.open_edges.size()) {
      if (d2 <= r * r) return true;
      continue;
    }
    const auto& [a, b] = m.open_edges[i];
    const Eigen::Vector3d ab = b - a;
    const double L2 = ab.squaredNorm();
    const double s = L2 > 0 ? std::clamp((x - a).dot(ab) / L2, 0.0, 1.0) : 0.0;
    if ((a + s * ab - x).squaredNorm() <= r * r) return true;
  }
  return false;
}

double DataSurface::distance(const Eigen::Vector3d& x, double cap, double good) const {
  const auto& m = *impl_;
  thread_local Hints hints;
  hints.use_for(m.serial);
  if (!m.triangles.empty()) {
    // BVH walk in squared distances, nearest box first, pruning boxes farther than the best
    // triangle so far (or than the cap).
    const double cap2 = cap * cap * (1.0 + 1e-12), good2 = good * good;
    double best = cap2;
    // Queries come in runs along one patch: the triangles nearest the last few queries of this
    // thread (same surface) give a first upper bound, often good enough to stop at once. The
    // walk below stays exact: it only prunes boxes farther than a distance already reached.
    std::uint32_t best_id = hints.ids[0];
    for (const std::uint32_t id : hints.ids) {
      const auto& t = m.triangles[id];
      if (const double d2 = point_triangle_distance2(x, t[0], t[1], t[2]); d2 < best) best = d2, best_id = id;
    }
    if (best <= good2) {
      hints.remember(best_id);
      return std::sqrt(best);
    }
    m.bvh.nearest(x, best, good2, [&](std::uint32_t id) {
      const auto& t = m.triangles[id];
      if (const double d2 = point_triangle_distance2(x, t[0], t[1], t[2]); d2 < best) best = d2, best_id = id;
    });
    if (!(best < cap2)) return kInf;
    hints.remember(best_id);
    return std::sqrt(best);
  }
  // The distance to the union of every point's disc: each disc's distance is lipschitz()-Lipschitz
  // (1 for flat discs), so is their minimum. As for a mesh: queries come in runs along one patch,
  // so the discs nearest this thread's last few queries give a first bound, and one within good
  // settles "within good?".
  // Then every disc whose box lies nearer, nearest box first. (The discs of the 12 points nearest
  // x, which this asked until now, are not enough: a query 0.4E past where one disc held it at
  // 0.2E lost that disc from its 12 nearest and read 3.2E beside a densely sampled scan line —
  // radar.xyz at 1e-2, where the fit's lattice check and bench fit's views saw fins that were
  // not there.)
  double best = kInf;
  std::uint32_t best_id = hints.ids[0];
  for (const std::uint32_t i : hints.ids)
    if (const double d = m.disc_distance(i, x); d < best) best = d, best_id = i;
  if (best <= good) return best;
  const double cap2 = cap * cap * (1.0 + 1e-12);
  double best2 = std::min(best * best, cap2);
  m.discs().nearest(x, best2, good * good, [&](std::uint32_t i) {
    // A disc lies no nearer than its point less its radius (and its bend's height): most items
    // of a leaf go by that.
    const double reach = m.reach_of_bend(i);
    const double far = (x - m.points[i]).norm() - (reach == 0.0 ? m.disc[i] : std::hypot(m.disc[i], reach));
    if (far > 0 && far * far >= best2) return;
    if (const double d = m.disc_distance(i, x); d * d < best2) best2 = d * d, best = d, best_id = i;
  });
  if (!(best <= cap)) return kInf;
  hints.remember(best_id);
  return best;
}

std::optional<double> DataSurface::intersect(const Ray& ray, double tmin, bool* front, double tmax) const {
  const auto hit = first_hit(ray, tmin, tmax);
  if (!hit) return std::nullopt;
  if (front) *front = hit->front;
  return hit->t;
}

std::optional<DataSurface::RayHit> DataSurface::first_hit(const Ray& ray, double tmin, double tmax) const {
  const auto& m = *impl_;
  double best = tmax;
  RayHit hit;
  if (m.triangles.empty()) {
    // Points: the nearest tangent disc the ray crosses (the union of discs distance() measures
    // to); front when the disc's normal faces the ray. Of discs crossed at the same depth (a
    // plane's, all in one plane), the one whose point is nearest relative to its spacing.
    std::uint32_t best_i = 0;
    double best_rel = std::numeric_limits<double>::infinity();
    const auto tie = [&] { return 1e-9 * std::max(1.0, std::abs(best) < kInf ? std::abs(best) : 1.0); };
    m.discs().traverse(ray, tmin, [&] { return best < tmax ? best + tie() : best; }, [&](std::uint32_t i) {
      if (!(m.disc[i] > 0)) return;
      const double d = m.disc_hit(i, ray, tmin, std::min(tmax, best + tie()));
      if (!(d < kInf)) return;
      const double rel = (ray.at(d) - m.points[i]).norm() / std::max(m.spacing[i], 1e-300);
      if (d < best - tie() || rel < best_rel) best = std::min(best, d), best_i = i, best_rel = rel;
    });
    if (!(best < tmax)) return std::nullopt;
    hit.t = best;
    hit.normal = m.disc_normal(best_i, ray.at(best));
    hit.front = hit.normal.dot(ray.dir) < 0.0;
    hit.reach = m.disc[best_i];
    hit.from_sample = (ray.at(best) - m.points[best_i]).norm();
    hit.spacing = m.spacing[best_i];
    return hit;
  }
  std::uint32_t best_i = 0;
  bool best_front = false;
  m.bvh.traverse(ray, tmin, [&] { return best; }, [&](std::uint32_t i) {
    // Möller–Trumbore in double, both sides.
    const auto& t = m.triangles[i];
    const Eigen::Vector3d e1 = t[1] - t[0], e2 = t[2] - t[0];
    const Eigen::Vector3d p = ray.dir.cross(e2);
    const double det = e1.dot(p);
    if (det == 0.0) return;
    const double inv = 1.0 / det;
    const Eigen::Vector3d s = ray.origin - t[0];
    const double u = s.dot(p) * inv;
    if (u < 0.0 || u > 1.0) return;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = ray.dir.dot(q) * inv;
    if (v < 0.0 || u + v > 1.0) return;
    const double d = e2.dot(q) * inv;
    if (d > tmin && d < best) best = d, best_front = det > 0.0, best_i = i;
  });
  if (!(best < tmax)) return std::nullopt;
  hit.t = best;
  hit.front = best_front != m.wound_inward;
  const auto& t = m.triangles[best_i];
  hit.normal = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
  if ((hit.normal.dot(ray.dir) < 0.0) != hit.front) hit.normal = -hit.normal;  // outward
  return hit;
}

double zero_set_excess(const SlimPatch& patch, const DataSurface& data, double bound, int grid, int max_depth) {
  struct Cell {
    int axis;
    double a, b, h;  // line through (a, b) in the two other local coordinates; cell side h
    int depth;
  };
  // A sheet point of the cell is within reach of the cell's sample on the best-aligned axis
  // (|n·axis| ≥ 1/√3): half the cell diagonal, stretched by at most √3 along the sheet.
  constexpr double kReach = 0.7071 * 1.7321;
  constexpr double kAligned = 0.57;
  // Reused by the thread's next call (a 64² lattice pushes 12,288 cells: allocating them afresh
  // showed as malloc and memmove in a fit's profile).
  thread_local std::vector<Cell> stack;
  stack.clear();
  const double h0 = 2.0 / grid;
  for (int axis = 0; axis < 3; ++axis)
    for (int i = 0; i < grid; ++i)
      for (int j = 0; j < grid; ++j) stack.push_back({axis, -1.0 + (i + 0.5) * h0, -1.0 + (j + 0.5) * h0, h0, 0});
  const double min_reach = bound / 16.0;
  // A clipped patch reaches farthest along its clip planes: the curve where its zero set meets a
  // plane (inside the others) is sampled at a spacing of bound/2 (a tilted cut past an open
  // boundary leaves a wedge thinner than the lattice spacing; bunny-size balls are hundreds of E
  // across).
  for (const ClipPlane& plane : patch.clips) {
    const double nn = plane.n.norm();
    if (!(nn > 0)) continue;
    const Eigen::Vector3d n = plane.n / nn;
    const double off = plane.d / nn;  // plane: n·u + off = 0
    if (std::abs(off) < 1.0) {
      const double r = std::sqrt(1.0 - off * off);
      const Eigen::Vector3d p0 = -off * n;
      const Eigen::Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
      const double step = std::max(0.5 * bound / patch.radius, 2.0 * r / 4096.0);
      const int lines = static_cast<int>(std::ceil(2.0 * r / step));
      for (int axis = 0; axis < 2; ++axis) {
        const Eigen::Vector3d& along = axis == 0 ? e1 : e2;
        const Eigen::Vector3d& across = axis == 0 ? e2 : e1;
        for (int i = 0; i < lines; ++i) {
          const Ray line{p0 + (-r + (i + 0.5) * step) * across, along};
          const Roots roots = solve_ray_quadratic(ray_quadratic(patch.local, line));
          for (int k = 0; k < roots.count; ++k) {
            const Eigen::Vector3d u = line.at(roots.t[k]);
            if (!(u.squaredNorm() < 1.0) || !patch.clips.keeps(u + 1e-9 * n)) continue;
            const Eigen::Vector3d x = patch.centre + patch.radius * u;
            const double d = data.distance(x, bound, bound);
            if (!(d <= bound)) return std::isnan(d) ? kInf : data.distance(x);
          }
        }
      }
    }
  }
  // Past a cloud's open boundary: a large ball's zero set running on past the rim, where it
  // leaves the ball a sliver thinner than the lattice's spacing, is met on lines along the
  // boundary points' normals 1.25, 2, 3 and 5 bounds past where their discs end (an open cylinder
  // fitted at 1e-3: 0.04 % of its pixels 2-8E from its data, unseen, once the data stopped at the
  // rim, DataSurface::cut_at_rims).
  {
    thread_local std::vector<Ray> past;
    const std::array<double, 4> offsets{1.25 * bound, 2.0 * bound, 3.0 * bound, 5.0 * bound};
    data.past_boundary(patch.centre, patch.radius, offsets, past);
    for (const Ray& w : past) {
      const Ray line{(w.origin - patch.centre) / patch.radius, w.dir};
      const Roots roots = solve_ray_quadratic(ray_quadratic(patch.local, line));
      for (int k = 0; k < roots.count; ++k) {
        const Eigen::Vector3d u = line.at(roots.t[k]);
        if (!(u.squaredNorm() < 1.0) || !patch.clips.keeps(u)) continue;
        const Eigen::Vector3d x = patch.centre + patch.radius * u;
        const double d = data.distance(x, bound, bound);
        if (!(d <= bound)) return std::isnan(d) ? kInf : data.distance(x);
      }
    }
  }
  std::size_t met = 0;  // zero-set points the lattice met inside the ball
  while (!stack.empty()) {
    const Cell c = stack.back();
    stack.pop_back();
    const int a1 = (c.axis + 1) % 3, a2 = (c.axis + 2) % 3;
    // Cells wholly outside the ball's cross-section hold no part of the zero set.
    const double ea = std::max(0.0, std::abs(c.a) - 0.5 * c.h), eb = std::max(0.0, std::abs(c.b) - 0.5 * c.h);
    if (ea * ea + eb * eb >= 1.0) continue;  // (std::hypot: 5 % of a fit at 1e-4)
    Ray line;
    line.origin = Eigen::Vector3d::Zero();
    line.origin[a1] = c.a;
    line.origin[a2] = c.b;
    line.dir = Eigen::Vector3d::Unit(c.axis);
    const Roots roots = solve_ray_quadratic(ray_quadratic(patch.local, line));
    const double reach = kReach * c.h * patch.radius * data.lipschitz();
    bool split = false;
    for (int k = 0; k < roots.count; ++k) {
      const Eigen::Vector3d u = line.at(roots.t[k]);
      if (!(u.squaredNorm() < 1.0) || !patch.clips.keeps(u)) continue;
      ++met;
      const Eigen::Vector3d x = patch.centre + patch.radius * u;
      const Eigen::Vector3d g = patch.local.gradient(u);
      const bool may_split = std::abs(g[c.axis]) >= kAligned * g.norm() && reach > min_reach && c.depth < max_depth;
      // Any triangle within the bound settles "within?" (d is then an upper bound on the distance:
      // the nearest of the triangles this thread met last, mostly the nearest of all). A cell
      // whose reach is past the bound splits whatever the distance, so it asks no more: asking
      // every sample for the minimum that would vouch for its cell cost a BVH walk each (36 % of
      // a bunny fit at 1e-4, whose lattice's first cells all reach past the bound). Elsewhere the
      // cell splits unless the distance vouches for it, asked as before where the upper bound
      // does not: the lattice, and so the fit, does not depend on which triangles the thread met.
      const double d = data.distance(x, bound, bound);
      if (!(d <= bound)) return std::isnan(d) ? kInf : data.distance(x);
      if (may_split && d + reach > bound)
        split = reach >= bound || data.distance(x, bound, bound - reach) + reach > bound;
    }
    if (!split) continue;
    const double q = 0.25 * c.h;
    for (const double da : {-q, q})
      for (const double db : {-q, q}) stack.push_back({c.axis, c.a + da, c.b + db, 0.5 * c.h, c.depth + 1});
  }
  // A zero set thinner than the lattice's spacing falls between its lines: a wire fitted at an E
  // of its radius came out as a cylinder 1/500 of its ball across that ran 2 units (100 bounds)
  // past the data's ends, and the check met nothing. Where the lattice met (almost) nothing,
  // lines along each principal axis of the quadratic part, through the planes of the other axes
  // at the quadric's centre, spaced bound/2, meet such a tube or needle wherever it runs.
  if (met < 4) {
    double excess = 0.0;
    for_thin_zero_set(patch, 0.5 * bound / patch.radius, [&](const Eigen::Vector3d& u) {
      const Eigen::Vector3d x = patch.centre + patch.radius * u;
      const double d = data.distance(x, bound, bound);
      if (d <= bound) return true;
      excess = std::isnan(d) ? kInf : data.distance(x);
      return false;
    });
    if (excess > 0) return excess;
  }
  return 0.0;
}

}  // namespace quadrix
