#include "fit/normals.h"

#include <algorithm>
#include <limits>
#include <cmath>
#include <optional>
#include <numbers>
#include <queue>
#include <tuple>
#include <utility>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "fit/data_surface.h"
#include "fit/point_index.h"

namespace quadrix {

namespace {

// estimate_normals: how clearly a component's normals must face away from (or towards) a
// centroid for it to decide their orientation, and how far they must lie off it, relative to
// their distance, for the component not to count as flat.
constexpr double kDecisive = 0.5;
constexpr double kFlat = 0.02;
// on_own_sheet: a neighbour farther off the nearest half's plane than 30° and this many times
// that plane's roughness lies on another sheet.
constexpr double kOffSheetRoughness = 10.0;
// The orientation graph: the sine of the steepest a neighbour may lie off a point's tangent
// plane (15°) beyond this many times its neighbourhood's roughness.
constexpr double kSameSheetSine = 0.25881904510252074;
constexpr double kStepRoughness = 6.0;

// Knife edges (orient_by_parity): the rays each voter casts (a direction and its opposite, along
// its normal and tilted this far from it), how many of the kRayPairs must agree for a vote to
// count, and a ray's crossings at most; voters at most, their smoothness, and how a vote stands.
constexpr int kRayPairs = 5;
constexpr double kRayTilt = 0.3490658503988659;  // 20°
constexpr int kDecidingPairs = 4;
constexpr int kMaxCrossings = 24;
constexpr std::size_t kMaxVoters = 8000, kMinComponentVoters = 64;
constexpr double kSmooth = 0.25;
constexpr std::size_t kConfirm = 8, kAlike = 4;
constexpr double kMinorityShare = 0.02, kClosedShare = 0.75;
// ... or, where only kPlateClosedShare decided (a plate under two spacings thick), its standing
// votes split nearly evenly (kPlateSplit each way: a whole side inside out) among at least
// kMinComponentVoters smooth voters.
constexpr double kPlateClosedShare = 0.5, kPlateSplit = 0.25;
// A voter's rays start this many of its spacings out, past its own sheet's discs.
constexpr double kOwnSheet = 0.75;
// A side of a knife edge needs this many of a rim point's neighbours for its plane, and the
// sides' means must lie this many of their roughnesses apart.
constexpr std::size_t kMinSide = 5;
constexpr double kSidesApart = 3.0;
// ... and its side's normals agree when their signed sum along its plane's normal is this share
// of their absolute sum.
constexpr double kSideAgrees = 0.8;

// The scatter matrix Σ (q − mean)(q − mean)ᵀ of the first `count` neighbours that `take` (by
// their place in nb) keeps; `kept` gets how many it kept.
template <class Take>
Eigen::Matrix3d covariance(std::span<const Eigen::Vector3d> points, const std::vector<Neighbour>& nb, std::size_t count,
                           const Take& take, std::size_t* kept = nullptr) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::size_t m = 0;
  for (std::size_t j = 0; j < count; ++j)
    if (take(j)) mean += points[nb[j].first], ++m;
  if (kept) *kept = m;
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  if (m == 0) return C;
  mean /= double(m);
  for (std::size_t j = 0; j < count; ++j)
    if (take(j)) {
      const Eigen::Vector3d d = points[nb[j].first] - mean;
      C += d * d.transpose();
    }
  return C;
}

// The PCA of the `want` points nearest p (p itself among them when it is a point of the cloud),
// widened to 2 and 4 times as many where they lie along a line (a scanner's lines farther apart
// than their points: any plane through the line fits them). nb: the last neighbourhood asked, at
// least `ask` points, nearest first.
Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> neighbourhood_pca(const PointIndex& index,
                                                                 std::span<const Eigen::Vector3d> points,
                                                                 const Eigen::Vector3d& p, std::size_t want,
                                                                 std::size_t ask, std::vector<Neighbour>& nb,
                                                                 std::size_t* used = nullptr) {
  const std::size_t n = points.size();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  for (std::size_t scale = 1; scale <= 4; scale *= 2) {
    const std::size_t w = std::min(scale * want, n);
    index.nearest(p, std::max(w, ask), nb);
    const std::size_t kk = std::min(w, nb.size());
    eig.compute(covariance(points, nb, kk, [](std::size_t) { return true; }));
    if (used) *used = kk;
    if (eig.info() != Eigen::Success || spreads_over_a_plane(eig.eigenvalues()) || w == n) break;
  }
  return eig;
}

// Where the k nearest points reach another sheet (two sheets 0.03 apart, sampled every 0.01: at
// a sparse spot half of them lie on the other sheet, the gap's variance exceeds the plane's, and
// 242 of 20,000 PCA normals lay along the sheets), the normal is the plane of the nearest half
// (k/2, at least 6), and its roughness that plane's, then of the k nearest that lie within 30° of that plane or within 10 times
// its roughness (the nearest half's RMS distance from it). On one sheet, smooth or noisy, the k
// nearest all do, and the normal is the plain PCA's (30° alone, or 6 times the roughness, turned
// CGAL's noisy sphere_20k_normal, without its normals, 41 % and 10 % inside out).
void on_own_sheet(std::span<const Eigen::Vector3d> points, std::size_t i, const std::vector<Neighbour>& nb, std::size_t k,
                  Eigen::Vector3d& normal, double& rough) {
  const auto plane_of = [&](const auto& take) -> std::optional<std::pair<Eigen::Vector3d, double>> {
    std::size_t count = 0;
    const Eigen::Matrix3d C = covariance(points, nb, k, take, &count);
    if (count < 5) return std::nullopt;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
    if (eig.info() != Eigen::Success || !spreads_over_a_plane(eig.eigenvalues())) return std::nullopt;
    return std::pair{Eigen::Vector3d(eig.eigenvectors().col(0).normalized()), std::sqrt(std::max(0.0, eig.eigenvalues()[0]) / double(count))};
  };
  const std::size_t half = std::max<std::size_t>(6, k / 2);
  const auto near = plane_of([&](std::size_t j) { return j < half; });
  if (!near) return;
  const auto on_sheet = [&](std::size_t j) {
    const Eigen::Vector3d v = points[nb[j].first] - points[i];
    return std::abs(near->first.dot(v)) <= std::max(0.5 * v.norm(), kOffSheetRoughness * near->second);
  };
  bool all = true;
  for (std::size_t j = 0; j < k && all; ++j) all = on_sheet(j);
  if (all) return;  // one sheet: the plain PCA stands
  const auto refined = plane_of(on_sheet);
  std::tie(normal, rough) = refined ? *refined : *near;
}


// Crossings of the data's surface (the points' tangent discs) along a ray from a point on it,
// past its own sheet (tmin). Hits closer along the ray than twice the hit disc's radius over the
// cosine of the crossing (at most 4) are one crossing: a sheet's overlapping discs. −1 past
// kMaxCrossings (a ray along a sheet, or through fuzz: no parity to read).
int crossings(const DataSurface& surface, const Ray& ray, double tmin) {
  int count = 0;
  double t = tmin;
  while (const auto hit = surface.first_hit(ray, t)) {
    if (++count > kMaxCrossings) return -1;
    t = hit->t + 2.0 * hit->reach / std::max(std::abs(hit->normal.dot(ray.dir)), 0.25);
  }
  return count;
}

// A point's vote on its normal n by ray parity: on a closed surface a ray leaving a point on its
// outward side crosses the surface an even number of times, on its inward side an odd number.
// Each of kRayPairs directions (n, and n tilted by kRayTilt four ways) is cast both ways; +1: n
// faces out, −1: in, when at least kDecidingPairs pairs say so; else 0 (an open sheet, where
// both sides are even, or rays that disagree: near a rim, through a gap between discs).
int parity_vote(const DataSurface& surface, const Eigen::Vector3d& p, const Eigen::Vector3d& n, double tmin) {
  const Eigen::Vector3d u = n.unitOrthogonal(), v = n.cross(u);
  int out = 0, in = 0;
  for (int k = 0; k < kRayPairs; ++k) {
    Eigen::Vector3d d = n;
    if (k > 0) {
      const double a = (k - 1) * (std::numbers::pi / 2);
      d = std::cos(kRayTilt) * n + std::sin(kRayTilt) * (std::cos(a) * u + std::sin(a) * v);
    }
    const int ahead = crossings(surface, Ray{p, d}, tmin);
    const int behind = ahead < 0 ? -1 : crossings(surface, Ray{p, -d}, tmin);
    if (ahead >= 0 && behind >= 0) {
      out += ahead % 2 == 0 && behind % 2 == 1;
      in += ahead % 2 == 1 && behind % 2 == 0;
    }
    if (out >= kDecidingPairs) return 1;
    if (in >= kDecidingPairs) return -1;
    const int left = kRayPairs - 1 - k;
    if (out + left < kDecidingPairs && in + left < kDecidingPairs) return 0;
  }
  return 0;
}

// Prim's minimum spanning forest over the orientation graph (adjacency of point v:
// adj[offset[v] .. offset[v + 1]), weight 1 − |nᵢ·nⱼ|), grown from all `seeds` at once: each
// point reached is turned to agree with the one it was reached from. `done` marks the points
// taken (the seeds too).
void propagate_orientation(std::span<const std::uint32_t> seeds, const std::vector<std::uint32_t>& offset,
                           const std::vector<std::uint32_t>& adj, std::vector<Eigen::Vector3d>& normals,
                           std::vector<std::uint8_t>& done) {
  using Item = std::pair<double, std::pair<std::uint32_t, std::uint32_t>>;  // weight, (parent, child)
  std::priority_queue<Item, std::vector<Item>, std::greater<>> heap;
  const auto push_edges = [&](std::uint32_t v) {
    done[v] = 1;
    for (std::uint32_t e = offset[v]; e < offset[v + 1]; ++e)
      if (!done[adj[e]]) heap.push({1.0 - std::abs(normals[v].dot(normals[adj[e]])), {v, adj[e]}});
  };
  for (const auto v : seeds) push_edges(v);
  while (!heap.empty()) {
    const auto [w, edge] = heap.top();
    heap.pop();
    const auto [parent, child] = edge;
    if (done[child]) continue;
    if (normals[child].dot(normals[parent]) < 0) normals[child] = -normals[child];
    push_edges(child);
  }
}

// Knife edges. Across a rim sharper than about 60° (a lens, a blade, a wedge) the PCA normals of
// the rim's points lie between the two sides' and the propagation carries one side's
// orientation over the rim onto the other, turning it inside out (a lens whose caps meet at 20°
// or 39°: one cap, half the normals). So points vote by ray parity (parity_vote) against the
// tangent discs of the voters of their own component (another part of the scene would add its
// own crossings): every point of a cloud up to kMaxVoters, else every stride-th in Morton order
// (spread over the cloud); only smooth ones (rough ≤ kSmooth × gap, gap the distance to the 6th
// nearest point), as in a noisy shell the rays cross the fuzz at random; components with fewer
// than kMinComponentVoters vote nothing. A vote stands when at least kAlike of the voter's
// kConfirm nearest voters vote alike (a lone vote is a ray through a gap). A component where
// some stand against the propagated normals, at least kMinorityShare of its standing votes go
// each way (a knife edge turns one side of a component, not all of it), and kClosedShare of its
// smooth voters decided (closed: below) is propagated again from every standing voter at once,
// each turned as it voted, the rest from the nearest of them along the minimum spanning forest
// (weight 1 − |nᵢ·nⱼ|), and its rim points then take their own side's plane (below). Other
// components (open sheets, whose rays escape both ways, noisy shells, parts all of whose votes
// say one thing) stay as they were. Returns how many normals point the other way than on entry.
struct OrientationGraph {
  const std::vector<std::uint32_t>& offset;  // adjacency of point v: adj[offset[v] .. offset[v + 1])
  const std::vector<std::uint32_t>& adj;
  const std::vector<std::vector<std::uint32_t>>& members;  // each component's points
  const std::vector<std::int32_t>& comp;                   // each point's component
};
std::size_t orient_by_parity(std::span<const Eigen::Vector3d> points, std::vector<Eigen::Vector3d>& normals,
                             const PointIndex& index, std::size_t k, const std::vector<double>& rough,
                             const std::vector<double>& gap, const OrientationGraph& g) {
  const std::size_t n = points.size();
  const auto order = index.order();
  const std::size_t stride = (n + kMaxVoters - 1) / kMaxVoters;
  std::vector<std::uint32_t> voter;
  for (std::size_t o = 0; o < n; o += stride) voter.push_back(order[o]);
  const std::size_t nv = voter.size();
  if (nv < kConfirm + 1) return 0;
  std::vector<Eigen::Vector3d> vp(nv), vn(nv);
  for (std::size_t j = 0; j < nv; ++j) vp[j] = points[voter[j]], vn[j] = normals[voter[j]];
  const std::vector<Eigen::Vector3d> entry = normals;  // for the count of those turned
  std::vector<std::int8_t> vote(nv, 0);
  std::vector<std::uint8_t> smooth(nv, 0);
  // Each component's voters cast their rays against that component's discs alone: another part
  // of the scene, open or not (a lens in an open bowl, over a ground plane), would add crossings
  // that have nothing to do with this one's inside.
  std::vector<std::vector<std::uint32_t>> voters_of(g.members.size());
  for (std::size_t j = 0; j < nv; ++j) voters_of[g.comp[voter[j]]].push_back(std::uint32_t(j));
  for (const auto& own : voters_of) {
    if (own.size() < kMinComponentVoters) continue;
    std::vector<Eigen::Vector3d> cp(own.size()), cn(own.size());
    for (std::size_t r = 0; r < own.size(); ++r) cp[r] = vp[own[r]], cn[r] = vn[own[r]];
    const DataSurface surface = DataSurface::from_points(cp, cn);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, own.size(), 64), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t r = range.begin(); r != range.end(); ++r) {
        const std::uint32_t j = own[r];
        if (rough[voter[j]] > kSmooth * gap[voter[j]]) continue;
        smooth[j] = 1;
        vote[j] = std::int8_t(parity_vote(surface, cp[r], cn[r], kOwnSheet * surface.spacing(r)));
      }
    });
  }
  // A closed surface decides most smooth voters' parity (kitten 91 %, lenses 89–96 %, meshes
  // sampled by 20,000 points 53–80 %); an open scan few, as its rays escape both ways, and those
  // by what it happens to hide (bun000_rawscan 3.5 %, radar.xyz 28 %: body points behind an ear
  // vote "in", and bun000 had 31,833 normals turned before this gate): a component turns only
  // where kClosedShare of them decided. A closed plate 1.6–1.9 spacings thick decides 57–67 %,
  // and the propagation had turned one whole side of it inside out (CGAL's turbine blade: 49.6 %
  // of its normals, and its fit at 3e-3 left 38 % of its pixels open; a 1 × 4 slab), so its
  // standing votes split about evenly (751 "in" against 759): from kPlateClosedShare decided, a
  // component turns where they split so (kPlateSplit each way), which a few clusters of votes an
  // open scan's occlusions cast do not.
  std::vector<std::size_t> smooth_in(g.members.size(), 0), decided_in(g.members.size(), 0);
  for (std::size_t j = 0; j < nv; ++j) smooth_in[g.comp[voter[j]]] += smooth[j], decided_in[g.comp[voter[j]]] += vote[j] != 0;
  const PointIndex voters_index(vp);
  std::vector<std::int8_t> stands(n, 0);
  std::vector<std::size_t> ins(g.members.size(), 0), outs(g.members.size(), 0);
  std::vector<Neighbour> nb;
  for (std::size_t j = 0; j < nv; ++j) {
    if (vote[j] == 0) continue;
    voters_index.nearest(vp[j], kConfirm + 1, nb);
    std::size_t alike = 0;
    for (const auto& [other, d2] : nb) alike += other != j && vote[other] == vote[j];
    if (alike < kAlike) continue;
    stands[voter[j]] = vote[j];
    (vote[j] < 0 ? ins : outs)[g.comp[voter[j]]] += 1;
  }
  std::vector<std::uint8_t> done(n, 0);
  std::vector<std::uint32_t> seeds;
  std::vector<std::uint32_t> rim;  // points of turned components near their rim
  for (std::size_t c = 0; c < g.members.size(); ++c) {
    const double minority = double(std::min(ins[c], outs[c])), standing = double(ins[c] + outs[c]);
    const double decided = double(decided_in[c]), smooth_voters = double(smooth_in[c]);
    const bool closed = decided >= kClosedShare * smooth_voters;
    const bool plate = decided >= kPlateClosedShare * smooth_voters && minority >= kPlateSplit * standing &&
                       smooth_in[c] >= kMinComponentVoters;
    if (ins[c] == 0 || minority < kMinorityShare * standing || !(closed || plate)) continue;
    seeds.clear();
    for (auto v : g.members[c])
      if (stands[v] != 0) {
        if (stands[v] < 0) normals[v] = -normals[v];
        seeds.push_back(v);
      }
    propagate_orientation(seeds, g.offset, g.adj, normals, done);
    // The rim: points with a neighbour facing the other way, and their neighbours.
    const std::size_t first_of_component = rim.size();
    for (auto v : g.members[c])
      for (std::uint32_t e = g.offset[v]; e < g.offset[v + 1]; ++e)
        if (normals[v].dot(normals[g.adj[e]]) < 0) {
          rim.push_back(v);
          break;
        }
    const std::size_t edge = rim.size();
    for (std::size_t r = first_of_component; r < edge; ++r)
      for (std::uint32_t e = g.offset[rim[r]]; e < g.offset[rim[r] + 1]; ++e) rim.push_back(g.adj[e]);
  }
  std::sort(rim.begin(), rim.end());
  rim.erase(std::unique(rim.begin(), rim.end()), rim.end());
  // The rim's own normals. A rim point's k nearest straddle the knife edge, so their PCA plane
  // lies between its two sides (a 20° lens: nearly along its axis on both caps) and the tangent
  // discs stood out past the edge, half of them facing the other side's way. The neighbours are
  // split by the side of that middle plane they lie on (each side of the edge), and the point
  // takes the PCA plane of the side whose plane passes nearer it (facing: below).
  std::vector<Eigen::Vector3d> refined(rim.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rim.size(), 64), [&](const tbb::blocked_range<std::size_t>& range) {
    std::vector<Neighbour> near;
    for (std::size_t r = range.begin(); r != range.end(); ++r) {
      const std::uint32_t v = rim[r];
      refined[r] = normals[v];
      index.nearest(points[v], k, near);
      if (std::all_of(near.begin(), near.end(), [&](const Neighbour& q) { return normals[q.first].dot(normals[v]) >= 0; }))
        continue;  // not on a rim
      Eigen::Vector3d middle = Eigen::Vector3d::Zero();
      for (const auto& [j, d2] : near) middle += points[j];
      middle /= double(near.size());
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> all(covariance(points, near, near.size(), [](std::size_t) { return true; }));
      if (all.info() != Eigen::Success) continue;
      const Eigen::Vector3d across = all.eigenvectors().col(0);
      struct Side {
        Eigen::Vector3d normal, mean;
        double rough = 0;
        bool ok = false;
      } side[2];
      for (int h = 0; h < 2; ++h) {
        const double sign = h == 0 ? 1.0 : -1.0;
        const auto take = [&](std::size_t j) { return sign * across.dot(points[near[j].first] - middle) > 0; };
        std::size_t kept = 0;
        const Eigen::Matrix3d C = covariance(points, near, near.size(), take, &kept);
        if (kept < kMinSide) continue;
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
        if (eig.info() != Eigen::Success || !spreads_over_a_plane(eig.eigenvalues())) continue;
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (std::size_t j = 0; j < near.size(); ++j)
          if (take(j)) mean += points[near[j].first];
        side[h] = {eig.eigenvectors().col(0).normalized(), mean / double(kept),
                   std::sqrt(std::max(0.0, eig.eigenvalues()[0]) / double(kept)), true};
      }
      // Two sides, not the two halves of one noisy sheet: their means lie apart across the
      // middle plane by kSidesApart times their roughness.
      if (!side[0].ok || !side[1].ok ||
          std::abs(across.dot(side[0].mean - side[1].mean)) <= kSidesApart * std::max(side[0].rough, side[1].rough))
        continue;
      const int own = std::abs(side[0].normal.dot(points[v] - side[0].mean)) <=
                              std::abs(side[1].normal.dot(points[v] - side[1].mean))
                          ? 0
                          : 1;
      // Facing as most of its side's points already do where they clearly agree; else away from
      // the other side, right at a convex edge (a lens's rim), wrong at a concave one (a notch),
      // which the side's own normals decide.
      Eigen::Vector3d normal = side[own].normal;
      double along = 0, across_sum = 0;
      for (std::size_t j = 0; j < near.size(); ++j)
        if ((across.dot(points[near[j].first] - middle) > 0) == (own == 0)) {
          const double a = normals[near[j].first].dot(normal);
          along += a, across_sum += std::abs(a);
        }
      if (std::abs(along) > kSideAgrees * across_sum ? along < 0 : normal.dot(side[own].mean - side[1 - own].mean) < 0)
        normal = -normal;
      if (normal.allFinite()) refined[r] = normal;
    }
  });
  for (std::size_t r = 0; r < rim.size(); ++r) normals[rim[r]] = refined[r];
  std::size_t turned = 0;
  for (std::size_t i = 0; i < n; ++i) turned += normals[i].dot(entry[i]) < 0;
  return turned;
}

}  // namespace

