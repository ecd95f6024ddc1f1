#include "convert/to_mesh.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <span>
#include <numeric>
#include <numbers>
#include <optional>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include <fmt/format.h>

#include "convert/between_views.h"
#include "convert/kuhn_bisection.h"
#include "convert/mesh_measure.h"
#include "convert/mesh_union.h"
#include "core/bounds.h"
#include "core/culling.h"
#include "core/implicit/surface.h"
#include "core/error.h"
#include "core/log.h"
#include "core/reference.h"
#include "core/slim.h"
#include "fit/data_surface.h"
#include "fit/point_index.h"
#include "fit/surface_error.h"

namespace quadrix {
namespace {

constexpr int kPermutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};

bool has_any_colour(const Model& m) {
  for (const auto& s : m.slims)
    if (s.colour) return true;
  for (const auto& t : m.tets)
    if (t.colour) return true;
  for (const auto& g : m.glyphs)
    if (g.colour) return true;
  return false;
}

/// Triangles being collected, with an optional colour per vertex.
/// The colour of a primitive that has none.
constexpr Rgb kDefaultGrey{200, 200, 200};

struct Builder {
  PolygonMesh mesh;
  bool colours = false;
  int add_vertex(const Eigen::Vector3d& p, const Rgb& c) {
    mesh.vertices.push_back(p);
    if (colours) mesh.colours.push_back(c);
    return static_cast<int>(mesh.vertices.size()) - 1;
  }
  void add_triangle(int a, int b, int c) {
    if (a == b || b == c || a == c) return;
    const int f[3] = {a, b, c};
    mesh.add_face(f);
  }
  /// The triangle wound so its normal has a positive component along `outward`.
  void add_triangle_facing(int a, int b, int c, const Eigen::Vector3d& outward) {
    const auto& V = mesh.vertices;
    if ((V[b] - V[a]).cross(V[c] - V[a]).dot(outward) < 0) std::swap(b, c);
    add_triangle(a, b, c);
  }
};

/// Marching tetrahedra on one tetrahedron: values at four nodes, positive outside. crossing(i, j)
/// gives the mesh vertex on the edge between local nodes i and j; triangles are oriented so their
/// normal points from the negative nodes to the positive ones.
template <typename Crossing>
void march(const std::array<Eigen::Vector3d, 4>& p, const std::array<double, 4>& f, Builder& out,
           Crossing&& crossing) {
  int pos[4], neg[4], np = 0, nn = 0;
  for (int i = 0; i < 4; ++i) (f[i] >= 0.0 ? pos[np++] : neg[nn++]) = i;
  if (np == 0 || nn == 0) return;
  Eigen::Vector3d cp = Eigen::Vector3d::Zero(), cn = Eigen::Vector3d::Zero();
  for (int i = 0; i < np; ++i) cp += p[pos[i]] / np;
  for (int i = 0; i < nn; ++i) cn += p[neg[i]] / nn;
  const Eigen::Vector3d outward = cp - cn;
  const auto emit = [&](int a, int b, int c) { out.add_triangle_facing(a, b, c, outward); };
  if (np == 1 || nn == 1) {
    const bool lone_pos = np == 1;
    const int lone = lone_pos ? pos[0] : neg[0];
    const int* others = lone_pos ? neg : pos;
    emit(crossing(lone, others[0]), crossing(lone, others[1]), crossing(lone, others[2]));
    return;
  }
  const int a = crossing(pos[0], neg[0]), b = crossing(pos[0], neg[1]), c = crossing(pos[1], neg[1]),
            d = crossing(pos[1], neg[0]);
  emit(a, b, c);
  emit(a, c, d);
}

/// Root in [0, 1] of the quadric along p + s(q − p) nearest the linear estimate, else that estimate.
double edge_root(const Quadric& f, const Eigen::Vector3d& p, const Eigen::Vector3d& q, double fp, double fq) {
  const double linear = fp / (fp - fq);
  const Eigen::Vector3d d = q - p;
  const double a = d.dot(f.A * d), b = 2.0 * d.dot(f.A * p + f.b), c = f.eval(p);
  double best = linear, best_gap = std::numeric_limits<double>::infinity();
  const auto consider = [&](double s) {
    if (s >= 0.0 && s <= 1.0 && std::abs(s - linear) < best_gap) {
      best = s;
      best_gap = std::abs(s - linear);
    }
  };
  if (std::abs(a) <= 1e-14 * (std::abs(b) + std::abs(c))) {
    if (b != 0.0) consider(-c / b);
  } else {
    const double disc = b * b - 4.0 * a * c;
    if (disc >= 0.0) {
      const double sq = std::sqrt(disc);
      const double qq = -0.5 * (b + std::copysign(sq, b));
      if (qq != 0.0) consider(c / qq);
      consider(qq / a);
    }
  }
  return std::clamp(best, 0.0, 1.0);
}

// ---- implicit surfaces --------------------------------------------------------------------------

/// Cells along an implicit's bounds' longest side at level 0; doubled per level, at most kMaxImplicitCells.
constexpr int kImplicitCells = 32;
constexpr int kMaxImplicitCells = 256;

/// An implicit surface (core/implicit) by marching tetrahedra over its bounds: a grid of
/// kImplicitCells << k cells along the longest side (at most kMaxImplicitCells), each cube split
/// in the 6 tetrahedra of Kuhn's split (the same diagonal in every cube, so neighbours share their
/// faces' triangulation), S's sign at the nodes (not finite: outside), each crossing found by
/// bisection on S along its grid edge, so the vertices lie on S = 0 to double precision. The mesh
/// is open where the bounds cut the surface: the renderer draws S = 0 inside them only.
void mesh_implicit(const ImplicitSurface& surface, int k, Builder& out) {
  const implicit::CompiledImplicit c = implicit::compile(surface);
  const Rgb colour = surface.colour.value_or(kDefaultGrey);
  const Eigen::Vector3d lo = c.bounds.min, extent = c.bounds.max - c.bounds.min;
  const int cells = std::min(kImplicitCells << std::min(k, 16), kMaxImplicitCells);
  Eigen::Vector3i n;
  for (int a = 0; a < 3; ++a) n[a] = std::max(1, static_cast<int>(std::ceil(cells * extent[a] / extent.maxCoeff())));
  const Eigen::Vector3d h = extent.cwiseQuotient(n.cast<double>());
  const Eigen::Vector3i nodes = n + Eigen::Vector3i::Ones();
  const auto index = [&](const Eigen::Vector3i& i) {
    return static_cast<std::uint64_t>(i.x()) + static_cast<std::uint64_t>(nodes.x()) * (i.y() + static_cast<std::uint64_t>(nodes.y()) * i.z());
  };
  const auto at = [&](const Eigen::Vector3i& i) -> Eigen::Vector3d {
    Eigen::Vector3d p;
    for (int a = 0; a < 3; ++a) p[a] = i[a] == n[a] ? c.bounds.max[a] : lo[a] + h[a] * i[a];
    return p;
  };
  const auto value = [&](const Eigen::Vector3d& p) {
    const double v = c.expression.value(p, c.parameters);
    return std::isfinite(v) ? v : 1.0;
  };
  std::vector<double> f(static_cast<std::size_t>(nodes.x()) * nodes.y() * nodes.z());
  tbb::parallel_for(0, nodes.z(), [&](int z) {
    for (int y = 0; y < nodes.y(); ++y)
      for (int x = 0; x < nodes.x(); ++x) {
        const Eigen::Vector3i i(x, y, z);
        f[index(i)] = value(at(i));
      }
  });
  std::unordered_map<std::uint64_t, int> vertex_of_edge;  // key: lower node · node count + upper node
  const std::uint64_t total = f.size();
  constexpr int kPermutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int z = 0; z < n.z(); ++z)
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x) {
        const Eigen::Vector3i base(x, y, z);
        for (const auto& perm : kPermutations) {
          std::array<Eigen::Vector3i, 4> node;
          node[0] = base;
          for (int j = 0; j < 3; ++j) node[j + 1] = node[j] + Eigen::Vector3i::Unit(perm[j]);
          std::array<Eigen::Vector3d, 4> p;
          std::array<double, 4> v;
          std::array<std::uint64_t, 4> id;
          bool positive = false, negative = false;
          for (int j = 0; j < 4; ++j) {
            id[j] = index(node[j]);
            p[j] = at(node[j]);
            v[j] = f[id[j]];
            (v[j] >= 0.0 ? positive : negative) = true;
          }
          if (!positive || !negative) continue;
          march(p, v, out, [&](int i, int j) {
            const std::uint64_t a = std::min(id[i], id[j]), b = std::max(id[i], id[j]);
            const auto [it, fresh] = vertex_of_edge.try_emplace(a * total + b, 0);
            if (!fresh) return it->second;
            // Bisection between the nodes' positions (signs as march splits them: ≥ 0 and < 0).
            Eigen::Vector3d in = v[i] < 0.0 ? p[i] : p[j], outside = v[i] < 0.0 ? p[j] : p[i];
            for (int step = 0; step < 60 && (outside - in).squaredNorm() > 0.0; ++step) {
              const Eigen::Vector3d mid = 0.5 * (in + outside);
              if (mid == in || mid == outside) break;
              (value(mid) >= 0.0 ? outside : in) = mid;
            }
            it->second = out.add_vertex(0.5 * (in + outside), colour);
            return it->second;
          });
        }
      }
}

// ---- tetrahedron patches ----------------------------------------------------------------------

// An edge between vertices a and b, either way round: the smaller index in the high half.
std::uint64_t edge_key(int a, int b) {
  const auto [lo, hi] = std::minmax(a, b);
  return static_cast<std::uint64_t>(lo) << 32 | static_cast<std::uint32_t>(hi);
}


struct Key4 {
  std::array<std::uint64_t, 4> v{};
  bool operator==(const Key4&) const = default;
};
struct Key4Hash {
  std::size_t operator()(const Key4& k) const {
    std::uint64_t h = 1469598103934665603ull;
    for (const auto x : k.v) h = (h ^ x) * 1099511628211ull;
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

// How far the flat triangles of a lattice k to an edge can leave a tetrahedron patch's surface,
// estimated: along a lattice edge E/k (parallel to an edge E of the tetrahedron) the quadric
// departs from the line between its ends by |EᵀAE|/(4k²) at the middle, which is a distance of
// that over |∇f| (∇f = 2(Ay + b), here its least at the corners and the centroid). Where the
// departure is large against the gradient, the lattice can also join or miss pieces of the
// surface (neghip: two caps at a tetrahedron's corners joined by a sheet through its middle,
// 0.45 from the drawn surface). Not a bound: the lattice's inner octahedra have diagonals along
// none of the edges (a reviewer found |DᵀAD| up to 4.9× the largest edge term in a quarter of
// Marschner–Lobb's pieces), a departure inside a lattice tetrahedron can reach 3/8 rather than 1/4,
// and the gradient can be smaller between the points asked; the threshold (half of the
// bound, mesh_tets) was chosen with this estimate, and the measured error decides. 0 where the
// quadric has no zero in the ball about the centroid through the farthest corner: |f(y) − f(0)|
// ≤ ‖A‖r² + |∇f(0)|r there.
double lattice_sag(const TetPatch& t, int k) {
  const Eigen::Vector3d c = t.centroid();
  double departs = 0, reach = 0;
  for (int i = 0; i < 4; ++i) {
    reach = std::max(reach, (t.corners[i] - c).norm());
    for (int j = i + 1; j < 4; ++j) {
      const Eigen::Vector3d e = t.corners[j] - t.corners[i];
      departs = std::max(departs, std::abs(e.dot(t.quadric.A * e)));
    }
  }
  if (departs == 0.0) return 0.0;  // a plane: exact
  const double a = t.quadric.A.cwiseAbs().rowwise().sum().maxCoeff();  // ≥ ‖A‖₂
  const double g0 = t.quadric.gradient(Eigen::Vector3d::Zero()).norm();
  if (std::abs(t.quadric.eval(Eigen::Vector3d::Zero())) > (a * reach + g0) * reach) return 0.0;  // no surface inside
  departs /= 4.0 * k * k;
  double g = g0;
  for (const auto& x : t.corners) g = std::min(g, t.quadric.gradient(x - c).norm());
  return g > 0.0 ? departs / g : std::numeric_limits<double>::infinity();
}

// Tetrahedron patches cut where a lattice of k to an edge would leave their surface by more than
// `sag` (lattice_sag), by conforming longest-edge bisection (Rivara): a tetrahedron is cut at its
// longest edge together with every tetrahedron around that edge, a neighbour whose own longest
// edge is another being cut there first, so the pieces share whole faces and the lattices of
// neighbours still meet node for node. Each piece keeps its patch's quadric (moved to its own
// centroid) and colour: the surface drawn is unchanged. Cuts are begun on pieces fewer than
// `generations` cuts deep (a cut's closure can cut a neighbour a few generations deeper), and
// none once there are max_tets pieces (the closure of the last may pass it by a few).
// Besides, a piece holding one of `cut_at`'s points (where a mesh made before was measured beyond
// its bound) is cut, first, while its longest edge is above that point's `longest`, up to
// kCutAtGenerations deep: the estimate cannot see every departure, the measure can.
struct CutAt {
  Eigen::Vector3d at;
  double longest;  ///< cut the piece holding `at` while its longest edge is longer
};
constexpr int kCutAtGenerations = 18;  // about six halvings of every edge

double longest_edge(const std::array<Eigen::Vector3d, 4>& c) {
  double l = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) l = std::max(l, (c[i] - c[j]).norm());
  return l;
}

/// Calls `visit` with each of `sorted` (by x of `.at`) inside the tetrahedron or on it within a
/// rounding, until it returns true.
template <class T, class F>
void points_in_tetrahedron(const std::array<Eigen::Vector3d, 4>& c, std::span<const T> sorted, F&& visit) {
  Eigen::Vector3d lo = c[0], hi = lo;
  double size = 0;
  for (int i = 1; i < 4; ++i) lo = lo.cwiseMin(c[i]), hi = hi.cwiseMax(c[i]), size = std::max(size, (c[i] - c[0]).norm());
  const double eps = 1e-9 * size;
  auto it = std::lower_bound(sorted.begin(), sorted.end(), lo.x() - eps, [](const T& p, double x) { return p.at.x() < x; });
  if (it == sorted.end() || it->at.x() > hi.x() + eps) return;
  Eigen::Matrix3d m;
  for (int i = 0; i < 3; ++i) m.col(i) = c[i + 1] - c[0];
  const Eigen::PartialPivLU<Eigen::Matrix3d> lu(m);
  for (; it != sorted.end() && it->at.x() <= hi.x() + eps; ++it) {
    if ((it->at.array() < lo.array() - eps).any() || (it->at.array() > hi.array() + eps).any()) continue;
    const Eigen::Vector3d w = lu.solve(it->at - c[0]);
    if ((w.array() >= -1e-9).all() && w.sum() <= 1 + 1e-9 && visit(*it)) return;
  }
}

/// For each of `points` inside one of `pieces`, where to cut that piece once more: the point and
/// half the piece's longest edge (the drawn surface's points beyond a mesh, where the lattice
/// missed a part of the surface: a noisy volume's small blobs).
std::vector<CutAt> cuts_at_points(std::span<const TetPatch> pieces, std::span<const Eigen::Vector3d> points) {
  struct At {
    Eigen::Vector3d at;
    std::size_t index;
  };
  std::vector<At> sorted;
  for (std::size_t i = 0; i < points.size(); ++i) sorted.push_back({points[i], i});
  std::sort(sorted.begin(), sorted.end(), [](const At& a, const At& b) { return a.at.x() < b.at.x(); });
  std::vector<double> longest(points.size(), -1.0);
  for (const TetPatch& t : pieces) {
    const double edge = longest_edge(t.corners);
    points_in_tetrahedron(t.corners, std::span<const At>(sorted), [&](const At& a) {
      longest[a.index] = std::max(longest[a.index], 0.5 * edge);
      return false;
    });
  }
  std::vector<CutAt> out;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (longest[i] > 0) out.push_back({points[i], longest[i]});
  return out;
}
std::vector<TetPatch> refine_for_lattice(std::span<const TetPatch> patches, int k, double sag, int generations,
                                         std::size_t max_tets, std::span<const CutAt> cut_at = {}) {
  if (cut_at.empty() &&
      (generations <= 0 || std::none_of(patches.begin(), patches.end(), [&](const TetPatch& t) { return lattice_sag(t, k) > sag; })))
    return {patches.begin(), patches.end()};
  std::vector<Eigen::Vector3d> vx;
  std::map<std::array<double, 3>, int> vid;
  const auto vertex = [&](const Eigen::Vector3d& x) {
    const auto [it, fresh] = vid.try_emplace(std::array<double, 3>{x.x(), x.y(), x.z()}, int(vx.size()));
    if (fresh) vx.push_back(x);
    return it->second;
  };
  struct Tet {
    std::array<int, 4> v;
    int patch, generation;
    bool alive = true;
  };
  std::vector<Tet> tets;
  std::unordered_map<std::uint64_t, std::vector<int>> around;  // edge → tetrahedra (dead ones too)
  const auto add = [&](const Tet& t) {
    tets.push_back(t);
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) around[edge_key(t.v[i], t.v[j])].push_back(int(tets.size() - 1));
  };
  // Edges ordered by length, ties by key: every tetrahedron around an edge agrees on it.
  const auto longer = [&](std::uint64_t e, std::uint64_t f) {
    const double le = (vx[e >> 32] - vx[e & 0xffffffffu]).squaredNorm(), lf = (vx[f >> 32] - vx[f & 0xffffffffu]).squaredNorm();
    return le != lf ? le > lf : e > f;
  };
  const auto longest = [&](const Tet& t) {
    std::uint64_t best = edge_key(t.v[0], t.v[1]);
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        if (const auto e = edge_key(t.v[i], t.v[j]); longer(e, best)) best = e;
    return best;
  };
  for (std::size_t p = 0; p < patches.size(); ++p) {
    Tet t{{}, int(p), 0};
    for (int i = 0; i < 4; ++i) t.v[i] = vertex(patches[p].corners[i]);
    add(t);
  }
  const auto piece = [&](const Tet& t) {
    const TetPatch& parent = patches[t.patch];
    TetPatch q;
    for (int i = 0; i < 4; ++i) q.corners[i] = vx[t.v[i]];
    q.quadric = parent.quadric.translated_to_origin(q.centroid() - parent.centroid());
    q.colour = parent.colour;
    return q;
  };
  std::size_t alive = tets.size();
  // Cut edge e (and every tetrahedron around it), cutting longer edges first where they are.
  const auto bisect = [&](std::uint64_t first) {
    std::vector<std::uint64_t> stack{first};
    while (!stack.empty()) {  // a cut's closure is finished whatever the count: no crack is left
      const std::uint64_t e = stack.back();
      auto& list = around[e];
      int t = -1;
      while (!list.empty() && t < 0) {
        if (tets[list.back()].alive) t = list.back();
        else list.pop_back();
      }
      if (t < 0) {
        stack.pop_back();
        continue;
      }
      const std::uint64_t l = longest(tets[t]);
      if (l != e) {
        stack.push_back(l);
        continue;
      }
      const int a = int(e >> 32), b = int(e & 0xffffffffu);
      const int m = vertex(0.5 * (vx[a] + vx[b]));
      Tet parent = tets[t];
      tets[t].alive = false;
      for (const int drop : {a, b}) {
        Tet child = parent;
        child.generation = parent.generation + 1;
        for (auto& v : child.v)
          if (v == drop) v = m;
        add(child);
      }
      ++alive;
    }
  };
  // The points to cut at, by x, for the pieces' boxes to find theirs.
  std::vector<CutAt> points(cut_at.begin(), cut_at.end());
  std::sort(points.begin(), points.end(), [](const CutAt& a, const CutAt& b) { return a.at.x() < b.at.x(); });
  // Whether piece t holds a point it must be cut at: inside it, or on it within a rounding.
  const auto cut_here = [&](const Tet& t) {
    if (points.empty() || t.generation >= kCutAtGenerations) return false;
    const std::uint64_t e = longest(t);
    const double edge = (vx[e >> 32] - vx[e & 0xffffffffu]).norm();
    bool found = false;
    const std::array<Eigen::Vector3d, 4> corners{vx[t.v[0]], vx[t.v[1]], vx[t.v[2]], vx[t.v[3]]};
    points_in_tetrahedron(corners, std::span<const CutAt>(points), [&](const CutAt& c) {
      return found = c.longest * (1 + 1e-9) < edge;  // a halved edge is half only to a rounding
    });
    return found;
  };
  // Each round cuts the pieces still over `sag`, those farthest over it first (the pieces to cut at
  // points before them), until the count reaches max_tets.
  // The cuts at points are not held to max_tets (they are few, and the estimate's cuts can reach it
  // first: HeadMR's 84,870 tetrahedra came to 8× at every lattice).
  for (int round = 0; round < std::max(generations, cut_at.empty() ? 0 : kCutAtGenerations); ++round) {
    std::vector<std::pair<double, int>> over;
    for (std::size_t t = 0; t < tets.size(); ++t)
      if (tets[t].alive) {
        if (cut_here(tets[t])) over.emplace_back(std::numeric_limits<double>::infinity(), int(t));
        else if (tets[t].generation < generations && alive < max_tets)
          if (const double q = lattice_sag(piece(tets[t]), k); q > sag) over.emplace_back(q, int(t));
      }
    if (over.empty()) break;
    std::sort(over.begin(), over.end(), std::greater<>());
    for (const auto& [q, t] : over) {
      if (alive >= max_tets && std::isfinite(q)) break;
      if (tets[t].alive) bisect(longest(tets[t]));
    }
  }
  log::debug("mesh: {} tetrahedra cut into {} pieces for a lattice of {}", patches.size(), alive, k);
  std::vector<TetPatch> out;
  out.reserve(alive);
  for (const Tet& t : tets)
    if (t.alive) out.push_back(piece(t));
  return out;
}