NormalEstimation estimate_normals(std::span<const Eigen::Vector3d> points, const NormalEstimationOptions& options) {
  const std::size_t n = points.size();
  if (n < 3) throw InvalidInput(fmt::format("estimate_normals: {} points; at least 3 are needed", n));
  for (std::size_t i = 0; i < n; ++i)
    if (!points[i].allFinite()) throw InvalidInput(fmt::format("estimate_normals: point {} is not finite", i));
  const std::size_t k = std::clamp<std::size_t>(options.neighbours, 3, n);
  const std::size_t km = std::clamp<std::size_t>(options.mst_neighbours, 2, n);
  const PointIndex index(points);

  NormalEstimation out;
  out.normals.resize(n);
  std::vector<std::uint32_t> graph(n * km);  // the km nearest neighbours of each point (self excluded)
  std::vector<std::uint8_t> degree(n, 0);
  std::vector<double> rough(n, 0.0);  // RMS distance of the PCA's points from its plane
  std::vector<double> gap(n, 0.0);    // distance to the 6th nearest point
  const auto order = index.order();  // visited in Morton order (PointIndex::order)
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& range) {
    std::vector<Neighbour> nb;
    for (std::size_t o = range.begin(); o != range.end(); ++o) {
      const std::size_t i = order[o];
      std::size_t used = 1;
      const auto eig = neighbourhood_pca(index, points, points[i], k, km + 1, nb, &used);
      out.normals[i] = eig.eigenvectors().col(0).normalized();  // smallest eigenvalue
      rough[i] = std::sqrt(std::max(0.0, eig.eigenvalues()[0]) / double(std::max<std::size_t>(1, used)));
      gap[i] = nb.empty() ? 0.0 : std::sqrt(nb[std::min<std::size_t>(6, nb.size() - 1)].second);
      if (spreads_over_a_plane(eig.eigenvalues()) && nb.size() >= k) on_own_sheet(points, i, nb, k, out.normals[i], rough[i]);
      if (!out.normals[i].allFinite()) out.normals[i] = Eigen::Vector3d::UnitZ();
      if (nb.size() > std::max(k, km + 1)) nb.resize(std::max(k, km + 1));  // the graph: the nearest km
      std::uint8_t d = 0;
      for (std::size_t j = 0; j < nb.size() && d < km; ++j)
        if (nb[j].first != i) graph[i * km + d++] = nb[j].first;
      degree[i] = d;
    }
  });

  // The orientation graph joins points of one sheet only: two points either of which lies more
  // than 15° off the other's tangent plane, and farther off it than 6 times the roughness of the
  // other's neighbourhood, lie on different sheets (the two sides of a thin plate), which the
  // propagation would orient alike (two sheets 0.03 apart, sampled every 0.01 without normals:
  // one component, every normal +z, the lower sheet's facing in; 2,179 patches at 1e-3 instead
  // of 68 with their true normals). Such edges are left out; a noisy sheet's are not (CGAL's
  // sphere_20k_normal without its normals: 15° alone split it into 5,069 parts, 3 times the
  // roughness into 8, and turned 1.5 % more of its normals inside out).
  for (std::size_t i = 0; i < n; ++i) {
    std::uint8_t d = 0;
    for (std::size_t j = 0; j < degree[i]; ++j) {
      const std::uint32_t t = graph[i * km + j];
      const Eigen::Vector3d v = points[t] - points[i];
      const double reach = kSameSheetSine * v.norm();
      if (std::abs(out.normals[i].dot(v)) > std::max(reach, kStepRoughness * rough[i]) ||
          std::abs(out.normals[t].dot(v)) > std::max(reach, kStepRoughness * rough[t]))
        continue;
      graph[i * km + d++] = t;
    }
    degree[i] = d;
  }
  // Symmetric adjacency: the kNN relation is not symmetric; add reverse edges.
  std::vector<std::uint32_t> offset(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < degree[i]; ++j) {
      ++offset[i + 1];
      ++offset[graph[i * km + j] + 1];
    }
  for (std::size_t i = 0; i < n; ++i) offset[i + 1] += offset[i];
  std::vector<std::uint32_t> adj(offset[n]);
  {
    std::vector<std::uint32_t> fill(offset.begin(), offset.end() - 1);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < degree[i]; ++j) {
        const std::uint32_t t = graph[i * km + j];
        adj[fill[i]++] = t;
        adj[fill[t]++] = std::uint32_t(i);
      }
  }

  // Components, each with its own seed.
  std::vector<std::int32_t> comp(n, -1);
  std::vector<std::vector<std::uint32_t>> members;
  for (std::size_t s = 0; s < n; ++s) {
    if (comp[s] >= 0) continue;
    const auto id = std::int32_t(members.size());
    members.emplace_back();
    std::vector<std::uint32_t> stack{std::uint32_t(s)};
    comp[s] = id;
    while (!stack.empty()) {
      const std::uint32_t v = stack.back();
      stack.pop_back();
      members[id].push_back(v);
      for (std::uint32_t e = offset[v]; e < offset[v + 1]; ++e)
        if (comp[adj[e]] < 0) {
          comp[adj[e]] = id;
          stack.push_back(adj[e]);
        }
    }
  }
  out.components = members.size();
  out.component.assign(comp.begin(), comp.end());

  // How a component's normals face: > 0 outward, < 0 inward. From its own centroid c where the
  // normals are clearly signed against it (Σ nᵢ·(pᵢ − c) beyond half Σ |nᵢ·(pᵢ − c)|) and the
  // component is not nearly flat (Σ |nᵢ·(pᵢ − c)| beyond kFlat of Σ |pᵢ − c|); else from the
  // cloud's centroid where they are clearly signed against that (each side of a thin plate lies
  // wholly on its side of the plate's middle); else a curved component faces away from its
  // centroid by the weighted majority, and a flat one (a single scan of a wall) faces +z, the
  // default view's front, where the majority of noise would pick either side.
  Eigen::Vector3d all = Eigen::Vector3d::Zero();
  for (const auto& p : points) all += p;
  all /= double(n);
  struct Facing {
    double along = 0, across = 0, spread = 0;
  };
  const auto facing = [&](const std::vector<std::uint32_t>& m, const Eigen::Vector3d& c) {
    Facing f;
    for (auto v : m) {
      const double a = out.normals[v].dot(points[v] - c);
      f.along += a, f.across += std::abs(a), f.spread += (points[v] - c).norm();
    }
    return f;
  };
  const auto outwardness = [&](const std::vector<std::uint32_t>& m, const Eigen::Vector3d& own) {
    const Facing f = facing(m, own);
    if (f.across > kFlat * f.spread && std::abs(f.along) > kDecisive * f.across) return f.along;
    // The cloud's centroid is another only for a part of it (one part's is its own).
    if (m.size() < n) {
      const Facing g = facing(m, all);
      if (g.across > 1e-9 * g.spread && std::abs(g.along) > kDecisive * g.across) return g.along;
    }
    if (f.across > kFlat * f.spread) return f.along;
    double z = 0;
    for (auto v : m) z += out.normals[v].z();
    return z;
  };
  // Prim's MST per component (weight 1 − |nᵢ·nⱼ|), propagating orientation from parent to child.
  std::vector<std::uint8_t> done(n, 0);
  for (const auto& m : members) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (auto v : m) centroid += points[v];
    centroid /= double(m.size());
    std::uint32_t seed = m[0];
    double far = -1;
    for (auto v : m)
      if (const double d = (points[v] - centroid).squaredNorm(); d > far) {
        far = d;
        seed = v;
      }
    if (out.normals[seed].dot(points[seed] - centroid) < 0) out.normals[seed] = -out.normals[seed];
    propagate_orientation(std::span(&seed, 1), offset, adj, out.normals, done);
    // Global outward test (outwardness above).
    if (outwardness(m, centroid) < 0) {
      for (auto v : m) out.normals[v] = -out.normals[v];
      ++out.flipped_components;
    }
  }
  out.turned_by_parity = orient_by_parity(points, out.normals, index, k, rough, gap, {offset, adj, members, comp});
  return out;
}

GivenNormalsCheck check_given_normals(std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals,
                                      std::size_t neighbours, std::size_t samples) {
  GivenNormalsCheck out;
  const std::size_t n = points.size();
  if (n < 4 || normals.size() != n || samples == 0) return out;
  const PointIndex index(points);
  const std::size_t k = std::clamp<std::size_t>(neighbours, 3, n - 1);
  const std::size_t m = std::min(n, samples);
  std::vector<std::uint8_t> off(m, 0), against(m, 0), used(m, 0), spread(m, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 256), [&](const tbb::blocked_range<std::size_t>& range) {
    std::vector<Neighbour> nb;
    for (std::size_t s = range.begin(); s != range.end(); ++s) {
      const std::size_t i = s * n / m;
      const double nn = normals[i].norm();
      if (!(nn > 0)) continue;
      const Eigen::Vector3d ni = normals[i] / nn;
      const auto es = neighbourhood_pca(index, points, points[i], k + 1, k + 1, nb);
      if (es.info() != Eigen::Success || !(es.eigenvalues()[1] > 0)) continue;  // collinear or coincident
      used[s] = 1;
      if (spreads_over_a_plane(es.eigenvalues())) spread[s] = 1, off[s] = std::abs(ni.dot(es.eigenvectors().col(0))) < 0.5;
      // Orientation: the 8 nearest distinct neighbours.
      double agreeing[8];
      std::size_t seen = 0, agree = 0;
      for (const auto& [j, d2] : nb) {
        if (!(d2 > 0) || seen == 8) continue;
        ++seen;
        if (ni.dot(normals[j]) >= 0) agreeing[agree++] = std::abs(ni.dot(points[j] - points[i]));
      }
      std::nth_element(agreeing, agreeing + agree / 2, agreeing + agree);
      const double rough = agree > 0 ? agreeing[agree / 2] : 0.0;
      std::size_t on_sheet = 0, opposed = 0;
      seen = 0;
      for (const auto& [j, d2] : nb) {
        if (!(d2 > 0) || seen == 8) continue;
        ++seen;
        const double h = std::abs(ni.dot(points[j] - points[i]));
        if (h > 0.5 * std::sqrt(d2)) continue;  // more than 30° off the tangent plane
        const bool opp = ni.dot(normals[j]) < 0;
        if (opp && h > 2.0 * rough) continue;  // off the sheet its agreeing neighbours lie on
        ++on_sheet;
        opposed += opp;
      }
      against[s] = 3 * opposed > on_sheet;
    }
  });
  for (std::size_t s = 0; s < m; ++s)
    out.points += used[s], out.spread += spread[s], out.off_plane += off[s], out.against += against[s];
  return out;
}

}  // namespace quadrix