// Tetrahedron patches on lattices of k to an edge, each cut first (refine_for_lattice) where that
// lattice would leave its surface by more than half the bound (kSagOfBound).
// With `cut_at` (points where a mesh made before left its bound), the pieces holding them are cut
// too (refine_for_lattice); `face_cut_at`, when given, gets for each face made the point and edge
// length that would cut its piece once more: the face's centroid and half its piece's longest edge.
void mesh_tets(const Model& model, int k, double bound, Builder& out, std::span<const CutAt> cut_at = {},
               std::vector<CutAt>* face_cut_at = nullptr, std::vector<TetPatch>* pieces = nullptr) {
  constexpr int kCutGenerations = 6;  // cuts begun; a cut's closure can reach a few deeper
  constexpr std::size_t kMaxPieces = 8;  // times the patches
  // The estimate's threshold, against the bound: a quarter before the lattice rounds measured and
  // cut what it misses; half now (with the rounds, neghip 293k -> 274k triangles, Marschner-Lobb
  // 41³ 3.28M -> 2.06M, both within); the whole bound left Marschner-Lobb 41³ outside (1.67 bounds).
  constexpr double kSagOfBound = 0.5;
  std::vector<TetPatch> tets =
      refine_for_lattice(model.tets, k, kSagOfBound * bound, kCutGenerations, kMaxPieces * model.tets.size(), cut_at);
  // Corners welded by exact position, so neighbours name their shared lattice points alike.
  std::map<std::array<double, 3>, std::uint64_t> corner_ids;
  const auto corner_id = [&](const Eigen::Vector3d& x) {
    return corner_ids.emplace(std::array<double, 3>{x.x(), x.y(), x.z()}, corner_ids.size()).first->second;
  };
  const auto sub = edgewise_subdivision(k);
  struct Node {
    Eigen::Vector3d x;
    double value;
  };
  std::unordered_map<Key4, Node, Key4Hash> nodes;
  struct EdgeKey {
    Key4 a, b;
    bool operator==(const EdgeKey&) const = default;
  };
  struct EdgeHash {
    std::size_t operator()(const EdgeKey& e) const { return Key4Hash{}(e.a) * 31 + Key4Hash{}(e.b); }
  };
  std::unordered_map<EdgeKey, int, EdgeHash> crossings;
  std::set<std::array<int, 3>> zero_faces;  // triangles of three nodes on the surface, made once
  for (const TetPatch& tet : tets) {
    const std::size_t first_face = out.mesh.face_count();
    const Eigen::Vector3d centroid = tet.centroid();
    std::array<std::uint64_t, 4> g;
    for (int i = 0; i < 4; ++i) g[i] = corner_id(tet.corners[i]);
    const Rgb colour = tet.colour.value_or(kDefaultGrey);
    const double thickness = tetrahedron_thickness(tet.corners);
    // The mesh vertex of a crossing (an edge, or a node as {key, key}), made at x the first time.
    const auto vertex_at = [&](const EdgeKey& ek, const Eigen::Vector3d& x) {
      if (const auto it = crossings.find(ek); it != crossings.end()) return it->second;
      const int v = out.add_vertex(x, colour);
      crossings.emplace(ek, v);
      return v;
    };
    const auto node_of = [&](const Eigen::Vector3i& x) -> std::pair<Key4, Node> {
      const int c[4] = {k - x[0], x[0] - x[1], x[1] - x[2], x[2]};
      // (global corner id, count, local corner): sorted by id, so a point shared with a neighbour
      // gets the same key and the same position (the same sum in the same order).
      std::array<std::tuple<std::uint64_t, int, int>, 4> parts;
      for (int i = 0; i < 4; ++i) parts[i] = {c[i] == 0 ? ~std::uint64_t{0} : g[i], c[i], i};  // unused corners last
      std::sort(parts.begin(), parts.end());
      Key4 key;
      Eigen::Vector3d pos = Eigen::Vector3d::Zero();
      for (int i = 0; i < 4; ++i) {
        const auto [id, count, local] = parts[i];
        key.v[i] = count == 0 ? 0 : ((id + 1) << 16 | static_cast<std::uint64_t>(count));
        pos += (static_cast<double>(count) / k) * tet.corners[local];
      }
      // A node within 1e-6 of the tetrahedron's thickness of the surface counts as on it (value
      // 0, the positive side): a bilinear quad's patch runs along four of its tetrahedron's
      // edges, whose nodes the float32 corners of a .qxm scatter to either side (6e-9 off on a
      // unit quad). Relative to the thickness, not the size: a nearly planar quad's tetrahedron
      // is thinner than 1e-6 of its size, and all its nodes would count as on the surface.
      const Eigen::Vector3d u = pos - centroid;
      double value = tet.quadric.eval(u);
      if (std::abs(value) <= 1e-6 * thickness * tet.quadric.gradient(u).norm()) value = 0.0;
      return {key, {pos, value}};
    };
    for (const auto& s : sub) {
      std::array<Key4, 4> keys;
      std::array<Eigen::Vector3d, 4> p;
      std::array<double, 4> f;
      for (int i = 0; i < 4; ++i) {
        auto [key, node] = node_of(s[i]);
        const auto it = nodes.emplace(key, node).first;
        keys[i] = key;
        p[i] = it->second.x;
        f[i] = it->second.value;
      }
      // Three nodes on the surface (value 0) and the fourth off it: the surface there is their
      // face, whichever side the fourth lies on (marching alone finds it only from the negative
      // side: a bilinear quad's patch hugs its tetrahedron's faces at the two corners on its
      // positive side, and those corners were left open). Each such face is made once.
      if (int(f[0] == 0.0) + int(f[1] == 0.0) + int(f[2] == 0.0) + int(f[3] == 0.0) == 3) {
        int off = 0;
        while (f[off] == 0.0) ++off;
        std::array<int, 3> v;
        for (int i = 0, n = 0; i < 4; ++i)
          if (i != off) v[n++] = vertex_at(EdgeKey{keys[i], keys[i]}, p[i]);
        std::array<int, 3> sorted = v;
        std::sort(sorted.begin(), sorted.end());
        if (zero_faces.insert(sorted).second) {
          const auto& V = out.mesh.vertices;
          const Eigen::Vector3d mid = (V[v[0]] + V[v[1]] + V[v[2]]) / 3.0;
          out.add_triangle_facing(v[0], v[1], v[2], f[off] > 0 ? Eigen::Vector3d(p[off] - mid) : Eigen::Vector3d(mid - p[off]));
        }
        continue;
      }
      march(p, f, out, [&](int i, int j) {
        if (f[j] >= 0.0) std::swap(i, j);  // i on the positive side: a canonical edge direction
        // A node on the surface (value 0) is its own crossing, as in the face rule above.
        const double s = f[i] == 0.0 ? 0.0 : edge_root(tet.quadric, p[i] - centroid, p[j] - centroid, f[i], f[j]);
        // A crossing at a lattice point (the surface through a node) is that node's one vertex.
        constexpr double kAtNode = 1e-9;
        if (s <= kAtNode) return vertex_at(EdgeKey{keys[i], keys[i]}, p[i]);
        if (s >= 1 - kAtNode) return vertex_at(EdgeKey{keys[j], keys[j]}, p[j]);
        return vertex_at(EdgeKey{keys[i], keys[j]}, p[i] + s * (p[j] - p[i]));
      });
    }
    if (face_cut_at) {
      const double longest = longest_edge(tet.corners);
      for (std::size_t f = first_face; f < out.mesh.face_count(); ++f) {
        const auto t = out.mesh.face(f);
        const auto& V = out.mesh.vertices;
        face_cut_at->push_back({(V[t[0]] + V[t[1]] + V[t[2]]) / 3.0, 0.5 * longest});
      }
    }
  }
  if (pieces) *pieces = std::move(tets);
}

// ---- glyphs -----------------------------------------------------------------------------------

/// Unit icosphere subdivided `levels` times: vertices and triangles (counter-clockwise outside).
void icosphere(int levels, std::vector<Eigen::Vector3d>& v, std::vector<std::array<int, 3>>& tris) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
       {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& x : v) x.normalize();
  tris = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
          {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
          {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    const auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      if (const auto it = mid.find(key); it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> next;
    next.reserve(tris.size() * 4);
    for (const auto& [a, b, c] : tris) {
      const int ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      next.insert(next.end(), {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}});
    }
    tris = std::move(next);
  }
}

/// Sides of a cylinder of radius r: the sagitta r(1 − cos(π/n)) ≤ bound/2, doubled `extra` times.
int cylinder_segments(double r, double bound, int extra) {
  const double ratio = std::clamp(1.0 - 0.5 * bound / r, -1.0, 1.0);
  const int n = std::clamp(static_cast<int>(std::ceil(std::numbers::pi / std::acos(ratio))), 8, 4096);
  return std::min(n << extra, 1 << 16);
}

/// A closed tube of radius r from p to q, capped flat: rings of vertices at fractions t of the way
/// (the first 0, the last 1), each in its colour; the caps' centres take their ring's colour.
void mesh_tube(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double r, int n,
               std::span<const std::pair<double, Rgb>> rings, Builder& out) {
  const Eigen::Vector3d axis = (q - p).normalized();
  const Eigen::Vector3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
  const int base = static_cast<int>(out.mesh.vertices.size());
  for (const auto& [t, colour] : rings)
    for (int i = 0; i < n; ++i) {
      const double a = 2.0 * std::numbers::pi * i / n;
      out.add_vertex(p + t * (q - p) + r * (std::cos(a) * e1 + std::sin(a) * e2), colour);
    }
  const int bottom = out.add_vertex(p, rings.front().second), top = out.add_vertex(q, rings.back().second);
  const int last = base + n * static_cast<int>(rings.size() - 1);
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    for (int k = base; k < last; k += n) {
      const int b0 = k + i, b1 = k + j, t0 = k + n + i, t1 = k + n + j;
      out.add_triangle(b0, b1, t1);
      out.add_triangle(b0, t1, t0);
    }
    out.add_triangle(bottom, base + j, base + i);
    out.add_triangle(top, last + i, last + j);
  }
}

void mesh_glyph(const Glyph& g, double bound, int extra, Builder& out) {
  const Rgb colour = g.colour.value_or(kDefaultGrey);
  if (g.kind == GlyphKind::cylinder) {
    const Eigen::Vector3d half = g.axes.col(0);
    const std::pair<double, Rgb> rings[2] = {{0.0, colour}, {1.0, colour}};
    mesh_tube(g.centre - half, g.centre + half, g.radius, cylinder_segments(g.radius, bound, extra), rings, out);
    return;
  }
  const Eigen::Matrix3d M = g.kind == GlyphKind::sphere ? Eigen::Matrix3d(g.radius * Eigen::Matrix3d::Identity()) : g.axes;
  const Eigen::Vector3d axis_lengths = M.colwise().norm();  // semi-axes (axes are orthogonal)
  const double a_max = axis_lengths.maxCoeff(), a_min = axis_lengths.minCoeff();
  const double rho = a_min * a_min / a_max;  // smallest radius of curvature
  // An icosphere's edge after l levels is about 1.05/2^l on the unit sphere; a flat triangle of
  // edge e sits about e²/(6ρ) inside a surface of curvature radius ρ.
  const double e = std::sqrt(6.0 * rho * 0.5 * bound);
  int levels = std::clamp(static_cast<int>(std::ceil(std::log2(1.0515 * a_max / e))), 1, 8);
  levels = std::min(levels + extra, 9);
  std::vector<Eigen::Vector3d> v;
  std::vector<std::array<int, 3>> tris;
  icosphere(levels, v, tris);
  const bool flips = M.determinant() < 0;
  const int base = static_cast<int>(out.mesh.vertices.size());
  for (const auto& u : v) out.add_vertex(g.centre + M * u, colour);
  for (const auto& [a, b, c] : tris) flips ? out.add_triangle(base + a, base + c, base + b) : out.add_triangle(base + a, base + b, base + c);
}

}  // namespace

std::vector<std::size_t> bond_halves(const std::vector<Glyph>& glyphs) {
  std::vector<std::size_t> partner(glyphs.size(), kNoPartner);
  std::vector<std::size_t> cyl;
  for (std::size_t i = 0; i < glyphs.size(); ++i)
    if (glyphs[i].kind == GlyphKind::cylinder && glyphs[i].axes.col(0).norm() > 0) cyl.push_back(i);
  if (cyl.size() < 2) return partner;
  std::vector<Eigen::Vector3d> tip;  // each cylinder's end at centre + half axis
  for (const std::size_t i : cyl) tip.push_back(glyphs[i].centre + glyphs[i].axes.col(0));
  const PointIndex index{std::span<const Eigen::Vector3d>(tip)};
  std::vector<Neighbour> nb;
  for (std::size_t k = 0; k < cyl.size(); ++k) {
    const Glyph& a = glyphs[cyl[k]];
    if (partner[cyl[k]] != kNoPartner) continue;
    const double len = a.axes.col(0).norm();
    index.radius(tip[k], 1e-5 * len, nb);
    for (const auto& [j, d2] : nb) {
      const std::size_t other = cyl[j];
      if (other == cyl[k] || partner[other] != kNoPartner) continue;
      const Glyph& b = glyphs[other];
      const Eigen::Vector3d ua = a.axes.col(0) / len, ub = b.axes.col(0).normalized();
      if (std::abs(b.radius - a.radius) > 1e-6 * a.radius || ua.dot(ub) > -1.0 + 1e-9) continue;
      partner[cyl[k]] = other;
      partner[other] = cyl[k];
      break;
    }
  }
  return partner;
}

namespace {

/// The glyphs as their union (convert/mesh_union.h), added to `out`: each glyph meshed closed on
/// its own, the union's vertices coloured as the glyph vertex at their place, or, made on an
/// intersection curve, the nearest glyph vertex. Spheres and ellipsoids alone are joined pairwise
/// (corefinement, about twice as fast); with cylinders (bonds) the glyphs are autorefined as one
/// soup, where pairwise corefinement crashed. Returns how many unions CGAL refused.
std::size_t mesh_glyph_union(const std::vector<Glyph>& glyphs, double bound, int extra, Builder& out) {
  std::vector<PolygonMesh> parts;
  std::vector<Eigen::Vector3d> at;
  std::vector<Rgb> colour;
  parts.reserve(glyphs.size());
  // A glyph given twice is meshed once: the union of two equal meshes is all coplanar faces.
  // Keyed by what is meshed: its kind, centre, radius (spheres, cylinders) and axes (ellipsoids,
  // a cylinder's half axis).
  std::set<std::array<double, 14>> seen;
  std::size_t repeated = 0;
  const bool cylinders =
      std::any_of(glyphs.begin(), glyphs.end(), [](const Glyph& g) { return g.kind == GlyphKind::cylinder; });
  const auto add_part = [&](Builder& one) {
    for (std::size_t v = 0; v < one.mesh.vertices.size(); ++v) {
      at.push_back(one.mesh.vertices[v]);
      if (out.colours) colour.push_back(one.mesh.colours[v]);
    }
    one.mesh.colours.clear();
    parts.push_back(std::move(one.mesh));
  };
  // A bond's two halves (convert glyphs: capped cylinders of one radius from each atom to the
  // middle, each in its atom's colour) as one tube: their caps at the middle were two polygons a
  // rounding apart, whose exact intersection left slivers that crossed once rounded to doubles
  // (80 pairs on two bonds). The tube's rings just either side of the middle carry the two colours.
  const std::vector<std::size_t> partner = bond_halves(glyphs);
  // The spheres (atoms), to find the one a tube's end lies in.
  std::vector<Eigen::Vector3d> sphere_centre;
  std::vector<double> sphere_radius;
  for (const Glyph& g : glyphs)
    if (g.kind == GlyphKind::sphere) sphere_centre.push_back(g.centre), sphere_radius.push_back(g.radius);
  const PointIndex spheres{std::span<const Eigen::Vector3d>(sphere_centre)};
  std::vector<Neighbour> near;
  // Whether a sphere holds a tube's end at p, the tube's radius r in from its surface: an atom
  // the bond starts in.
  const auto buried = [&](const Eigen::Vector3d& p, double r) {
    if (sphere_centre.empty()) return false;
    spheres.nearest(p, std::min<std::size_t>(4, sphere_centre.size()), near);
    return std::any_of(near.begin(), near.end(),
                       [&](const Neighbour& s) { return std::sqrt(s.second) + r <= (1 + 1e-5) * sphere_radius[s.first]; });
  };
  for (std::size_t i = 0; i < glyphs.size(); ++i) {
    if (partner[i] == kNoPartner || partner[i] < i) continue;
    const Glyph &a = glyphs[i], &b = glyphs[partner[i]];
    const Rgb ca = a.colour.value_or(kDefaultGrey), cb = b.colour.value_or(kDefaultGrey);
    // Each tube ends a little inside its atoms, at its own depth (up to 0.007 of its radius):
    // every bond of an atom capped at the atom's centre met the others at that one point, and
    // CGAL's autorefinement crashed there (4lfq and 4ins balls-and-sticks and licorice read from
    // their PDB files). The caps stay inside the atoms (licorice's atoms, of the tubes' radius,
    // leave a rim of 2.5e-5 radii). An end no atom holds stays where it is.
    Eigen::Vector3d p = a.centre - a.axes.col(0), q = b.centre - b.axes.col(0);
    {
      const Eigen::Vector3d u = (q - p).normalized();
      const double shift = 1e-3 * a.radius * double(1 + i % 7);
      if (buried(p, a.radius)) p += shift * u;
      if (buried(q, a.radius)) q -= shift * u;
    }
    const double split = a.axes.col(0).norm() / (a.axes.col(0).norm() + b.axes.col(0).norm());
    constexpr double kBand = 1e-3;  // of the tube's length: where the colour turns
    const std::pair<double, Rgb> rings[4] = {{0.0, ca}, {split - kBand, ca}, {split + kBand, cb}, {1.0, cb}};
    Builder one;
    one.colours = out.colours;
    mesh_tube(p, q, a.radius, cylinder_segments(a.radius, bound, extra), rings, one);
    add_part(one);
  }
  log::debug("mesh: {} bonds' halves meshed as one tube each",
             std::count_if(partner.begin(), partner.end(), [](std::size_t p) { return p != kNoPartner; }) / 2);
  for (std::size_t gi = 0; gi < glyphs.size(); ++gi) {
    const Glyph& g = glyphs[gi];
    if (partner[gi] != kNoPartner) continue;
    const bool sphere = g.kind == GlyphKind::sphere;
    std::array<double, 14> key{double(static_cast<int>(g.kind)), g.centre.x(), g.centre.y(), g.centre.z(),
                               g.kind == GlyphKind::ellipsoid ? 0.0 : g.radius};
    for (int k = 0; k < 9; ++k) key[std::size_t(5 + k)] = sphere ? 0.0 : g.axes(k / 3, k % 3);
    if (!seen.insert(key).second) {
      ++repeated;
      continue;
    }
    Builder one;
    one.colours = out.colours;
    mesh_glyph(g, bound, extra, one);
    add_part(one);
  }
  if (repeated > 0) log::info("mesh: {} glyphs given more than once meshed once", repeated);
  MeshUnion u = cylinders ? union_by_autorefinement(std::move(parts)) : union_of_closed_meshes(std::move(parts));
  if (!u.why.empty())
    log::warn("mesh: the union of {} glyphs failed ({}): {}", u.parts, u.why,
              u.apart ? "they are meshed whole, overlapping ones crossing" : "its best attempt is kept");
  else if (u.failed > 0)
    log::warn("mesh: {} of {} unions of overlapping glyphs refused by CGAL (not a closed manifold): those glyphs are "
              "meshed whole and cross", u.failed, u.parts - 1);
  const int base = static_cast<int>(out.mesh.vertices.size());
  if (out.colours) {
    const PointIndex index{std::span<const Eigen::Vector3d>(at)};
    std::vector<Neighbour> nb;
    for (const auto& p : u.mesh.vertices) {
      index.nearest(p, 1, nb);
      out.add_vertex(p, colour[nb.front().first]);
    }
  } else {
    for (const auto& p : u.mesh.vertices) out.add_vertex(p, Rgb{});
  }
  for (std::size_t f = 0; f < u.mesh.face_count(); ++f) {
    const auto face = u.mesh.face(f);
    out.add_triangle(base + face[0], base + face[1], base + face[2]);
  }
  return u.failed;
}

// ---- SLIM -------------------------------------------------------------------------------------

struct SlimGrid {
  Eigen::Vector3d origin;
  double h;
  Eigen::Vector3i n;  // nodes per axis
  std::uint64_t index(const Eigen::Vector3i& i) const {
    return (static_cast<std::uint64_t>(i.z()) * n.y() + i.y()) * n.x() + i.x();
  }
  Eigen::Vector3i node(std::uint64_t k) const {
    return {static_cast<int>(k % n.x()), static_cast<int>(k / n.x() % n.y()), static_cast<int>(k / n.x() / n.y())};
  }
  Eigen::Vector3d at(const Eigen::Vector3i& i) const { return origin + h * i.cast<double>(); }
};

/// Where the drawn blend crosses the line o + s·dir (0 ≤ s ≤ length): entries (front faces seen
/// going +dir) and exits (front faces seen going −dir), as +1/−1 events sorted by s. A blended hit
/// is passed by starting the next trace behind every patch hit it blended.
std::vector<std::pair<double, int>> blend_crossings(const ReferenceScene& scene, const TraceOptions& trace,
                                                    const Eigen::Vector3d& o, const Eigen::Vector3d& dir, double length) {
  std::vector<std::pair<double, int>> events;
  thread_local std::vector<SlimSample> used;
  for (const int side : {+1, -1}) {
    const Ray ray{side > 0 ? o : Eigen::Vector3d(o + length * dir), side * dir};
    double tmin = 0;
    for (int k = 0; k < 64; ++k) {
      const auto hit = scene.trace(ray, tmin, length, trace, &used);
      if (!hit) break;
      events.emplace_back(side > 0 ? hit->t : length - hit->t, side);
      double behind = hit->t;
      for (const SlimSample& u : used) behind = std::max(behind, u.hit.t);
      tmin = behind + 1e-9 * length;
    }
  }
  std::sort(events.begin(), events.end());
  return events;
}

/// The SLIM grid of spacing h: one spare node beyond the patches' bounds on each side.
SlimGrid slim_grid(const Model& model, double h) {
  Box3 box;
  for (const auto& s : model.slims) box.extend(bounds(s));
  if (model.slims.empty()) box = bounds(model);  // a closed tetrahedron model on the grid
  SlimGrid grid;
  grid.h = h;
  grid.origin = box.min - Eigen::Vector3d::Constant(h);
  grid.n = ((box.max - grid.origin) / h).array().ceil().cast<int>() + 2;
  return grid;
}

/// Finest SLIM grid refinement: cells of h / 2^kGridLevels.
constexpr int kGridLevels = 3;

/// Rounds of open sheets on patches' rims drawn alone (fin_sheets).
constexpr int kFinRounds = 5;

/// Rounds that leave out the opened mesh's last faces with samples beyond the bound, and how many
/// faces one round may leave out at least (else a thousandth of the mesh's).
constexpr int kTrimRounds = 3;
// A lattice round cuts at most this many faces' pieces (or 1 in 200 of the faces).
constexpr std::size_t kLatticeRoundFaces = 4096;
constexpr std::size_t kTrimFaces = 64;

/// × bound: how far the opened mesh's vertices may move off the surface they were on, towards
/// drawn points beyond the bound (between_views.h; 0.85 for a closed mesh). The opened mesh's
/// faces that a move takes beyond the bound are left out after (kTrimRounds), so its vertices may
/// go the whole bound: the kitten's fit at 1e-3, a blend of sheets seen at a grazing angle 1.05
/// bounds from the mesh at 0.85, within the bound at 1.
constexpr double kOpenedMaxOffset = 1.0;

using LatticeEdge = std::pair<std::uint64_t, std::uint64_t>;
struct LatticeEdgeHash {
  std::size_t operator()(const LatticeEdge& e) const {
    const std::uint64_t h = (e.first * 0x9E3779B97F4A7C15ull) ^ (e.second + 0x632BE59BD9B4E019ull + (e.first << 6));
    return static_cast<std::size_t>(h ^ (h >> 31));
  }
};
std::uint64_t lattice_key(const Eigen::Vector3i& p) {
  return static_cast<std::uint64_t>(p.x()) | static_cast<std::uint64_t>(p.y()) << 21 | static_cast<std::uint64_t>(p.z()) << 42;
}

/// SLIM patches as marching tetrahedra (Kuhn split of a grid of spacing h; the cells in `refined`
/// cut further by conforming bisection, convert/kuhn_bisection.h, so thin parts and gaps between
/// coarse nodes get nodes of their own). Which side of the surface a node lies on is decided by
/// the drawn blend itself: along the grid lines through it (one per axis), a node is inside when
/// the last crossing before it is an entry, and the majority of the three lines decides, so one
/// line grazing a gap cannot flip it. Sides from one consistent labelling make the triangles
/// closed wherever the surface is. Crossings on cell edges are placed by the blended Taubin
/// distance Σwᵢdᵢ/Σwᵢ; the caller moves them onto the blend.
void mesh_slims(const Model& model, const ReferenceScene& scene, const TraceOptions& trace, double h,
                std::span<const KuhnCellDepth> refined, Builder& out, std::vector<std::uint8_t>& on_surface) {
  const SlimGrid grid = slim_grid(model, h);
  const std::uint64_t total = static_cast<std::uint64_t>(grid.n.x()) * grid.n.y() * grid.n.z();
  // Bits 0–2: inside as seen along x, y, z; bit 3: a corner of a cell the surface crosses (or of
  // a refined cell); bit 4: the lowest corner of a refined cell.
  std::vector<std::uint8_t> state(total, 0);
  // Inside along the line o + s·dir at each of `at` (line parameters, ascending not required).
  const auto inside_along = [&](const Eigen::Vector3d& o, const Eigen::Vector3d& dir, double length,
                                const auto& at, const auto& mark) {
    const auto events = blend_crossings(scene, trace, o, dir, length);
    if (events.empty()) return;
    for (std::size_t k = 0; k < at.size(); ++k) {
      // Inside when the last crossing at or before it is an entry.
      const auto it = std::upper_bound(events.begin(), events.end(), at[k],
                                       [](double s, const std::pair<double, int>& e) { return s < e.first; });
      if (it != events.begin() && std::prev(it)->second > 0) mark(k);
    }
  };
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    const int n1 = grid.n[a1], n2 = grid.n[a2], len = grid.n[axis];
    const Eigen::Vector3d dir = Eigen::Vector3d::Unit(axis);
    std::vector<double> at(len);
    for (int k = 0; k < len; ++k) at[k] = k * h;
    tbb::parallel_for(tbb::blocked_range<int>(0, n1 * n2), [&](const tbb::blocked_range<int>& r) {
      for (int line = r.begin(); line < r.end(); ++line) {
        Eigen::Vector3i i = Eigen::Vector3i::Zero();
        i[a1] = line % n1;
        i[a2] = line / n1;
        inside_along(grid.at(i), dir, (len - 1) * h, at, [&](std::size_t k) {
          Eigen::Vector3i j = i;
          j[axis] = static_cast<int>(k);
          state[grid.index(j)] |= static_cast<std::uint8_t>(1u << axis);  // lines write disjoint nodes
        });
      }
    });
  }
  const auto corner_of = [&](std::uint64_t k0, int c) {
    return k0 + (c & 1) + ((c >> 1) & 1) * grid.n.x() + ((c >> 2) & 1) * static_cast<std::uint64_t>(grid.n.x()) * grid.n.y();
  };
  // Refined cells: their tetrahedra on the lattice of spacing h / S, and the nodes of that
  // lattice they add (not coarse nodes), labelled by their own three lines as coarse ones are.
  constexpr int S = 1 << kGridLevels;
  KuhnRefinement fine;
  if (!refined.empty()) fine = refine_kuhn_cells(grid.n - Eigen::Vector3i::Ones(), refined, kGridLevels);
  for (const Eigen::Vector3i& c : fine.cells) {
    const std::uint64_t k0 = grid.index(c);
    state[k0] |= 16u;
    for (int k = 0; k < 8; ++k) state[corner_of(k0, k)] |= 8u;
  }
  const auto is_coarse = [](const Eigen::Vector3i& p) { return p.x() % S == 0 && p.y() % S == 0 && p.z() % S == 0; };
  std::vector<Eigen::Vector3i> fine_nodes;
  std::unordered_map<std::uint64_t, int> fine_index;
  for (const auto& t : fine.tets)
    for (const auto& p : t)
      if (!is_coarse(p) && fine_index.emplace(lattice_key(p), static_cast<int>(fine_nodes.size())).second)
        fine_nodes.push_back(p);
  std::vector<std::uint8_t> fine_votes(fine_nodes.size(), 0);
  const auto lattice_at = [&](const Eigen::Vector3i& p) -> Eigen::Vector3d {
    return grid.origin + (h / S) * p.cast<double>();
  };
  for (int axis = 0; axis < 3; ++axis) {
    // Fine nodes grouped by the line along `axis` through them.
    std::unordered_map<std::uint64_t, std::vector<int>> lines;
    for (std::size_t k = 0; k < fine_nodes.size(); ++k) {
      Eigen::Vector3i q = fine_nodes[k];
      q[axis] = 0;
      lines[lattice_key(q)].push_back(static_cast<int>(k));
    }
    std::vector<const std::vector<int>*> list;
    for (const auto& [key, nodes] : lines) list.push_back(&nodes);
    const Eigen::Vector3d dir = Eigen::Vector3d::Unit(axis);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, list.size()), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t l = r.begin(); l < r.end(); ++l) {
        const std::vector<int>& nodes = *list[l];
        Eigen::Vector3i q = fine_nodes[nodes[0]];
        q[axis] = 0;
        std::vector<double> at(nodes.size());
        for (std::size_t k = 0; k < nodes.size(); ++k) at[k] = fine_nodes[nodes[k]][axis] * (h / S);
        inside_along(lattice_at(q), dir, (grid.n[axis] - 1) * h, at,
                     [&](std::size_t k) { fine_votes[nodes[k]] |= static_cast<std::uint8_t>(1u << axis); });
      }
    });
  }
  // Fine nodes by the refined cell holding them (the lowest, where several do).
  std::unordered_map<std::uint64_t, std::vector<int>> fine_in_cell;
  for (std::size_t k = 0; k < fine_nodes.size(); ++k) {
    const Eigen::Vector3i c = (fine_nodes[k] / S).cwiseMin(grid.n - Eigen::Vector3i::Constant(2));
    fine_in_cell[grid.index(c)].push_back(static_cast<int>(k));
  }
  // Cells whose corners are not all unanimous alike (all three lines inside, or all outside):
  // the surface may cross them. Their corners get the blended distance. Refined cells are
  // marched as their tetrahedra instead.
  std::vector<std::uint64_t> cells;
  for (int z = 0; z + 1 < grid.n.z(); ++z)
    for (int y = 0; y + 1 < grid.n.y(); ++y)
      for (int x = 0; x + 1 < grid.n.x(); ++x) {
        const std::uint64_t k0 = grid.index({x, y, z});
        if (state[k0] & 16u) continue;
        const unsigned first = state[k0] & 7u;
        bool mixed = first != 0u && first != 7u;
        for (int c = 1; c < 8 && !mixed; ++c) mixed = (state[corner_of(k0, c)] & 7u) != first;
        if (mixed) cells.push_back(k0);
      }
  for (const std::uint64_t k0 : cells)
    for (int c = 0; c < 8; ++c) state[corner_of(k0, c)] |= 8u;
  // The blended Taubin distance at those corners: the blend's own weights where a ball holds the
  // node, else weights over balls grown by kReach (so every corner near the surface has a value).
  struct Acc {
    double w = 0, wd = 0;
    double we = 0, wde = 0;
  };
  constexpr double kReach = 1.5;
  const auto accumulate = [&](const SlimPatch& s, const Eigen::Vector3d& x, Acc& a) {
    const Eigen::Vector3d u = (x - s.centre) / s.radius;
    const double r = u.norm();
    const double we = slim_weight(r / kReach);
    if (!(we > 0.0)) return;
    const double gn = s.local.gradient(u).norm();
    if (!(gn > 1e-12)) return;
    const double d = s.radius * s.local.eval(u) / gn;  // Taubin's distance, world units
    a.we += we;
    a.wde += we * d;
    const double w = slim_weight(r);
    if (!(w > 0.0) || !s.clips.keeps(u)) return;
    a.w += w;
    a.wd += w * d;
  };
  std::unordered_map<std::uint64_t, Acc> acc;
  acc.reserve(cells.size() * 2);
  std::vector<Acc> fine_acc(fine_nodes.size());
  for (const SlimPatch& s : model.slims) {
    const double reach = kReach * s.radius;
    const Eigen::Vector3i lo = ((s.centre.array() - reach - grid.origin.array()) / h).floor().cast<int>().max(0);
    const Eigen::Vector3i hi =
        ((s.centre.array() + reach - grid.origin.array()) / h).ceil().cast<int>().min(grid.n.array() - 1);
    for (int z = lo.z(); z <= hi.z(); ++z)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int x = lo.x(); x <= hi.x(); ++x) {
          const Eigen::Vector3i i(x, y, z);
          const std::uint64_t k = grid.index(i);
          if (state[k] & 16u)
            if (const auto it = fine_in_cell.find(k); it != fine_in_cell.end())
              for (const int f : it->second) accumulate(s, lattice_at(fine_nodes[f]), fine_acc[f]);
          if (state[k] & 8u) accumulate(s, grid.at(i), acc[k]);
        }
  }
  const auto acc_of = [&](const Eigen::Vector3i& p) -> const Acc* {
    if (is_coarse(p)) {
      const auto it = acc.find(grid.index(p / S));
      return it == acc.end() ? nullptr : &it->second;
    }
    return &fine_acc[fine_index.at(lattice_key(p))];
  };
  const auto value = [&](const Eigen::Vector3i& p) -> std::optional<double> {
    const Acc* a = acc_of(p);
    if (!a) return std::nullopt;
    if (a->w > 0) return a->wd / a->w;
    if (a->we > 0) return a->wde / a->we;
    return std::nullopt;
  };
  // A node the three lines agree on takes their side. Where they split (a line grazing the
  // surface sees a chord the blend shows at a slant, or misses it), the distance's sign decides
  // when the node is within a ball, else the majority.
  const auto is_inside = [&](const Eigen::Vector3i& p) {
    const unsigned votes = is_coarse(p) ? state[grid.index(p / S)] & 7u : fine_votes[fine_index.at(lattice_key(p))];
    if (votes == 0u || votes == 7u) return votes == 7u;
    if (const Acc* a = acc_of(p); a && a->w > 0) return a->wd < 0;
    return std::popcount(votes) >= 2;
  };
  std::unordered_map<LatticeEdge, int, LatticeEdgeHash> crossings;  // edge → vertex
  const Rgb grey{200, 200, 200};
  const auto march_tet = [&](const std::array<Eigen::Vector3i, 4>& lattice) {
    std::array<Eigen::Vector3d, 4> p;
    std::array<double, 4> side;
    for (int s = 0; s < 4; ++s) {
      p[s] = lattice_at(lattice[s]);
      side[s] = is_inside(lattice[s]) ? -1.0 : 1.0;
    }
    march(p, side, out, [&](int i, int j) {
      const std::uint64_t a = lattice_key(lattice[i]), b = lattice_key(lattice[j]);
      const LatticeEdge ek = std::minmax(a, b);
      if (const auto it = crossings.find(ek); it != crossings.end()) return it->second;
      // The blend where the edge enters it, seen from its outer end, as a ray would see it.
      const int o = side[i] > 0 ? i : j, n = o == i ? j : i;
      const Eigen::Vector3d d = p[n] - p[o];
      const double len = d.norm();
      if (const auto hit = scene.trace({p[o], d / len}, 0.0, len, trace);
          hit && (hit->kind == PrimitiveKind::slim || model.slims.empty())) {
        const int v = out.add_vertex(hit->point, hit->colour);
        crossings.emplace(ek, v);
        on_surface.push_back(1);
        return v;
      }
      // Else the distance's root where its signs agree with the sides, else the edge's middle;
      // the caller moves it onto the blend along its normal.
      double t = 0.5;
      const auto fa = value(lattice[i]), fb = value(lattice[j]);
      if (fa && fb && *fa * side[i] >= 0 && *fb * side[j] >= 0 && *fa != *fb) t = std::clamp(*fa / (*fa - *fb), 0.0, 1.0);
      const int v = out.add_vertex(p[i] + t * (p[j] - p[i]), grey);
      crossings.emplace(ek, v);
      on_surface.push_back(0);
      return v;
    });
  };
  for (const std::uint64_t k0 : cells) {
    const Eigen::Vector3i base = grid.node(k0) * S;
    for (const auto& perm : kPermutations) {
      std::array<Eigen::Vector3i, 4> corner;
      corner[0] = base;
      for (int s = 0; s < 3; ++s) corner[s + 1] = corner[s] + S * Eigen::Vector3i::Unit(perm[s]);
      march_tet(corner);
    }
  }
  for (const auto& t : fine.tets) march_tet(t);
}

/// The drawn surface seen along −n from p + reach·n, within 2·reach: the first hit.
std::optional<SurfaceHit> along_normal(const ReferenceScene& scene, const TraceOptions& trace,
                                       const Eigen::Vector3d& p, const Eigen::Vector3d& n, double reach) {
  const Ray ray{p + reach * n, -n};
  return scene.trace(ray, 0.0, 2.0 * reach, trace);
}

/// Moves each SLIM-made vertex onto the drawn surface along its normal, then (drop_unmet) drops the
/// triangles with a vertex whose normal line met no SLIM surface within reach: they span a hole of
/// the blend (an open scan's SLIM fit), where the grid's closed labelling put a cap the renderer
/// does not draw. Without drop_unmet such a vertex stays where it is. reach_of (optional, per vertex
/// from first): a shorter reach for that vertex.
void snap_to_surface(const ReferenceScene& scene, const TraceOptions& trace, double reach, std::size_t first,
                     const std::vector<std::uint8_t>& on_surface, Builder& out, bool drop_unmet = true,
                     const std::vector<double>* reach_of = nullptr, bool any_kind = false) {
  const std::vector<Eigen::Vector3d> normals = vertex_normals(out.mesh);
  std::vector<std::uint8_t> snapped(out.mesh.vertices.size(), 1);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(first, out.mesh.vertices.size()),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t v = r.begin(); v < r.end(); ++v) {
                        if (on_surface[v - first]) continue;
                        snapped[v] = 0;
                        if (!(normals[v].norm() > 0)) continue;
                        const double r = reach_of ? std::min(reach, (*reach_of)[v - first]) : reach;
                        const auto hit = along_normal(scene, trace, out.mesh.vertices[v], normals[v], r);
                        if (!hit || (hit->kind != PrimitiveKind::slim && !any_kind)) continue;
                        out.mesh.vertices[v] = hit->point;
                        if (out.colours) out.mesh.colours[v] = hit->colour;
                        snapped[v] = 1;
                      }
                    });
  if (!drop_unmet) return;
  PolygonMesh kept;
  std::vector<int> remap(out.mesh.vertices.size(), -1);
  for (std::size_t v = 0; v < first; ++v) remap[v] = static_cast<int>(v);
  kept.vertices.assign(out.mesh.vertices.begin(), out.mesh.vertices.begin() + first);
  if (out.colours) kept.colours.assign(out.mesh.colours.begin(), out.mesh.colours.begin() + first);
  for (std::size_t f = 0; f < out.mesh.face_count(); ++f) {
    const auto face = out.mesh.face(f);
    if (!std::all_of(face.begin(), face.end(), [&](int v) { return snapped[v] != 0; })) continue;
    std::array<int, 3> tri;
    for (int i = 0; i < 3; ++i) {
      int& m = remap[face[i]];
      if (m < 0) {
        m = static_cast<int>(kept.vertices.size());
        kept.vertices.push_back(out.mesh.vertices[face[i]]);
        if (out.colours) kept.colours.push_back(out.mesh.colours[face[i]]);
      }
      tri[i] = m;
    }
    kept.add_face(tri);
  }
  out.mesh = std::move(kept);
}

/// The mesh without the faces marked in `drop` (per face, non-zero: left out); every vertex kept.
PolygonMesh without_faces(const PolygonMesh& m, std::span<const std::uint8_t> drop) {
  PolygonMesh out;
  out.vertices = m.vertices;
  out.colours = m.colours;
  out.normals = m.normals;
  for (std::size_t f = 0; f < m.face_count(); ++f)
    if (f >= drop.size() || !drop[f]) out.add_face(m.face(f));
  return out;
}

/// Sets each vertex's normal to the drawn surface's (the CPU reference's shading normal) where the
/// line along the vertex's angle-weighted normal meets it within reach (the hit nearest the vertex,
/// seen from outside first), else to that angle-weighted normal. Where the drawn surface has a
/// crease at the vertex (its drawn normal more than kCreaseDeg off a neighbouring vertex's: a
/// polyhedral model's edges and corners, a clipped patch's crease), one normal cannot hold it:
/// such a vertex gets its faces' angle-weighted normal, as programs reading a mesh without normals
/// compute (a cube's corner drawn by one face's normal was 90° off the other two). Returns how
/// many vertices took their faces' normal.
std::size_t set_drawn_normals(PolygonMesh& mesh, const ReferenceScene& scene, const TraceOptions& trace, double reach) {
  constexpr double kCreaseDeg = 45.0;
  const double crease_cos = std::cos(kCreaseDeg * std::numbers::pi / 180.0);
  const std::size_t V = mesh.vertices.size();
  // Per vertex: its faces' normal weighted by their angles there (unit; zero for a vertex of
  // degenerate faces only).
  const std::vector<Eigen::Vector3d> faces = vertex_normals(mesh, NormalWeight::angle);
  std::vector<Eigen::Vector3d> drawn(V, Eigen::Vector3d::Zero());  // zero: none met
  tbb::parallel_for(std::size_t{0}, V, [&](std::size_t v) {
    if (faces[v].squaredNorm() == 0) return;
    const Eigen::Vector3d &n = faces[v], &p = mesh.vertices[v];
    std::optional<SurfaceHit> best;
    double best_d = std::numeric_limits<double>::infinity();
    for (const double side : {1.0, -1.0}) {
      const auto hit = scene.trace(Ray{p + side * reach * n, -side * n}, 0.0, 2.0 * reach, trace);
      if (!hit) continue;
      const double d = std::abs(hit->t - reach);
      if (d < best_d) best_d = d, best = hit;
    }
    if (!best || !best->normal.allFinite() || !(best->normal.norm() > 0)) return;
    const Eigen::Vector3d m = best->normal.normalized();
    drawn[v] = m.dot(n) < 0 ? Eigen::Vector3d(-m) : m;  // the shading normal faces the ray
  });
  std::vector<std::uint8_t> crease(V, 0);
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const auto t = mesh.face(f);
    for (std::size_t k = 0; k < t.size(); ++k) {
      const int a = t[k], b = t[(k + 1) % t.size()];
      if (drawn[a].squaredNorm() > 0 && drawn[b].squaredNorm() > 0 && drawn[a].dot(drawn[b]) < crease_cos) crease[a] = crease[b] = 1;
    }
  }
  mesh.normals.assign(V, Eigen::Vector3d::UnitZ());  // a vertex of degenerate faces only: any unit vector
  std::size_t from_faces = 0;
  for (std::size_t v = 0; v < V; ++v) {
    if (drawn[v].squaredNorm() > 0 && !crease[v]) {
      mesh.normals[v] = drawn[v];
      continue;
    }
    ++from_faces;
    if (faces[v].squaredNorm() > 0) mesh.normals[v] = faces[v];
  }
  return from_faces;
}

std::size_t count_open_edges(const PolygonMesh& m) {
  std::unordered_map<std::uint64_t, int> uses;
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    const auto v = m.face(f);
    for (std::size_t i = 0; i < v.size(); ++i) {
      const auto [a, b] = std::minmax(v[i], v[(i + 1) % v.size()]);
      ++uses[static_cast<std::uint64_t>(a) << 32 | static_cast<std::uint32_t>(b)];
    }
  }
  return static_cast<std::size_t>(std::count_if(uses.begin(), uses.end(), [](const auto& e) { return e.second != 2; }));
}

// ---- local refinement (SLIM) ------------------------------------------------------------------

/// Closes seams between pieces meshed apart (each tetrahedron, glyph and the SLIM grid make their
/// own vertices): open edges' vertices within eps of each other become one, and an open edge with
/// another piece's open-edge vertices on it (within eps, strictly inside: a T-junction, where a
/// flat triangle's coarser lattice meets a finer one) has its triangle split at them, as a fan
/// from the opposite corner. Nothing moves by more than eps; faces that the welding makes
/// degenerate, and the second copy of a triangle, are dropped. Returns how many vertices were
/// welded and edges split.
std::pair<std::size_t, std::size_t> close_seams(PolygonMesh& m, double eps) {
  const auto open_vertices = [&] {
    std::unordered_map<std::uint64_t, int> uses;
    for (std::size_t f = 0; f < m.face_count(); ++f) {
      const auto t = m.face(f);
      for (int i = 0; i < 3; ++i) ++uses[edge_key(t[i], t[(i + 1) % 3])];
    }
    std::vector<std::uint8_t> open(m.vertices.size(), 0);
    for (const auto& [k, n] : uses)
      if (n == 1) open[k >> 32] = open[k & 0xffffffffu] = 1;
    return std::pair{std::move(uses), std::move(open)};
  };
  // Open vertices by grid cell of side `cell`.
  const auto cell_of = [](const Eigen::Vector3d& p, double cell) {
    return Eigen::Vector3i((p / cell).array().floor().cast<int>());
  };
  const auto cell_key = [](const Eigen::Vector3i& c) {
    return (static_cast<std::uint64_t>(c.x() & 0x1fffff) << 42) | (static_cast<std::uint64_t>(c.y() & 0x1fffff) << 21) |
           static_cast<std::uint64_t>(c.z() & 0x1fffff);
  };
  // Welding.
  std::size_t welded = 0;
  {
    const auto [uses, open] = open_vertices();
    std::vector<int> to(m.vertices.size());
    std::iota(to.begin(), to.end(), 0);
    std::unordered_map<std::uint64_t, std::vector<int>> grid;
    const double cell = 2.0 * eps;
    for (std::size_t v = 0; v < m.vertices.size(); ++v) {
      if (!open[v]) continue;
      const Eigen::Vector3i c = cell_of(m.vertices[v], cell);
      int found = -1;
      for (int dx = -1; dx <= 1 && found < 0; ++dx)
        for (int dy = -1; dy <= 1 && found < 0; ++dy)
          for (int dz = -1; dz <= 1 && found < 0; ++dz)
            if (const auto it = grid.find(cell_key(c + Eigen::Vector3i(dx, dy, dz))); it != grid.end())
              for (const int w : it->second)
                if ((m.vertices[w] - m.vertices[v]).norm() <= eps) {
                  found = w;
                  break;
                }
      if (found >= 0) {
        to[v] = found;
        ++welded;
      } else {
        grid[cell_key(c)].push_back(static_cast<int>(v));
      }
    }
    if (welded > 0) {
      PolygonMesh out;
      out.vertices = m.vertices;
      out.colours = m.colours;
      std::set<std::array<int, 3>> seen;
      for (std::size_t f = 0; f < m.face_count(); ++f) {
        const auto t = m.face(f);
        const std::array<int, 3> w = {to[t[0]], to[t[1]], to[t[2]]};
        if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) continue;
        std::array<int, 3> sorted = w;
        std::sort(sorted.begin(), sorted.end());
        if (!seen.insert(sorted).second) continue;
        out.add_face(w);
      }
      m = std::move(out);
    }
  }
  // T-junctions: open vertices strictly inside open edges.
  std::size_t split = 0;
  const auto [uses, open] = open_vertices();
  double length = 0;
  std::size_t n_open = 0;
  for (const auto& [k, n] : uses)
    if (n == 1) length += (m.vertices[k >> 32] - m.vertices[k & 0xffffffffu]).norm(), ++n_open;
  if (n_open == 0) return {welded, 0};
  const double cell = std::max(length / static_cast<double>(n_open), 4.0 * eps);
  std::unordered_map<std::uint64_t, std::vector<int>> grid;
  for (std::size_t v = 0; v < m.vertices.size(); ++v)
    if (open[v]) grid[cell_key(cell_of(m.vertices[v], cell))].push_back(static_cast<int>(v));
  // Per face, its open edges' inner points (sorted along the edge).
  std::vector<std::array<std::vector<int>, 3>> inner(m.face_count());
  std::vector<std::size_t> touched;
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    const auto t = m.face(f);
    bool any = false;
    for (int i = 0; i < 3; ++i) {
      const int a = t[i], b = t[(i + 1) % 3];
      if (uses.at(edge_key(a, b)) != 1) continue;
      const Eigen::Vector3d pa = m.vertices[a], ab = m.vertices[b] - pa;
      const double len2 = ab.squaredNorm();
      if (!(len2 > 0)) continue;
      const Eigen::Vector3i lo = cell_of(pa.cwiseMin(m.vertices[b]).array() - eps, cell),
                            hi = cell_of(pa.cwiseMax(m.vertices[b]).array() + eps, cell);
      if (((hi - lo).array() + 1).cast<double>().prod() > 4096) continue;  // a long edge across many cells
      std::vector<std::pair<double, int>> on;
      for (int x = lo.x(); x <= hi.x(); ++x)
        for (int y = lo.y(); y <= hi.y(); ++y)
          for (int z = lo.z(); z <= hi.z(); ++z)
            if (const auto it = grid.find(cell_key({x, y, z})); it != grid.end())
              for (const int v : it->second) {
                if (v == a || v == b) continue;
                const double s = (m.vertices[v] - pa).dot(ab) / len2;
                if (s * std::sqrt(len2) <= eps || (1.0 - s) * std::sqrt(len2) <= eps) continue;
                if ((pa + s * ab - m.vertices[v]).norm() <= eps) on.emplace_back(s, v);
              }
      if (on.empty()) continue;
      std::sort(on.begin(), on.end());
      for (const auto& [s, v] : on) inner[f][i].push_back(v);
      split += on.size();
      any = true;
    }
    if (any) touched.push_back(f);
  }
  if (split == 0) return {welded, 0};
  PolygonMesh out;
  out.vertices = m.vertices;
  out.colours = m.colours;
  std::size_t next_touched = 0;
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    const auto t = m.face(f);
    if (next_touched >= touched.size() || touched[next_touched] != f) {
      out.add_face(t);
      continue;
    }
    ++next_touched;
    // Each split edge in turn: the triangle holding it becomes a fan from its opposite corner
    // (the other two edges stay whole in the fan's end triangles).
    std::vector<std::array<int, 3>> tris = {{t[0], t[1], t[2]}};
    for (int i = 0; i < 3; ++i) {
      if (inner[f][i].empty()) continue;
      const int a = t[i], b = t[(i + 1) % 3];
      for (std::size_t k = 0; k < tris.size(); ++k) {
        const auto tri = tris[k];
        int j = 0;
        while (j < 3 && !(tri[j] == a && tri[(j + 1) % 3] == b)) ++j;
        if (j == 3) continue;
        const int c = tri[(j + 2) % 3];
        tris.erase(tris.begin() + static_cast<std::ptrdiff_t>(k));
        int prev = a;
        for (const int v : inner[f][i]) tris.push_back({prev, v, c}), prev = v;
        tris.push_back({prev, b, c});
        break;
      }
    }
    for (const auto& tri : tris) out.add_face(tri);
  }
  m = std::move(out);
  return {welded, split};
}


/// Longest-edge bisection (Rivara) of the marked faces among those from first_face on, closed so
/// no T-junction remains: a face with an edge to split has its longest edge split too, and every
/// edge is split at one shared midpoint in both its faces (so a closed mesh stays closed). A marked
/// face is also split at the edges `beyond_edges` names (per face, bit i: its edge from vertex i to
/// i + 1 mod 3; an edge whose midpoint is beyond the bound: cutting only the longest edge would
/// leave that sample where it is, in one of the halves). A face is bisected at its longest edge,
/// then each half at the other split edge it holds. Returns, per face of the new mesh, the face it
/// was cut from or is, and whether it is new; the midpoints are appended as vertices.
struct Bisected {
  std::vector<std::size_t> from;
  std::vector<std::uint8_t> fresh;
};
Bisected bisect_marked(Builder& out, std::size_t first_face, const std::vector<std::uint8_t>& marked,
                       const std::vector<std::uint8_t>& beyond_edges) {
  const PolygonMesh& m = out.mesh;
  const std::vector<Eigen::Vector3d>* V = &m.vertices;  // moves to the new mesh below
  const auto longer = [&](int a, int b, int c, int d) {  // edge (a, b) longer than (c, d), ties by key
    const double l1 = ((*V)[a] - (*V)[b]).squaredNorm(), l2 = ((*V)[c] - (*V)[d]).squaredNorm();
    return l1 != l2 ? l1 > l2 : edge_key(a, b) > edge_key(c, d);
  };
  const auto longest = [&](std::span<const int> t) {
    int best = 0;
    for (int i = 1; i < 3; ++i)
      if (longer(t[i], t[(i + 1) % 3], t[best], t[(best + 1) % 3])) best = i;
    return edge_key(t[best], t[(best + 1) % 3]);
  };
  // Each edge's faces (more than two: the edge is open or non-manifold). Open edges (the blend's
  // own holes) are never split: their count stays as it was.
  struct EdgeFaces {
    int uses = 0;
    std::size_t face[2] = {0, 0};
  };
  std::unordered_map<std::uint64_t, EdgeFaces> edges;
  edges.reserve(3 * (m.face_count() - first_face) / 2 + 1);
  for (std::size_t f = first_face; f < m.face_count(); ++f) {
    const auto t = m.face(f);
    for (int i = 0; i < 3; ++i) {
      EdgeFaces& e = edges[edge_key(t[i], t[(i + 1) % 3])];
      if (e.uses < 2) e.face[e.uses] = f;
      ++e.uses;
    }
  }
  std::unordered_map<std::uint64_t, int> midpoint;  // edge → its midpoint vertex (−1 until made)
  std::vector<std::uint64_t> to_close;              // split edges whose faces are not yet closed
  const auto split_edge = [&](std::uint64_t e) {
    if (edges.at(e).uses == 2 && midpoint.emplace(e, -1).second) to_close.push_back(e);
  };
  for (std::size_t f = first_face; f < m.face_count(); ++f) {
    if (!marked[f]) continue;
    const auto t = m.face(f);
    split_edge(longest(t));
    for (int i = 0; i < 3; ++i)
      if (beyond_edges[f] >> i & 1u) split_edge(edge_key(t[i], t[(i + 1) % 3]));
  }
  while (!to_close.empty()) {  // the closure: a split edge forces its faces' longest ones
    const EdgeFaces e = edges.at(to_close.back());
    to_close.pop_back();
    for (int k = 0; k < 2; ++k) split_edge(longest(m.face(e.face[k])));
  }
  // Midpoints numbered in edge order, whatever order the closure reached them in.
  std::vector<std::uint64_t> split_edges;
  split_edges.reserve(midpoint.size());
  for (const auto& [key, v] : midpoint) split_edges.push_back(key);
  std::sort(split_edges.begin(), split_edges.end());
  for (const std::uint64_t key : split_edges) {
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
    midpoint[key] = out.add_vertex(0.5 * ((*V)[a] + (*V)[b]), out.colours ? out.mesh.colours[a] : kDefaultGrey);
  }
  PolygonMesh next;
  next.vertices = std::move(out.mesh.vertices);
  next.colours = std::move(out.mesh.colours);
  V = &next.vertices;
  Bisected out_faces;
  const auto split = [&](auto&& self, std::array<int, 3> t, std::size_t from, bool is_new) -> void {
    int best = -1;
    for (int i = 0; i < 3; ++i)
      if (midpoint.contains(edge_key(t[i], t[(i + 1) % 3])) &&
          (best < 0 || longer(t[i], t[(i + 1) % 3], t[best], t[(best + 1) % 3])))
        best = i;
    if (best < 0) {
      next.add_face(t);
      out_faces.from.push_back(from);
      out_faces.fresh.push_back(is_new);
      return;
    }
    const int u = t[best], v = t[(best + 1) % 3], w = t[(best + 2) % 3], mid = midpoint.at(edge_key(u, v));
    self(self, {u, mid, w}, from, true);
    self(self, {mid, v, w}, from, true);
  };
  for (std::size_t f = 0; f < m.face_count(); ++f) {
    const auto t = m.face(f);
    if (f < first_face) {
      next.add_face(t);
      out_faces.from.push_back(f);
      out_faces.fresh.push_back(0);
    } else {
      split(split, {t[0], t[1], t[2]}, f, false);
    }
  }
  out.mesh = std::move(next);
  return out_faces;
}

/// The area of the faces from first_face on with a sample beyond the bound (where->faces): what a
/// refinement is judged by. Counting samples would not do: cutting a face whose surface no cut
/// reaches (a step of the blend between two sheets farther apart than its push) turns its four
/// samples beyond into sixteen, on a quarter of the area each.
double area_beyond(const PolygonMesh& m, const BeyondSamples& where, double bound, std::size_t first_face) {
  double area = 0;
  for (std::size_t f = first_face; f < m.face_count() && f < where.faces.size(); ++f) {
    if (!(where.faces[f] > bound)) continue;
    const auto t = m.face(f);
    area += 0.5 * (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]).norm();
  }
  return area;
}

/// Whether a local refinement made things worse and is to be undone: it left a larger area of
/// faces beyond the bound than it found, or a maximum more than a quarter larger (a midpoint that
/// jumped to another sheet). The maximum itself may stay: the faces over a step of the blend keep
/// it whatever is cut, and are left out later (open_parts).
bool refinement_worse(const PolygonMesh& before, const BeyondSamples& before_where, const MeshDistance& before_distance,
                      const PolygonMesh& after, const BeyondSamples& after_where, const MeshDistance& after_distance,
                      double bound, std::size_t first_face) {
  if (after_distance.misses > before_distance.misses) return true;
  if (after_distance.max > 1.25 * before_distance.max) return true;
  return area_beyond(after, after_where, bound, first_face) > area_beyond(before, before_where, bound, first_face);
}

/// Local refinement of the SLIM triangles (faces from first_face on): rounds of bisect_marked on
/// the faces with a sample beyond the bound (mesh → surface, measured on the new faces only) and,
/// once there are none, on the faces nearest the drawn surface's points beyond it (surface →
/// mesh); each midpoint moved onto the blend along its normal (snap_to_surface, kept where its
/// line meets none). Returns the rounds used, and the mesh before them with its measure.
struct LocalRefinement {
  int rounds = 0;
  bool measured = false;  ///< round 0 ran: `before` and `before_where` hold the whole mesh's measure
  MeshDistance before;    ///< mesh → surface of the whole mesh before the first cut
  BeyondSamples before_where;
  PolygonMesh unrefined;
  /// Surface → mesh of the mesh returned, when the last round measured it and cut nothing after
  std::optional<SurfaceError> surface;
};

/// surface_error: surface → mesh of a mesh, keeping its points beyond the bound.
using SurfaceMeasure = std::function<SurfaceError(const PolygonMesh&)>;

LocalRefinement refine_locally(const ReferenceScene& scene, const TraceOptions& trace, const ToMeshOptions& o,
                               double bound, double reach, double snap_reach, std::size_t first_face, Builder& b,
                               SampleMemo& memo, const SurfaceMeasure& surface_error, bool any_kind = false) {
  std::vector<std::uint8_t> fresh(b.mesh.face_count(), 0);
  std::fill(fresh.begin() + static_cast<std::ptrdiff_t>(first_face), fresh.end(), 1);
  // Per face: its worst sample, and how many generations it has been cut without that dropping
  // below 3/4 of its parent's (a gap of the blend no mesh follows: cut no further).
  std::vector<double> worst(b.mesh.face_count(), std::numeric_limits<double>::infinity());
  std::vector<std::uint8_t> stalls(b.mesh.face_count(), 0);
  constexpr int kMaxStalls = 2;
  std::vector<std::uint8_t> resnapped;  // vertices already moved along their normal once
  LocalRefinement out;
  if (o.local_refinements > 0) out.unrefined = b.mesh;
  std::size_t surface_beyond_before = std::numeric_limits<std::size_t>::max();
  int round = 0;
  for (; round < o.local_refinements && b.mesh.face_count() < o.max_triangles; ++round) {
    // Mesh → surface on the new faces (the others were measured within the bound before).
    // With the faces around them, so their vertices' normals are the whole mesh's.
    std::vector<std::uint8_t> touched(b.mesh.vertices.size(), 0);
    for (std::size_t f = first_face; f < b.mesh.face_count(); ++f)
      if (fresh[f])
        for (const int v : b.mesh.face(f)) touched[v] = 1;
    // Round 0 measures the whole mesh (all faces are new but those of other primitives), so that
    // the measure stands for the unrefined mesh should the refinement be undone.
    PolygonMesh part;
    std::vector<std::size_t> of_part;
    if (round == 0) {
      of_part.resize(b.mesh.face_count());
      std::iota(of_part.begin(), of_part.end(), std::size_t{0});
    } else {
      part.vertices = b.mesh.vertices;
      for (std::size_t f = first_face; f < b.mesh.face_count(); ++f) {
        const auto t = b.mesh.face(f);
        if (fresh[f] || touched[t[0]] || touched[t[1]] || touched[t[2]]) {
          part.add_face(t);
          of_part.push_back(f);
        }
      }
    }
    BeyondSamples part_beyond;
    const MeshDistance md = mesh_to_surface(scene, trace, round == 0 ? b.mesh : part, reach, bound, &part_beyond, &memo);
    if (round == 0) {
      out.before = md;
      out.before_where = part_beyond;
      out.measured = true;
    }
    std::vector<std::uint8_t> marked(b.mesh.face_count(), 0), beyond_edges(b.mesh.face_count(), 0);
    for (std::size_t k = 0; k < of_part.size(); ++k) {
      const std::size_t f = of_part[k];
      if (!fresh[f]) continue;
      const double e = part_beyond.faces[k];
      if (e > bound && !(e < 0.75 * worst[f])) ++stalls[f];
      worst[f] = e;
      marked[f] = e > bound && stalls[f] < kMaxStalls;
      beyond_edges[f] = part_beyond.edges[k];
    }
    resnapped.resize(b.mesh.vertices.size(), 0);
    // A vertex beyond the bound (a crossing the blend shows along its grid edge but not along its
    // normal) moves onto the blend along its normal, as a new one does.
    // Its reach: half its longest edge, so it cannot jump to another sheet of a thin part.
    std::vector<std::uint8_t> keep(b.mesh.vertices.size(), 1);
    std::vector<double> half_edge(b.mesh.vertices.size(), 0.0);
    bool any_vertex = false;
    for (std::size_t v = 0; v < keep.size(); ++v)
      if (part_beyond.vertices[v] && !resnapped[v] && (round > 0 || touched[v]))  // SLIM vertices only
        keep[v] = 0, resnapped[v] = 1, any_vertex = true;
    if (any_vertex) {
      for (std::size_t f = first_face; f < b.mesh.face_count(); ++f) {
        const auto t = b.mesh.face(f);
        for (int i = 0; i < 3; ++i) {
          const double l = 0.5 * (b.mesh.vertices[t[i]] - b.mesh.vertices[t[(i + 1) % 3]]).norm();
          half_edge[t[i]] = std::max(half_edge[t[i]], l);
          half_edge[t[(i + 1) % 3]] = std::max(half_edge[t[(i + 1) % 3]], l);
        }
      }
      snap_to_surface(scene, trace, snap_reach, 0, keep, b, /*drop_unmet=*/false, &half_edge, any_kind);
    }
    std::size_t n_marked = static_cast<std::size_t>(std::count(marked.begin(), marked.end(), 1));
    if (md.beyond == 0) {
      // Surface → mesh: the faces whose bounding sphere reaches within a beyond point's distance.
      const SurfaceError se = surface_error(b.mesh);
      // Cuts that leave as many of the drawn surface's pixels beyond the bound as the last ones
      // did do not reach them (a part or gap the grid missed, which no cut creates): stop.
      if (se.beyond_points.empty() || se.beyond >= surface_beyond_before) {
        out.surface = se;
        break;
      }
      surface_beyond_before = se.beyond;
      const auto& V = b.mesh.vertices;
      for (std::size_t f = first_face; f < b.mesh.face_count(); ++f) {
        const auto t = b.mesh.face(f);
        const Eigen::Vector3d c = (V[t[0]] + V[t[1]] + V[t[2]]) / 3.0;
        const double rad = std::max({(V[t[0]] - c).norm(), (V[t[1]] - c).norm(), (V[t[2]] - c).norm()});
        for (const auto& [p, d] : se.beyond_points)
          if ((p - c).norm() <= d + rad) {
            marked[f] = 1;
            ++n_marked;
            break;
          }
      }
      log::info("mesh: local round {}: {} surface points beyond the bound, {} faces near them", round + 1,
                se.beyond_points.size(), n_marked);
      if (n_marked == 0) break;
    } else {
      log::info("mesh: local round {}: {} samples beyond the bound (max {:.3g}) on {} faces measured, {} to cut", round + 1,
                md.beyond, md.max, of_part.size(), n_marked);
      if (n_marked == 0 && !any_vertex) break;
    }
    const std::size_t first_vertex = b.mesh.vertices.size();
    Bisected cut = bisect_marked(b, first_face, marked, beyond_edges);
    std::vector<double> next_worst(cut.from.size());
    std::vector<std::uint8_t> next_stalls(cut.from.size());
    for (std::size_t f = 0; f < cut.from.size(); ++f) {
      next_worst[f] = worst[cut.from[f]];
      next_stalls[f] = stalls[cut.from[f]];
    }
    fresh = std::move(cut.fresh);
    worst = std::move(next_worst);
    stalls = std::move(next_stalls);
    // A midpoint's reach: half its parent edge (the length of its halves), and no more than twice
    // its parent face's worst sample (at least 4 bounds), so it cannot jump to another sheet.
    const std::size_t added = b.mesh.vertices.size() - first_vertex;
    std::vector<double> edge_of(added, 0.0), cap_of(added, 0.0);
    for (std::size_t f = first_face; f < b.mesh.face_count(); ++f) {
      const auto t = b.mesh.face(f);
      for (int i = 0; i < 3; ++i) {
        const int v = t[i];
        if (static_cast<std::size_t>(v) < first_vertex) continue;
        const std::size_t k = v - first_vertex;
        edge_of[k] = std::max(edge_of[k], (b.mesh.vertices[v] - b.mesh.vertices[t[(i + 1) % 3]]).norm());
        cap_of[k] = std::max(cap_of[k], std::max(2.0 * worst[f], 4.0 * bound));
      }
    }
    std::vector<double> reach_of(added);
    for (std::size_t k = 0; k < added; ++k) reach_of[k] = std::min(edge_of[k], cap_of[k]);
    snap_to_surface(scene, trace, snap_reach, first_vertex, std::vector<std::uint8_t>(added, 0), b, /*drop_unmet=*/false,
                    &reach_of, any_kind);
  }
  out.rounds = round;
  return out;
}

// ---- fins (SLIM) ------------------------------------------------------------------------------

/// Open sheets for what a closed inside/outside labelling cannot hold: where the drawn surface's
/// points beyond the bound lie on one patch's own zero set (a patch's rim drawn alone, running on
/// as a fin past where its neighbours' surface turns), that patch's surface there as a grid of
/// triangles over its tangent plane (step grid_step, at least R/128): nodes on the quadric (along
/// the plane's normal), inside the ball and clip planes, and drawn (within half the bound of the
/// blend along the node's normal or its 13 lines, as mesh → surface measures it); cells with three
/// or four nodes so and one farther than the bound from `mesh`. The triangles come with their own
/// vertices (their edges open), facing the patch's outside.
struct FinSheets {
  PolygonMesh mesh;
  std::vector<Rgb> colours;  ///< per vertex: its patch's colour
  std::size_t patches = 0;
};
FinSheets fin_sheets(const Model& model, const ReferenceScene& scene, const TraceOptions& trace, const PolygonMesh& mesh,
                     std::span<const SurfaceError::Beyond> beyond, double bound, double grid_step) {
  FinSheets fins;
  PolygonMesh& out = fins.mesh;
  // Per point: the patch whose zero set it lies on (within half a bound). A point of the blend
  // between two sheets lies on neither: a sheet of the blend itself, seen along the heaviest
  // patch's normal, was tried and drawn 1.5 bounds off where other views see it (the kitten).
  std::vector<int> patch_of(beyond.size(), -1);
  tbb::parallel_for(std::size_t{0}, beyond.size(), [&](std::size_t k) {
    double best_d = 0.5 * bound;
    for (std::size_t i = 0; i < model.slims.size(); ++i) {
      const SlimPatch& s = model.slims[i];
      if ((beyond[k].point - s.centre).squaredNorm() >= s.radius * s.radius) continue;
      const Eigen::Vector3d u = (beyond[k].point - s.centre) / s.radius;
      if (!s.clips.keeps(u)) continue;
      const double gn = s.local.gradient(u).norm();
      if (!(gn > 1e-12)) continue;
      const double d = std::abs(s.radius * s.local.eval(u) / gn);
      if (d <= best_d) patch_of[k] = static_cast<int>(i), best_d = d;
    }
  });
  std::map<int, std::vector<Eigen::Vector3d>> on_patch;  // patch → the points beyond on its zero set
  for (std::size_t k = 0; k < beyond.size(); ++k)
    if (patch_of[k] >= 0) on_patch[patch_of[k]].push_back(beyond[k].point);
  if (on_patch.empty()) return fins;
  const DataSurface near_mesh = DataSurface::from_mesh(mesh);
  for (const auto& [index, points] : on_patch) {
    const SlimPatch& s = model.slims[index];
    const double step = std::max(grid_step, s.radius / 128.0);  // at most 257² nodes per patch
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const auto& p : points) c += p / static_cast<double>(points.size());
    const Eigen::Vector3d n0 = s.local.gradient((c - s.centre) / s.radius).normalized();
    if (!n0.allFinite()) continue;
    const Eigen::Vector3d e1 = n0.unitOrthogonal(), e2 = n0.cross(e1);
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const auto& p : points) {
      const Eigen::Vector2d q((p - c).dot(e1), (p - c).dot(e2));
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
    lo = (lo.array() - 2.0 * step).max(-s.radius);
    hi = (hi.array() + 2.0 * step).min(s.radius);
    const int ni = static_cast<int>(std::ceil((hi.x() - lo.x()) / step)) + 1, nj = static_cast<int>(std::ceil((hi.y() - lo.y()) / step)) + 1;
    struct Node {
      Eigen::Vector3d x, n;
      bool drawn = false, far = false;
    };
    std::vector<Node> nodes(static_cast<std::size_t>(ni) * nj);
    tbb::parallel_for(0, ni * nj, [&](int k) {
      Node& node = nodes[k];
      const Eigen::Vector3d x0 = c + (lo.x() + (k % ni) * step) * e1 + (lo.y() + (k / ni) * step) * e2;
      // The quadric along x0 + t·n0, local units: the root nearest x0.
      const Eigen::Vector3d u0 = (x0 - s.centre) / s.radius;
      const double qa = n0.dot(s.local.A * n0), qb = 2.0 * n0.dot(s.local.A * u0 + s.local.b), qc = s.local.eval(u0);
      double t = std::numeric_limits<double>::infinity();
      if (std::abs(qa) <= 1e-14 * (std::abs(qb) + std::abs(qc))) {
        if (qb != 0.0) t = -qc / qb;
      } else if (const double disc = qb * qb - 4.0 * qa * qc; disc >= 0.0) {
        const double qq = -0.5 * (qb + std::copysign(std::sqrt(disc), qb));
        for (const double r : {qq / qa, qq != 0.0 ? qc / qq : std::numeric_limits<double>::infinity()})
          if (std::abs(r) < std::abs(t)) t = r;
      }
      if (!(std::abs(t) <= 1.0)) return;
      const Eigen::Vector3d u = u0 + t * n0;
      if (u.squaredNorm() >= 1.0 || !s.clips.keeps(u)) return;
      node.x = s.centre + s.radius * u;
      node.n = s.local.gradient(u).normalized();
      if (!node.n.allFinite()) return;
      const double d = nearest_along_lines(scene, trace, node.x, node.n, 2.0 * bound, 0.25 * bound);
      node.drawn = d >= 0 && d <= 0.5 * bound;
      node.far = node.drawn && near_mesh.distance(node.x, 2.0 * bound) > bound;
    });
    std::vector<int> vertex(nodes.size(), -1);
    const auto vertex_of = [&](int k) {
      if (vertex[k] < 0) {
        vertex[k] = static_cast<int>(out.vertices.size());
        out.vertices.push_back(nodes[k].x);
        fins.colours.push_back(s.colour.value_or(kDefaultGrey));
      }
      return vertex[k];
    };
    const auto add = [&](int a, int b, int d) {
      const Eigen::Vector3d normal = nodes[a].n + nodes[b].n + nodes[d].n;
      if ((nodes[b].x - nodes[a].x).cross(nodes[d].x - nodes[a].x).dot(normal) < 0) std::swap(b, d);
      const int f[3] = {vertex_of(a), vertex_of(b), vertex_of(d)};
      out.add_face(f);
    };
    const std::size_t faces_before = out.face_count();
    for (int j = 0; j + 1 < nj; ++j)
      for (int i = 0; i + 1 < ni; ++i) {
        const int k[4] = {j * ni + i, j * ni + i + 1, (j + 1) * ni + i + 1, (j + 1) * ni + i};
        if (!std::any_of(k, k + 4, [&](int x) { return nodes[x].far; })) continue;
        const int drawn = static_cast<int>(std::count_if(k, k + 4, [&](int x) { return nodes[x].drawn; }));
        if (drawn == 4) {
          add(k[0], k[1], k[2]);
          add(k[0], k[2], k[3]);
        } else if (drawn == 3) {  // at the rim: the three drawn corners
          int t[3], n = 0;
          for (const int x : k)
            if (nodes[x].drawn) t[n++] = x;
          add(t[0], t[1], t[2]);
        }
      }
    fins.patches += out.face_count() > faces_before;
  }
  return fins;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double median_radius(const Model& m) {
  std::vector<double> r;
  for (const auto& s : m.slims) r.push_back(s.radius);
  std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
  return r[r.size() / 2];
}

}  // namespace

std::vector<std::array<Eigen::Vector3i, 4>> edgewise_subdivision(int k) {
  std::vector<std::array<Eigen::Vector3i, 4>> out;
  const auto inside = [k](const Eigen::Vector3i& x) { return k >= x[0] && x[0] >= x[1] && x[1] >= x[2] && x[2] >= 0; };
  for (int a = 0; a < k; ++a)
    for (int b = 0; b <= a; ++b)
      for (int c = 0; c <= b; ++c)
        for (const auto& perm : kPermutations) {
          std::array<Eigen::Vector3i, 4> t;
          t[0] = {a, b, c};
          bool ok = inside(t[0]);
          for (int s = 0; s < 3 && ok; ++s) {
            t[s + 1] = t[s];
            ++t[s + 1][perm[s]];
            ok = inside(t[s + 1]);
          }
          if (ok) out.push_back(t);
        }
  return out;
}

MeshDistance mesh_distance(const Model& model, const PolygonMesh& mesh, double reach, double bound) {
  if (model.empty()) throw InvalidInput("mesh_distance: the model is empty (no primitives)");
  const ReferenceScene scene(model);
  TraceOptions trace;
  trace.slim = slim_blend_of(model);
  return mesh_to_surface(scene, trace, mesh, reach, bound);
}

/// At -vv: the `shown` drawn points farthest from the mesh, each as "mesh: <what> at (x, y, z): d
/// from the mesh".
void log_farthest(std::span<const SurfaceError::Beyond> points, std::size_t shown, const char* what) {
  if (log::level() > log::Level::debug || points.empty()) return;
  std::vector<SurfaceError::Beyond> worst(points.begin(), points.end());
  shown = std::min(shown, worst.size());
  std::partial_sort(worst.begin(), worst.begin() + std::ptrdiff_t(shown), worst.end(),
                    [](const auto& x, const auto& y) { return x.distance > y.distance; });
  for (std::size_t k = 0; k < shown; ++k)
    log::debug("mesh: {} at ({:.6g}, {:.6g}, {:.6g}): {:.3g} from the mesh", what, worst[k].point.x(), worst[k].point.y(),
               worst[k].point.z(), worst[k].distance);
}

/// The drawn surface under faces left out of a mesh: at each such face's centroid, edge midpoints
/// and the points halfway from its centroid to its corners, what a view along the face's normal
/// sees from either side (within reach). Traced once; gap_error measures them against each mesh
/// that remains (surface → mesh where the views' pixels may be wider than the gap). Lines that
/// meet nothing give no point: nothing is drawn there.
std::vector<Eigen::Vector3d> drawn_under(const ReferenceScene& scene, const TraceOptions& trace, const PolygonMesh& from,
                                         std::span<const std::size_t> faces, double reach) {
  std::vector<std::array<std::optional<Eigen::Vector3d>, 14>> hits(faces.size());
  tbb::parallel_for(std::size_t{0}, faces.size(), [&](std::size_t k) {
    const auto t = from.face(faces[k]);
    const Eigen::Vector3d &a = from.vertices[t[0]], &b = from.vertices[t[1]], &c = from.vertices[t[2]];
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (!(n.norm() > 0)) return;
    n.normalize();
    const Eigen::Vector3d g = (a + b + c) / 3.0;
    const Eigen::Vector3d at[7] = {g, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a), 0.5 * (g + a), 0.5 * (g + b), 0.5 * (g + c)};
    for (int i = 0; i < 7; ++i)
      for (int side = 0; side < 2; ++side)
        if (const auto hit = along_normal(scene, trace, at[i], side ? Eigen::Vector3d(-n) : n, reach))
          hits[k][2 * i + side] = hit->point;
  });
  std::vector<Eigen::Vector3d> out;
  for (const auto& row : hits)
    for (const auto& h : row)
      if (h) out.push_back(*h);
  return out;
}

/// The drawn points under the faces left out (drawn_under) against the mesh that remains: their
/// distances, and those beyond the bound (optional).
MeshDistance gap_error(std::span<const Eigen::Vector3d> drawn, const PolygonMesh& kept, double bound,
                       std::vector<SurfaceError::Beyond>* beyond_points = nullptr) {
  MeshDistance out;
  if (drawn.empty()) return out;
  if (kept.face_count() == 0) {
    out.max = std::numeric_limits<double>::infinity();
    out.samples = out.beyond = drawn.size();
    return out;
  }
  const DataSurface mesh = DataSurface::from_mesh(kept);
  std::vector<double> d(drawn.size());
  tbb::parallel_for(std::size_t{0}, drawn.size(), [&](std::size_t k) { d[k] = mesh.distance(drawn[k]); });
  double sum2 = 0;
  for (std::size_t k = 0; k < d.size(); ++k) {
    ++out.samples;
    sum2 += d[k] * d[k];
    out.max = std::max(out.max, d[k]);
    out.beyond += d[k] > bound;
    if (beyond_points && d[k] > bound) beyond_points->push_back({drawn[k], d[k]});
  }
  out.rms = std::sqrt(sum2 / static_cast<double>(out.samples));
  return out;
}

bool unions_glyphs(const Model& model) { return model.glyphs.size() > 1; }

ToMeshResult mesh_model(const Model& model, const ToMeshOptions& o) {
  if (model.empty()) throw InvalidInput("cannot mesh an empty model (no primitives)");
  const Box3 box = bounds(model);
  const double diagonal = box.diagonal();
  const double bound = o.max_error > 0 ? o.max_error : 1e-3 * diagonal;
  if (!std::isfinite(bound) || !(bound > 0)) throw InvalidInput(fmt::format("mesh: max error {} is not positive", bound));
  const ReferenceScene scene(model);
  // The sides of SLIM grid nodes are read from the blend alone (tets and glyphs would hide it).
  Model slims_only;
  std::optional<ReferenceScene> slim_scene;
  if (!model.slims.empty() && (!model.tets.empty() || !model.glyphs.empty() || !model.implicits.empty())) {
    slims_only.slims = model.slims;
    slim_scene.emplace(slims_only);
  }
  TraceOptions trace;
  trace.slim = slim_blend_of(model, o.slim_offset);
  // SLIM grid: a chord of length h sits about h²κ/8 off a surface of curvature κ; patches bend
  // over their radius R at most, so h = sqrt(8·bound·R)/2 starts near the bound. At most 256 cells
  // along the diagonal at first; refinements halve it.
  const double slim_h0 = model.slims.empty()
                             ? 0
                             : std::max(std::min(median_radius(model) / 2.0, 0.5 * std::sqrt(8.0 * bound * median_radius(model))),
                                        diagonal / 256.0);

  // Surface → mesh points beyond the bound kept for local and grid refinement.
  constexpr std::size_t kKeepBeyond = 1u << 14;
  // Surface → mesh, keeping `keep` of the drawn surface's points beyond the bound. The drawn
  // surface is ray-cast from the views once, for every mesh measured.
  std::optional<SurfaceViews> views;
  const auto surface_error = [&](const PolygonMesh& mesh, std::size_t keep) {
    const auto t0 = std::chrono::steady_clock::now();
    const SurfaceErrorOptions so{.views = o.views, .resolution = o.view_resolution, .bound = bound, .keep_beyond_points = keep,
                                 .holes = false};
    if (!views)
      views = render_surface_views(
          [&](const Ray& ray) -> std::optional<double> {
            if (const auto hit = scene.trace(ray, 0.0, std::numeric_limits<double>::infinity(), trace)) return hit->t;
            return std::nullopt;
          },
          box, so);
    // A mesh with no triangle (the grid passed between the parts of a surface thinner than its
    // spacing): every drawn pixel is beyond it, at no finite distance.
    bool any = false;
    for (std::size_t f = 0; f < mesh.face_count() && !any; ++f) {
      const auto vs = mesh.face(f);
      const Eigen::Vector3d &a = mesh.vertices[vs[0]], &b = mesh.vertices[vs[1]], &c = mesh.vertices[vs[2]];
      any = !is_sliver((b - a).cross(c - a).norm(), std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()}));
    }
    if (!any) {
      SurfaceError none;
      for (const auto& t : views->t)
        for (const double d : t) none.pixels += d >= 0;
      none.beyond = none.pixels;
      none.share_beyond = none.pixels ? 1.0 : 0.0;
      none.max = none.p999 = none.p99 = none.rms = none.pixels ? std::numeric_limits<double>::infinity() : 0.0;
      return none;
    }
    SurfaceError se = measure_surface_error(*views, DataSurface::from_mesh(mesh), so);
    log::debug("mesh: surface -> mesh measured in {:.2f} s: {} pixels beyond the bound, max {:.3g}", seconds_since(t0),
               se.beyond, se.max);
    log_farthest(se.beyond_points, 8, "drawn surface");  // where the mesh leaves the drawn surface most
    return se;
  };
  const auto set_surface_side = [&](ToMeshResult& r, const SurfaceError& se) {
    r.surface_to_mesh = {se.max, se.rms, se.p99, se.pixels, 0, se.beyond};
    r.within = r.mesh_to_surface.misses == 0 && r.max_error() <= bound && r.mesh.face_count() > 0;
  };
  const auto measure_surface_side = [&](ToMeshResult& r, std::size_t keep = 0) {
    std::vector<Eigen::Vector3d> beyond;
    // With nothing meshed, every drawn pixel counts as beyond it (surface_error).
    const SurfaceError se = surface_error(r.mesh, keep);
    set_surface_side(r, se);
    for (const auto& b : se.beyond_points) beyond.push_back(b.point);
    r.within = r.mesh_to_surface.misses == 0 && r.max_error() <= bound && r.mesh.face_count() > 0;
    return beyond;
  };
  const auto share_beyond = [](const MeshDistance& d) {
    return d.samples == 0 ? 0.0 : static_cast<double>(d.beyond) / static_cast<double>(d.samples);
  };
  ToMeshResult best;
  bool have_best = false;
  // Mesh → surface samples measured so far at this level (each grid round makes most of the
  // SLIM mesh again as it was: those samples are not traced again).
  SampleMemo memo;
  const Eigen::Vector3d slim_extent = [&] {
    Box3 b;
    for (const auto& s : model.slims) b.extend(bounds(s));
    return model.slims.empty() ? Eigen::Vector3d(Eigen::Vector3d::Zero()) : Eigen::Vector3d(b.max - b.min);
  }();
  // One mesh at a resolution level, the SLIM grid's cells in `refined` cut finer; with, when
  // `where` is given, the centroids of its SLIM triangles with a sample beyond the bound.
  // `surface_bad`, `surface_measured`: where the last local round's surface → mesh measure holds
  // for the mesh returned, it is its figure, and its points beyond the bound are given.
  // The last mesh made: its SLIM triangles' first face, and the reach its samples were measured with.
  std::size_t slim_first_face = 0;
  double mesh_reach = 0;
  // Tetrahedron pieces cut where a mesh made before left its bound (lattice rounds, below), and
  // for the last mesh made, each of its tetrahedron faces' point and length to cut it at.
  std::vector<CutAt> tet_cut_at, tet_face_cut_at;
  std::vector<TetPatch> tet_pieces;
  const auto mesh_at = [&](int level, std::span<const KuhnCellDepth> refined, std::vector<Eigen::Vector3d>* where,
                           std::vector<Eigen::Vector3d>* surface_bad = nullptr, bool* surface_measured = nullptr,
                           bool* undone = nullptr) {
    Builder b;
    b.colours = has_any_colour(model);
    tet_face_cut_at.clear();
    if (!model.tets.empty()) mesh_tets(model, 1 << level, bound, b, tet_cut_at, &tet_face_cut_at, &tet_pieces);
    std::size_t unions_failed = 0;
    const bool glyph_union = o.union_glyphs && unions_glyphs(model) && model.glyphs.size() <= o.union_max_glyphs;
    if (glyph_union)
      unions_failed = mesh_glyph_union(model.glyphs, bound, level, b);
    else
      for (const Glyph& g : model.glyphs) mesh_glyph(g, bound, level, b);
    for (const ImplicitSurface& s : model.implicits) mesh_implicit(s, level, b);
    double reach = 4.0 * bound;
    LocalRefinement local;
    const std::size_t first_face = b.mesh.face_count();
    slim_first_face = first_face;
    if (!model.slims.empty()) {
      const double h = slim_h0 / (1 << level);
      const std::size_t first = b.mesh.vertices.size();
      std::vector<std::uint8_t> on_surface;
      const auto t0 = std::chrono::steady_clock::now();
      mesh_slims(model, slim_scene ? *slim_scene : scene, trace, h, refined, b, on_surface);
      snap_to_surface(scene, trace, 1.5 * h, first, on_surface, b);
      const auto t1 = std::chrono::steady_clock::now();
      reach = std::max(reach, 1.5 * h);
      mesh_reach = reach;
      local = refine_locally(scene, trace, o, bound, reach, 1.5 * h, first_face, b, memo,
                             [&](const PolygonMesh& m) { return surface_error(m, kKeepBeyond); });
      log::debug("mesh: SLIM grid ({} refined cells) in {:.2f} s, local refinement in {:.2f} s", refined.size(),
                 std::chrono::duration<double>(t1 - t0).count(),
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count());
    }
    ToMeshResult r;
    r.bound = bound;
    r.glyph_union = glyph_union;
    r.glyph_unions_failed = unions_failed;
    r.refinements = level;
    r.local_rounds = local.rounds;
    r.mesh = std::move(b.mesh);
    BeyondSamples beyond;
    if (local.measured && local.rounds == 0) {  // nothing was cut: round 0's measure is this mesh's
      r.mesh_to_surface = local.before;
      beyond = std::move(local.before_where);
    } else {
      r.mesh_to_surface = mesh_to_surface(scene, trace, r.mesh, reach, bound, &beyond, &memo);
    }
    // Local refinement that made things worse (refinement_worse: a blend whose sheets its normals
    // cannot tell apart) is undone, with round 0's measure of the unrefined mesh.
    if (local.rounds > 0 && refinement_worse(local.unrefined, local.before_where, local.before, r.mesh, beyond,
                                             r.mesh_to_surface, bound, first_face)) {
      log::info("mesh: local refinement left {} samples beyond the bound (max {:.3g}), {} before it (max {:.3g}): undone",
                r.mesh_to_surface.beyond, r.mesh_to_surface.max, local.before.beyond, local.before.max);
      r.mesh = std::move(local.unrefined);
      r.mesh_to_surface = local.before;
      beyond = std::move(local.before_where);
      r.local_rounds = 0;
      if (undone) *undone = true;
    }
    r.open_edges = count_open_edges(r.mesh);
    log::debug("mesh: mesh -> surface samples so far: {} traced, {} from the memo", memo.traced(), memo.reused());
    if (surface_bad && local.surface && r.local_rounds == local.rounds) {  // its last measure is this mesh's
      const SurfaceError& se = *local.surface;
      r.surface_to_mesh = {se.max, se.rms, se.p99, se.pixels, 0, se.beyond};
      r.within = r.mesh_to_surface.misses == 0 && r.max_error() <= bound && r.mesh.face_count() > 0;
      surface_bad->clear();
      for (const auto& p : se.beyond_points) surface_bad->push_back(p.point);
      *surface_measured = true;
    }
    if (where)
      for (std::size_t f = first_face; f < r.mesh.face_count() && f < beyond.faces.size(); ++f)
        if (beyond.faces[f] > bound) {
          const auto t = r.mesh.face(f);
          where->push_back((r.mesh.vertices[t[0]] + r.mesh.vertices[t[1]] + r.mesh.vertices[t[2]]) / 3.0);
        }
    return r;
  };
  const auto total_beyond = [](const ToMeshResult& r) { return r.mesh_to_surface.beyond + r.surface_to_mesh.beyond; };
  // Where the drawn surface's points beyond the bound lie on one patch's zero set, seen alone (a
  // rim running on as a fin past where its neighbours' surface turns, which no closed labelling
  // holds), that patch's surface there is added as an open sheet, in rounds (each round's points
  // beyond the bound may lie on the last one's rims); a round kept only if it leaves fewer
  // samples beyond the bound (both ways) and no larger maximum. Leaves the surface side measured.
  // With `gap` (faces left out of that mesh), the drawn surface under them counts on the surface
  // side too (gap_error), and its points beyond the bound are given to fin_sheets as the views' are.
  struct Gap {
    std::span<const Eigen::Vector3d> drawn;  ///< drawn_under the faces left out
  };
  const auto surface_side_with_gap = [&](ToMeshResult& r, const Gap& gap, std::size_t keep) {
    SurfaceError se = surface_error(r.mesh, keep);
    set_surface_side(r, se);
    if (!gap.drawn.empty()) {
      std::vector<SurfaceError::Beyond> points;
      const MeshDistance g = gap_error(gap.drawn, r.mesh, bound, keep ? &points : nullptr);
      MeshDistance& side = r.surface_to_mesh;
      const double n0 = static_cast<double>(side.samples), n1 = static_cast<double>(g.samples);
      side.rms = std::sqrt((n0 * side.rms * side.rms + n1 * g.rms * g.rms) / (n0 + n1));
      side.p99 = std::max(side.p99, g.p99);  // the views' (the gap's points are not ranked with them)
      side.max = std::max(side.max, g.max);
      side.samples += g.samples;
      side.beyond += g.beyond;
      r.within = r.within && g.beyond == 0;
      log_farthest(points, 5, "drawn surface under a face left out");
      se.beyond_points.insert(se.beyond_points.end(), points.begin(), points.end());
    }
    return se.beyond_points;
  };
  const auto add_fins = [&](ToMeshResult r, int level, const Gap& gap) {
    // Each mesh's surface side measured once, its points beyond the bound kept for the next round.
    std::vector<SurfaceError::Beyond> beyond = surface_side_with_gap(r, gap, kKeepBeyond);
    for (int round = 0; round < kFinRounds && !r.within; ++round) {
      if (beyond.empty()) break;
      // Coarse sheets first (cells of 2 bounds), halved each round down to half a bound: the points
      // left beyond lie at sheets' rims, where cells that need three drawn corners stop short.
      const double step = std::max(std::min(0.5 * slim_h0 / (1 << level), 2.0 * bound) / (1 << round), 0.5 * bound);
      const FinSheets fins = fin_sheets(model, scene, trace, r.mesh, beyond, bound, step);
      if (fins.mesh.face_count() == 0) break;
      ToMeshResult next = r;
      const int base = static_cast<int>(next.mesh.vertices.size());
      next.mesh.vertices.insert(next.mesh.vertices.end(), fins.mesh.vertices.begin(), fins.mesh.vertices.end());
      if (!next.mesh.colours.empty()) next.mesh.colours.insert(next.mesh.colours.end(), fins.colours.begin(), fins.colours.end());
      for (std::size_t f = 0; f < fins.mesh.face_count(); ++f) {
        const auto t = fins.mesh.face(f);
        const int tri[3] = {base + t[0], base + t[1], base + t[2]};
        next.mesh.add_face(tri);
      }
      next.mesh_to_surface = mesh_to_surface(scene, trace, next.mesh, mesh_reach, bound, nullptr, &memo);
      if (next.mesh_to_surface.beyond > r.mesh_to_surface.beyond) {
        // A sheet's triangle between drawn nodes can still bow away from the drawn surface (hippo1
        // fitted at 1e-3: 3 triangles, one of them at 1.2 bounds): those of this round's sheets
        // with a sample beyond the bound are left out.
        BeyondSamples at;
        mesh_to_surface(scene, trace, next.mesh, mesh_reach, bound, &at, &memo);
        std::vector<std::uint8_t> drop(next.mesh.face_count(), 0);
        const std::size_t first_fin = r.mesh.face_count();
        for (std::size_t f = first_fin; f < next.mesh.face_count() && f < at.faces.size(); ++f) drop[f] = at.faces[f] > bound;
        if (std::count(drop.begin(), drop.end(), std::uint8_t{1}) > 0) {
          next.mesh = without_faces(next.mesh, drop);
          next.mesh_to_surface = mesh_to_surface(scene, trace, next.mesh, mesh_reach, bound, nullptr, &memo);
        }
      }
      std::vector<SurfaceError::Beyond> next_beyond = surface_side_with_gap(next, gap, kKeepBeyond);
      next.open_edges = count_open_edges(next.mesh);
      log::info("mesh: fin round {}: {} triangles on {} patches' rims; beyond the bound {} / {} (was {} / {}), max {:.3g} / {:.3g}",
                round + 1, fins.mesh.face_count(), fins.patches, next.mesh_to_surface.beyond, next.surface_to_mesh.beyond,
                r.mesh_to_surface.beyond, r.surface_to_mesh.beyond, next.mesh_to_surface.max, next.surface_to_mesh.max);
      if (!next.within && (total_beyond(next) >= total_beyond(r) || next.mesh_to_surface.max > std::max(bound, r.mesh_to_surface.max) ||
                           next.surface_to_mesh.max > std::max(bound, r.surface_to_mesh.max)))
        break;
      next.fin_rounds = r.fin_rounds + 1;
      next.fin_triangles = r.fin_triangles + (next.mesh.face_count() - r.mesh.face_count());
      r = std::move(next);
      beyond = std::move(next_beyond);
    }
    return r;
  };
  // Where grazing views see the blend off the surface the mesh follows (the per-ray blend differs
  // by view direction), the vertices move part of the way towards what they see
  // (convert/between_views.h; `offset` keeps how far each has moved); a round kept only while it
  // leaves fewer samples beyond the bound (both ways) and no larger maximum. Leaves the surface
  // side measured.
  // mesh_excess: a round may leave mesh samples beyond the bound (and a larger maximum there)
  // while it leaves fewer samples beyond in all, for a caller that leaves those faces out next.
  const auto view_moves = [&](ToMeshResult r, std::vector<double>& offset, const Gap& gap,
                              double max_offset = BetweenViewsOptions{}.max_offset, bool mesh_excess = false) {
    std::vector<SurfaceError::Beyond> beyond = surface_side_with_gap(r, gap, kKeepBeyond);
    for (int round = 0; round < o.view_rounds && !r.within && r.surface_to_mesh.beyond > 0; ++round) {
      ToMeshResult next = r;
      std::vector<double> next_offset = offset;
      const std::size_t moved = move_between_views(next.mesh, beyond, {.bound = bound, .max_offset = max_offset, .first_face = slim_first_face}, next_offset);
      if (moved == 0) break;
      next.mesh_to_surface = mesh_to_surface(scene, trace, next.mesh, mesh_reach, bound, nullptr, &memo);
      std::vector<SurfaceError::Beyond> next_beyond = surface_side_with_gap(next, gap, kKeepBeyond);
      log::info("mesh: view round {}: {} vertices moved; beyond the bound {} / {} (was {} / {}), max {:.3g} / {:.3g}", round + 1,
                moved, next.mesh_to_surface.beyond, next.surface_to_mesh.beyond, r.mesh_to_surface.beyond,
                r.surface_to_mesh.beyond, next.mesh_to_surface.max, next.surface_to_mesh.max);
      if (!next.within && (total_beyond(next) >= total_beyond(r) ||
                           (!mesh_excess && next.mesh_to_surface.max > std::max(bound, r.mesh_to_surface.max)) ||
                           next.surface_to_mesh.max > std::max(bound, r.surface_to_mesh.max)))
        break;
      next.view_rounds = r.view_rounds + 1;
      r = std::move(next);
      offset = std::move(next_offset);
      beyond = std::move(next_beyond);
    }
    return r;
  };

  // Progress never goes back: the grid's levels and the tetrahedra's lattices after them share it.
  double progress_shown = -1;
  const auto progress = [&](double fraction) {
    if (o.progress && fraction > progress_shown) o.progress(progress_shown = fraction);
  };
  // A closed tetrahedron model meshed on one grid, as SLIM is (mesh_slims: nodes labelled
  // inside/outside by the drawn surface along the grid lines through them, vertices where grid
  // edges meet it), at halving spacings from the SLIM rule with the tetrahedra's median longest
  // edge for R, until within the bound or a halving brings the larger maximum down by less than a
  // fifth. A skin's tetrahedra are slivers (thickness over longest edge at the median: caffeine
  // 0.009) and its mixed cells meet along faces triangulated differently on each side: a
  // sliver's own lattice lays triangles in its slab across the strip where the surface crosses
  // it, and neighbours' lattices do not meet (caffeine: 0.0612 for a bound of 0.0129, 38,942 open
  // edges, 1.49M triangles; on the grid 0.0105, closed, 84,928 triangles).
  const bool closed_tets = model.slims.empty() && model.glyphs.empty() && model.implicits.empty() && !model.tets.empty() &&
                           surfaces_are_closed(model);
  double median_edge = 0;
  // Tetrahedra their own lattice meshes exactly or along their edges: planes (flat quads and
  // triangles) and surfaces through all four corners (bilinear quads).
  std::size_t lattice_exact = 0;
  if (closed_tets) {
    std::vector<double> edges;
    edges.reserve(model.tets.size());
    for (const TetPatch& t : model.tets) {
      const double l = longest_edge(t.corners);
      edges.push_back(l);
      const Eigen::Vector3d c = t.centroid();
      const bool plane = t.quadric.A.cwiseAbs().maxCoeff() * l <= 1e-12 * t.quadric.b.norm();
      lattice_exact += plane || std::all_of(t.corners.begin(), t.corners.end(), [&](const Eigen::Vector3d& x) {
        return std::abs(t.quadric.eval(x - c)) <= 1e-9 * l * t.quadric.gradient(x - c).norm();
      });
    }
    std::nth_element(edges.begin(), edges.begin() + std::ptrdiff_t(edges.size() / 2), edges.end());
    median_edge = edges[edges.size() / 2];
  }
  const auto mesh_on_grid = [&]() -> std::optional<ToMeshResult> {
    const double R = median_edge;
    const double h0 = std::max(std::min(R / 2.0, 0.5 * std::sqrt(8.0 * bound * R)), diagonal / 256.0);
    std::optional<ToMeshResult> on_grid;
    for (int level = 0; level <= o.max_refinements; ++level) {
      const double h = h0 / (1 << level);
      if ((((box.max - box.min) / h).array() + 4.0).prod() > 1.5e9) break;  // a byte per node, as SLIM's
      progress(static_cast<double>(level) / (o.max_refinements + 1));
      const auto t0 = std::chrono::steady_clock::now();
      Builder b;
      b.colours = has_any_colour(model);
      std::vector<std::uint8_t> on_surface;
      mesh_slims(model, scene, trace, h, {}, b, on_surface);
      snap_to_surface(scene, trace, 1.5 * h, 0, on_surface, b, /*drop_unmet=*/true, nullptr, /*any_kind=*/true);
      // The SLIM grid's local refinement: the triangles with samples beyond the bound cut by
      // longest-edge bisection, new vertices moved onto the surface (undone where it made things
      // worse: refinement_worse).
      const double reach = std::max(4.0 * bound, 1.5 * h);
      LocalRefinement local = refine_locally(scene, trace, o, bound, reach, 1.5 * h, 0, b, memo,
                                             [&](const PolygonMesh& m) { return surface_error(m, kKeepBeyond); },
                                             /*any_kind=*/true);
      ToMeshResult r;
      r.bound = bound;
      r.refinements = level;
      r.on_grid = true;
      r.local_rounds = local.rounds;
      r.mesh = std::move(b.mesh);
      BeyondSamples beyond;
      r.mesh_to_surface = mesh_to_surface(scene, trace, r.mesh, reach, bound, &beyond, &memo);
      if (local.rounds > 0 && refinement_worse(local.unrefined, local.before_where, local.before, r.mesh, beyond,
                                               r.mesh_to_surface, bound, 0)) {
        r.mesh = std::move(local.unrefined);
        r.mesh_to_surface = local.before;
        r.local_rounds = 0;
      }
      r.open_edges = count_open_edges(r.mesh);
      measure_surface_side(r);
      log::info("mesh: on one grid of spacing {:.3g}: {} triangles, max {:.3g} / {:.3g}, {} open edges ({:.1f} s)", h,
                r.mesh.face_count(), r.mesh_to_surface.max, r.surface_to_mesh.max, r.open_edges, seconds_since(t0));
      const bool converging = !on_grid || r.max_error() <= 0.8 * on_grid->max_error();
      if (!on_grid || r.max_error() < on_grid->max_error()) on_grid = std::move(r);
      if (on_grid->within || !converging || on_grid->mesh.face_count() * 4 > o.max_triangles) break;
    }
    return on_grid;
  };
  // The grid goes first, and the tetrahedra's own lattices only where it ends outside the bound,
  // unless most tetrahedra are planes or hold their surface through all four corners (quads):
  // their lattices mesh them exactly or along their edges (cube_quad: 12 triangles, exact;
  // spot_quadrangulated: within the bound, closed, 21,532 triangles, its curved quads cut by
  // refine_for_lattice, 1.3e-3 off; 20,528 uncut, 1.5e-3 off), where the grid
  // rounds sharp edges off (cube_quad on the grid: 166,612 triangles, 2,356 open edges).
  std::optional<ToMeshResult> grid_mesh;
  if (closed_tets && 2 * lattice_exact < model.tets.size()) grid_mesh = mesh_on_grid();
  const bool grid_within = grid_mesh && grid_mesh->within;
  // The lattice rounds cut only a tessellation's cells (core/model.h tetrahedra_tessellate): a quad
  // mesh's tetrahedra meet only along edges, and cutting their pieces apart opened its seams
  // (beast 6 -> 10,602 open edges); a skin's mixed cells are triangulated differently on each side
  // of a shared face, and a cut there leaves T-junctions.
  const bool tessellation = model.slims.empty() && !model.tets.empty() && tetrahedra_tessellate(model);
  for (int level = 0; level <= o.max_refinements && !grid_within; ++level) {
    // The SLIM grid keeps a byte per node: no doubling past kMaxNodes of them.
    constexpr double kMaxNodes = 1.5e9;
    if (have_best && !model.slims.empty() &&
        ((slim_extent / (slim_h0 / (1 << level))).array() + 4.0).prod() > kMaxNodes) {
      if (best.surface_to_mesh.samples == 0) measure_surface_side(best);
      break;
    }
    progress(static_cast<double>(level) / (o.max_refinements + 1));
    const bool grid_refining = !model.slims.empty() && o.grid_refinements > 0;
    std::vector<Eigen::Vector3d> bad, surface_bad;
    bool surface_measured = false;
    bool undone = false;
    ToMeshResult r = mesh_at(level, {}, grid_refining ? &bad : nullptr, &surface_bad, &surface_measured, &undone);
    // Tetrahedra alone: where a few of the lattice's faces stay beyond the bound (a quadric that
    // bends within its piece more than the sag estimate sees: a noisy scan's, lobster: 12 of 20M
    // samples, 1.4 bounds), the pieces that made them are cut (each edge about halved) and the
    // mesh made again, in rounds, a round kept while it leaves fewer samples beyond the bound and
    // no larger maximum; the doubling follows only where that does not reach the bound (far fewer
    // triangles than a doubling).
    if (tessellation && o.lattice_rounds > 0 && r.mesh.face_count() > 0) {
      std::vector<Eigen::Vector3d> surface_beyond = measure_surface_side(r, kKeepBeyond);
      surface_measured = true;
      for (int round = 0; round < o.lattice_rounds && !r.within; ++round) {
        BeyondSamples at;
        mesh_to_surface(scene, trace, r.mesh, 4.0 * bound, bound, &at, &memo);
        std::vector<CutAt> more;
        for (std::size_t f = 0; f < tet_face_cut_at.size() && f < at.faces.size(); ++f)
          if (at.faces[f] > bound) more.push_back(tet_face_cut_at[f]);
        const std::size_t faces_beyond = more.size();
        // Many faces beyond the bound: the lattice is too coarse everywhere, for a doubling.
        if (faces_beyond + surface_beyond.size() == 0 ||
            faces_beyond > std::max<std::size_t>(kLatticeRoundFaces, r.mesh.face_count() / 200))
          break;
        const std::vector<CutAt> missed = cuts_at_points(tet_pieces, surface_beyond);
        more.insert(more.end(), missed.begin(), missed.end());
        if (more.empty()) break;
        const std::size_t kept = tet_cut_at.size();
        tet_cut_at.insert(tet_cut_at.end(), more.begin(), more.end());
        ToMeshResult next = mesh_at(level, {}, nullptr);
        std::vector<Eigen::Vector3d> next_surface_beyond = measure_surface_side(next, kKeepBeyond);
        log::info("mesh: lattice round {}: the pieces of {} faces and drawn points beyond the bound cut, {} triangles; beyond the bound {} / {} "
                  "(was {} / {}), max {:.3g} / {:.3g}",
                  round + 1, more.size(), next.mesh.face_count(), next.mesh_to_surface.beyond, next.surface_to_mesh.beyond,
                  r.mesh_to_surface.beyond, r.surface_to_mesh.beyond, next.mesh_to_surface.max, next.surface_to_mesh.max);
        // (Open edges may grow: where the surface reaches the volume's border, the pieces cut
        // there add border edges; a tessellation's cuts are conforming and open no seam.)
        if (!next.within && (total_beyond(next) >= total_beyond(r) || next.max_error() > r.max_error())) {
          tet_cut_at.resize(kept);
          break;
        }
        next.lattice_rounds = r.lattice_rounds + 1;
        r = std::move(next);
        surface_beyond = std::move(next_surface_beyond);
      }
    }
    // Where the triangles' refinement was undone, the samples beyond the bound come from a blend
    // whose sheets the mesh's normals cannot tell apart (cracks of a fit), not from parts the grid
    // missed; a finer grid there follows the same cracks (the kitten: more samples beyond and a
    // larger maximum after each round), so the grid is not refined.
    if (grid_refining && undone) log::info("mesh: local refinement undone: no grid refinement");
    if (grid_refining && !undone) {
      // Where samples stay beyond the bound after the triangles' own refinement (parts or gaps
      // thinner than the grid, which no cut of its triangles creates), the grid cells holding
      // them are cut finer, one level per round, and the whole SLIM mesh made again; a round
      // kept only while it leaves fewer samples beyond the bound (both ways) and no larger maximum.
      if (!surface_measured) surface_bad = measure_surface_side(r, kKeepBeyond);
      bad.insert(bad.end(), surface_bad.begin(), surface_bad.end());
      surface_measured = true;
      const SlimGrid grid = slim_grid(model, slim_h0 / (1 << level));
      std::unordered_map<std::uint64_t, int> depth;  // refined cell → depth
      for (int round = 0; round < o.grid_refinements && !r.within && r.mesh.face_count() < o.max_triangles; ++round) {
        std::unordered_set<std::uint64_t> raised;
        for (const Eigen::Vector3d& p : bad) {
          const Eigen::Vector3i c = ((p - grid.origin) / grid.h).array().floor().cast<int>();
          if ((c.array() < 0).any() || (c.array() > grid.n.array() - 2).any()) continue;
          const std::uint64_t k = grid.index(c);
          if (raised.contains(k)) continue;
          if (int& d = depth[k]; d < kGridLevels) {
            ++d;
            raised.insert(k);
          }
        }
        if (raised.empty()) break;
        for (std::size_t k = 0; k < bad.size(); k += std::max<std::size_t>(1, bad.size() / 8))
          log::debug("mesh: grid round {}: beyond the bound at ({:.6g}, {:.6g}, {:.6g})", round + 1, bad[k].x(), bad[k].y(),
                     bad[k].z());
        std::vector<KuhnCellDepth> refined;
        for (const auto& [k, d] : depth) refined.push_back({grid.node(k), d});
        std::vector<Eigen::Vector3d> next_bad, next_surface_bad;
        bool next_measured = false;
        ToMeshResult next = mesh_at(level, refined, &next_bad, &next_surface_bad, &next_measured);
        if (!next_measured) next_surface_bad = measure_surface_side(next, kKeepBeyond);
        next_bad.insert(next_bad.end(), next_surface_bad.begin(), next_surface_bad.end());
        log::info("mesh: grid round {}: {} cells cut finer ({} raised), {} triangles; beyond the bound {} / {} (was {} / {}), max {:.3g} / {:.3g}",
                  round + 1, depth.size(), raised.size(), next.mesh.face_count(), next.mesh_to_surface.beyond,
                  next.surface_to_mesh.beyond, r.mesh_to_surface.beyond, r.surface_to_mesh.beyond,
                  next.mesh_to_surface.max, next.surface_to_mesh.max);
        if (!next.within && (total_beyond(next) >= total_beyond(r) || next.max_error() > r.max_error())) break;
        next.grid_rounds = round + 1;
        next.refined_cells = depth.size();
        r = std::move(next);
        bad = std::move(next_bad);
      }
    }
    // Where grazing views see the blend off the surface the mesh follows (the per-ray blend differs
    // by view direction), the vertices move part of the way towards what they see; a round kept
    // only while it leaves fewer samples beyond the bound (both ways) and no larger maximum.
    std::vector<double> view_offset;  // per vertex: how far the view rounds moved it
    if (!model.slims.empty() && !undone && !r.within && o.view_rounds > 0) {
      r = view_moves(std::move(r), view_offset, Gap{});
      surface_measured = true;
    }
    // Parts of the drawn surface no closed inside/outside labelling holds (open_parts), tried two
    // ways and the better mesh kept (within the bound first, then the smaller maximum, then, with
    // maxima within 2 % of each other, the smaller mesh):
    //  - closed: the mesh as it is, with open sheets where a patch's rim is drawn alone (add_fins);
    //  - opened: SLIM faces with a sample still beyond the bound left out first, then add_fins:
    //    those over cracks of the blend (nothing drawn there) always; where the local refinement
    //    ran, the others too, unless they are over 5 % of the faces. Those lie over steps: two
    //    sheets farther apart than the blend's push, which the drawn surface jumps between at a
    //    ball's rim. A closed mesh bridges the step, its samples between the sheets whatever is
    //    cut (the kitten's scanned base fitted at 1e-3: sheets 6.6E apart over noisy points). The
    //    drawn surface under the faces left out is measured against what remains (drawn_under,
    //    gap_error), since the views' pixels may be wider than the gap.
    if (!model.slims.empty() && !r.within && o.open_parts) {
      const auto better = [&](const ToMeshResult& x, const ToMeshResult& y) {
        if (x.within != y.within) return x.within;
        // Maxima within 2 % of each other: the smaller mesh (sheets that do not bring the
        // maximum down cost triangles: CGAL's oni.ply fitted at 1e-3, 0.0101 either way).
        const double mx = x.max_error(), my = y.max_error();
        if (std::isinf(mx) || std::isinf(my) || std::abs(mx - my) > 0.02 * std::max(mx, my)) return mx < my;
        return x.mesh.face_count() < y.mesh.face_count();
      };
      std::optional<ToMeshResult> opened;
      if (r.mesh_to_surface.beyond > 0) {
        BeyondSamples where;
        mesh_to_surface(scene, trace, r.mesh, mesh_reach, bound, &where, &memo);
        ToMeshResult next = r;
        // Faces over a crack (a sample in no patch's ball) always; the others only where the local
        // refinement ran and left them beyond (a smooth surface's coarse faces are refined, not
        // left out).
        const bool refined = r.local_rounds > 0;
        const auto over_crack = [&](std::size_t f) {
          const auto t = r.mesh.face(f);
          const auto& V = r.mesh.vertices;
          const Eigen::Vector3d at[4] = {(V[t[0]] + V[t[1]] + V[t[2]]) / 3.0, 0.5 * (V[t[0]] + V[t[1]]),
                                         0.5 * (V[t[1]] + V[t[2]]), 0.5 * (V[t[2]] + V[t[0]])};
          return std::any_of(at, at + 4, [&](const Eigen::Vector3d& c) {
            return std::none_of(model.slims.begin(), model.slims.end(), [&](const SlimPatch& s) {
              return (c - s.centre).squaredNorm() < s.radius * s.radius && s.clips.keeps((c - s.centre) / s.radius);
            });
          });
        };
        std::vector<std::uint8_t> leave(r.mesh.face_count(), 0);  // 1: over a crack, 2: still beyond
        tbb::parallel_for(slim_first_face, r.mesh.face_count(), [&](std::size_t f) {
          if (where.faces[f] > bound) leave[f] = over_crack(f) ? 1 : refined ? 2 : 0;
        });
        // More than 5 % of the SLIM faces still beyond the bound after refinement: not a surface
        // with a few steps but one no mesh at this grid follows (CGAL's oni.ply fitted at 1e-3,
        // below its sampling: 148,318 of 1.57M faces at the first doubling, their gap measured for
        // minutes); only the faces over cracks are left out then.
        if (static_cast<std::size_t>(std::count(leave.begin(), leave.end(), 2)) * 20 > r.mesh.face_count() - slim_first_face)
          std::replace(leave.begin(), leave.end(), std::uint8_t{2}, std::uint8_t{0});
        std::vector<std::size_t> left_out;
        for (std::size_t f = 0; f < r.mesh.face_count(); ++f)
          if (leave[f]) left_out.push_back(f);
        next.mesh = without_faces(r.mesh, leave);
        if (!left_out.empty()) {
          next.mesh_to_surface = mesh_to_surface(scene, trace, next.mesh, mesh_reach, bound, nullptr, &memo);
          next.open_edges = count_open_edges(next.mesh);
          next.surface_to_mesh = {};
          next.within = false;
          log::info("mesh: {} faces beyond the bound left out; mesh -> surface: {} samples beyond the bound (was {}), max {:.3g}",
                    left_out.size(), next.mesh_to_surface.beyond, r.mesh_to_surface.beyond, next.mesh_to_surface.max);
          next.faces_left_out = left_out.size();
          const std::vector<Eigen::Vector3d> drawn = drawn_under(scene, trace, r.mesh, left_out, mesh_reach);
          next = add_fins(std::move(next), level, Gap{drawn});
          // The drawn points left beyond the bound may lie on no one patch's zero set (where two
          // sheets blend): the vertices move towards them, as in the view rounds above.
          // Twice: the moved vertices' points may lie on a patch's sheet again.
          std::vector<double> offset = view_offset;
          for (int pass = 0; pass < 2 && !next.within && o.view_rounds > 0; ++pass) {
            const std::size_t before = total_beyond(next);
            next = view_moves(std::move(next), offset, Gap{drawn}, kOpenedMaxOffset);
            if (pass == 0 && !next.within) next = add_fins(std::move(next), level, Gap{drawn});
            if (total_beyond(next) >= before) break;
          }
          // Faces the sheets and moves leave with a sample beyond the bound (a vertex's normal
          // turned where its neighbours were left out, a moved vertex): left out too, while few
          // and while it helps (the kitten's first doubling: 3 of 2.2M samples, at 1.14 bounds).
          std::vector<Eigen::Vector3d> gap = drawn;
          ToMeshResult best_trim = next;  // the best mesh of the rounds below
          for (int trim = 0; trim < kTrimRounds && !next.within; ++trim) {
            if (next.mesh_to_surface.beyond == 0) {
              // Only drawn points beyond the bound left, on no one patch's sheet (none came of
              // them): the vertices move towards them, and what that takes beyond the bound is
              // left out in the next round (hippo1 fitted at 1e-3: 4 pixels at 1.17 bounds).
              const std::size_t before = total_beyond(next);
              next = view_moves(std::move(next), offset, Gap{gap}, kOpenedMaxOffset, true);
              if (total_beyond(next) >= before) break;
              if (better(next, best_trim)) best_trim = next;
              continue;
            }
            BeyondSamples at;
            mesh_to_surface(scene, trace, next.mesh, mesh_reach, bound, &at, &memo);
            std::vector<std::size_t> out;
            std::vector<std::uint8_t> drop(next.mesh.face_count(), 0);
            for (std::size_t f = 0; f < next.mesh.face_count() && f < at.faces.size(); ++f)
              if (at.faces[f] > bound) out.push_back(f), drop[f] = 1;
            if (out.empty() || out.size() > std::max<std::size_t>(kTrimFaces, next.mesh.face_count() / 1000)) break;
            ToMeshResult t = next;
            t.mesh = without_faces(next.mesh, drop);
            std::vector<Eigen::Vector3d> more_gap = gap;
            const std::vector<Eigen::Vector3d> under = drawn_under(scene, trace, next.mesh, out, mesh_reach);
            more_gap.insert(more_gap.end(), under.begin(), under.end());
            t.mesh_to_surface = mesh_to_surface(scene, trace, t.mesh, mesh_reach, bound, nullptr, &memo);
            t.open_edges = count_open_edges(t.mesh);
            t.faces_left_out = next.faces_left_out + out.size();
            surface_side_with_gap(t, Gap{more_gap}, 0);
            log::info("mesh: trim {}: {} more faces left out; beyond the bound {} / {} (was {} / {}), max {:.3g} / {:.3g}",
                      trim + 1, out.size(), t.mesh_to_surface.beyond, t.surface_to_mesh.beyond, next.mesh_to_surface.beyond,
                      next.surface_to_mesh.beyond, t.mesh_to_surface.max, t.surface_to_mesh.max);
            // The drawn surface under the faces just left out, where a patch's own sheet holds it:
            // sheets there, as for the first faces left out.
            if (!t.within && t.surface_to_mesh.beyond > 0) t = add_fins(std::move(t), level, Gap{more_gap});
            if (!t.within && (total_beyond(t) >= total_beyond(next) || t.max_error() > next.max_error())) break;
            next = std::move(t);
            gap = std::move(more_gap);
            if (better(next, best_trim)) best_trim = next;
          }
          next = std::move(best_trim);
          opened = std::move(next);
        }
      }
      r = add_fins(std::move(r), level, Gap{});
      if (opened && better(*opened, r)) {
        log::info("mesh: the mesh with faces left out kept (max {:.3g} against {:.3g} closed)", opened->max_error(),
                  r.max_error());
        r = std::move(*opened);
      }
      surface_measured = true;
    }
    // A doubling is not converging where it leaves more than a quarter of the previous share of
    // samples beyond the bound (cracks or gaps of the blend itself, which no resolution closes),
    // or does not halve the larger of the two maxima (parts of the drawn surface that no closed
    // inside/outside labelling holds, at any resolution): the previous, smaller mesh is kept, or,
    // where only the maximum stays, the one nearer the surface.
    // Without SLIM patches (tetrahedra, glyphs) only the maximum counts, and a doubling goes on
    // while it brings it down by a fifth: their lattice converges as it doubles, though not by
    // halves at first, and the share of samples beyond the bound need not fall (a coarse torus of
    // quads: max 0.35, then 0.112 with 7 % of the samples beyond instead of 9.5 %, and the first
    // mesh was kept; hydrogen's volume: 0.122, 0.091, then 0.0245, within its bound).
    // An empty mesh is never kept over a finer one (a twisted quad's tetrahedron has the surface
    // through its corners and no triangle at the first level: it was kept, with exit 7).
    if (have_best && best.mesh.face_count() > 0) {
      if (!surface_measured) measure_surface_side(r);
      surface_measured = true;
      if (best.surface_to_mesh.samples == 0) measure_surface_side(best);
      const bool share_stays =
          !model.slims.empty() && share_beyond(r.mesh_to_surface) > 0.25 * share_beyond(best.mesh_to_surface);
      const bool max_stays = r.max_error() > (model.slims.empty() ? 0.8 : 0.5) * best.max_error();
      if (!r.within && (share_stays || max_stays)) {
        // Where only the maximum stays, the finer mesh is kept if it is nearer (its cost is paid).
        const bool keep_finer = !share_stays && r.max_error() < best.max_error();
        log::info("mesh: doubling {} not converging (max {:.3g} after {:.3g}, {} of {} samples beyond the bound after {} of {}): "
                  "the {} mesh kept",
                  level, r.max_error(), best.max_error(), r.mesh_to_surface.beyond, r.mesh_to_surface.samples,
                  best.mesh_to_surface.beyond, best.mesh_to_surface.samples, keep_finer ? "finer" : "previous");
        if (keep_finer) best = std::move(r);
        break;
      }
    }
    const bool last = level == o.max_refinements || r.mesh.face_count() * 4 > o.max_triangles;
    const bool close = r.mesh_to_surface.max <= bound && r.mesh_to_surface.misses == 0;
    if ((close || last) && !surface_measured) measure_surface_side(r);
    best = std::move(r);
    have_best = true;
    if (best.within || last) break;
  }
  progress(1.0);
  if (closed_tets && !grid_mesh && !best.within) grid_mesh = mesh_on_grid();
  if (grid_mesh && (!have_best || grid_mesh->within || grid_mesh->max_error() < best.max_error())) {
    if (have_best) log::info("mesh: the grid's mesh kept (max {:.3g} against {:.3g} on the tetrahedra's lattices)",
                             grid_mesh->max_error(), best.max_error());
    best = std::move(*grid_mesh);
    have_best = true;
  }
  // Pieces meshed apart meet at coincident vertices and T-junctions: closed where they coincide
  // within 1e-7 of the diagonal (a compact .qxm's float32 rounding moves corners by up to 5e-8 of
  // it; nothing moves farther, so the measures stand).
  if (best.open_edges > 0) {
    const auto [welded, split] = close_seams(best.mesh, 1e-7 * diagonal);
    if (welded + split > 0) {
      const std::size_t before = best.open_edges;
      best.open_edges = count_open_edges(best.mesh);
      log::debug("mesh: {} vertices welded and {} T-junctions split along open edges: {} open edges, {} before", welded,
                 split, best.open_edges, before);
    }
  }
  // Faces left out over cracks leave their vertices behind.
  if (const std::size_t unused = best.mesh.remove_unused_vertices(); unused > 0)
    log::debug("mesh: {} vertices no face uses dropped", unused);
  // Sheets left touching at a vertex (a face left out beside another's corner): one vertex per fan
  // (the bunny fitted at 1e-2 had 2, and MeshLab called its holes and genus undefined).
  best.pinched_vertices_split = split_pinched_vertices(best.mesh);
  if (o.normals) best.normals_from_faces = set_drawn_normals(best.mesh, scene, trace, std::max(4.0 * bound, 1e-9 * diagonal));
  return best;
}

}  // namespace quadrix
